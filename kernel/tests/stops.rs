//! Stop categories at the kernel's interface: what each cause commands, the
//! latch, and the reset that waits for a still arm (REQ-STOP-001..003).

use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::monitor::Limit;
use limb_kernel::state::RefusalReason;
use limb_kernel::stop::{StopCategory, RAMP_DOWN_TIME};
use limb_kernel::{Command, CommandMode, Kernel, KernelConfig, PathSample, Request, StateKind};
use limb_kernel::{State, StopReason};

const PERIOD: f64 = 0.001;

/// The arm held lifted: 0.12 m up, the robot carrying 6 N of its weight
/// (f_ext = −6 N in z: the set-point that holds it is 3 cm higher).
const LIFTED: Pose = Pose::new(0.05, 0.12, 0.3);
const WEIGHT: Wrench = Wrench::new(0.0, -6.0, 0.0);

fn frame(time: f64, pose: Pose, wrench: Wrench) -> PathSample {
    PathSample { time, pose, wrench }
}

/// A kernel in Grasp that has held the lifted arm for 0.2 s, and the time.
fn holding_the_lifted_arm() -> (Kernel, f64) {
    let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
    let mut time = 0.0;
    for _ in 0..200 {
        let command = kernel.step(Some(&frame(time, LIFTED, WEIGHT)), time);
        assert_eq!(command.state, StateKind::Grasp);
        time += PERIOD;
    }
    (kernel, time)
}

fn steps(kernel: &mut Kernel, time: &mut f64, n: usize, pose: Pose, wrench: Wrench) -> Command {
    let mut last = None;
    for _ in 0..n {
        last = Some(kernel.step(Some(&frame(*time, pose, wrench)), *time));
        *time += PERIOD;
    }
    last.unwrap()
}

/// REQ-STOP-001: a stop request is a hold: the stop commands carry the
/// category, a set-point that keeps carrying the arm's weight (the Grasp
/// hold, 3 cm above the measured pose would be x − f_ext/K; Grasp held the
/// measured pose here, so the hold moves to x − f_ext/K), and the impedance
/// law's wrench about it, never zero while the arm hangs on the robot.
#[test]
fn req_stop_001_a_stop_request_holds_the_arm() {
    let (mut kernel, mut time) = holding_the_lifted_arm();
    assert_eq!(kernel.request(Request::Stop, time), Ok(StateKind::SafeStop));
    let stop = kernel.stopped().unwrap();
    assert_eq!(stop.reason(), StopReason::Operator);
    assert_eq!(stop.category(), StopCategory::Hold);
    let command = steps(&mut kernel, &mut time, 1000, LIFTED, WEIGHT);
    assert_eq!(command.mode, CommandMode::Stop);
    assert_eq!(command.stop, Some(StopCategory::Hold));
    let held = command.set_point.unwrap().pose;
    assert!((held.z - (LIFTED.z + 0.03)).abs() < 1e-3, "{held:?}");
    assert!((command.wrench.fz - 6.0).abs() < 0.5, "{command:?}");
}

/// REQ-STOP-001: a stale sensor ramps the robot's force down: the
/// set-point goes to the last trusted measured pose over
/// `RAMP_DOWN_TIME` and the wrench to zero.
#[test]
fn req_stop_001_a_stale_sensor_ramps_the_wrench_down() {
    let (mut kernel, mut time) = holding_the_lifted_arm();
    let before = kernel.step(Some(&frame(time, LIFTED, WEIGHT)), time);
    time += PERIOD;
    // The same frame, 0.2 s later: stale.
    let stale = frame(time - PERIOD, LIFTED, WEIGHT);
    let first = kernel.step(Some(&stale), time + 0.2);
    assert_eq!(first.stop, Some(StopCategory::RampDown));
    match kernel.stopped().unwrap().reason() {
        StopReason::Monitor(v) => assert_eq!(v.limit, Limit::StaleSensor),
        other => panic!("{other:?}"),
    }
    // Continuous: the first stop command is where the last command was.
    assert_eq!(
        first.set_point.unwrap().pose,
        before.set_point.unwrap().pose
    );
    let mut t = time + 0.2;
    let mut last = first;
    while t < time + 0.2 + RAMP_DOWN_TIME + 0.01 {
        t += PERIOD;
        let command = kernel.step(Some(&stale), t);
        let (a, b) = (
            last.set_point.unwrap().pose,
            command.set_point.unwrap().pose,
        );
        assert!((a.z - b.z).abs() < 1e-4, "a step at {t}: {a:?} → {b:?}");
        last = command;
    }
    assert_eq!(last.wrench, Wrench::ZERO);
    assert_eq!(last.set_point.unwrap().pose, LIFTED);
}

