//! Zenoh supervision composes with any robot: a supervisor station drives a
//! whole session — start the estimation, the validated model, approve a
//! manipulation, finish it, emergency stop — of the KUKA FRI client against
//! the simulated FRI controller (real UDP on loopback, unpaced) and of the
//! reference plant in a node (paced), both `limb-session` sessions with
//! the Zenoh link as their supervisor. The e-stop's delay from arrival to
//! the kernel's request is measured and printed (README figures).

mod common;

use common::{connect, key, link_settings, wait_until, RigOptions, TIMEOUT};
use limb_arebo::device::on_simulated_held_arm;
use limb_kernel::arm::JointAngles;
use limb_kernel::{KernelConfig, StateKind};
use limb_kuka::loopback::run_loopback;
use limb_kuka::sim_controller::SimSettings;
use limb_kuka::FriVersion;
use limb_session::kernel_wire::State;
use limb_sim::robot::ReferenceRobot;
use limb_sim::{Plant, PlantParameters};
use limb_zenoh::link::{Link, LinkSettings};
use limb_zenoh::node::Node;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::supervision::LoopView;
use limb_zenoh::wire::{AckOutcome, SupervisorCommand};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The manipulation target (the scripted operator's).
const TARGET: JointAngles = JointAngles {
    shoulder_elevation: 1.0,
    elbow_flexion: 0.6,
};
/// Longest a whole estimation may take here [s of wall time].
const SESSION: Duration = Duration::from_secs(240);

/// The three sessions run one at a time. Run side by side, the AREBO
/// session sometimes stayed in Estimate until its 240 s limit (1 of 3 runs
/// of this file on a quiet machine, and once in CI) while each test alone
/// passed every time; the cause is not found yet (issue note of stop 24).
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Sends `command` until the kernel accepts it (a request waits in the
/// node's queue while the robot does not follow; a finish is refused while
/// the arm still moves); the state it led to. A refused command is sent
/// again; an ack that does not come is a failure (a resend might apply the
/// command twice: a second estimation after the first).
fn accepted(
    supervisor: &mut limb_zenoh::supervisor::SupervisorStation,
    command: SupervisorCommand,
) -> State {
    let start = Instant::now();
    while start.elapsed() < SESSION {
        let ack = supervisor
            .request(command, TIMEOUT)
            .unwrap_or_else(|e| panic!("{command:?}: {e} (the node lost its ack)"));
        if let AckOutcome::Accepted { state } = ack.outcome {
            return state;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    panic!("{command:?} never accepted");
}

/// Waits until the kernel is in `state`, failing at once when it stops
/// elsewhere.
fn reaches(view: &LoopView, state: StateKind, within: Duration) {
    let reached = wait_until(
        within,
        || matches!(view.state(), Some(s) if s == state || s == StateKind::SafeStop),
    );
    assert_eq!(
        view.state(),
        Some(state),
        "after {reached:?} (limit {within:?})"
    );
}

/// The supervisor station's script, on `view`'s node at `endpoint`; the
/// e-stop delay measured.
fn supervise(endpoint: &str, view: &LoopView, stopped: &AtomicBool) -> Duration {
    let mut supervisor = connect(endpoint, RigOptions::default().format, key());
    assert_eq!(
        accepted(&mut supervisor, SupervisorCommand::StartEstimation),
        State::from(StateKind::Estimate)
    );
    reaches(view, StateKind::Validated, SESSION);
    assert_eq!(
        accepted(
            &mut supervisor,
            SupervisorCommand::ApproveManipulation {
                target: TARGET.into()
            }
        ),
        State::from(StateKind::Manipulate)
    );
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(
        accepted(&mut supervisor, SupervisorCommand::FinishManipulation),
        State::from(StateKind::Validated)
    );
    supervisor.emergency_stop().unwrap();
    reaches(view, StateKind::SafeStop, TIMEOUT);
    stopped.store(true, Ordering::Release);
    supervisor.close().unwrap();
    view.last_emergency_stop_delay().expect("an e-stop delay")
}

/// A free loopback endpoint, the node's Zenoh configuration listening on
/// it, and its link settings (supervisor watchdog at 2 s: the station
/// sends no heartbeat while it waits).
fn node_side() -> (String, limb_zenoh::zenoh::Config, LinkSettings) {
    let endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port().unwrap());
    let config = peer_config(std::slice::from_ref(&endpoint), &[], 1000).unwrap();
    let settings = link_settings(&RigOptions {
        liveness_timeout: Duration::from_secs(2),
        ..RigOptions::default()
    });
    (endpoint, config, settings)
}

/// The unpaced loop steps faster than the publisher thread publishes a
/// sample; the samples it cannot take are dropped, never an ack or an
/// event (they once filled the whole queue: every ack was lost and the
/// station's script wedged).
#[test]
fn a_zenoh_supervisor_runs_a_whole_kuka_session() {
    let _serial = one_at_a_time();
    let (endpoint, config, settings) = node_side();
    let (link, supervision) = Link::open(config, &settings, KernelConfig::default()).unwrap();
    let view = supervision.view();
    let stopped = Arc::new(AtomicBool::new(false));
    let station = std::thread::spawn({
        let (endpoint, view, stopped) = (endpoint.clone(), view.clone(), Arc::clone(&stopped));
        move || supervise(&endpoint, &view, &stopped)
    });
    let run = run_loopback(
        SimSettings::new(FriVersion::V1_15),
        PlantParameters::new(0.30, 0.20),
        KernelConfig::default(),
        supervision,
        // 1 200 s of robot time. The session takes about 25 s, but the
        // loop is unpaced: on a quiet machine it runs about 45 times
        // faster than real time, so the station's wall-clock waits (2 s
        // of manipulation, 200 ms between refused finishes) each cost
        // about 100 s of robot time, and a budget of 120 s once ran out
        // before the finish was acknowledged. The loop ends when the
        // station stops; the budget only bounds a hang.
        1_200_000,
        // A station that failed ends the run at once (its panic is
        // reported below) instead of leaving the loop to its cycle budget.
        |_, _| stopped.load(Ordering::Acquire) || station.is_finished(),
    )
    .unwrap();
    let delay = station
        .join()
        .unwrap_or_else(|_| panic!("the supervisor station failed (its panic is above)"));
    let cycles = run.sim.stats().cycles;
    let counters = run.supervisor.counters();
    eprintln!(
        "KUKA session under Zenoh: e-stop delay {delay:?}; {cycles} controller cycles; \
         {} samples dropped; events {:?}",
        counters.samples_dropped, run.events
    );
    assert_eq!(counters.reliable_dropped, 0);
    assert!(run.events.iter().any(|e| matches!(
        e.event,
        limb_kernel::trace::Event::Transition {
            from: StateKind::Manipulate,
            to: StateKind::Validated,
            ..
        }
    )));
    assert_eq!(run.kernel.state().kind(), StateKind::SafeStop);
    link.close().unwrap();
}

/// AREBO over a real pseudo-terminal, its simulated device holding the
/// reference arm at the wrist (lock-stepped with the host, the kernel on
/// the device's clock), supervised over Zenoh like the KUKA arm.
///
/// The device streams as fast as the host answers (≈ 20 000 frames, 100 s
/// of its clock, per second of wall time on an idle 2-core machine), while
/// the script waits in wall time (2 s of manipulation, then resends). With
/// 40 000 frames the device ran out during that wait on an idle machine
/// (the loop ended, every later command was refused `Busy`: the failure
/// 2026-12-05, 3 of 3 runs) and passed under the load of a whole test run:
/// 2 000 000 frames (10 000 s of device time) outlast any script here; the
/// session ends with the e-stop and the node's shutdown, not the device.
#[test]
fn a_zenoh_supervisor_runs_a_whole_arebo_session() {
    let _serial = one_at_a_time();
    let (endpoint, config, settings) = node_side();
    let (device, robot) = on_simulated_held_arm(2_000_000).unwrap();
    let node = Node::spawn(
        config,
        &settings,
        None,
        Box::new(limb_kernel::Kernel::new(KernelConfig::default()).unwrap()),
        robot,
    )
    .unwrap();
    let stopped = AtomicBool::new(false);
    let start = Instant::now();
    let delay = supervise(&endpoint, node.view(), &stopped);
    let kernel = node.shutdown().unwrap();
    let wall = start.elapsed();
    let frames = device.join().unwrap().frames;
    eprintln!(
        "AREBO session under Zenoh: e-stop delay {delay:?}; {frames} device frames (5 ms each) in {wall:?}"
    );
    assert_eq!(kernel.state().kind(), StateKind::SafeStop);
}

#[test]
fn a_zenoh_supervisor_runs_a_whole_reference_plant_session() {
    let _serial = one_at_a_time();
    let (endpoint, config, settings) = node_side();
    let plant = Plant::new(PlantParameters::new(0.30, 0.20)).unwrap();
    let period = Duration::from_millis(1);
    let node = Node::spawn(
        config,
        &settings,
        Some(period),
        Box::new(limb_kernel::Kernel::new(KernelConfig::default()).unwrap()),
        ReferenceRobot::new(plant, 1000.0, f64::INFINITY),
    )
    .unwrap();
    let stopped = AtomicBool::new(false);
    let delay = supervise(&endpoint, node.view(), &stopped);
    eprintln!("reference plant node under Zenoh: e-stop delay {delay:?} (period {period:?})");
    let kernel = node.shutdown().unwrap();
    assert_eq!(kernel.state().kind(), StateKind::SafeStop);
}
