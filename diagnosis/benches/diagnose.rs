//! Time to diagnose one 29 s arm log, lengths not given (fitted with the
//! effects), across all fourteen candidates, on one thread and on two, beside
//! its unit of work — one run of the reference plant over the same log —
//! measured in the same process.
//!
//! ```text
//! cargo bench -p limb-diagnosis --bench diagnose
//! ```
//!
//! The medians are written to `benchmarks/diagnose.md`, which the READMEs
//! show.
//!
//! The log: `shared/data/effects/backlash.csv` (2 917 samples, 29.16 s).

use criterion::Criterion;
use limb_diagnosis::plant::arm::{diagnose, ArmBuild, ArmModel, Lengths};
use limb_diagnosis::Model;
use std::hint::black_box;
use std::time::Duration;

fn log() -> Vec<limb_sim::log::Record> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/effects/backlash.csv");
    limb_sim::log::read(&path).expect("the shared backlash log")
}

fn benches(c: &mut Criterion) {
    let records = log();
    let mut group = c.benchmark_group("diagnose_29s_log");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(40));
    let model = ArmModel::new(Lengths::Given(0.3, 0.2), ArmBuild::Rod, &records).expect("model");
    let mass = model
        .candidates()
        .iter()
        .position(|c| c.name == "mass_mismatch")
        .expect("a dynamics-side candidate");
    group.bench_function("one_plant_run", |b| {
        b.iter(|| {
            model
                .predict(black_box(&[limb_diagnosis::Applied {
                    candidate: mass,
                    values: vec![1.1],
                }]))
                .expect("sim")
        })
    });
    // One thread is the work itself; two, the machine's two cores, are
    // what `limb diagnose` uses here.
    for threads in [1, 2] {
        group.bench_function(format!("all_candidates_{threads}_threads"), |b| {
            b.iter(|| {
                diagnose(
                    Lengths::Fitted,
                    ArmBuild::Rod,
                    black_box(&records),
                    threads,
                    &|_| {},
                )
                .expect("diagnosis")
            })
        });
    }
    group.finish();
}

/// Criterion's median of one benchmark of the group [s].
fn median(function: &str) -> Option<f64> {
    let target = std::env::var("CARGO_TARGET_DIR")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../target").to_string());
    let path = format!("{target}/criterion/diagnose_29s_log/{function}/new/estimates.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    json["median"]["point_estimate"]
        .as_f64()
        .map(|ns| ns * 1e-9)
}

fn write_figures() {
    let (Some(plant), Some(one), Some(two)) = (
        median("one_plant_run"),
        median("all_candidates_1_threads"),
        median("all_candidates_2_threads"),
    ) else {
        eprintln!("criterion estimates missing: benchmarks/diagnose.md not written");
        return;
    };
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "unknown".into());
    let report = format!(
        "# Diagnosis benchmark\n\n`cargo bench -p limb-diagnosis --bench diagnose` on this machine \
         (criterion medians, 10 samples each, all three in one process; load average {load} \
         on 2 cores when the bench finished). The log: \
         `shared/data/effects/backlash.csv` (2 917 samples, 29.16 s), lengths not given (fitted), \
         all fourteen candidates.\n\n\
         | measured | median | plant runs |\n|---|---|---|\n\
         | one run of the reference plant over the log (the unit of work) | {:.2} ms | 1 |\n\
         | diagnosis, all candidates, 1 thread | {one:.2} s | {:.0} |\n\
         | diagnosis, all candidates, 2 threads | {two:.2} s | {:.0} |\n",
        plant * 1e3,
        one / plant,
        two / plant
    );
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../benchmarks/diagnose.md");
    if let Err(error) = std::fs::write(path, report) {
        eprintln!("could not write {path}: {error}");
    }
}

fn main() {
    let mut criterion = Criterion::default().configure_from_args();
    benches(&mut criterion);
    criterion.final_summary();
    let measuring = !std::env::args().any(|a| a == "--test" || a == "--list");
    if measuring {
        write_figures();
    }
}
