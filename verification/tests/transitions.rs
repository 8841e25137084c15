//! The transition table: every state × every request, against the table
//! the state module documents; plus the refusals that carry a reason.

use limb_kernel::arm::JointAngles;
use limb_kernel::state::TargetError;
use limb_kernel::{Kernel, PathSample, RefusalReason, Request, StateKind};
use limb_verification::scenario::{arm, kernel_after_lift, kernel_in_grasp, lift_frame, TARGET};

const REQUESTS: [Request; 5] = [
    Request::StartEstimation,
    Request::ApproveManipulation(TARGET),
    Request::FinishManipulation,
    Request::Stop,
    Request::Reset,
];

/// A kernel in `state` and the time of its last step.
fn kernel_in(state: StateKind) -> (Kernel, f64) {
    let arm = arm(0.30, 0.20);
    match state {
        StateKind::Grasp => (kernel_in_grasp(&arm), 0.0),
        StateKind::Estimate => {
            let mut kernel = kernel_in_grasp(&arm);
            kernel.request(Request::StartEstimation, 0.0).unwrap();
            (kernel, 0.0)
        }
        StateKind::Validated => kernel_after_lift(&arm),
        StateKind::Manipulate => {
            let (mut kernel, t) = kernel_after_lift(&arm);
            kernel
                .request(Request::ApproveManipulation(TARGET), t)
                .unwrap();
            (kernel, t)
        }
        StateKind::SafeStop => {
            let mut kernel = kernel_in_grasp(&arm);
            kernel.request(Request::Stop, 0.0).unwrap();
            // The arm still for 1 s: the reset is then allowed (REQ-STOP-003).
            let rest = lift_frame(&arm, 0.0);
            for i in 1..=1000 {
                let time = f64::from(i) * 1e-3;
                kernel.step(Some(&PathSample { time, ..rest }), time);
            }
            (kernel, 1.0)
        }
    }
}

/// The state a request leads to, or `None` when it must be refused as not
/// allowed in that state.
fn expected(state: StateKind, request: Request) -> Option<StateKind> {
    use StateKind::*;
    match (state, request) {
        (_, Request::Stop) => Some(SafeStop),
        (Grasp, Request::StartEstimation) => Some(Estimate),
        (Validated, Request::ApproveManipulation(_)) => Some(Manipulate),
        (Manipulate, Request::FinishManipulation) => Some(Validated),
        (SafeStop, Request::Reset) => Some(Grasp),
        _ => None,
    }
}

/// REQ-SM-001, REQ-SM-002: every state × request pair follows the table;
/// a refused request names the request and state and leaves the state as
/// it was.
#[test]
fn req_sm_001_every_state_and_request_follows_the_table() {
    let states = StateKind::ALL;
    for state in states {
        for request in REQUESTS {
            let (mut kernel, t) = kernel_in(state);
            assert_eq!(kernel.state().kind(), state);
            let result = kernel.request(request, t);
            match expected(state, request) {
                Some(to) => {
                    assert_eq!(result, Ok(to), "{state:?} × {request:?}");
                    assert_eq!(kernel.state().kind(), to);
                }
                None => {
                    let refusal = result.expect_err("must be refused");
                    assert_eq!(refusal.reason, RefusalReason::NotAllowedInState);
                    assert_eq!((refusal.request, refusal.state), (request, state));
                    assert_eq!(kernel.state().kind(), state, "a refusal changed the state");
                }
            }
        }
    }
}

/// REQ-SM-003: a manipulation target outside the joint limits is refused
/// with the violated limit, and the kernel stays in Validated.
#[test]
fn req_sm_003_target_outside_joint_limits_is_refused() {
    let (mut kernel, t) = kernel_in(StateKind::Validated);
    let hyperextended = JointAngles {
        shoulder_elevation: 0.6,
        elbow_flexion: -0.5,
    };
    let refusal = kernel
        .request(Request::ApproveManipulation(hyperextended), t)
        .unwrap_err();
    assert!(matches!(
        refusal.reason,
        RefusalReason::Target(TargetError::JointLimits(_))
    ));
    assert_eq!(kernel.state().kind(), StateKind::Validated);
    let nan = JointAngles {
        shoulder_elevation: f64::NAN,
        elbow_flexion: 0.5,
    };
    assert!(kernel
        .request(Request::ApproveManipulation(nan), t)
        .is_err());
    assert_eq!(kernel.state().kind(), StateKind::Validated);
}

