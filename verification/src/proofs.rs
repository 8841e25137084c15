//! Proof harnesses. Under `cargo kani` each `proof_*` function is a Kani
//! proof over every value of its `kani::any()` inputs; under `cargo test`
//! the same functions run through [`crate::kani_stand_in`], which samples
//! the inputs (`tests/kani_harnesses.rs`). The assertions are the checking
//! functions of [`crate::checks`], so both engines check the same property.
//!
//! Unwind bounds: `step` loops only over the rate window (at most
//! [`limb_kernel::monitor::rates::RATE_WINDOW_CAPACITY`] = 128 frames, so
//! 130 iterations bound it) and, when the estimation motion ends, over the
//! grasp path; the step proofs start in states where the motion cannot end
//! within the harness, so 130 suffices. The estimator proof bounds the path
//! to 8 samples; its loops run at most over that path, hence 10.

#[cfg(not(kani))]
use crate::kani_stand_in as kani;

use crate::checks::{
    check_command, checked_step, envelope_violation, model_violation, SessionOracle,
};
use crate::scenario::{arm, kernel_after_lift, kernel_in_grasp, lift_angles, LIFT_WRENCH, TARGET};
use limb_kernel::arm::JointAngles;
use limb_kernel::config::SafetyLimits;
use limb_kernel::estimation::online::JointEnvelope;
use limb_kernel::estimation::{estimate_arm, Method};
use limb_kernel::geometry::{Pose, PoseRate, Wrench};
use limb_kernel::impedance::ImpedanceLaw;
use limb_kernel::monitor::force::ForceMonitor;
use limb_kernel::monitor::joint_limits::JointLimitMonitor;
use limb_kernel::monitor::workspace::WorkspaceMonitor;
use limb_kernel::motion::SetPoint;
use limb_kernel::{Command, Kernel, KernelConfig, PathSample, Request, StateKind};
use std::sync::OnceLock;

fn any_pose() -> Pose {
    Pose::new(kani::any(), kani::any(), kani::any())
}

fn any_wrench() -> Wrench {
    Wrench::new(kani::any(), kani::any(), kani::any())
}

fn any_frame() -> PathSample {
    PathSample {
        time: kani::any(),
        pose: any_pose(),
        wrench: any_wrench(),
    }
}

fn any_request() -> Request {
    match kani::any::<u8>() % 6 {
        0 => Request::StartEstimation,
        1 => Request::ApproveManipulation(TARGET),
        2 => Request::ApproveManipulation(JointAngles {
            shoulder_elevation: kani::any(),
            elbow_flexion: kani::any(),
        }),
        3 => Request::FinishManipulation,
        4 => Request::Stop,
        _ => Request::Reset,
    }
}

/// A kernel that has validated the scenario arm, built once and cloned.
fn validated_kernel() -> (Kernel, f64) {
    static KERNEL: OnceLock<(Kernel, f64)> = OnceLock::new();
    KERNEL
        .get_or_init(|| kernel_after_lift(&arm(0.30, 0.20)))
        .clone()
}

/// REQ-MON-001: the force monitor trips exactly when the force magnitude,
/// the torque or the force rate is beyond its limit (NaN included).
#[cfg_attr(kani, kani::proof)]
pub fn proof_force_monitor_trips_beyond_limits() {
    let l = SafetyLimits::default();
    let monitor = ForceMonitor {
        max_force: l.max_force,
        max_torque: l.max_torque,
        max_force_rate: l.max_force_rate,
    };
    let wrench = any_wrench();
    let rate: f64 = kani::any();
    let beyond = !(wrench.force_magnitude() <= l.max_force
        && wrench.ty.abs() <= l.max_torque
        && rate <= l.max_force_rate);
    let verdict = monitor.check(wrench, rate);
    assert_eq!(verdict.is_err(), beyond, "force monitor verdict");
    kani::cover!(verdict.is_err(), "force monitor: trips");
    kani::cover!(verdict.is_ok(), "force monitor: passes");
}

/// REQ-MON-004: the workspace monitor trips for a grasp point or elbow
/// below the table or a grasp point outside the box.
#[cfg_attr(kani, kani::proof)]
pub fn proof_workspace_monitor_trips_beyond_limits() {
    let l = SafetyLimits::default();
    let monitor = WorkspaceMonitor {
        x: l.workspace_x,
        z: l.workspace_z,
        table_tolerance: l.table_tolerance,
    };
    let pose = any_pose();
    let elbow_z: f64 = kani::any();
    let elbow = limb_kernel::geometry::Point::new(0.0, elbow_z);
    let floor = -l.table_tolerance;
    let beyond = !(pose.z >= floor
        && elbow_z >= floor
        && l.workspace_x.contains(pose.x)
        && l.workspace_z.contains(pose.z));
    let verdict = monitor.check(pose, Some(elbow));
    assert_eq!(verdict.is_err(), beyond, "workspace monitor verdict");
    kani::cover!(verdict.is_err(), "workspace monitor: trips");
    kani::cover!(verdict.is_ok(), "workspace monitor: passes");
}

