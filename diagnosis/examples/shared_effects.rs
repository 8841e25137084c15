//! Diagnoses every labelled log of `shared/data/effects/` (the
//! independent implementation's) and prints a Markdown table: answer,
//! fitted parameters against the label, held-out gap, where, wall time.
//!
//! `cargo run --release -p limb-diagnosis --example shared_effects`

use limb_diagnosis::verdict::diagnose;
use std::path::Path;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/effects");
    let labels: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("labels.json"))?)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("| log | answer | fitted (label) | held-out gap before → after [σ] | shrink | where | time |");
    println!("|---|---|---|---|---|---|---|");
    for label in labels.as_array().ok_or("labels.json is not a list")? {
        let file = label["file"].as_str().ok_or("no file")?;
        let records = limb_sim::log::read(&dir.join(file))?;
        let (l1, l2) = (
            label["l1"].as_f64().ok_or("no l1")?,
            label["l2"].as_f64().ok_or("no l2")?,
        );
        let start = Instant::now();
        let d = diagnose(l1, l2, &records, threads, &|_| {})?.diagnosis;
        let took = start.elapsed().as_secs_f64();
        let fitted: Vec<String> = match d.ranking.first() {
            Some(r) if d.effect != "none" => r
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
        println!(
            "| {file} | {} | {} | {:.3} → {:.3} | {:.1} % | {place}{band} | {took:.1} s |",
            d.effect,
            fitted.join(", "),
            d.gap.before,
            d.gap.after,
            100.0 * d.gap.shrink
        );
    }
    Ok(())
}
