//! The typed states of a session and the transitions between them.
//!
//! ```text
//!            StartEstimation           motion done,          ApproveManipulation
//!   Grasp ──────────────────▶ Estimate ─────────────▶ Validated ──────────────▶ Manipulate
//!     ▲                          │      validator ok     ▲  │                      │
//!     │ Reset                    │                       │  └──────────────────────┘
//!     │                          ▼                       │     FinishManipulation
//!  SafeStop ◀──── any violation, Stop, rejected estimate, failure (from every state)
//! ```
//!
//! # Theory of operation
//! Each state is a struct holding exactly what it needs; each transition is
//! a method that consumes the state it leaves. [`Validated`] and
//! [`Manipulate`] hold a [`ValidatedArm`], which only
//! [`crate::validate::validate`] constructs, and the only way to build a
//! `Validated` is [`Estimate::conclude`], which calls the validator. So a
//! `Manipulate` without a validated model does not compile. [`SafeStop`] is
//! latched: its only exit is [`SafeStop::reset`], back to [`Grasp`].
//!
//! The runtime wrapper ([`crate::kernel`]) holds one of these in an enum
//! and refuses, with a reason, any request the current state has no
//! transition for.

use crate::arm::JointAngles;
use crate::estimation::{estimate_arm, EstimateError, Method};
use crate::geometry::{Point, Pose};
use crate::monitor::joint_limits::JointLimitMonitor;
use crate::monitor::workspace::WorkspaceMonitor;
use crate::monitor::Violation;
use crate::motion::{
    EstimationMotion, EstimationMotionParameters, MinimumJerkMove, PlanError, SetPoint,
};
use crate::path::PathSample;
use crate::validate::{validate, Rejection, ValidatedArm, ValidationLimits};

/// Names of the states, for events and reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u8)]
pub enum StateKind {
    /// Holding the wrist, arm at rest, no model.
    Grasp = 1,
    /// Running the estimation motion and recording the path.
    Estimate = 2,
    /// Holding still with a validated arm model.
    Validated = 3,
    /// Moving the arm under the monitors.
    Manipulate = 4,
    /// Latched stop.
    SafeStop = 5,
}

/// Why the kernel entered SafeStop.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum StopReason {
    /// A monitor tripped.
    Monitor(Violation),
    /// The operator (or a supervisor) asked for a stop.
    Operator,
    /// The estimator could not produce an estimate.
    EstimationFailed(EstimateError),
    /// The validator rejected the estimate.
    ModelRejected(Rejection),
    /// The grasp path outgrew its buffer before the motion ended.
    PathBufferFull,
    /// A motion could not be planned.
    PlanFailed(PlanError),
    /// The command generator produced a non-finite set-point.
    NonFiniteCommand,
}

/// Grasp: the robot holds the wrist where it found it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grasp {
    hold: Option<Pose>,
}

/// Estimate: the estimation motion is running.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    motion: EstimationMotion,
    started_at: f64,
}

/// Validated: a validated model, the arm held still.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Validated {
    arm: ValidatedArm,
    hold: Pose,
}

/// Manipulate: a planned move of the arm under the validated model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Manipulate {
    arm: ValidatedArm,
    motion: MinimumJerkMove,
    started_at: f64,
}

/// SafeStop: latched; holds the pose where it stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafeStop {
    hold: Option<Pose>,
    reason: StopReason,
}

/// A manipulation move that passed the target checks; only
/// [`Validated::plan_manipulation`] makes one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManipulationPlan {
    motion: MinimumJerkMove,
}

/// Why a manipulation target was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum TargetError {
    /// Outside the joint limits (or not finite).
    JointLimits(Violation),
    /// Grasp point or elbow outside the workspace.
    Workspace(Violation),
    /// The move could not be planned.
    Plan(PlanError),
}

impl StateKind {
    /// Every state, in diagram order.
    pub const ALL: [StateKind; 5] = [
        StateKind::Grasp,
        StateKind::Estimate,
        StateKind::Validated,
        StateKind::Manipulate,
        StateKind::SafeStop,
    ];
}

impl Grasp {
    /// The initial state: no pose latched yet.
    pub const fn new() -> Self {
        Self { hold: None }
    }

