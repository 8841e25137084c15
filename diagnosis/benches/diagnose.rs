//! Time to diagnose one 29 s arm log across all ten candidates, beside
//! its unit of work — one run of the reference plant over the same log —
//! measured in the same process.
//!
//! ```text
//! cargo bench -p limb-diagnosis --bench diagnose
//! ```
//!
//! The log: `shared/data/effects/backlash.csv` (2 917 samples, 29.16 s).

use criterion::{criterion_group, criterion_main, Criterion};
use limb_diagnosis::arm::ArmModel;
use limb_diagnosis::verdict::diagnose;
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
    let model = ArmModel::new(0.3, 0.2, &records).expect("model");
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
    for threads in [1, 2] {
        group.bench_function(format!("all_candidates_{threads}_threads"), |b| {
            b.iter(|| diagnose(0.3, 0.2, black_box(&records), threads, &|_| {}).expect("diagnosis"))
        });
    }
    group.finish();
}

criterion_group!(diagnosis, benches);
criterion_main!(diagnosis);
