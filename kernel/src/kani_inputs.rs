//! Symbolic inputs and fixed starting points for the proof harnesses of
//! the kernel's modules (`mod verification`).
//!
//! Under `cargo kani` every `kani::any()` is every value of its type; under
//! `cargo test` the sampling stand-in draws them (edge values favoured).
//! The fixed starting points are small and built directly: a
//! [`ValidatedArm`] made by the real validator from a fixed estimate, not by
//! running a session (a harness never runs the ~3 000-step lift).

#[cfg(not(kani))]
use limb_kani_stand_in as kani;

use crate::arm::JointAngles;
use crate::config::{SafetyLimits, ValidationLimits};
use crate::estimation::{ArmEstimate, FitEvidence, Method};
use crate::geometry::{Point, Pose, PoseRate, Wrench};
use crate::motion::SetPoint;
use crate::path::PathSample;
use crate::state::Request;
use crate::validate::{validate, ValidatedArm};

// Any value of each input type, component by component (every f64,
// NaN and infinities included): `kani::any::<Pose>()`. The one trait
// serves real Kani and the sampling stand-in (its `Arbitrary::any` is
// Kani's signature).

impl kani::Arbitrary for Pose {
    fn any() -> Self {
        Pose::new(kani::any(), kani::any(), kani::any())
    }
}

impl kani::Arbitrary for PoseRate {
    fn any() -> Self {
        PoseRate::new(kani::any(), kani::any(), kani::any())
    }
}

impl kani::Arbitrary for SetPoint {
    fn any() -> Self {
        SetPoint {
            pose: kani::any(),
            velocity: kani::any(),
            acceleration: kani::any(),
        }
    }
}

impl kani::Arbitrary for Wrench {
    fn any() -> Self {
        Wrench::new(kani::any(), kani::any(), kani::any())
    }
}

impl kani::Arbitrary for PathSample {
    fn any() -> Self {
        PathSample {
            time: kani::any(),
            pose: kani::any(),
            wrench: kani::any(),
        }
    }
}

/// Either any frame, or (so that the nominal branch is reached under the
/// sampling stand-in too) a plausible one: `pose` measured at `time` with
/// no interaction force. Kani explores both.
pub(crate) fn any_frame_or_at(pose: Pose, time: f64) -> PathSample {
    if kani::any() {
        kani::any()
    } else {
        PathSample {
            time,
            pose,
            wrench: Wrench::ZERO,
        }
    }
}

/// [`any_frame_or_at`] as far as a running step's monitors pass it
/// under `limits` on the frame alone: finite, each force component and
/// the torque within their limits (the force monitor bounds the
/// magnitude, no smaller than either component), on or above the table
/// and inside the workspace box. The monitors judge each frame before the
/// state's step ([`crate::kernel::Kernel::step`]), so a state's step meets
/// only such frames.
pub(crate) fn any_frame_the_monitors_pass(
    pose: Pose,
    time: f64,
    limits: &SafetyLimits,
) -> PathSample {
    let frame = any_frame_or_at(pose, time);
    kani::assume(the_monitors_pass(&frame, limits));
    frame
}

/// True when a running step's monitors pass `frame` under `limits` as
/// far as the frame alone decides ([`any_frame_the_monitors_pass`]).
pub(crate) fn the_monitors_pass(frame: &PathSample, limits: &SafetyLimits) -> bool {
    let (p, w) = (frame.pose, frame.wrench);
    frame.time.is_finite()
        && p.is_finite()
        && w.is_finite()
        && libm::fabs(w.fx) <= limits.max_force
        && libm::fabs(w.fz) <= limits.max_force
        && libm::fabs(w.ty) <= limits.max_torque
        && p.z >= -limits.table_tolerance
        && limits.workspace_x.contains(p.x)
        && limits.workspace_z.contains(p.z)
}

/// Any request, targets included.
pub(crate) fn any_request() -> Request {
    match kani::any::<u8>() % 6 {
        0 => Request::StartEstimation,
        1 => Request::ApproveManipulation(MANIPULATION_TARGET),
        2 => Request::ApproveManipulation(JointAngles {
            shoulder_elevation: kani::any(),
            elbow_flexion: kani::any(),
        }),
        3 => Request::FinishManipulation,
        4 => Request::Stop,
        _ => Request::Reset,
    }
}

