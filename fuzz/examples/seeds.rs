//! Writes the committed seed corpus `fuzz/seeds/<target>/` from the
//! project's own golden vectors: the FRI example datagrams of every
//! version and session state (`limb_kuka::vectors`), the golden messages of
//! `adapters/arebo/PROTOCOL.md` and `adapters/zenoh/PROTOCOL.md`, the
//! default kernel configuration, and the first rows of two shared logs.
//!
//! `cargo run --manifest-path fuzz/Cargo.toml --example seeds -- ../shared`
//! (the path of the shared inputs; run from the repository root).

use limb_kernel::KernelConfig;
use limb_kuka::vectors::{example_command, example_monitoring, SESSION_STATES};
use limb_kuka::{encode_command, encode_monitoring, FriVersion};
use limb_zenoh::wire::WireFormat;
use std::fs;
use std::path::{Path, PathBuf};

type Seeds = Vec<(String, Vec<u8>)>;

/// The fenced block after `<!-- golden: NAME -->` in `document`; `text`
/// blocks hold hex (whitespace between bytes ignored).
fn golden(document: &str, name: &str) -> Vec<u8> {
    let marker = format!("<!-- golden: {name} -->");
    let after = document
        .split_once(&marker)
        .unwrap_or_else(|| panic!("no golden {name}"))
        .1;
    let mut lines = after.lines().skip_while(|l| !l.starts_with("```"));
    let fence = lines.next().unwrap_or_default();
    let body: Vec<&str> = lines.take_while(|l| !l.starts_with("```")).collect();
    if fence == "```text" {
        let hex: String = body.concat().split_whitespace().collect();
        (0..hex.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).expect("hex golden"))
            .collect()
    } else {
        body.join("\n").into_bytes()
    }
}

fn fri() -> (Seeds, Seeds) {
    let mut datagrams = Seeds::new();
    let mut session = Seeds::new();
    for (index, version) in FriVersion::ALL.into_iter().enumerate() {
        let selector = u8::try_from(index).expect("six versions");
        let mut cycles = vec![selector, 10];
        for state in SESSION_STATES {
            let monitoring = encode_monitoring(&example_monitoring(state, version), version)
                .expect("vector encodes");
            let mut seed = vec![selector];
            seed.extend(&monitoring);
            datagrams.push((format!("monitoring-{version}-{state:?}"), seed));
            if let Some(command) = example_command(state, version) {
                let mut seed = vec![selector + 6];
                seed.extend(encode_command(&command, version).expect("vector encodes"));
                datagrams.push((format!("command-{version}-{state:?}"), seed));
            }
            let length = u16::try_from(monitoring.len()).expect("short datagram");
            cycles.push(1);
            cycles.extend(length.to_le_bytes());
            cycles.extend(&monitoring);
        }
        session.push((format!("walk-{version}"), cycles));
    }
    (datagrams, session)
}

fn zenoh(protocol: &str) -> (Seeds, Seeds, Seeds) {
    let mut commands = Seeds::new();
    for name in ["command", "command_update_limits"] {
        let mut seed = vec![0];
        seed.extend(golden(protocol, name));
        commands.push((name.to_string(), seed));
    }
    let mut cbor = vec![1];
    cbor.extend(golden(protocol, "command-cbor-hex"));
    commands.push(("command-cbor".to_string(), cbor));
    let estops = vec![("estop".to_string(), golden(protocol, "estop"))];
    let mut heartbeat = vec![0];
    heartbeat.extend(golden(protocol, "heartbeat"));
    (commands, estops, vec![("heartbeat".to_string(), heartbeat)])
}

fn arebo(protocol: &str) -> Seeds {
    let names = [
        "heartbeat",
        "set_control_torque",
        "set_control_target",
        "stream_frame",
    ];
    let all: Vec<u8> = names.iter().flat_map(|n| golden(protocol, n)).collect();
    let mut seeds: Seeds = names
        .iter()
        .map(|n| (n.to_string(), golden(protocol, n)))
        .collect();
    seeds.push(("all".to_string(), all));
    seeds
}

fn config() -> Seeds {
    let config = KernelConfig::default();
    [
        (WireFormat::Json, 0u8, "json"),
        (WireFormat::Cbor, 1, "cbor"),
    ]
    .into_iter()
    .map(|(format, mode, name)| {
        let mut seed = vec![mode];
        seed.extend(format.encode(&config).expect("default config encodes"));
        (format!("default-{name}"), seed)
    })
    .collect()
}

/// The header and first `rows` rows of the text file at `path`.
fn head(path: &Path, rows: usize) -> Vec<u8> {
    let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let lines: Vec<&str> = text.lines().take(rows + 1).collect();
    (lines.join("\n") + "\n").into_bytes()
}

/// Kernel sessions: a start (grasp, lifting, validated, manipulating)
/// followed by pseudo-random actions (the input is read by `arbitrary`).
fn kernel_sessions() -> Seeds {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    (0..8u8)
        .map(|start| {
            let mut seed = vec![start];
            for _ in 0..96 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                seed.push(state.to_le_bytes()[0]);
            }
            (format!("session-{start}"), seed)
        })
        .collect()
}

fn write(root: &Path, target: &str, seeds: Seeds) {
    let dir = root.join(target);
    fs::create_dir_all(&dir).expect("seed directory");
    for (name, bytes) in seeds {
        fs::write(dir.join(name), bytes).expect("seed written");
    }
}

fn main() {
    let shared = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "../shared".into()),
    );
    let root = Path::new("fuzz/seeds");
    let zenoh_protocol = fs::read_to_string("adapters/zenoh/PROTOCOL.md").expect("zenoh protocol");
    let arebo_protocol = fs::read_to_string("adapters/arebo/PROTOCOL.md").expect("arebo protocol");
    let (datagrams, session) = fri();
    write(root, "fri_datagram", datagrams);
    write(root, "fri_session", session);
    write(root, "arebo_stream", arebo(&arebo_protocol));
    let (commands, estops, heartbeats) = zenoh(&zenoh_protocol);
    write(root, "zenoh_command", commands);
    write(root, "zenoh_estop", estops);
    write(root, "zenoh_heartbeat", heartbeats);
    write(root, "kernel_config", config());
    write(root, "kernel_sequence", kernel_sessions());
    let plant = head(&shared.join("data/nominal/case1.csv"), 20);
    write(root, "plant_log", vec![("case1-head".to_string(), plant)]);
    let drive = head(&shared.join("data/real/emps/estimation.csv"), 40);
    write(root, "drive_log", vec![("emps-head".to_string(), drive)]);
}
