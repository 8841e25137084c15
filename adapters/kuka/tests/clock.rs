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