/// REQ-MON-005: the joint-limit monitor trips exactly when the
/// independent model check of [`model_violation`] finds the pose outside
/// the joint ranges or off the model (elbow height aside, which the
/// workspace monitor guards).
#[cfg_attr(kani, kani::proof)]
pub fn proof_joint_limit_monitor_trips_beyond_limits() {
    let config = KernelConfig::default();
    let l = &config.limits;
    let arm = arm(0.30, 0.20);
    let monitor = JointLimitMonitor {
        shoulder_elevation: l.shoulder_elevation,
        elbow_flexion: l.elbow_flexion,
        max_model_mismatch: l.max_model_mismatch,
    };
    // Draw poses near the arm so both verdicts are reachable.
    let q = JointAngles {
        shoulder_elevation: kani::any::<f64>() * 0.5 + 0.8,
        elbow_flexion: kani::any::<f64>() * 0.8 + 1.0,
    };
    let nominal = arm.forward(q);
    let offset: f64 = kani::any();
    let pose = Pose::new(nominal.x + offset * 0.01, nominal.z, nominal.psi);
    let elbow = arm.elbow_from_pose(pose);
    kani::assume(elbow.z >= 0.0 || !elbow.z.is_finite());
    let verdict = monitor.check(&arm, pose);
    assert_eq!(
        verdict.is_err(),
        model_violation(pose, &config, &arm),
        "joint-limit monitor verdict"
    );
    kani::cover!(verdict.is_err(), "joint-limit monitor: trips");
    kani::cover!(verdict.is_ok(), "joint-limit monitor: passes");
}

/// REQ-CMD-001, REQ-CMD-002: for any pose, velocity and set-point the
/// impedance wrench is finite and within the force and torque limits, and
/// a limited wrench is flagged.
#[cfg_attr(kani, kani::proof)]
pub fn proof_impedance_wrench_is_saturated_and_finite() {
    let config = KernelConfig::default();
    let l = &config.limits;
    let law = ImpedanceLaw::new(&config.impedance, l.max_force, l.max_torque, l.max_speed);
    let set_point = SetPoint {
        pose: any_pose(),
        velocity: PoseRate::new(kani::any(), kani::any(), kani::any()),
        acceleration: PoseRate::new(kani::any(), kani::any(), kani::any()),
    };
    // Either fully arbitrary, or at the set-point (the nominal branch).
    let (pose, velocity) = if kani::any() {
        (
            any_pose(),
            PoseRate::new(kani::any(), kani::any(), kani::any()),
        )
    } else {
        (set_point.pose, set_point.velocity)
    };
    let out = law.command(pose, velocity, set_point);
    assert!(out.wrench.is_finite(), "wrench is finite");
    assert!(out.wrench.force_magnitude() <= l.max_force * (1.0 + 1e-12));
    assert!(out.wrench.ty.abs() <= l.max_torque);
    let limited = out.saturation.force || out.saturation.torque || out.saturation.non_finite;
    kani::cover!(limited, "impedance: saturated");
    kani::cover!(!out.saturation.any(), "impedance: within limits");
}

/// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step from Grasp or from
/// Validated with any frame and any clock never panics, gives a command
/// that passes [`check_command`], and stops on any instantaneous violation.
#[cfg_attr(kani, kani::proof)]
#[cfg_attr(kani, kani::unwind(130))]
pub fn proof_step_is_total() {
    let (mut kernel, t) = if kani::any() {
        (kernel_in_grasp(&arm(0.30, 0.20)), 0.0)
    } else {
        validated_kernel()
    };
    let mut oracle = SessionOracle::default();
    let mut frame = any_frame();
    if kani::any() {
        // A plausible frame with one arbitrary field keeps the nominal
        // branch reachable.
        frame = PathSample {
            time: t + 0.01,
            pose: frame.pose,
            wrench: LIFT_WRENCH,
        };
    }
    let now = if kani::any() { frame.time } else { kani::any() };
    let result = checked_step(&mut kernel, &mut oracle, &frame, now);
    assert_eq!(result.err(), None);
    let stopped = kernel.state().kind() == StateKind::SafeStop;
    kani::cover!(stopped, "step: stops");
    kani::cover!(!stopped, "step: continues");
}