/// REQ-SM-003: a target within the joint limits whose grasp point lies
/// outside the workspace box is refused with the workspace violation (not
/// the joint limits), and the kernel stays in Validated. With the default
/// limits every target that passes the joint limits lies inside the box,
/// so the box is narrowed the way a clinician would, by a limit update in
/// Validated (REQ-SM-007) that keeps the held arm inside it; the same
/// target is accepted once the default box is restored.
#[test]
fn req_sm_003_target_outside_the_workspace_is_refused() {
    use limb_kernel::config::{Interval, SafetyLimits};
    use limb_kernel::monitor::Limit;
    use limb_kernel::State;
    let (mut kernel, t) = kernel_in(StateKind::Validated);
    let State::Validated(validated) = kernel.state() else {
        panic!("the lift did not validate");
    };
    let hold = validated.hold().pose;
    let goal = validated.arm().geometry().forward(TARGET);
    // A box in x whose edge lies halfway between the held grasp point and
    // the target's: the arm is held inside it, the target is outside.
    let edge = 0.5 * (hold.x + goal.x);
    assert!(
        (hold.x - goal.x).abs() > 0.02,
        "hold {hold:?}, goal {goal:?}"
    );
    let default = SafetyLimits::default();
    let workspace_x = if goal.x < hold.x {
        Interval::new(edge, default.workspace_x.high)
    } else {
        Interval::new(default.workspace_x.low, edge)
    };
    kernel
        .update_limits(SafetyLimits {
            workspace_x,
            ..default
        })
        .expect("a narrower workspace is a valid limit update in Validated");
    let refusal = kernel
        .request(Request::ApproveManipulation(TARGET), t)
        .unwrap_err();
    let RefusalReason::Target(TargetError::Workspace(violation)) = refusal.reason else {
        panic!("refused for {:?}, not the workspace", refusal.reason);
    };
    assert_eq!(violation.limit, Limit::WorkspaceX);
    assert_eq!(violation.value, goal.x);
    assert_eq!(refusal.reason.code(), 4);
    assert_eq!(TargetError::Workspace(violation).code(), 2);
    assert!(refusal
        .reason
        .to_string()
        .starts_with("target: workspace: workspace_x"));
    assert_eq!(
        (refusal.request, refusal.state),
        (Request::ApproveManipulation(TARGET), StateKind::Validated)
    );
    assert_eq!(kernel.state().kind(), StateKind::Validated);
    // The held arm is inside the narrowed box: the next step holds.
    let command = kernel.step(
        Some(&limb_kernel::PathSample {
            time: t + 0.01,
            pose: hold,
            wrench: limb_verification::scenario::LIFT_WRENCH,
        }),
        t + 0.01,
    );
    assert_eq!(command.state, StateKind::Validated);
    // The same target within the default box is accepted.
    kernel.update_limits(default).unwrap();
    assert_eq!(
        kernel.request(Request::ApproveManipulation(TARGET), t + 0.01),
        Ok(StateKind::Manipulate)
    );
}

/// REQ-SM-004: estimation starts only from a fresh, finite measurement,
/// and no request is honoured with a non-finite or reversed clock.
#[test]
fn req_sm_004_start_needs_fresh_data_and_a_sane_clock() {
    let (mut kernel, _) = kernel_in(StateKind::Grasp);
    let refusal = kernel.request(Request::StartEstimation, 1.0).unwrap_err();
    assert_eq!(refusal.reason, RefusalReason::NoFreshMeasurement);
    let refusal = kernel
        .request(Request::StartEstimation, f64::NAN)
        .unwrap_err();
    assert_eq!(refusal.reason, RefusalReason::InvalidTime);
    let (mut kernel, t) = kernel_in(StateKind::Validated);
    let refusal = kernel
        .request(Request::ApproveManipulation(TARGET), t - 1.0)
        .unwrap_err();
    assert_eq!(refusal.reason, RefusalReason::InvalidTime);
    assert_eq!(kernel.state().kind(), StateKind::Validated);
}

