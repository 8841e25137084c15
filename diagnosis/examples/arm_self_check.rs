//! The blind self-check of the arm diagnosis (what `limb diagnose
//! --self-check N --seed S --json` prints), with every finished log as
//! one JSON line on stderr, for a run left in the background:
//! `cargo run --release -p limb-diagnosis --example arm_self_check -- N SEED [THREADS] [robot|human|all] > summary.json 2> progress.jsonl`
//! (`robot`: plant.md's ten, the default; `human`: a person's arm's four, see `blind::Focus`).
use limb_diagnosis::plant::arm::blind::{run_focused, Focus};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<u64>());
    let count = args.next().transpose()?.unwrap_or(20) as usize;
    let seed = args.next().transpose()?.unwrap_or(1);
    let threads = match args.next().transpose()? {
        Some(n) => n as usize,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let name = std::env::args().nth(4).unwrap_or_else(|| "robot".into());
    let focus = Focus::parse(&name).ok_or(format!("focus `{name}`: robot, human or all"))?;
    let start = Instant::now();
    let summary = run_focused(count, seed, threads, focus, &|case| {
        let line = serde_json::json!({"elapsed_s": start.elapsed().as_secs_f64(), "case": case});
        eprintln!("{line}");
    })?;
    println!("{}", serde_json::to_string_pretty(&summary)?);
    eprintln!(
        "{count} logs, seed {seed}, {threads} threads: {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
