//! The history-based monitors (speed, force rate, watchdog), each tripped
//! on purpose in the state it guards, with the limit named in the stop
//! reason; and a quiet nominal lift.

use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::monitor::Limit;
use limb_kernel::{Kernel, PathSample, Request, State, StateKind, StopReason};
use limb_verification::scenario::{arm, kernel_after_lift, kernel_in_grasp, LIFT_WRENCH};

fn stop_limit(kernel: &Kernel) -> Option<Limit> {
    match kernel.state() {
        State::SafeStop(stop) => match stop.reason() {
            StopReason::Monitor(violation) => Some(violation.limit),
            _ => None,
        },
        _ => None,
    }
}

fn estimating() -> Kernel {
    let mut kernel = kernel_in_grasp(&arm(0.30, 0.20));
    kernel.request(Request::StartEstimation, 0.0).unwrap();
    kernel
}

fn frame(time: f64, pose: Pose, wrench: Wrench) -> PathSample {
    PathSample { time, pose, wrench }
}

/// REQ-MON-003: a grasp point moving at 0.2 m/s, horizontally or
/// vertically, stops the estimation; after a reset the window starts afresh,
/// so the jump to a new grasp pose is not read as speed.
#[test]
fn req_mon_003_fast_grasp_point_stops() {
    for (vx, vz) in [(0.2, 0.0), (0.0, 0.2)] {
        let mut kernel = estimating();
        for i in 1..=20 {
            let t = f64::from(i) * 0.01;
            kernel.step(
                Some(&frame(t, Pose::new(vx * t, vz * t, 0.0), LIFT_WRENCH)),
                t,
            );
        }
        assert_eq!(stop_limit(&kernel), Some(Limit::Speed), "({vx}, {vz})");
        // A reset waits for the stop's set-point at rest and a still arm
        // (REQ-STOP-003).
        let stopped = Pose::new(vx * 0.2, vz * 0.2, 0.0);
        for i in 21..=200 {
            let t = f64::from(i) * 0.01;
            kernel.step(Some(&frame(t, stopped, LIFT_WRENCH)), t);
        }
        kernel.request(Request::Reset, 2.0).unwrap();
        let elsewhere = Pose::new(0.1, 0.05, 0.0);
        kernel.step(Some(&frame(2.01, elsewhere, LIFT_WRENCH)), 2.01);
        kernel.request(Request::StartEstimation, 2.01).unwrap();
        kernel.step(Some(&frame(2.02, elsewhere, LIFT_WRENCH)), 2.02);
        assert_eq!(kernel.state().kind(), StateKind::Estimate, "({vx}, {vz})");
    }
}

/// REQ-MON-002: a force that jumps by 30 N within 10 ms stops,
/// although the force itself stays under its limit.
#[test]
fn req_mon_002_force_rate_jump_stops() {
    let mut kernel = estimating();
    // A full rate window (50 ms) of a steady force, then a 30 N jump.
    for i in 1..=6 {
        let t = f64::from(i) * 0.01;
        kernel.step(Some(&frame(t, Pose::default(), Wrench::ZERO)), t);
    }
    assert_eq!(stop_limit(&kernel), None);
    kernel.step(
        Some(&frame(0.07, Pose::default(), Wrench::new(30.0, 0.0, 0.0))),
        0.07,
    );
    assert_eq!(stop_limit(&kernel), Some(Limit::ForceRate));
}

