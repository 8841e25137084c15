//! End to end over real UDP on loopback: the simulated FRI controller
//! drives the reference plant, the FRI client runs the kernel, the whole
//! estimation motion at a 1 ms send period (unpaced: as fast as the loop
//! answers, see README).

use limb_kernel::StateKind;
use limb_kuka::kernel_controller::Overlay;
use limb_kuka::loopback::{run_reference_session, LoopbackRun};
use limb_kuka::sim_controller::SimSettings;
use limb_kuka::FriVersion;
use std::sync::Mutex;

/// Estimation motion (~29.3 s) + start-up, in 1 ms cycles.
const ESTIMATION_CYCLES: u64 = 32_000;

/// One loop at a time, to keep the suite's load on two cores modest.
static SERIAL: Mutex<()> = Mutex::new(());

fn estimate(version: FriVersion, overlay: Overlay) -> LoopbackRun {
    let _serial = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut sim = SimSettings::new(version);
    sim.overlay = overlay;
    let run = run_reference_session(sim, ESTIMATION_CYCLES, |_, state| {
        state >= StateKind::Validated
    })
    .unwrap();
    let record = run.controller.record();
    eprintln!(
        "{version} {overlay:?}: sim {:?}\nclient {:?}\nevents {:?}\nmodel {:?}",
        {
            let mut stats = run.sim.stats().clone();
            stats.round_trips_us.clear();
            stats
        },
        run.client,
        record.events,
        record.model
    );
    run
}

fn assert_estimated(run: &LoopbackRun) {
    let record = run.controller.record();
    assert!(
        record
            .events
            .iter()
            .any(|(_, what)| what.starts_with("Estimate → Validated")),
        "{:?}",
        record.events
    );
    assert_ne!(run.controller.kernel().state().kind(), StateKind::SafeStop);
    let model = record.model.expect("a validated model");
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
