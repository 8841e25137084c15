//! Regenerates the estimator accuracy tables of
//! `kernel/src/estimation/README.md`:
//!
//! ```text
//! cargo run -p limb-kernel --release --example estimation_table
//! ```
//!
//! Errors are estimate − truth in mm; truth from plant.md Table 1 /
//! `labels.json` and the logged shoulder (ground truth, used only here).

#[path = "../tests/support/logs.rs"]
mod logs;

use limb_kernel::config::ValidationLimits;
use limb_kernel::estimation::{estimate_arm, Method};
use limb_kernel::validate::{validate, Rejection};

const METHODS: [(Method, &str); 3] = [
    (Method::Hough, "hough"),
    (Method::Ls, "ls"),
    (Method::Auto, "auto"),
];

fn row(name: &str, log: &logs::Log, l1: f64, l2: f64) {
    let mut cells = Vec::new();
    for (method, _) in METHODS {
        cells.push(match estimate_arm(&log.path, method) {
            Ok(e) => {
                let shoulder = log
                    .shoulder
                    .map_or(f64::NAN, |s| e.shoulder.distance(s) * 1e3);
                format!(
                    "{:+.2} / {:+.2} / {:.2}",
                    (e.upper_arm_length - l1) * 1e3,
                    (e.forearm_length - l2) * 1e3,
                    shoulder
                )
            }
            Err(error) => format!("{error:?}"),
        });
    }
    println!("| {name} | {} |", cells.join(" | "));
}

/// What `Auto` saw on a log and what the default validator says.
fn evidence_row(name: &str, log: &logs::Log) {
    match estimate_arm(&log.path, Method::Auto) {
        Ok(e) => {
            let v = e.evidence;
            let start = log.path.first().map(|s| s.pose.point()).unwrap_or_default();
            let verdict = match validate(&e, start, &ValidationLimits::default()) {
                Ok(_) => "accepted".to_string(),
                Err(rejection) => format!("{rejection:?}"),
            };
            // The start-pose mismatch: the only check left failing when every
            // other limit is wide open and the mismatch tolerance is zero.
            let open = ValidationLimits {
                min_arc: 0.0,
                max_residual: f64::MAX,
                max_method_disagreement: f64::MAX,
                max_geometry_mismatch: 0.0,
                max_shoulder_height: f64::MAX,
                ..ValidationLimits::default()
            };
            let mismatch = match validate(&e, start, &open) {
                Err(Rejection::GeometryInconsistent(m)) => format!("{:.2}", m * 1e3),
                other => format!("{other:?}"),
            };
            println!(
                "| {name} | {:.2} / {:.2} | {:.3} / {:.3} | {:.3} | {mismatch} | {} / {} | {verdict} |",
                v.forearm_arc,
                v.upper_arm_arc,
                v.forearm_residual * 1e3,
                v.upper_arm_residual * 1e3,
                v.method_disagreement.map_or(f64::NAN, |d| d * 1e3),
                v.forearm_samples,
                v.upper_arm_samples,
            );
        }
        Err(error) => println!("| {name} | {error:?} | | | | |"),
    }
}

fn main() {
    let header = METHODS
        .map(|(_, name)| format!("{name}: l1 / l2 / shoulder"))
        .join(" | ");
    println!("Six noisy benchmark logs (errors in mm):\n\n| log | {header} |\n|---|---|---|---|");
    for case in 1..=6 {
        let (l1, l2) = logs::case_lengths(case);
        row(
            &format!("noisy/case{case}"),
            &logs::read(&format!("noisy/case{case}.csv")),
            l1,
            l2,
        );
    }
    println!("\nLabelled effect logs (errors in mm):\n\n| log | {header} |\n|---|---|---|---|");
    let effects = logs::labelled_effects();
    for e in &effects {
        row(
            &e.effect,
            &logs::read(&format!("effects/{}", e.file)),
            e.l1,
            e.l2,
        );
    }
    println!(
        "\n`Auto` evidence and the default validator:\n\n| log | arcs [rad] phase 1 / 2 | RMS residual [mm] 1 / 2 | Hough disagreement [mm] | start-pose mismatch [mm] | samples 1 / 2 | validator |\n|---|---|---|---|---|---|---|"
    );
    for case in 1..=6 {
        let name = format!("noisy/case{case}");
        evidence_row(&name, &logs::read(&format!("{name}.csv")));
    }
    for e in &effects {
        evidence_row(&e.file, &logs::read(&format!("effects/{}", e.file)));
    }
}