/// REQ-MON-006: a stale frame, a frame from the past and a clock
/// running backwards each stop the kernel.
#[test]
fn req_mon_006_stale_reversed_and_clock_faults_stop() {
    // (name, two steps as (frame time, now), the limit that must trip)
    type Case = (&'static str, [(f64, f64); 2], Limit);
    let cases: [Case; 3] = [
        ("stale", [(0.01, 0.01), (0.02, 0.10)], Limit::StaleSensor),
        (
            "reversed",
            [(0.02, 0.02), (0.01, 0.02)],
            Limit::SensorTimeReversed,
        ),
        ("clock", [(0.02, 0.02), (0.02, 0.01)], Limit::ClockFault),
    ];
    for (name, steps, limit) in cases {
        let mut kernel = estimating();
        for (time, now) in steps {
            kernel.step(Some(&frame(time, Pose::default(), LIFT_WRENCH)), now);
        }
        assert_eq!(stop_limit(&kernel), Some(limit), "{name}");
    }
}

/// REQ-MON-006: the kernel alone judges silence. A step without a frame
/// within `max_sensor_age` of the newest frame gives the command a step
/// on that frame again would (same state, set-point and wrench), and past
/// it stops the kernel as a stale sensor with the frame's age; a kernel
/// never given a frame stops on a silent step, the age infinite.
#[test]
fn req_mon_006_silence_is_judged_by_the_kernel() {
    let max_age = limb_kernel::KernelConfig::default().limits.max_sensor_age;
    let last = frame(0.01, Pose::default(), LIFT_WRENCH);
    let (mut silent, mut replayed) = (estimating(), estimating());
    silent.step(Some(&last), last.time);
    replayed.step(Some(&last), last.time);
    let within = last.time + 0.5 * max_age;
    assert_eq!(
        silent.step(None, within),
        replayed.step(Some(&last), within)
    );
    assert_eq!(silent.state().kind(), StateKind::Estimate);

    let past = last.time + 2.0 * max_age;
    let command = silent.step(None, past);
    assert_eq!(command.state, StateKind::SafeStop);
    match silent.state() {
        State::SafeStop(stop) => match stop.reason() {
            StopReason::Monitor(v) => {
                assert_eq!(v.limit, Limit::StaleSensor);
                assert!((v.value - 2.0 * max_age).abs() < 1e-12, "age {}", v.value);
            }
            other => panic!("stopped for {other:?}"),
        },
        other => panic!("not stopped: {other:?}"),
    }

    let mut never = never_sensed();
    never.step(None, 0.0);
    match never.state() {
        State::SafeStop(stop) => match stop.reason() {
            StopReason::Monitor(v) => {
                assert_eq!(v.limit, Limit::StaleSensor);
                assert_eq!(v.value, f64::INFINITY);
            }
            other => panic!("stopped for {other:?}"),
        },
        other => panic!("not stopped: {other:?}"),
    }
}

/// A kernel in Grasp that was never given a frame.
fn never_sensed() -> Kernel {
    Kernel::new(limb_kernel::KernelConfig::default()).expect("default configuration")
}

/// REQ-MON-008: the nominal synthetic lift trips no monitor and ends
/// validated.
#[test]
fn req_mon_008_nominal_lift_is_quiet() {
    let (kernel, _) = kernel_after_lift(&arm(0.30, 0.20));
    assert_eq!(kernel.state().kind(), StateKind::Validated);
}

/// REQ-MON-012: the set-point is checked against the workspace before it is
/// commanded: with the box's top 3 mm above the grasp, the estimation lift's
/// set-point leaves the box while the measured grasp point stays at rest
/// inside it, and the kernel stops on the set-point (WorkspaceZ, its z).
#[test]
fn req_mon_012_a_set_point_outside_the_workspace_stops() {
    let mut config = limb_kernel::KernelConfig::default();
    config.limits.workspace_z.high = 0.003;
    let mut kernel = Kernel::new(config).unwrap();
    let rest = Pose::default();
    kernel.step(Some(&frame(0.0, rest, Wrench::ZERO)), 0.0);
    kernel.request(Request::StartEstimation, 0.0).unwrap();
    let mut highest = f64::NEG_INFINITY;
    for i in 1..=3000 {
        let t = f64::from(i) * 0.001;
        let c = kernel.step(Some(&frame(t, rest, Wrench::ZERO)), t);
        highest = highest.max(c.set_point.map_or(f64::NEG_INFINITY, |s| s.pose.z));
        if kernel.state().kind() == StateKind::SafeStop {
            break;
        }
    }
    let State::SafeStop(stop) = kernel.state() else {
        panic!("no stop: {:?}, highest {highest}", kernel.state().kind());
    };
    let StopReason::Monitor(violation) = stop.reason() else {
        panic!("{:?}", stop.reason());
    };
    assert_eq!(violation.limit, Limit::WorkspaceZ);
    assert!(violation.value > 0.003, "{violation:?}");
}
