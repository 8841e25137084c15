//! Each injected fault ends in its documented behaviour (README fault
//! table), never a panic: the simulated controller and the client with the
//! kernel over real loopback UDP, the fault in the middle of the
//! estimation motion (at cycle 600, ≈ 0.5 s after it started), unpaced.

use limb_kernel::StateKind;
use limb_kuka::faults::parse_schedule;
use limb_kuka::loopback::{run_reference_session, LoopbackRun};
use limb_kuka::messages::SessionState;
use limb_kuka::robot::Overlay;
use limb_kuka::sim_controller::SimSettings;
use limb_kuka::udp::MAX_JOINT_STEP;
use limb_kuka::FriVersion;
use limb_session::Operator;
use std::sync::Mutex;

/// One loop at a time, to keep the suite's load on two cores modest.
static SERIAL: Mutex<()> = Mutex::new(());

type Run = LoopbackRun<Operator>;

fn run(version: FriVersion, faults: &str, cycles: u64) -> Run {
    run_with_overlay(version, Overlay::JointPosition, faults, cycles)
}

fn run_with_overlay(version: FriVersion, overlay: Overlay, faults: &str, cycles: u64) -> Run {
    let _serial = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut sim = SimSettings::new(version);
    sim.overlay = overlay;
    sim.faults = parse_schedule(faults, 42).unwrap();
    let run = run_reference_session(sim, cycles, |_, _| false).unwrap();
    let stats = run.sim.stats();
    eprintln!(
        "{faults}: aborts {} entries {} missed {} (delivered {}) stray {} dropped {} jump {:.2e}\n  client {:?}\n  events {:?}",
        stats.overlay_aborts,
        stats.commanding_entries,
        stats.missed_cycles,
        stats.missed_with_delivery,
        stats.stray_replies,
        stats.datagrams_dropped,
        stats.max_entry_jump,
        run.robot.record().client,
        run.events
    );
    assert_eq!(stats.non_finite_replies, 0, "NaN on the wire");
    run
}

fn kernel_state(run: &Run) -> StateKind {
    run.kernel.state().kind()
}

fn stopped_because(run: &Run, cause: &str) -> bool {
    run.stopped_because(cause)
}

/// Still estimating, never aborted, one entry into commanding.
fn assert_rides_through(run: &Run) {
    assert_eq!(kernel_state(run), StateKind::Estimate);
    assert_eq!(run.sim.stats().overlay_aborts, 0);
    assert_eq!(run.sim.stats().commanding_entries, 1);
    assert_eq!(run.sim.state(), SessionState::CommandingActive);
}

/// Overlay aborted and re-entered from the IPO position without a jump;
/// the kernel stopped because the robot stopped following mid-motion.
fn assert_stopped_and_reentered(run: &Run, cause: &str) {
    assert_eq!(kernel_state(run), StateKind::SafeStop);
    assert!(stopped_because(run, cause), "no stop with {cause}");
    let stats = run.sim.stats();
    assert_eq!(stats.commanding_entries, 2);
    assert_eq!(run.sim.state(), SessionState::CommandingActive);
    assert!(
        stats.max_entry_jump <= MAX_JOINT_STEP + 1e-12,
        "{}",
        stats.max_entry_jump
    );
}

#[test]
fn random_loss_is_ridden_through_with_gaps_counted() {
    let run = run(FriVersion::V1_15, "random-loss@600:800:0.01", 1500);
    assert_rides_through(&run);
    let dropped = run.sim.stats().datagrams_dropped;
    assert!(dropped > 0);
    assert!(run.robot.record().client.gaps > 0 && run.robot.record().client.gaps <= dropped);
    assert!(run.sim.stats().missed_cycles >= dropped);
}

/// REQ-ADP-001.
#[test]
fn loss_burst_trips_the_watchdog_then_reenters_without_jump() {
    let run = run(FriVersion::V2_5, "burst-loss@600:50", 1200);
    assert!(run.outcome.stale_steps > 0);
    assert_stopped_and_reentered(&run, "stale_sensor");
    assert!(run.sim.stats().overlay_aborts >= 1);
}