/// REQ-SM-007: limits change only while the arm is held still and only
/// to a valid configuration; a refusal leaves the configuration as it was,
/// and an accepted change takes effect at the next step.
#[test]
fn req_sm_007_limits_change_only_while_held_and_only_when_valid() {
    use limb_kernel::config::{ConfigError, ConfigField, ConfigProblem, SafetyLimits};
    use limb_kernel::LimitUpdateRefusal;
    let tighter = SafetyLimits {
        max_force: 5.0,
        ..SafetyLimits::default()
    };
    for state in StateKind::ALL {
        let (mut kernel, _) = kernel_in(state);
        let result = kernel.update_limits(tighter);
        if matches!(state, StateKind::Estimate | StateKind::Manipulate) {
            assert_eq!(result, Err(LimitUpdateRefusal::NotAllowedInState(state)));
            assert_eq!(kernel.config().limits, SafetyLimits::default());
        } else {
            assert_eq!(result, Ok(()), "{state:?}");
            assert_eq!(kernel.config().limits.max_force, 5.0);
        }
    }
    let (mut kernel, t) = kernel_in(StateKind::Validated);
    let invalid = SafetyLimits {
        max_speed: -1.0,
        ..SafetyLimits::default()
    };
    assert_eq!(
        kernel.update_limits(invalid),
        Err(LimitUpdateRefusal::Invalid(ConfigError::new(
            ConfigField::MaxSpeed,
            ConfigProblem::NotPositive
        )))
    );
    assert_eq!(kernel.config().limits, SafetyLimits::default());
    // The scenario's 11 N lift wrench is beyond a 5 N limit: the next step stops.
    kernel.update_limits(tighter).unwrap();
    let arm = arm(0.30, 0.20);
    let frame = limb_verification::scenario::lift_frame(&arm, t);
    let next = limb_kernel::PathSample {
        time: t + 0.01,
        ..frame
    };
    assert_eq!(
        kernel.step(Some(&next), t + 0.01).state,
        StateKind::SafeStop
    );
}

/// REQ-CFG-001: a limit update beyond the ceilings is refused with the
/// field and the reason, whatever state the kernel is in, and the limits
/// stay as they were: no update switches a monitor off by a huge value
/// (the fuzz target `kernel_sequence` accepted a force limit of 4.1e224 N).
#[test]
fn req_cfg_001_limits_beyond_the_ceilings_are_refused() {
    use limb_kernel::config::{ConfigError, ConfigField, ConfigProblem, SafetyLimits};
    use limb_kernel::LimitUpdateRefusal;
    let (mut kernel, _) = kernel_in(StateKind::Validated);
    let huge = SafetyLimits {
        max_force: 4.1e224,
        ..SafetyLimits::default()
    };
    assert_eq!(
        kernel.update_limits(huge),
        Err(LimitUpdateRefusal::Invalid(ConfigError::new(
            ConfigField::MaxForce,
            ConfigProblem::BeyondCeiling
        )))
    );
    assert_eq!(kernel.config().limits, SafetyLimits::default());
    assert_eq!(kernel.update_limits(SafetyLimits::CEILING), Ok(()));
    let slack = SafetyLimits {
        max_sensor_age: 0.5,
        ..SafetyLimits::CEILING
    };
    assert_eq!(
        kernel.update_limits(slack),
        Err(LimitUpdateRefusal::Invalid(ConfigError::new(
            ConfigField::MaxSensorAge,
            ConfigProblem::BeyondCeiling
        )))
    );
}