/// REQ-STOP-003, REQ-SM-006: the stop stays latched with its first reason until a
/// reset; a reset is refused while the stop's set-point moves, while the
/// arm moves, and without a fresh measurement, and accepted once the arm
/// is still: Grasp then holds the stop's set-point at rest.
#[test]
fn req_stop_003_a_reset_waits_for_a_still_arm() {
    let (mut kernel, mut time) = holding_the_lifted_arm();
    assert_eq!(kernel.request(Request::Stop, time), Ok(StateKind::SafeStop));
    steps(&mut kernel, &mut time, 10, LIFTED, WEIGHT);
    let not_still = Err(RefusalReason::ArmNotStill);
    // The hold's set-point is still moving to x − f_ext/K.
    assert_eq!(
        kernel.request(Request::Reset, time).map_err(|r| r.reason),
        not_still
    );
    // A second cause does not replace the first.
    let _ = kernel.step(
        Some(&frame(time, LIFTED, Wrench::new(f64::NAN, 0.0, 0.0))),
        time,
    );
    assert_eq!(kernel.request(Request::Stop, time), Ok(StateKind::SafeStop));
    assert_eq!(kernel.stopped().unwrap().reason(), StopReason::Operator);
    let command = steps(&mut kernel, &mut time, 1000, LIFTED, WEIGHT);
    let rest = command.set_point.unwrap();
    // The arm moving at 5 cm/s.
    for k in 0..100 {
        let moved = Pose::new(
            LIFTED.x + 0.05 * f64::from(k) * PERIOD,
            LIFTED.z,
            LIFTED.psi,
        );
        kernel.step(Some(&frame(time, moved, WEIGHT)), time);
        time += PERIOD;
    }
    assert_eq!(
        kernel.request(Request::Reset, time).map_err(|r| r.reason),
        not_still
    );
    // Still again, but the last frame is 0.2 s old.
    let moved = Pose::new(LIFTED.x + 0.005, LIFTED.z, LIFTED.psi);
    steps(&mut kernel, &mut time, 200, moved, WEIGHT);
    assert_eq!(
        kernel
            .request(Request::Reset, time + 0.2)
            .map_err(|r| r.reason),
        not_still
    );
    assert_eq!(kernel.state().kind(), StateKind::SafeStop);
    assert_eq!(kernel.request(Request::Reset, time), Ok(StateKind::Grasp));
    let State::Grasp(grasp) = kernel.state() else {
        panic!("not in Grasp")
    };
    assert_eq!(grasp.held(), Some(rest.pose));
    let command = kernel.step(Some(&frame(time, moved, WEIGHT)), time);
    assert_eq!(
        command.set_point,
        Some(rest),
        "the reset stepped the set-point"
    );
    assert_eq!(command.stop, None);
}

/// REQ-STOP-001, REQ-CMD-003: a non-finite command is the only motors-off
/// cause (no set-point, no wrench: `Command::check` refuses either).
#[test]
fn req_stop_001_motors_off_commands_nothing() {
    assert_eq!(
        StopReason::NonFiniteCommand.category(),
        StopCategory::MotorsOff
    );
    for reason in [StopReason::Operator, StopReason::PathBufferFull] {
        assert_ne!(reason.category(), StopCategory::MotorsOff);
    }
    let limits = KernelConfig::default().limits;
    let motors_off = Command {
        state: StateKind::SafeStop,
        mode: CommandMode::Stop,
        set_point: None,
        wrench: Wrench::ZERO,
        saturation: Default::default(),
        stop: Some(StopCategory::MotorsOff),
    };
    assert_eq!(motors_off.check(&limits), Ok(()));
    let pushing = Command {
        wrench: Wrench::new(0.0, 1.0, 0.0),
        ..motors_off
    };
    assert!(pushing.check(&limits).is_err());
}

