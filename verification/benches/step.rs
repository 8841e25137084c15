//! REQ-TIME-001: benchmark of one kernel step in Manipulate (monitors + impedance), with
//! the bare impedance law measured side by side as the baseline.
//!
//! Two measurements in one process:
//! * criterion's estimate of the mean time per step, for `step/manipulate`
//!   and the baseline `impedance/law`;
//! * a per-call latency distribution (median, 99th, 99.9th percentile, max)
//!   over the whole manipulation move, each call timed on its own.
//!
//! The figures are written to `benchmarks/step.md`, which the README shows.
//! Run: `cargo bench -p limb-verification --bench step`.

use criterion::{black_box, Criterion};
use limb_kernel::arm::JointAngles;
use limb_kernel::impedance::ImpedanceLaw;
use limb_kernel::motion::SetPoint;
use limb_kernel::{Kernel, PathSample, Request, StateKind};
use limb_verification::scenario::{arm, kernel_after_lift, lift_angles, LIFT_WRENCH, TARGET};
use std::time::{Duration, Instant};

/// Control period of the benchmark [s] (FRI at 1 kHz).
const PERIOD: f64 = 0.001;

/// Steps of the measured arm motion during the bench move (10 s at 1 kHz).
const MOVE_STEPS: u32 = 10_000;

/// A kernel that just entered Manipulate, and the frames of the arm moving
/// smoothly in joint space from where the lift left it to the target while
/// the kernel's set-point moves there too.
fn manipulation() -> (Kernel, Vec<PathSample>) {
    let arm = arm(0.30, 0.20);
    let (mut kernel, t) = kernel_after_lift(&arm);
    assert_eq!(kernel.state().kind(), StateKind::Validated);
    kernel
        .request(Request::ApproveManipulation(TARGET), t)
        .expect("target is valid");
    let base = kernel.clone();
    let from = lift_angles(t);
    let mut frames = Vec::new();
    for i in 1..=MOVE_STEPS + 100 {
        let s = f64::from(i.min(MOVE_STEPS)) / f64::from(MOVE_STEPS);
        let s = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
        let q = JointAngles {
            shoulder_elevation: from.shoulder_elevation
                + s * (TARGET.shoulder_elevation - from.shoulder_elevation),
            elbow_flexion: from.elbow_flexion + s * (TARGET.elbow_flexion - from.elbow_flexion),
        };
        let now = t + f64::from(i) * PERIOD;
        let frame = PathSample {
            time: now,
            pose: arm.forward(q),
            wrench: LIFT_WRENCH,
        };
        let command = kernel.step(&frame, now);
        assert_eq!(
            command.state,
            StateKind::Manipulate,
            "the bench move must stay in Manipulate"
        );
        frames.push(frame);
    }
    (base, frames)
}

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    let index = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[index]
}

fn main() {
    let (base, frames) = manipulation();
    let now = |i: usize| frames[i].time;
    let config = *base.config();
    let law = ImpedanceLaw::new(
        &config.impedance,
        config.limits.max_force,
        config.limits.max_torque,
        config.limits.max_speed,
    );

    let mut criterion = Criterion::default().configure_from_args().without_plots();
    criterion.bench_function("step/manipulate", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut left = iters;
            while left > 0 {
                let mut kernel = base.clone();
                let n = (left as usize).min(frames.len());
                let start = Instant::now();
                for (i, frame) in frames[..n].iter().enumerate() {
                    black_box(kernel.step(black_box(frame), now(i)));
                }
                total += start.elapsed();
                left -= n as u64;
            }
            total
        })
    });
    criterion.bench_function("impedance/law", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) % frames.len();
            let frame = &frames[i];
            black_box(law.command(
                black_box(frame.pose),
                black_box(limb_kernel::geometry::PoseRate::ZERO),
                black_box(SetPoint::hold(frame.pose)),
            ))
        })
    });
    criterion.final_summary();

    // Per-call latency, each call timed alone, several passes over the move.
    let mut samples = Vec::with_capacity(frames.len() * 20);
    let mut baseline = Vec::with_capacity(frames.len() * 20);
    for _ in 0..20 {
        let mut kernel = base.clone();
        for (i, frame) in frames.iter().enumerate() {
            let start = Instant::now();
            black_box(kernel.step(black_box(frame), now(i)));
            samples.push(start.elapsed());
            let start = Instant::now();
            black_box(law.command(
                black_box(frame.pose),
                black_box(limb_kernel::geometry::PoseRate::ZERO),
                black_box(SetPoint::hold(frame.pose)),
            ));
            baseline.push(start.elapsed());
        }
    }
    samples.sort();
    baseline.sort();
    let row = |name: &str, s: &[Duration]| {
        format!(
            "| {name} | {} | {:.0} | {:.0} | {:.0} | {:.0} |",
            s.len(),
            percentile(s, 0.5).as_nanos(),
            percentile(s, 0.99).as_nanos(),
            percentile(s, 0.999).as_nanos(),
            s.last().map_or(0, Duration::as_nanos),
        )
    };
    let ratio = percentile(&samples, 0.5).as_nanos() as f64
        / percentile(&baseline, 0.5).as_nanos().max(1) as f64;
    let report = format!(
        "# Kernel step benchmark\n\n\
         `cargo bench -p limb-verification --bench step` on this machine; each call \
         timed alone (includes ~20-30 ns of `Instant::now` overhead).\n\n\
         | measured | calls | median [ns] | p99 [ns] | p99.9 [ns] | max [ns] |\n\
         |---|---|---|---|---|---|\n{}\n{}\n\n\
         Median ratio, step in Manipulate / bare impedance law (same process, \
         interleaved): {ratio:.1}.\n",
        row("step in Manipulate (monitors + impedance)", &samples),
        row("baseline: bare impedance law", &baseline),
    );
    print!("{report}");
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../benchmarks/step.md");
    if let Err(error) = std::fs::write(path, report) {
        eprintln!("could not write {path}: {error}");
    }
}
