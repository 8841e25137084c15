//! Freshness from the robot's own clock: the simulated FRI controller in
//! real time (10 ms send period) over loopback UDP, its time stamps
//! faulted; the kernel sees the stamps as the robot sent them and its
//! watchdog ends each fault in SafeStop with the fault's named reason.
//! The kernel's sensor-age limit is 0.1 s here (ten periods) so that a
//! loaded machine's scheduling jitter is not mistaken for the fault.

use limb_kernel::monitor::Limit;
use limb_kernel::trace::{Cause, Event};
use limb_kernel::{KernelConfig, StateKind, StopReason};
use limb_kuka::faults::parse_schedule;
use limb_kuka::loopback::{run_loopback, LoopbackRun};
use limb_kuka::sim_controller::{Pacing, SimSettings};
use limb_kuka::FriVersion;
use limb_session::{Operator, SessionPlan};
use limb_sim::PlantParameters;

fn run(faults: &str, cycles: u64) -> LoopbackRun<Operator> {
    let mut sim = SimSettings::new(FriVersion::V1_15);
    sim.pacing = Pacing::RealTime;
    sim.send_period_ms = 10;
    sim.faults = parse_schedule(faults, 7).unwrap();
    let mut config = KernelConfig::default();
    config.limits.max_sensor_age = 0.1;
    let run = run_loopback(
        sim,
        PlantParameters::new(0.30, 0.20),
        config,
        Operator::continuing(SessionPlan::default()),
        cycles,
        |_, state| state == StateKind::SafeStop,
    )
    .unwrap();
    eprintln!("{faults}: {:?}", run.events);
    run
}

/// The watchdog limit the kernel stopped on.
fn stopped_on(run: &LoopbackRun<Operator>) -> Option<Limit> {
    run.events.iter().find_map(|event| match event.event {
        Event::Transition {
            to: StateKind::SafeStop,
            cause: Cause::Stop(StopReason::Monitor(violation)),
            ..
        } => Some(violation.limit),
        _ => None,
    })
}

#[test]
fn a_robot_clock_that_jumps_back_is_a_reversed_stamp() {
    let run = run("clock-back@30:1000:5", 90);
    assert_eq!(run.kernel.state().kind(), StateKind::SafeStop);
    assert_eq!(stopped_on(&run), Some(Limit::SensorTimeReversed));
}

#[test]
fn a_robot_clock_that_stalls_ages_its_frames() {
    let run = run("clock-stall@30:1000", 90);
    assert_eq!(run.kernel.state().kind(), StateKind::SafeStop);
    assert_eq!(stopped_on(&run), Some(Limit::StaleSensor));
}

#[test]
fn a_robot_clock_that_repeats_its_stamps_ages_its_frames() {
    let run = run("clock-repeat@30:1000", 120);
    assert_eq!(run.kernel.state().kind(), StateKind::SafeStop);
    assert_eq!(stopped_on(&run), Some(Limit::StaleSensor));
}

/// The simulated controller's clock keeps wall time when its process is
/// descheduled: a 25 ms stall between two cycles (paced, 1 ms period, no
/// client answering) is run through by the plant, so the robot's time
/// after it is the wall time since the start to within 10 ms (a loaded
/// machine may deschedule the last cycle too; the stall is 25 ms) and the
/// periods lost are counted. Before, each overrun re-anchored the tick grid
/// without advancing the plant: its stamps fell behind the host clock by
/// every lost period and, 20 ms of lag later, the client's watchdog called
/// fresh frames stale (85 of 95 sessions of a paced soak on a quiet
/// machine).
#[test]
fn the_simulated_robot_clock_keeps_wall_time_through_a_stall() {
    let loopback = std::net::SocketAddr::from(([127, 0, 0, 1], 0));
    let silent = std::net::UdpSocket::bind(loopback).unwrap();
    let mut sim = SimSettings::new(FriVersion::V1_15);
    sim.pacing = Pacing::RealTime;
    sim.send_period_ms = 1;
    let mut controller = limb_kuka::sim_controller::SimController::bind(
        loopback,
        silent.local_addr().unwrap(),
        sim,
        PlantParameters::new(0.30, 0.20),
    )
    .unwrap();
    let start = std::time::Instant::now();
    let plant_start = controller.plant().time();
    for _ in 0..10 {
        controller.run_cycle().unwrap();
    }
    std::thread::sleep(std::time::Duration::from_millis(25));
    for _ in 0..10 {
        controller.run_cycle().unwrap();
    }
    let wall = start.elapsed().as_secs_f64();
    let robot = controller.plant().time() - plant_start;
    assert!(
        controller.stats().periods_lost >= 24,
        "{:?}",
        controller.stats().periods_lost
    );
    // The stall is on record as the machine's disturbance, at the cycle
    // after it (the soak's evidence for a stop the machine caused).
    let stall = controller
        .stats()
        .disturbances
        .iter()
        .find(|d| d.periods_lost >= 24)
        .copied();
    assert!(
        stall.is_some_and(|d| d.cycle == 10 && !d.reply_missed),
        "{:?}",
        controller.stats().disturbances
    );
    assert!(
        (wall - robot).abs() <= 0.01,
        "robot time {robot:.4} s, wall time {wall:.4} s"
    );
}