/// REQ-STOP-001: a stop's wrench stays within the limits of
/// the moment it is commanded, also when they were lowered after the
/// wrench it ramps down from (Grasp allows a limit update). Found by the
/// `kernel_sequence` fuzz target: the first stop command repeated the
/// wrench commanded under the wider limits.
#[test]
fn req_stop_001_a_stop_wrench_obeys_limits_lowered_before_it() {
    let (mut kernel, mut time) = holding_the_lifted_arm();
    // The arm pushed 5 cm above the Grasp hold over 1 s: the spring pulls
    // it back with about 10 N.
    let mut pose = LIFTED;
    let mut command = None;
    for _ in 0..1000 {
        pose.z += 0.05 / 1000.0;
        command = Some(kernel.step(Some(&frame(time, pose, WEIGHT)), time));
        time += PERIOD;
    }
    let pulled = command.unwrap().wrench.force_magnitude();
    assert!(pulled > 8.0, "{pulled} N");
    let mut limits = kernel.config().limits;
    limits.max_force = 5.0;
    kernel.update_limits(limits).unwrap();
    // A non-finite frame: a ramp-down from the wrench commanded last.
    let nan = frame(time, Pose::new(f64::NAN, pose.z, pose.psi), WEIGHT);
    let first = kernel.step(Some(&nan), time);
    assert_eq!(first.stop, Some(StopCategory::RampDown));
    assert!(first.wrench.force_magnitude() <= 5.0 + 1e-9, "{first:?}");
    assert!(first.saturation.force, "{first:?}");
    assert_eq!(first.check(&kernel.config().limits), Ok(()));
    let next = kernel.step(Some(&nan), time + PERIOD);
    assert!(next.wrench.force_magnitude() <= 5.0 + 1e-9, "{next:?}");
}

/// REQ-STOP-002: a frame the monitors refuse is not trusted. One frame of
/// a position glitch (5 m, 1 km or 1e300 m off: beyond the workspace box)
/// stops the kernel, and the stop holds the arm as an operator's stop at
/// the same moment does: no larger force over its first 0.2 s (seen with
/// the frame left in the rate window: 45 N, the force limit, against
/// 15 N), and 2 s later the set-point within 1 mm and 1 mrad of that
/// stop's and the arm's weight carried (seen with the frame taken into
/// the holding pose: the set-point 0.1 m towards a 5 m glitch; the
/// weight dropped after a 1e300 m one).
#[test]
fn req_stop_002_a_refused_frame_does_not_move_the_hold() {
    let held_after = |glitch: Option<Pose>| {
        let (mut kernel, mut time) = holding_the_lifted_arm();
        steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT);
        match glitch {
            Some(pose) => {
                let command = steps(&mut kernel, &mut time, 1, pose, WEIGHT);
                assert_eq!(command.state, StateKind::SafeStop);
            }
            None => {
                kernel.request(Request::Stop, time).unwrap();
                steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT);
            }
        }
        // The largest force commanded over the stop's first 0.2 s.
        let mut peak: f64 = 0.0;
        for _ in 0..200 {
            let command = steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT);
            peak = peak.max(command.wrench.force_magnitude());
        }
        let command = steps(&mut kernel, &mut time, 1800, LIFTED, WEIGHT);
        assert_eq!(command.stop, Some(StopCategory::Hold));
        (command.set_point.unwrap().pose, command.wrench, peak)
    };
    let (pose, wrench, peak) = held_after(None);
    assert!((wrench.fz - 6.0).abs() < 0.5, "{wrench:?}");
    for (glitch, along) in [5.0, 1e3, 1e300]
        .into_iter()
        .flat_map(|g| [(g, "in x"), (g, "in z")])
    {
        let off = if along == "in x" {
            Pose::new(LIFTED.x + glitch, LIFTED.z, LIFTED.psi)
        } else {
            Pose::new(LIFTED.x, LIFTED.z + glitch, LIFTED.psi)
        };
        let (p, w, most) = held_after(Some(off));
        let case = format!("{glitch} m {along}");
        assert!(
            most < peak + 0.5,
            "{case}: {most} N at the stop, not {peak} N"
        );
        assert!((p.psi - pose.psi).abs() < 1e-3, "{case}: {p:?}");
        assert!(
            p.point().distance(pose.point()) < 1e-3,
            "{case}: held at {p:?}, not {pose:?}"
        );
        assert!(
            (w.fz - wrench.fz).abs() < 0.5,
            "{case}: {w:?}, not {wrench:?}"
        );
    }
}

