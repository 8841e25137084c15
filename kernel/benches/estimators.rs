//! Estimator timings on one 300-point path, beside a literal implementation
//! of the paper's Algorithm 1 (paper: 1.7334 s Hough, 5.1 ms LS, MATLAB on an
//! i7-3630, 300 points).
//!
//! ```text
//! cargo bench -p limb-kernel --bench estimators
//! ```
//!
//! The path: phase 1 of `shared/data/noisy/case3.csv` (l2 = 0.2 m), 300
//! samples evenly spaced over it (the paper's path length).

#[path = "../tests/support/logs.rs"]
#[allow(dead_code)]
mod logs;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use limb_kernel::estimation::{
    detect_phases, estimate_arm, fit_circle_geometric, fit_circle_kasa, fit_circle_taubin,
    fit_forearm_pose, hough_circle_normals, FreeCorrections, Method, PointModel,
};
use limb_kernel::path::PathSample;
use std::time::Duration;

/// The paper's ρ: largest radius and half-width of the centre search [mm].
const RHO: i64 = 500;
/// Accumulator side for s and t: σ = ς = 2ρ cells of 1 mm (eq. 17).
const SIDE: i64 = 2 * RHO;

/// Paper Algorithm 1, literally: a dense ρ × σ × ς accumulator of 1 mm
/// cells (500 × 1000 × 1000 u16, 1 GB), zeroed, then for every sample and
/// every s in [x_i − ρ, x_i + ρ] the centre t on the sample's normal
/// (eq. 18, frame S: the centre lies along (cos psi, −sin psi)), r from
/// eq. 13, one vote if r ≤ ρ; finally the argmax over all cells. The s and
/// t axes start at the first sample's x − ρ and z − ρ. Returns r* [m].
fn hough_literal(samples: &[PathSample], accumulator: &mut [u16]) -> f64 {
    accumulator.fill(0);
    let origin_x = (samples[0].pose.x * 1e3).round() as i64 - RHO;
    let origin_z = (samples[0].pose.z * 1e3).round() as i64 - RHO;
    for sample in samples {
        let (x, z) = (sample.pose.x * 1e3, sample.pose.z * 1e3);
        let slope = sample.pose.psi.tan();
        let x_cell = x.round() as i64;
        for s in x_cell - RHO..=x_cell + RHO {
            let t = (z - (s as f64 - x) * slope).round() as i64;
            let r = ((x - s as f64).powi(2) + (z - t as f64).powi(2))
                .sqrt()
                .round() as i64;
            let (si, ti) = (s - origin_x, t - origin_z);
            if r <= RHO && r > 0 && (0..SIDE).contains(&si) && (0..SIDE).contains(&ti) {
                accumulator[(((r - 1) * SIDE + si) * SIDE + ti) as usize] += 1;
            }
        }
    }
    let (best, _) = accumulator
        .iter()
        .enumerate()
        .max_by_key(|&(_, votes)| *votes)
        .unwrap();
    (best as i64 / (SIDE * SIDE) + 1) as f64 * 1e-3
}

fn path() -> (Vec<PathSample>, Vec<PathSample>) {
    let log = logs::read("noisy/case3.csv");
    let phases = detect_phases(&log.path, &PointModel::GRASP).unwrap();
    let n = phases.forearm.len();
    let short = (0..300)
        .map(|i| log.path[phases.forearm.start + i * (n - 1) / 299])
        .collect();
    (short, log.path)
}

fn estimators(c: &mut Criterion) {
    let (samples, full_log) = path();
    let grasp = PointModel::GRASP;
    let collected: Vec<_> = grasp.points(&samples, 0..samples.len()).collect();
    let points = || collected.iter().copied();
    let mut group = c.benchmark_group("300-point phase-1 path");
    group.bench_function("kasa (paper LS)", |b| {
        b.iter(|| fit_circle_kasa(black_box(points())))
    });
    group.bench_function("taubin", |b| {
        b.iter(|| fit_circle_taubin(black_box(points())))
    });
    group.bench_function("taubin + robust geometric", |b| {
        b.iter(|| fit_circle_geometric(points(), fit_circle_taubin(black_box(points())).unwrap()))
    });
    group.bench_function("forearm-pose model (auto phase 1)", |b| {
        b.iter(|| {
            fit_forearm_pose(
                black_box(&samples),
                0..samples.len(),
                &grasp,
                FreeCorrections::default(),
            )
        })
    });
    group.bench_function("bounded hough", |b| {
        b.iter(|| {
            hough_circle_normals(samples.len(), |i| {
                black_box(&samples)
                    .get(i)
                    .map(|s| (s.pose.point(), s.pose.psi))
            })
        })
    });
    let mut accumulator = vec![0u16; (RHO * SIDE * SIDE) as usize];
    let r = hough_literal(&samples, &mut accumulator);
    eprintln!("literal Algorithm 1: r* = {r} m");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(30));
    group.bench_function("paper algorithm 1, literal (500x1000x1000)", |b| {
        b.iter(|| hough_literal(black_box(&samples), &mut accumulator))
    });
    group.finish();
    let mut group = c.benchmark_group("whole log (2917 samples)");
    for (method, name) in [
        (Method::Ls, "estimate_arm ls"),
        (Method::Hough, "estimate_arm hough"),
        (Method::Auto, "estimate_arm auto"),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| estimate_arm(black_box(&full_log), method))
        });
    }
    group.finish();
}

criterion_group!(benches, estimators);
criterion_main!(benches);