    /// The hold set-point, latching `measured` the first time.
    pub fn hold(&mut self, measured: Pose) -> SetPoint {
        SetPoint::hold(*self.hold.get_or_insert(measured))
    }

    /// Starts the estimation motion from grasp pose `grasp` at time `now`.
    ///
    /// # Errors
    /// Gives the state back with the planning error.
    pub fn start_estimation(
        self,
        grasp: Pose,
        now: f64,
        parameters: &EstimationMotionParameters,
    ) -> Result<Estimate, (Self, PlanError)> {
        match EstimationMotion::new(grasp, parameters) {
            Ok(motion) => Ok(Estimate {
                motion,
                started_at: now,
            }),
            Err(error) => Err((self, error)),
        }
    }

    /// Stops.
    pub fn stop(self, reason: StopReason, at: Option<Pose>) -> SafeStop {
        SafeStop::latch(reason, at.or(self.hold))
    }
}

impl Default for Grasp {
    fn default() -> Self {
        Self::new()
    }
}

impl Estimate {
    /// The set-point at time `now`.
    pub fn set_point(&self, now: f64) -> SetPoint {
        self.motion.at(now - self.started_at)
    }

    /// True once the lift and the hold are over at `now`.
    pub fn is_finished(&self, now: f64) -> bool {
        self.motion.is_finished(now - self.started_at)
    }

    /// The grasp pose the motion started from.
    pub fn grasp_pose(&self) -> Pose {
        self.motion.lift().start()
    }

    /// Estimates the arm from `path` and validates it: the only way into
    /// [`Validated`]. The arm is then held at the motion's goal.
    ///
    /// # Errors
    /// The stop reason: estimation failed or the model was rejected.
    pub fn conclude(
        self,
        path: &[PathSample],
        method: Method,
        limits: &ValidationLimits,
    ) -> Result<Validated, StopReason> {
        let estimate = estimate_arm(path, method).map_err(StopReason::EstimationFailed)?;
        let start: Point = path
            .first()
            .map_or(self.grasp_pose().point(), |s| s.pose.point());
        let arm = validate(&estimate, start, limits).map_err(StopReason::ModelRejected)?;
        Ok(Validated {
            arm,
            hold: self.motion.lift().goal(),
        })
    }

    /// Stops.
    pub fn stop(self, reason: StopReason, at: Option<Pose>) -> SafeStop {
        SafeStop::latch(reason, at)
    }
}

impl Validated {
    /// The validated model.
    pub fn arm(&self) -> &ValidatedArm {
        &self.arm
    }

    /// The hold set-point.
    pub fn hold(&self) -> SetPoint {
        SetPoint::hold(self.hold)
    }

    /// Plans a move of the arm to joint angles `target` from the hold pose,
    /// checked against the joint limits and the workspace under the
    /// validated model.
    ///
    /// # Errors
    /// Why the target is refused.
    pub fn plan_manipulation(
        &self,
        target: JointAngles,
        peak_speed: f64,
        joints: &JointLimitMonitor,
        workspace: &WorkspaceMonitor,
    ) -> Result<ManipulationPlan, TargetError> {
        let geometry = self.arm.geometry();
        let goal = geometry.forward(target);
        joints
            .check(geometry, goal)
            .map_err(TargetError::JointLimits)?;
        workspace
            .check(goal, Some(geometry.elbow(target)))
            .map_err(TargetError::Workspace)?;
        let motion =
            MinimumJerkMove::new(self.hold, goal, peak_speed).map_err(TargetError::Plan)?;
        Ok(ManipulationPlan { motion })
    }

    /// Starts the checked move `plan` at time `now`.
    pub fn begin_manipulation(self, plan: ManipulationPlan, now: f64) -> Manipulate {
        Manipulate {
            arm: self.arm,
            motion: plan.motion,
            started_at: now,
        }
    }

    /// Stops.
    pub fn stop(self, reason: StopReason, at: Option<Pose>) -> SafeStop {
        SafeStop::latch(reason, at.or(Some(self.hold)))
    }
}

impl Manipulate {
    /// The validated model.
    pub fn arm(&self) -> &ValidatedArm {
        &self.arm
    }

    /// The set-point at time `now`.
    pub fn set_point(&self, now: f64) -> SetPoint {
        self.motion.at(now - self.started_at)
    }

