//! Diagnoses every labelled log of `shared/data/effects/` (the
//! independent implementation's) without its arm lengths and prints a
//! Markdown table: effects added, fitted parameters against the label,
//! the corrected arm's error, held-out gap, unexplained share, wall time.
//!
//! `cargo run --release -p limb-diagnosis --example shared_effects [NAME]`
//! (with NAME, only the logs whose file name contains it)

use limb_diagnosis::plant::arm::{diagnose, ArmBuild, Lengths};
use std::path::Path;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/effects");
    let labels: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("labels.json"))?)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("| log | effects added | fitted (label) | arm error l1, l2 [mm] | held-out gap before → after [σ] | shrink | unexplained | where | time |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for label in labels.as_array().ok_or("labels.json is not a list")? {
        let file = label["file"].as_str().ok_or("no file")?;
        if std::env::args()
            .nth(1)
            .is_some_and(|only| !file.contains(&only))
        {
            continue;
        }
        let records = limb_sim::log::read(&dir.join(file))?;
        let (l1, l2) = (
            label["l1"].as_f64().ok_or("no l1")?,
            label["l2"].as_f64().ok_or("no l2")?,
        );
        let start = Instant::now();
        let d = diagnose(Lengths::Fitted, ArmBuild::Rod, &records, threads, &|_| {})?.diagnosis;
        let took = start.elapsed().as_secs_f64();
        let fitted: Vec<String> = match d.effects.first() {
            Some(r) => r
                .params
                .iter()
                .map(|(k, v)| {
                    let truth = label["params"][k.as_str()].as_f64().unwrap_or(f64::NAN);
                    format!("{k} {v:.4} ({truth:.4})")
                })
                .collect(),
            _ => Vec::new(),
        };
        let place = match (d.location.t_start, d.location.t_end) {
            (Some(a), Some(b)) => format!("{} {a:.1}-{b:.1} s", d.location.signals.join(",")),
            _ => "-".into(),
        };
        let band = d
            .location
            .band_hz
            .map_or(String::new(), |[lo, hi]| format!(", {lo:.2}-{hi:.2} Hz"));
        let added: Vec<&str> = d.effects.iter().map(|e| e.effect.as_str()).collect();
        let unexplained = d.unexplained.as_ref().map_or("-".to_string(), |u| {
            format!("{:.1} % ({})", 100.0 * u.share, u.signals.join(","))
        });
        println!(
            "| {file} | {} | {} | {:+.2}, {:+.2} | {:.3} → {:.3} | {:.1} % | {unexplained} | {place}{band} | {took:.1} s |",
            if added.is_empty() { "none".to_string() } else { added.join(", ") },
            fitted.join(", "),
            1e3 * (d.arm.l1 - l1),
            1e3 * (d.arm.l2 - l2),
            d.gap.before,
            d.gap.after,
            100.0 * d.gap.shrink
        );
    }
    Ok(())
}
