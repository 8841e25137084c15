//! End to end over real UDP on loopback: the simulated FRI controller
//! drives the reference plant, the FRI client runs the kernel, the whole
//! estimation motion at a 1 ms send period (unpaced: as fast as the loop
//! answers, see README).

use limb_kernel::StateKind;
use limb_kuka::loopback::{run_reference_session, LoopbackRun};
use limb_kuka::robot::Overlay;
use limb_kuka::sim_controller::{Pacing, SimSettings};
use limb_kuka::FriVersion;
use limb_session::operator::describe;
use limb_session::Operator;

type Run = LoopbackRun<Operator>;
use std::sync::Mutex;

/// Estimation motion (~29.3 s) + start-up, in 1 ms cycles.
const ESTIMATION_CYCLES: u64 = 32_000;

/// One loop at a time, to keep the suite's load on two cores modest.
static SERIAL: Mutex<()> = Mutex::new(());

fn estimate(version: FriVersion, overlay: Overlay) -> Run {
    let _serial = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut sim = SimSettings::new(version);
    sim.overlay = overlay;
    let run = run_reference_session(sim, ESTIMATION_CYCLES, |_, state| {
        state >= StateKind::Validated
    })
    .unwrap();
    eprintln!(
        "{version} {overlay:?}: sim {:?}\nclient {:?}\nevents {:?}\nmodel {:?}",
        {
            let mut stats = run.sim.stats().clone();
            stats.round_trips_us.clear();
            stats
        },
        run.robot.record().client,
        run.events,
        run.outcome.model
    );
    run
}

fn assert_estimated(run: &Run) {
    assert!(
        run.events
            .iter()
            .any(|event| describe(event).starts_with("Estimate → Validated")),
        "{:?}",
        run.events
    );
    assert_ne!(run.kernel.state().kind(), StateKind::SafeStop);
    let model = run.outcome.model.expect("a validated model");
    let truth = run.sim.plant().truth();
    assert!((model.upper_arm_length - 0.30).abs() < 1e-3, "{model:?}");
    assert!((model.forearm_length - 0.20).abs() < 1e-3, "{model:?}");
    let shoulder_error = model.shoulder.distance(truth.shoulder);
    assert!(shoulder_error < 1e-3, "{model:?} vs {truth:?}");
    let stats = run.sim.stats();
    assert_eq!(stats.non_finite_replies, 0);
    assert_eq!(stats.commanding_entries, 1);
    assert_eq!(stats.overlay_aborts, 0);
}

#[test]
fn joint_position_overlay_estimates_the_arm_over_udp() {
    let run = estimate(FriVersion::V1_15, Overlay::JointPosition);
    assert_estimated(&run);
}

#[test]
fn wrench_overlay_estimates_the_arm_over_udp() {
    let run = estimate(FriVersion::V2_7, Overlay::Wrench);
    assert_estimated(&run);
}

/// Paced for 2 s: the controller keeps its period (200 cycles of 10 ms, the
/// longest commanding period, take 2 s of wall time, not less) and the
/// client answers nearly every cycle in time. Not 1 ms: a debug build of
/// both sides (median cycle ≈ 0.5 ms) does not hold 1 kHz on two shared
/// cores; the 1 ms figures come from the release harness (README). The
/// bound leaves room for a loaded machine.
#[test]
fn paced_loop_keeps_the_send_period() {
    let _serial = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut sim = SimSettings::new(FriVersion::V1_15);
    sim.pacing = Pacing::RealTime;
    sim.send_period_ms = 10;
    let started = std::time::Instant::now();
    let run = run_reference_session(sim, 200, |_, _| false).unwrap();
    let wall = started.elapsed().as_secs_f64();
    let stats = run.sim.stats();
    assert!(wall >= 1.99, "{wall} s");
    assert_eq!(stats.cycles, 200);
    assert!(
        stats.replies_on_time >= 180,
        "{} on time, {} missed, {} late, states {:?}, {:?}",
        stats.replies_on_time,
        stats.missed_cycles,
        stats.late_replies,
        stats.state_cycles,
        stats.latency()
    );
    assert_eq!(stats.non_finite_replies, 0);
    assert!(stats.latency().p50_us < 10_000.0, "{:?}", stats.latency());
}
