//! Replays logs of a blind self-check from its progress lines (what
//! `arm_self_check` writes on stderr, one JSON line per finished log):
//! each log is simulated again from its withheld effects, arm and noise
//! seed, and diagnosed as the check did, with every selection step's five
//! best candidates printed:
//! `cargo run --release -p limb-diagnosis --example arm_replay -- progress.jsonl INDEX[,INDEX…] [THREADS]`
use limb_diagnosis::plant::arm::blind::{simulate, Case};
use limb_diagnosis::plant::arm::{diagnose, ArmBuild, Lengths};
use limb_sim::effects::Effect;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: arm_replay PROGRESS.jsonl INDEX[,INDEX…] [THREADS]";
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or(usage)?;
    let wanted = args
        .next()
        .ok_or(usage)?
        .split(',')
        .map(str::parse::<usize>)
        .collect::<Result<Vec<_>, _>>()?;
    let threads = args.next().map_or(Ok(2), |t| t.parse::<usize>())?;
    #[derive(serde::Deserialize)]
    struct Line {
        case: Case,
    }
    // The last line of a finished run is its summary in words, not JSON.
    let cases = std::fs::read_to_string(&path)?
        .lines()
        .filter_map(|line| serde_json::from_str::<Line>(line).ok())
        .map(|line| line.case)
        .filter(|case| wanted.contains(&case.index))
        .collect::<Vec<_>>();
    for index in wanted
        .iter()
        .filter(|i| cases.iter().all(|c| c.index != **i))
    {
        eprintln!("{path}: no log {index}");
    }
    for case in &cases {
        let effects = case
            .truth
            .iter()
            .zip(&case.params)
            .map(|(name, params)| {
                let pairs: Vec<(&str, f64)> =
                    params.iter().map(|(k, v)| (k.as_str(), *v)).collect();
                Effect::new(name, &pairs)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let ((l1, l2), start) = (case.arm, Instant::now());
        let records = simulate(l1, l2, case.seed, &effects)?;
        let diagnosed = diagnose(Lengths::Fitted, ArmBuild::Rod, &records, threads, &|_| {})?;
        let d = &diagnosed.diagnosis;
        let truth: Vec<String> = case
            .truth
            .iter()
            .zip(&case.params)
            .map(|(name, params)| {
                let values: Vec<String> = params
                    .iter()
                    .map(|(k, v)| format!("{k} = {v:.4}"))
                    .collect();
                format!("{name} ({})", values.join(", "))
            })
            .collect();
        println!(
            "log {}: truth {}, arm ({l1:.4}, {l2:.4}) m, seed {}",
            case.index,
            names(&truth),
            case.seed
        );
        println!(
            "  then: {}, arm off by {:.1} mm; now: {}, l1 {:+.1} mm, l2 {:+.1} mm, gap {:.2} → {:.2} σ ({:.0} s)",
            names(&case.added),
            case.arm_error * 1e3,
            names(&d.effects.iter().map(|e| e.effect.clone()).collect::<Vec<_>>()),
            (d.arm.l1 - l1) * 1e3,
            (d.arm.l2 - l2) * 1e3,
            d.gap.before,
            d.gap.after,
            start.elapsed().as_secs_f64()
        );
        for (k, step) in diagnosed.selection.steps.iter().enumerate() {
            let best: Vec<String> = step
                .ranking
                .iter()
                .take(5)
                .map(|r| {
                    format!(
                        "{} {:.2} σ ({})",
                        r.effect,
                        r.held_out_after,
                        r.parameters_text()
                    )
                })
                .collect();
            let added = step.added.as_deref().unwrap_or("nothing");
            println!("  step {k}, added {added}: {}", best.join("; "));
        }
    }
    Ok(())
}

/// `items` comma-separated, `none` when there are none.
fn names(items: &[String]) -> String {
    if items.is_empty() {
        "none".to_string()
    } else {
        items.join(", ")
    }
}