    /// Ends the manipulation, holding the set-point reached at `now`.
    pub fn finish(self, now: f64) -> Validated {
        Validated {
            arm: self.arm,
            hold: self.set_point(now).pose,
        }
    }

    /// Stops.
    pub fn stop(self, reason: StopReason, at: Option<Pose>) -> SafeStop {
        SafeStop::latch(reason, at)
    }
}

impl SafeStop {
    fn latch(reason: StopReason, hold: Option<Pose>) -> Self {
        Self {
            hold: hold.filter(|p| p.is_finite()),
            reason,
        }
    }

    /// Why the kernel stopped.
    pub fn reason(&self) -> StopReason {
        self.reason
    }

    /// The pose held; `None` when no finite pose was ever known (the robot
    /// then holds its own current position).
    pub fn hold(&self) -> Option<SetPoint> {
        self.hold.map(SetPoint::hold)
    }

    /// The operator's reset: back to [`Grasp`], with no model.
    pub fn reset(self) -> Grasp {
        Grasp::new()
    }
}

#[cfg(any(test, kani))]
impl Validated {
    /// Validated with the validator's `arm`, held at `hold`: the state a
    /// session reaches after estimation, for proofs that start there
    /// without running a session (the arm still comes only from
    /// [`validate`]).
    pub(crate) fn holding(arm: ValidatedArm, hold: Pose) -> Self {
        Self { arm, hold }
    }
}

/// Proof of REQ-SM-003 and REQ-SM-006 at the level of the typed states.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    use crate::kani_inputs::{validated_arm, HOLD, MANIPULATION_TARGET};
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-SM-003: for any target a manipulation plan exists only for
    /// finite targets whose goal passes the joint-limit and workspace
    /// checks, and it moves from the hold pose. Unwind 16: the validator
    /// that makes the fixed arm checks 15 values for finiteness.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(16))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_sm_003_targets_are_checked() {
        let l = SafetyLimits::default();
        let joints = JointLimitMonitor {
            shoulder_elevation: l.shoulder_elevation,
            elbow_flexion: l.elbow_flexion,
            max_model_mismatch: l.max_model_mismatch,
        };
        let workspace = WorkspaceMonitor {
            x: l.workspace_x,
            z: l.workspace_z,
            table_tolerance: l.table_tolerance,
        };
        let validated = Validated::holding(validated_arm(), HOLD);
        let target = if kani::any() {
            JointAngles {
                shoulder_elevation: kani::any(),
                elbow_flexion: kani::any(),
            }
        } else {
            MANIPULATION_TARGET
        };
        let plan = validated.plan_manipulation(target, 0.05, &joints, &workspace);
        if let Ok(plan) = plan {
            assert!(target.is_finite(), "a non-finite target was planned");
            assert_eq!(plan.motion.start(), HOLD);
            assert!(plan.motion.goal().is_finite());
        }
        kani::cover!(plan.is_ok(), "target: planned");
        kani::cover!(
            matches!(plan, Err(TargetError::JointLimits(_))),
            "target: outside the joint limits"
        );
    }

    /// REQ-SM-006: a stop from any state latches the pose only when it is
    /// finite, and the only way out, a reset, leads to Grasp with no pose.
    #[cfg_attr(kani, kani::proof)]
    pub fn verify_req_sm_006_stop_holds_only_a_finite_pose() {
        let at = if kani::any() {
            Some(Pose::new(kani::any(), kani::any(), kani::any()))
        } else {
            None
        };
        let stop = Grasp::new().stop(StopReason::Operator, at);
        match (stop.hold(), at) {
            (Some(hold), Some(pose)) => {
                assert!(pose.is_finite() && hold == SetPoint::hold(pose));
                kani::cover!(true, "stop: holds the pose");
            }
            (None, Some(pose)) => {
                assert!(!pose.is_finite());
                kani::cover!(true, "stop: a non-finite pose is not held");
            }
            (Some(_), None) => panic!("a stop without a pose holds one"),
            (None, None) => {}
        }
        assert_eq!(stop.reason(), StopReason::Operator);
        assert_eq!(stop.reset(), Grasp::new());
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check("targets", 5_000, verify_req_sm_003_targets_are_checked);
            kani::check(
                "stop latch",
                5_000,
                verify_req_sm_006_stop_holds_only_a_finite_pose,
            );
        }
    }
}
