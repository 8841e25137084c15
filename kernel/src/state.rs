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

impl StopReason {
    /// Stable numeric code of the reason (logs, wire protocols); the
    /// payload has its own (e.g. [`crate::monitor::Limit::code`]).
    pub const fn code(&self) -> u16 {
        match self {
            StopReason::Monitor(_) => 1,
            StopReason::Operator => 2,
            StopReason::EstimationFailed(_) => 3,
            StopReason::ModelRejected(_) => 4,
            StopReason::PathBufferFull => 5,
            StopReason::PlanFailed(_) => 6,
            StopReason::NonFiniteCommand => 7,
        }
    }
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

impl TargetError {
    /// Stable numeric code of the error.
    pub const fn code(&self) -> u16 {
        match self {
            TargetError::JointLimits(_) => 1,
            TargetError::Workspace(_) => 2,
            TargetError::Plan(_) => 3,
        }
    }
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
