//! Diagnoses the EMPS benchmark (`../shared/data/real/emps`): fitted on
//! the estimation run, scored on the validation run; prints the answer
//! as JSON and the ranking of every selection step.
use limb_diagnosis::drive::outcome::Run;
use limb_diagnosis::drive::{diagnose, read, CUTOFF};
use limb_diagnosis::Options;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real/emps");
    let cutoff = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(CUTOFF);
    let (fit_file, held_file) = (dir.join("estimation.csv"), dir.join("validation.csv"));
    let (fit, held) = (read(&fit_file)?, read(&held_file)?);
    let options = Options {
        max_effects: limb_diagnosis::drive::outcome::MAX_EFFECTS,
        ..Options::default()
    };
    let start = std::time::Instant::now();
    let answer = diagnose(
        Run {
            name: "estimation.csv",
            log: &fit,
        },
        Some(Run {
            name: "validation.csv",
            log: &held,
        }),
        cutoff,
        &options,
    )?;
    println!("{}", serde_json::to_string_pretty(&answer)?);
    eprintln!("took {:.2?}", start.elapsed());
    Ok(())
}