/// REQ-SM-005: no sequence of three requests and frames reaches
/// Manipulate or Validated without a model validated since the last reset.
#[cfg_attr(kani, kani::proof)]
#[cfg_attr(kani, kani::unwind(130))]
pub fn proof_manipulate_needs_a_validated_model() {
    let (mut kernel, mut now) = if kani::any() {
        (kernel_in_grasp(&arm(0.30, 0.20)), 0.0)
    } else {
        validated_kernel()
    };
    // The arm stays where the scenario left it: frames stay plausible.
    let pose = arm(0.30, 0.20).forward(lift_angles(now));
    let mut oracle = SessionOracle::default();
    oracle.trust_current_model(&kernel);
    let mut manipulating = false;
    for _ in 0..3 {
        let _ = kernel.request(any_request(), now);
        assert_eq!(oracle.observe_events(&mut kernel), Ok(()));
        manipulating |= kernel.state().kind() == StateKind::Manipulate;
        now += 0.01;
        let frame = PathSample {
            time: now,
            pose,
            wrench: LIFT_WRENCH,
        };
        assert_eq!(
            checked_step(&mut kernel, &mut oracle, &frame, now).err(),
            None
        );
    }
    kani::cover!(manipulating, "gating: Manipulate reached");
}

/// REQ-SM-006, REQ-CMD-003: once stopped, every step and every request but Reset keeps
/// the same zero-motion, zero-wrench command.
#[cfg_attr(kani, kani::proof)]
#[cfg_attr(kani, kani::unwind(130))]
pub fn proof_safe_stop_is_latched() {
    let (mut kernel, t) = validated_kernel();
    kernel
        .request(Request::Stop, t)
        .expect("stop is always accepted");
    let first: Command = kernel.step(&any_frame(), kani::any());
    for _ in 0..3 {
        let request = any_request();
        kani::assume(request != Request::Reset);
        let _ = kernel.request(request, kani::any());
        let command = kernel.step(&any_frame(), kani::any());
        assert_eq!(command, first, "the stop command changed");
        assert_eq!(check_command(&command, kernel.config()), Ok(()));
    }
    kani::cover!(first.set_point.is_some(), "latch: holds a pose");
}

/// REQ-EST-001: the estimator returns an estimate or a typed error for any
/// path of up to 8 samples (NaN, duplicates, single points included).
#[cfg_attr(kani, kani::proof)]
#[cfg_attr(kani, kani::unwind(10))]
pub fn proof_estimator_is_total() {
    let length = usize::from(kani::any::<u8>() % 9);
    let mut path = [PathSample::default(); 8];
    for sample in path.iter_mut().take(length) {
        *sample = if kani::any() {
            any_frame()
        } else {
            PathSample::default()
        };
    }
    let result = estimate_arm(&path[..length], Method::Auto);
    if let Ok(estimate) = result {
        assert!(estimate.upper_arm_length.is_finite() && estimate.forearm_length.is_finite());
    }
    kani::cover!(result.is_err(), "estimator: typed error");
}

/// REQ-MON-011: during Estimate the joint-limit monitor on the provisional
/// model trips exactly when the worst-case shoulder elevation is above its
/// limit or the worst-case elbow flexion below it (NaN included), and
/// passes while no provisional model exists. Comparisons only: no loop, no
/// transcendental function, so no unwind bound is needed.
#[cfg_attr(kani, kani::proof)]
pub fn proof_req_mon_011_envelope_monitor_trips_beyond_limits() {
    let config = KernelConfig::default();
    let l = &config.limits;
    let monitor = JointLimitMonitor {
        shoulder_elevation: l.shoulder_elevation,
        elbow_flexion: l.elbow_flexion,
        max_model_mismatch: l.max_model_mismatch,
    };
    let envelope = JointEnvelope {
        max_shoulder_elevation: kani::any(),
        min_elbow_flexion: kani::any(),
    };
    let verdict = monitor.check_envelope(Some(envelope));
    let expected = envelope_violation(
        envelope.max_shoulder_elevation,
        envelope.min_elbow_flexion,
        &config,
    );
    assert_eq!(verdict.is_err(), expected);
    assert!(monitor.check_envelope(None).is_ok());
    kani::cover!(verdict.is_err(), "envelope monitor: trips");
    kani::cover!(verdict.is_ok(), "envelope monitor: passes");
}