#[test]
fn delayed_datagrams_are_late_replies_then_stop() {
    let run = run(FriVersion::V2_7, "delay@600:300:2", 1300);
    let stats = run.sim.stats();
    assert!(stats.stray_replies > 0);
    assert!(run.robot.record().client.stale_datagrams > 0);
    assert!(stats.overlay_aborts >= 1);
    assert_stopped_and_reentered(&run, "request stop");
}

#[test]
fn duplicates_are_dropped_and_answered_once() {
    let run = run(FriVersion::V1_11, "duplicate@600:100", 900);
    assert_eq!(run.robot.record().client.duplicates, 100);
    assert_eq!(run.sim.stats().stray_replies, 0);
    assert_rides_through(&run);
}

#[test]
fn reordered_datagrams_keep_the_newest() {
    let run = run(FriVersion::V2_5, "reorder@600:8", 900);
    assert_eq!(run.robot.record().client.stale_datagrams, 4);
    assert_eq!(run.robot.record().client.gaps, 4);
    assert_rides_through(&run);
}

#[test]
fn counter_jump_is_a_gap_and_handled() {
    let run = run(FriVersion::V1_16, "counter-jump@600:1:5000", 900);
    assert_eq!(run.robot.record().client.gaps, 1);
    assert_eq!(
        run.robot.record().client.stale_datagrams + run.robot.record().client.duplicates,
        0
    );
    assert_eq!(run.sim.stats().missed_with_delivery, 0);
    assert_rides_through(&run);
}

/// REQ-ADP-001.
#[test]
fn poor_quality_aborts_the_overlay_and_stops_the_kernel() {
    let run = run(FriVersion::V1_15, "poor-quality@600:30", 1000);
    assert_stopped_and_reentered(&run, "request stop");
    assert_eq!(run.sim.stats().overlay_aborts, 1);
}

/// REQ-ADP-001.
#[test]
fn drop_to_idle_is_silent_then_reenters_without_jump() {
    let run = run(FriVersion::V2_7, "idle@600:50", 1000);
    let stats = run.sim.stats();
    assert_eq!(stats.state_cycles[SessionState::Idle as usize], 50);
    assert_eq!(stats.stray_replies, 0, "the client answered in IDLE");
    assert!(run.outcome.unfollowed_stops >= 1);
    assert_stopped_and_reentered(&run, "request stop");
}

#[test]
fn garbage_is_rejected() {
    let run = run(FriVersion::V1_15, "garbage@600:100", 900);
    assert_eq!(run.robot.record().client.rejected, 100);
    assert_eq!(run.sim.stats().missed_cycles, 0);
    assert_rides_through(&run);
}

#[test]
fn wrong_crc_is_rejected_as_a_lost_datagram() {
    let run = run(FriVersion::V2_7, "wrong-crc@600:5", 900);
    assert_eq!(run.robot.record().client.rejected, 5);
    assert_eq!(run.sim.stats().missed_cycles, 5);
    assert_rides_through(&run);
}

/// REQ-ADP-001, wrench overlay: a loss burst trips the watchdog the same way; the
/// overlay re-enters (wrench mode has no joint target to jump: the first
/// replies carry the IPO/measured position and a zero wrench).
/// REQ-STOP-001: a stale sensor is a ramp-down: every stop command carries
/// that category and the wrench has fallen to zero 1 s after the stop.
#[test]
fn wrench_overlay_loss_burst_trips_the_watchdog_then_reenters() {
    let run = run_with_overlay(FriVersion::V2_7, Overlay::Wrench, "burst-loss@600:50", 1900);
    assert!(stopped_because(&run, "stale_sensor"));
    assert_eq!(kernel_state(&run), StateKind::SafeStop);
    assert_eq!(run.sim.stats().commanding_entries, 2);
    assert_eq!(run.sim.state(), SessionState::CommandingActive);
    let command = run.last_command.unwrap();
    assert_eq!(command.stop, Some(limb_kernel::StopCategory::RampDown));
    assert_eq!(command.wrench, limb_kernel::geometry::Wrench::ZERO);
    eprintln!("grasp after the stop: {:?}", run.sim.plant().truth());
}
