//! REQ-TIME-001, REQ-TIME-002: benchmark of kernel steps — in Manipulate
//! (monitors + impedance), in Estimate while recording a path sample and
//! while concluding (a slice of the refinement), with the bare impedance
//! law measured side by side as the baseline — and of every step of a whole
//! session, by state.
//!
//! Three measurements in one process:
//! * criterion's estimate of the mean time per step, for `step/manipulate`,
//!   `step/estimate-recording`, `step/estimate-concluding` and the baseline
//!   `impedance/law`;
//! * a per-call latency distribution (median, 99th, 99.9th percentile, max)
//!   over the whole manipulation move, each call timed on its own;
//! * every step of a whole session at 1 kHz (the synthetic lift of
//!   `limb_verification::scenario`), timed alone and grouped by state and
//!   Estimate phase, so the slowest step of a session is known.
//!
//! The figures are written to `benchmarks/step.md`, which the README shows.
//! Run: `cargo bench -p limb-verification --bench step`.

use criterion::{black_box, Criterion};
use limb_kernel::arm::JointAngles;
use limb_kernel::impedance::ImpedanceLaw;
use limb_kernel::motion::SetPoint;
use limb_kernel::path::is_due;
use limb_kernel::state::EstimateStage;
use limb_kernel::State;
use limb_kernel::{Kernel, PathSample, Request, StateKind};
use limb_verification::scenario::{
    arm, kernel_after_lift, kernel_in_grasp, lift_angles, lift_frame, LIFT_WRENCH, TARGET,
};
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
        let command = kernel.step(Some(&frame), now);
        assert_eq!(
            command.state,
            StateKind::Manipulate,
            "the bench move must stay in Manipulate"
        );
        frames.push(frame);
    }
    (base, frames)
}

/// Which kind of step a kernel is about to take.
fn step_kind(kernel: &Kernel, frame: &PathSample) -> &'static str {
    match kernel.state() {
        State::Estimate(estimate) => match estimate.stage() {
            EstimateStage::Concluding(_) => "Estimate, concluding (refinement slice)",
            _ if is_due(kernel.path().last(), frame.time) => "Estimate, recording a path sample",
            _ => "Estimate, between samples",
        },
        State::Grasp(_) => "Grasp",
        State::Validated(_) => "Validated",
        State::Manipulate(_) => "Manipulate",
        State::SafeStop(_) => "SafeStop",
    }
}

/// A whole session at 1 kHz on the synthetic lift: each step timed alone,
/// with the kind of step it was. Also returns a kernel about to take a
/// recording step and one about to take a concluding step, with the frame.
/// A kernel about to take a step, and the frame of that step.
type Poised = (Kernel, PathSample);

fn session() -> (Vec<(&'static str, Duration)>, Poised, Poised) {
    let arm = arm(0.30, 0.20);
    let mut kernel = kernel_in_grasp(&arm);
    kernel
        .request(Request::StartEstimation, 0.0)
        .expect("grasp is fresh");
    let mut times = Vec::new();
    let mut recording = None;
    let mut concluding = None;
    let mut i = 0u32;
    while kernel.state().kind() == StateKind::Estimate && i < 40_000 {
        i += 1;
        let t = f64::from(i) * PERIOD;
        let frame = lift_frame(&arm, t);
        let kind = step_kind(&kernel, &frame);
        if kind.contains("recording") && t > 10.0 && recording.is_none() {
            recording = Some((kernel.clone(), frame));
        }
        if kind.contains("concluding") && concluding.is_none() {
            concluding = Some((kernel.clone(), frame));
        }
        let start = Instant::now();
        black_box(kernel.step(Some(black_box(&frame)), t));
        times.push((kind, start.elapsed()));
    }
    let t = f64::from(i) * PERIOD;
    kernel
        .request(Request::ApproveManipulation(TARGET), t)
        .expect("target is valid");
    for j in 1..=2_000 {
        let now = t + f64::from(j) * PERIOD;
        let frame = PathSample {
            time: now,
            pose: arm.forward(lift_angles(t)),
            wrench: LIFT_WRENCH,
        };
        let kind = step_kind(&kernel, &frame);
        let start = Instant::now();
        black_box(kernel.step(Some(black_box(&frame)), now));
        times.push((kind, start.elapsed()));
    }
    (
        times,
        recording.expect("a recording step after 10 s"),
        concluding.expect("the session concludes"),
    )
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

    let (session_times, recording, concluding) = session();
    let mut criterion = Criterion::default().configure_from_args().without_plots();
    for (name, (kernel, frame)) in [
        ("step/estimate-recording", &recording),
        ("step/estimate-concluding", &concluding),
    ] {
        criterion.bench_function(name, |b| {
            b.iter_batched_ref(
                || kernel.clone(),
                |k| black_box(k.step(Some(black_box(frame)), frame.time)),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    criterion.bench_function("step/manipulate", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut left = iters;
            while left > 0 {
                let mut kernel = base.clone();
                let n = (left as usize).min(frames.len());
                let start = Instant::now();
                for (i, frame) in frames[..n].iter().enumerate() {
                    black_box(kernel.step(Some(black_box(frame)), now(i)));
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
            black_box(kernel.step(Some(black_box(frame)), now(i)));
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
    let mut kinds: Vec<&str> = session_times.iter().map(|(k, _)| *k).collect();
    kinds.sort_unstable();
    kinds.dedup();
    let mut session_rows = String::new();
    for kind in kinds {
        let mut s: Vec<Duration> = session_times
            .iter()
            .filter(|(k, _)| *k == kind)
            .map(|(_, d)| *d)
            .collect();
        s.sort();
        session_rows.push_str(&row(kind, &s));
        session_rows.push('\n');
    }
    let slowest = session_times
        .iter()
        .max_by_key(|(_, d)| *d)
        .map_or(("none", Duration::ZERO), |(k, d)| (*k, *d));
    let report = format!(
        "# Kernel step benchmark\n\n\
         `cargo bench -p limb-verification --bench step` on this machine; each call \
         timed alone (includes ~20-30 ns of `Instant::now` overhead).\n\n\
         | measured | calls | median [ns] | p99 [ns] | p99.9 [ns] | max [ns] |\n\
         |---|---|---|---|---|---|\n{}\n{}\n\n\
         Median ratio, step in Manipulate / bare impedance law (same process, \
         interleaved): {ratio:.1}.\n\n\
         ## Every step of a whole session (REQ-TIME-002)\n\n\
         The synthetic lift of `limb_verification::scenario` (l1 0.30 m, l2 0.20 m) \
         at 1 kHz from Grasp through the estimation (recording, shaping, the \
         refinement in slices while held) to Validated, then 2 s of Manipulate; \
         each step timed alone.\n\n\
         | step | calls | median [ns] | p99 [ns] | p99.9 [ns] | max [ns] |\n\
         |---|---|---|---|---|---|\n{session_rows}\n\
         Slowest step of the session: {} ns ({}). Criterion's means for \
         `step/estimate-recording`, `step/estimate-concluding` and \
         `step/manipulate` are printed above when the bench runs.\n",
        row("step in Manipulate (monitors + impedance)", &samples),
        row("baseline: bare impedance law", &baseline),
        slowest.1.as_nanos(),
        slowest.0,
    );
    print!("{report}");
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../benchmarks/step.md");
    if let Err(error) = std::fs::write(path, report) {
        eprintln!("could not write {path}: {error}");
    }
}