/// REQ-STOP-002: a stopped kernel passes over a frame the monitors would
/// refuse. Held after an operator's stop, one frame of a position glitch
/// (5 m or 1e300 m beyond the box) changes no command by more than 0.5 N
/// over the next 0.2 s, and the reset is then taken as without it (seen
/// with the frame trusted: 45 N, the force limit, at the glitch's step,
/// the weight let go, and 45 N from its rates after it).
#[test]
fn req_stop_002_a_stopped_kernel_passes_over_a_refused_frame() {
    let held = |glitch: Option<f64>| {
        let (mut kernel, mut time) = holding_the_lifted_arm();
        steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT);
        kernel.request(Request::Stop, time).unwrap();
        steps(&mut kernel, &mut time, 500, LIFTED, WEIGHT);
        let mut wrenches = Vec::new();
        if let Some(off) = glitch {
            let pose = Pose::new(LIFTED.x + off, LIFTED.z, LIFTED.psi);
            wrenches.push(steps(&mut kernel, &mut time, 1, pose, WEIGHT).wrench);
        } else {
            wrenches.push(steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT).wrench);
        }
        for _ in 0..200 {
            wrenches.push(steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT).wrench);
        }
        steps(&mut kernel, &mut time, 1000, LIFTED, WEIGHT);
        let reset = kernel.request(Request::Reset, time).map_err(|r| r.reason);
        (wrenches, reset)
    };
    let (calm, reset) = held(None);
    assert_eq!(reset, Ok(StateKind::Grasp));
    for off in [5.0, 1e300] {
        let (glitched, reset) = held(Some(off));
        assert_eq!(reset, Ok(StateKind::Grasp), "{off} m");
        for (step, (a, b)) in glitched.iter().zip(&calm).enumerate() {
            let differ = (a.fx - b.fx).hypot(a.fz - b.fz);
            assert!(differ < 0.5, "{off} m, step {step}: {a:?}, not {b:?}");
        }
    }
}

/// REQ-STOP-002: a session's first frame, refused by the monitors, is no
/// pose to hold. One frame 5 m (or 1e300 m) beyond the box, before any
/// trusted frame, stops the kernel; the good frames after it are not
/// pushed towards it (seen with the refused frame as the stop's fallback
/// pose: a hold latched 5 m off, 45 N, the force limit, towards it).
#[test]
fn req_stop_002_a_first_frame_refused_is_no_pose_to_hold() {
    for (off, along) in [(5.0, "x"), (5.0, "z"), (1e300, "x")] {
        let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
        let mut time = 0.0;
        let glitch = if along == "x" {
            Pose::new(LIFTED.x + off, LIFTED.z, LIFTED.psi)
        } else {
            Pose::new(LIFTED.x, LIFTED.z + off, LIFTED.psi)
        };
        let first = steps(&mut kernel, &mut time, 1, glitch, WEIGHT);
        assert_eq!(first.state, StateKind::SafeStop);
        let mut peak: f64 = 0.0;
        for _ in 0..2000 {
            let command = steps(&mut kernel, &mut time, 1, LIFTED, WEIGHT);
            peak = peak.max(command.wrench.force_magnitude());
            if let Some(set_point) = command.set_point {
                assert!(
                    set_point.pose.point().distance(LIFTED.point()) < 0.1,
                    "{off} m in {along}: held at {set_point:?}"
                );
            }
        }
        assert!(peak < 1.0, "{off} m in {along}: {peak} N");
    }
}
