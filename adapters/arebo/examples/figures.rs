//! Reproduces the paper's simulated experiments and writes the figures
//! next to the README:
//!
//! ```text
//! cargo run --release -p limb-arebo --example figures
//! ```
//!
//! Prints the calibration errors and median joint-angle errors; writes
//! `weight_support.csv` and `weight_support.svg` (the paper's Figure 17).

use limb_arebo::sim::{self, Setup, Trial};
use std::fmt::Write as _;
use std::path::Path;

fn svg(trials: &[Trial]) -> String {
    let (width, height, margin) = (640.0, 320.0, 40.0);
    let x = |k: usize| {
        margin + (k as f64 - 1.0) / (trials.len().max(2) as f64 - 1.0) * (width - 2.0 * margin)
    };
    let y = |alpha: f64| height - margin - alpha * (height - 2.0 * margin);
    let mut out = String::new();
    let _ = write!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" font-family=\"sans-serif\" font-size=\"11\">\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>"
    );
    for (low, high, xi) in [(1, 100, 0.6), (101, 200, 0.2), (201, 300, 0.0)] {
        if trials.len() >= low {
            let _ = write!(
                out,
                "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#bbb\" stroke-dasharray=\"4\"/>\
                 <text x=\"{:.1}\" y=\"{:.1}\">ξ = {xi}</text>",
                x(low),
                y(xi),
                x(high.min(trials.len())),
                y(xi),
                x(low) + 4.0,
                margin - 6.0
            );
        }
    }
    let points: Vec<String> = trials
        .iter()
        .map(|t| format!("{:.1},{:.1}", x(t.number), y(t.alpha)))
        .collect();
    let _ = write!(
        out,
        "<polyline fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.5\" points=\"{}\"/>",
        points.join(" ")
    );
    for t in trials.iter().filter(|t| !t.succeeded) {
        let _ = write!(
            out,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"1.5\" fill=\"#d62728\"/>",
            x(t.number),
            y(t.alpha)
        );
    }
    let _ = write!(
        out,
        "<line x1=\"{m}\" y1=\"{b}\" x2=\"{r}\" y2=\"{b}\" stroke=\"black\"/>\
         <line x1=\"{m}\" y1=\"{m}\" x2=\"{m}\" y2=\"{b}\" stroke=\"black\"/>\
         <text x=\"{m}\" y=\"{t}\">trial k (1-{n}); red dots: failed trials</text>\
         <text x=\"4\" y=\"{m}\">α = 1</text><text x=\"4\" y=\"{b}\">α = 0</text>\
         <text x=\"4\" y=\"{h}\">0.5</text></svg>",
        m = margin,
        b = height - margin,
        r = width - margin,
        t = height - 12.0,
        n = trials.len(),
        h = y(0.5)
    );
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let setup = Setup::default();
    let raw = Setup {
        compensated_backlash: [0.0; 3],
        ..setup
    };
    let clean = Setup {
        backlash: [0.0; 3],
        compensated_backlash: [0.0; 3],
        ..setup
    };
    for (name, variant) in [
        ("no backlash", clean),
        ("1 deg backlash, raw", raw),
        ("1 deg backlash, compensated", setup),
    ] {
        let model = sim::calibrate(variant, 1).map_err(|e| format!("calibration failed: {e:?}"))?;
        let errors = sim::polysine_experiment(variant, &model, 120.0, 2);
        println!(
            "{name}: psi_x error {:.3} deg, origin error {:.3} mm, length error {:.3} mm; \
             polysine 120 s median |error| flexion {:.3} deg (paper 2.10), abduction {:.3} deg (paper 1.30)",
            (model.psi_x() - variant.psi_x).to_degrees(),
            (model.origin() - variant.origin).norm() * 1e3,
            (model.length() - variant.length) * 1e3,
            errors.flexion.to_degrees(),
            errors.abduction.to_degrees()
        );
    }
    let model = sim::calibrate(setup, 1).map_err(|e| format!("calibration failed: {e:?}"))?;
    let trials = sim::weight_support_experiment(setup, &model, 300, 3);
    let folder = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut csv = String::from("trial,impairment,alpha,success\n");
    for t in &trials {
        let _ = writeln!(
            csv,
            "{},{},{:.5},{}",
            t.number,
            t.impairment,
            t.alpha,
            u8::from(t.succeeded)
        );
    }
    std::fs::write(folder.join("weight_support.csv"), csv)?;
    std::fs::write(folder.join("weight_support.svg"), svg(&trials))?;
    for (low, high) in [(1, 100), (101, 200), (201, 300)] {
        let block = &trials[low - 1..high.min(trials.len())];
        let rate = block.iter().filter(|t| t.succeeded).count() as f64 / block.len() as f64;
        let peak = block.iter().map(|t| t.alpha).fold(0.0, f64::max);
        println!(
            "trials {low}-{high}: success {:.0} %, alpha max {:.3}, alpha at end {:.3}",
            rate * 100.0,
            peak,
            block.last().map_or(f64::NAN, |t| t.alpha)
        );
    }
    Ok(())
}
