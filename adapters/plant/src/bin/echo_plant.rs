//! `limb-echo-plant [--tcp PORT] [--frames N]`: the smallest plant that
//! speaks `limb-plant/1`. Its grasp sits on the last commanded set-point
//! (none: where it was) with zero wrench; it has no arm and no truth.
//! With `--tcp PORT` it listens on 127.0.0.1:PORT (0: any free port, the
//! port printed on stderr as `listening on PORT`) for one client; else it
//! speaks on stdin/stdout. It sends `{"end": "frames done"}` after N
//! frames (default: never) and exits 0 at limb's `end` or end of input.

use std::io::{BufRead, BufReader, BufWriter, Write};
use std::net::TcpListener;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let option = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse::<u64>().ok())
    };
    let frames = option("--frames").unwrap_or(u64::MAX);
    let result = match option("--tcp") {
        Some(port) => TcpListener::bind(("127.0.0.1", u16::try_from(port).unwrap_or(0))).and_then(
            |listener| {
                eprintln!("listening on {}", listener.local_addr()?.port());
                let (stream, _) = listener.accept()?;
                stream.set_nodelay(true)?;
                serve(
                    BufReader::new(stream.try_clone()?),
                    BufWriter::new(stream),
                    frames,
                )
            },
        ),
        None => serve(
            BufReader::new(std::io::stdin().lock()),
            BufWriter::new(std::io::stdout().lock()),
            frames,
        ),
    };
    if let Err(error) = result {
        eprintln!("limb-echo-plant: {error}");
        std::process::exit(1);
    }
}

/// The value of `"key":NUMBER` in `line`, if it has one.
fn field(line: &str, key: &str) -> Option<f64> {
    let at = line.find(&format!("\"{key}\":"))? + key.len() + 3;
    let rest = &line[at..];
    let end = rest.find([',', '}']).unwrap_or(rest.len());
    rest[..end].trim().parse().ok()
}

fn serve(mut input: impl BufRead, mut output: impl Write, frames: u64) -> std::io::Result<()> {
    writeln!(
        output,
        "{{\"protocol\":\"limb-plant/1\",\"dt\":0.001,\"name\":\"echo\",\"truth\":[]}}"
    )?;
    output.flush()?;
    let mut line = String::new();
    input.read_line(&mut line)?;
    if !line.contains("\"protocol\"") {
        return Ok(());
    }
    let mut pose = [0.0_f64; 3];
    for n in 0..frames {
        let t = n as f64 * 0.001;
        writeln!(
            output,
            "{{\"frame\":{{\"t\":{t},\"x\":{},\"z\":{},\"psi\":{},\"fx\":0.0,\"fz\":0.0,\"ty\":0.0}}}}",
            pose[0], pose[1], pose[2]
        )?;
        output.flush()?;
        line.clear();
        if input.read_line(&mut line)? == 0 || line.contains("\"end\"") {
            return Ok(());
        }
        if let (Some(x), Some(z), Some(psi)) =
            (field(&line, "xd"), field(&line, "zd"), field(&line, "psid"))
        {
            pose = [x, z, psi];
        }
    }
    writeln!(output, "{{\"end\":\"frames done\"}}")?;
    output.flush()
}