/// A manipulation target beyond the default joint limits (the elbow
/// flexed 3.5 rad) [rad].
const TARGET_BEYOND_THE_LIMITS: JointAngles = JointAngles {
    shoulder_elevation: 1.0,
    elbow_flexion: 3.5,
};

/// A manipulation target that is not finite [rad].
const TARGET_NOT_FINITE: JointAngles = JointAngles {
    shoulder_elevation: f64::NAN,
    elbow_flexion: 0.6,
};

/// Any request, its target one of three that reach each outcome of the
/// target checks: accepted ([`MANIPULATION_TARGET`]), beyond the joint
/// limits, not finite. For the proofs about gating, where what any target
/// does is REQ-SM-003's proof (`verify_req_sm_003_targets_are_checked`).
pub(crate) fn any_request_of_known_targets() -> Request {
    match kani::any::<u8>() % 7 {
        0 => Request::StartEstimation,
        1 => Request::ApproveManipulation(MANIPULATION_TARGET),
        2 => Request::ApproveManipulation(TARGET_BEYOND_THE_LIMITS),
        3 => Request::ApproveManipulation(TARGET_NOT_FINITE),
        4 => Request::FinishManipulation,
        5 => Request::Stop,
        _ => Request::Reset,
    }
}

/// One of the three targets of [`any_request_of_known_targets`]:
/// accepted, beyond the joint limits, not finite.
pub(crate) fn any_known_target() -> JointAngles {
    match kani::any::<u8>() % 3 {
        0 => MANIPULATION_TARGET,
        1 => TARGET_BEYOND_THE_LIMITS,
        _ => TARGET_NOT_FINITE,
    }
}

/// Upper-arm length l1 of the fixed arm [m].
pub(crate) const UPPER_ARM: f64 = 0.30;
/// Forearm length l2 of the fixed arm [m].
pub(crate) const FOREARM: f64 = 0.20;
/// Shoulder of the fixed arm (frame S): extended on the table, the grasp
/// at the origin [m].
pub(crate) const SHOULDER: Point = Point::new(UPPER_ARM + FOREARM, 0.0);
/// A hold pose of the fixed arm: upper arm vertical (q1 = π/2), elbow
/// straight (q2 = 0), so the grasp is at (0.5, 0.5) m with psi = π/2.
pub(crate) const HOLD: Pose = Pose::new(0.5, 0.5, core::f64::consts::FRAC_PI_2);
/// A manipulation target inside the default joint limits and workspace
/// for the fixed arm [rad].
pub(crate) const MANIPULATION_TARGET: JointAngles = JointAngles {
    shoulder_elevation: 1.0,
    elbow_flexion: 0.6,
};

/// The fixed arm (l1 0.30 m, l2 0.20 m, shoulder at (0.5, 0) m), validated
/// by the real validator from an estimate whose geometry is axis-aligned:
/// the distances it checks are `hypot(d, 0)`, exact by the stub contract,
/// so it is accepted under Kani's stubs as under the real libm.
pub(crate) fn validated_arm() -> ValidatedArm {
    let estimate = ArmEstimate {
        upper_arm_length: UPPER_ARM,
        forearm_length: FOREARM,
        elbow: Point::new(FOREARM, 0.0),
        shoulder: SHOULDER,
        path_shoulder: SHOULDER,
        path_upper_arm_length: UPPER_ARM,
        grasp_pitch_offset: 0.0,
        method: Method::Auto,
        evidence: FitEvidence {
            forearm_arc: 1.3,
            upper_arm_arc: 1.3,
            forearm_residual: 1e-4,
            upper_arm_residual: 1e-4,
            residual_bias: 0.0,
            method_disagreement: Some(1e-4),
            forearm_samples: 1000,
            upper_arm_samples: 1000,
            outliers: 0,
            resolution: 0.0,
            uncertainty: None,
            play: None,
            compliance: None,
            trunk_compliance: None,
            grasp_slip: None,
            plane_tilt: None,
        },
    };
    let accepted = validate(
        &estimate,
        Point::new(0.0, 0.0),
        &ValidationLimits::default(),
    );
    // A refusal fails the proof here (no cover: a harness of a state
    // without a model never reaches this).
    accepted.expect("the fixed estimate is within every validation limit")
}
