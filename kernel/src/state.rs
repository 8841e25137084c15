//! The typed states of a session and the transitions between them.
//!
//! ```text
//!            StartEstimation        refinement done,        ApproveManipulation
//!   Grasp ──────────────────▶ Estimate ─────────────▶ Validated ──────────────▶ Manipulate
//!     ▲          (lifting → settling │      validator ok     ▲  │                      │
//!     │           in crate::lift,    │                       │  │                      │
//!     │           then concluding)   │                       │  │                      │
//!     │ Reset                    │                       │  └──────────────────────┘
//!     │                          ▼                       │     FinishManipulation
//!  SafeStop ◀──── any violation, Stop, rejected estimate, failure (from every state)
//! ```
//!
//! # Theory of operation
//! Each state is a struct holding exactly what it needs; each transition is
//! a method that consumes the state it leaves, except the stop, which
//! every state answers from a borrow (`stop(&self)`: the runtime wrapper
//! keeps its state until the stop replaces it, and copying the 2 kB state
//! into the call cost real Kani dearly). [`Validated`] and
//! [`Manipulate`] hold a [`ValidatedArm`], which only
//! [`crate::validate::validate`] constructs, and the only way to build a
//! `Validated` is the conclusion of [`Estimate::advance`], which calls the
//! validator. So a
//! `Manipulate` without a validated model does not compile. [`SafeStop`] is
//! latched: its only exit is [`SafeStop::reset`], back to [`Grasp`].
//!
//! The runtime wrapper ([`crate::kernel`]) holds one of these in [`State`]
//! and refuses, with a reason ([`Refusal`]), any [`Request`] the current
//! state has no transition for. [`Estimate::advance`] does one step of the
//! estimation (record, shape the lift, or a slice of the refinement); when
//! it returns [`EstimateStep::Validated`] the kernel enters that state.

use crate::arm::JointAngles;
use crate::config::ValidationLimits;
use crate::config::{ConfigError, KernelConfig};
use crate::estimation::online::OnlineEstimator;
use crate::estimation::refine::{Progress, Refinement, SAMPLES_PER_STEP};
use crate::estimation::tilt::PlaneTilt;
use crate::estimation::EstimateError;
use crate::geometry::{Pose, Wrench};
use crate::lift::{LiftCommand, LiftEnd, LiftSettings, ShapedLift};
use crate::monitor::joint_limits::JointEnvelope;
use crate::monitor::joint_limits::JointLimitMonitor;
use crate::monitor::workspace::WorkspaceMonitor;
use crate::monitor::Violation;
use crate::motion::{
    EstimationMotion, EstimationMotionParameters, MinimumJerkMove, PlanError, SetPoint,
};
use crate::path::{is_due, PathSample};
use crate::stop::StopReason;
use crate::stop::{StopCategory, StopMotion, HOLD_MIN_TIME, RAMP_DOWN_TIME};
use crate::validate::{validate, ValidatedArm};

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

/// Grasp: the robot holds the wrist where it found it.
///
/// Invariant: the hold is the mean of the first `frames` measured poses
/// (at most [`GRASP_HOLD_FRAMES`]), or the stop's set-point after a reset
/// (`frames` then [`GRASP_HOLD_FRAMES`]: nothing more is averaged in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grasp {
    hold: Option<Pose>,
    frames: u16,
}

/// Measured poses Grasp averages into its hold (frame S): the hold's noise
/// is the measurement's over 8. Each new pose moves the hold by its
/// deviation over the count, so the set-point never steps by one
/// measurement's noise (REQ-SM-009): a position-controlled robot that
/// starts following after some frames (FRI's COMMANDING_ACTIVE) would turn
/// that step into a force spike.
pub const GRASP_HOLD_FRAMES: u16 = 64;

/// Estimate: the estimation lift is running, shaped by the provisional
/// model ([`crate::lift`]), the path recorded and estimated online; then,
/// held still, the estimate is refined in bounded slices.
///
/// # Invariants
/// The stage only moves forward, Lifting → Concluding; the estimation's
/// conclusion (its hold, the lift's end, the refinement) exists only in
/// Concluding, so no step can refine while the path is still recorded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The grasp pose the motion started from (frame S).
    grasp: Pose,
    online: OnlineEstimator,
    /// The tilt of the arm's plane, from the recorded samples' lateral
    /// positions (REQ-EST-011).
    tilt: PlaneTilt,
    stage: EstimateStage,
}

/// Where the estimation is.
#[derive(Clone, Copy, Debug, PartialEq)]
// No heap (no_std, no alloc): the refinement's running sums (≈ 1 kB) live
// inline; the kernel is one fixed-size value.
#[allow(clippy::large_enum_variant)]
pub enum EstimateStage {
    /// The lift runs (its phases: [`crate::lift::LiftPhase`]); the path is
    /// recorded.
    Lifting(ShapedLift),
    /// The lift has ended and the arm settled: held still while the
    /// estimate is refined; nothing more is recorded.
    Concluding(Conclusion),
}

/// The estimation's conclusion in progress: where the arm is held, why the
/// lift ended, and the refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conclusion {
    /// The holding pose (frame S).
    pub hold: Pose,
    /// Why the lift ended.
    pub reason: LiftEnd,
    refinement: Refinement,
}

/// What one Estimate step produced.
#[derive(Clone, Copy, Debug, PartialEq)]
// The validated state is the larger variant (the model and its evidence);
// it is made once per session and moved into the kernel's state at once.
#[allow(clippy::large_enum_variant)]
pub enum EstimateStep {
    /// Follow this moving set-point (the lift).
    Move(SetPoint),
    /// Hold this set-point (paused, settling or concluding).
    Hold(SetPoint),
    /// The refinement finished and the validator accepted its estimate:
    /// the state to enter (its hold is the conclusion's).
    Validated(Validated),
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

/// SafeStop: latched; its category ([`StopReason::category`]) decides
/// what the robot does with the arm ([`crate::stop`]).
///
/// # Invariants
/// `hold`, the pose the set-point comes to rest at, is finite when present;
/// `motion`, when present, ends at `hold`; a motors-off stop has neither;
/// `wrench` is finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafeStop {
    hold: Option<Pose>,
    reason: StopReason,
    category: StopCategory,
    at: f64,
    motion: Option<StopMotion>,
    wrench: Wrench,
}

/// What the kernel knows at the instant it stops: where the set-point was,
/// what it commanded and where the arm is, each only when trusted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopStart {
    /// Kernel time of the stop [s] (NaN when the clock was not usable).
    pub now: f64,
    /// The set-point commanded last (pose, velocity, acceleration).
    pub set_point: Option<SetPoint>,
    /// The wrench commanded last.
    pub wrench: Wrench,
    /// The set-point that holds the arm where it is, x − f_ext/K (frame S),
    /// from trusted measurements.
    pub holding: Option<Pose>,
    /// The last trusted measured pose.
    pub measured: Option<Pose>,
    /// Peak grasp-point speed of the stop's move [m/s].
    pub peak_speed: f64,
    /// Peak forearm rate of the stop's move [rad/s].
    pub peak_rate: f64,
    /// Shortest move of a hold, per axis [s].
    pub min_time: f64,
    /// A hold's set-point coasts on by its velocity at the stop over half
    /// the move (it slows down along its path rather than turning back);
    /// not when the set-point was already heading for a holding pose.
    pub coast: bool,
}

impl StopStart {
    /// A stop at `now` that knows only the pose `at` (held still).
    pub fn at_pose(now: f64, at: Option<Pose>) -> Self {
        Self {
            now,
            set_point: at.map(SetPoint::hold),
            wrench: Wrench::ZERO,
            holding: at,
            measured: at,
            peak_speed: 0.1,
            peak_rate: 0.5,
            min_time: HOLD_MIN_TIME,
            coast: false,
        }
    }

    fn or_holding(self, hold: Option<Pose>) -> Self {
        Self {
            set_point: self.set_point.or(hold.map(SetPoint::hold)),
            ..self
        }
    }
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
        Self {
            hold: None,
            frames: 0,
        }
    }

    /// Holding `hold` as it is (no averaging): after a reset, where the
    /// robot was holding the stop's set-point.
    const fn holding(hold: Pose) -> Self {
        Self {
            hold: Some(hold),
            frames: GRASP_HOLD_FRAMES,
        }
    }

    /// The hold set-point, `measured` (finite: the kernel's monitors have
    /// passed it) averaged in while fewer than [`GRASP_HOLD_FRAMES`] poses
    /// have been: the running mean m_k = m_{k-1} + (p_k − m_{k-1}) / k.
    pub fn hold(&mut self, measured: Pose) -> SetPoint {
        let hold = match self.hold {
            Some(hold) if self.frames >= GRASP_HOLD_FRAMES => hold,
            Some(mean) => {
                self.frames += 1;
                let weight = 1.0 / f64::from(self.frames);
                Pose::new(
                    mean.x + (measured.x - mean.x) * weight,
                    mean.z + (measured.z - mean.z) * weight,
                    mean.psi + (measured.psi - mean.psi) * weight,
                )
            }
            None => {
                self.frames = 1;
                measured
            }
        };
        self.hold = Some(hold);
        SetPoint::hold(hold)
    }

    /// The pose held, once latched (frame S).
    pub fn held(&self) -> Option<Pose> {
        self.hold
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
            Ok(motion) => Ok(Estimate::lifting(grasp, ShapedLift::new(motion, now))),
            Err(error) => Err((self, error)),
        }
    }

    /// Stops (holding the Grasp hold when nothing was commanded yet).
    pub fn stop(&self, reason: StopReason, start: StopStart) -> SafeStop {
        SafeStop::latch(reason, start.or_holding(self.hold))
    }
}

impl Default for Grasp {
    fn default() -> Self {
        Self::new()
    }
}

impl Estimate {
    /// A fresh estimation from `grasp` (frame S) by `lift`, nothing
    /// recorded.
    fn lifting(grasp: Pose, lift: ShapedLift) -> Self {
        Estimate {
            grasp,
            online: OnlineEstimator::new(),
            tilt: PlaneTilt::new(),
            stage: EstimateStage::Lifting(lift),
        }
    }

    /// The grasp pose the motion started from (frame S).
    pub fn grasp_pose(&self) -> Pose {
        self.grasp
    }

    /// Where the estimation is.
    pub fn stage(&self) -> &EstimateStage {
        &self.stage
    }

    /// Why the lift ended, once it has.
    pub fn lift_ended(&self) -> Option<LiftEnd> {
        match &self.stage {
            EstimateStage::Lifting(lift) => lift.ended(),
            EstimateStage::Concluding(conclusion) => Some(conclusion.reason),
        }
    }

    /// The online estimate so far.
    pub fn online(&self) -> &OnlineEstimator {
        &self.online
    }

    /// One step at kernel time `now` with measured `frame` and its lateral
    /// position `lateral` [m, frame S]: while lifting, records the sample
    /// in the arm's plane ([`PlaneTilt::record`]) into `path` and the
    /// online estimate when one is due (at most one per
    /// [`PATH_SAMPLE_PERIOD`]) and shapes the lift;
    /// once the lift has settled, concludes: one slice of the refinement
    /// per step and, on the step it finishes, the validator (the only way
    /// into [`Validated`], held where the lift ended). O(1) work: one
    /// moment update, or at most [`SAMPLES_PER_STEP`] refinement samples.
    /// `judged` is the joint envelope at the frame's pose that the
    /// joint-limit monitor judged this step ([`Self::joint_envelope`]);
    /// the lift reuses it unless this step's sample changed the estimate.
    ///
    /// # Errors
    /// The path buffer is full, no forearm appeared in time, the
    /// estimation failed, or the validator rejected the estimate.
    pub fn advance<const N: usize>(
        &mut self,
        path: &mut heapless::Vec<PathSample, N>,
        frame: &PathSample,
        lateral: f64,
        now: f64,
        judged: Option<JointEnvelope>,
        config: &KernelConfig,
    ) -> Result<EstimateStep, StopReason> {
        let lift = match &mut self.stage {
            EstimateStage::Concluding(conclusion) => {
                return conclusion.advance(path, self.grasp, &config.validation)
            }
            EstimateStage::Lifting(lift) => lift,
        };
        let mut judged = Some(judged);
        if is_due(path.last(), frame.time) {
            path.push(self.tilt.record(frame, lateral))
                .map_err(|_| StopReason::PathBufferFull)?;
            self.online.record(path, &config.validation);
            judged = None;
        }
        let Some((hold, reason)) = lift.settled(now, config.lift_shaping.settle_time) else {
            let command = lift
                .advance(now, frame, &self.online, judged, &LiftSettings::of(config))
                .map_err(StopReason::EstimationFailed)?;
            return Ok(match command {
                LiftCommand::Move(set_point) => EstimateStep::Move(set_point),
                LiftCommand::Hold(set_point) => EstimateStep::Hold(set_point),
            });
        };
        self.conclude(path.len(), hold, reason, config)?;
        match &mut self.stage {
            EstimateStage::Concluding(conclusion) => {
                conclusion.advance(path, self.grasp, &config.validation)
            }
            // `conclude` has just made the stage Concluding.
            EstimateStage::Lifting(_) => Err(StopReason::EstimationFailed(
                EstimateError::UpperArmPhaseTooShort,
            )),
        }
    }

    /// Ends the lift, held at `hold` for `reason`: the stage becomes the
    /// refinement of the online estimate over a path of `path_len`
    /// samples. A function of its own, not inlined, so that the
    /// refinement's temporaries (1.4 kB each) live in its frame alone and
    /// not in every Estimate step's, under the refinement's slices (with
    /// them inlined, 200 bytes more in the refinement cost 856 bytes of
    /// the firmware's stack).
    ///
    /// # Errors
    /// The online estimate has no upper-arm phase yet.
    #[inline(never)]
    fn conclude(
        &mut self,
        path_len: usize,
        hold: Pose,
        reason: LiftEnd,
        config: &KernelConfig,
    ) -> Result<(), StopReason> {
        let refinement = Refinement::after(&self.online, path_len, &config.validation, &self.tilt)
            .ok_or(StopReason::EstimationFailed(
                EstimateError::UpperArmPhaseTooShort,
            ))?;
        self.stage = EstimateStage::Concluding(Conclusion {
            hold,
            reason,
            refinement,
        });
        Ok(())
    }

    /// The worst case of the person's joints at the grasp `frame` measured
    /// (through a compliant grasp, the grasp point its force implies)
    /// under the provisional model and the validator's ranges `prior`;
    /// `None` before a provisional forearm exists.
    pub fn joint_envelope(
        &self,
        frame: &PathSample,
        prior: &ValidationLimits,
    ) -> Option<JointEnvelope> {
        self.online.joint_envelope(frame.pose, frame.wrench, prior)
    }

    /// Stops.
    pub fn stop(&self, reason: StopReason, start: StopStart) -> SafeStop {
        SafeStop::latch(reason, start)
    }
}

impl Conclusion {
    /// One slice of the refinement over `path` (at most
    /// [`SAMPLES_PER_STEP`] samples), holding the arm; on the slice that
    /// finishes it, the validator under `limits`, the path's first sample
    /// (or the `grasp` pose, frame S) its start.
    ///
    /// # Errors
    /// The refinement failed or the validator rejected its estimate.
    fn advance(
        &mut self,
        path: &[PathSample],
        grasp: Pose,
        limits: &ValidationLimits,
    ) -> Result<EstimateStep, StopReason> {
        match self.refinement.advance(path, SAMPLES_PER_STEP) {
            Progress::Running(_) => Ok(EstimateStep::Hold(SetPoint::hold(self.hold))),
            Progress::Done(Ok(estimate)) => {
                let start = path.first().map_or(grasp.point(), |s| s.pose.point());
                let arm = validate(&estimate, start, limits).map_err(StopReason::ModelRejected)?;
                Ok(EstimateStep::Validated(Validated {
                    arm,
                    hold: self.hold,
                }))
            }
            Progress::Done(Err(error)) => Err(StopReason::EstimationFailed(error)),
        }
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
        if !target.is_finite() {
            // Refused before the kinematics, as the joint-limit monitor
            // refuses the non-finite goal such a target has (q1 + q2 of two
            // opposite infinities would make a NaN on the way).
            return Err(TargetError::JointLimits(Violation::new(
                crate::monitor::Limit::ModelMismatch,
                f64::NAN,
                joints.max_model_mismatch,
            )));
        }
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
    pub fn stop(&self, reason: StopReason, start: StopStart) -> SafeStop {
        SafeStop::latch(reason, start.or_holding(Some(self.hold)))
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
    pub fn stop(&self, reason: StopReason, start: StopStart) -> SafeStop {
        SafeStop::latch(reason, start)
    }
}

impl SafeStop {
    /// The stop of `reason` from `start`: its category's set-point move and
    /// wrench ([`crate::stop`]). Total: whatever is not finite is left out
    /// (no move, no pose, zero wrench).
    fn latch(reason: StopReason, start: StopStart) -> Self {
        let category = reason.category();
        let finite_set_point = start
            .set_point
            .filter(|s| s.pose.is_finite() && s.velocity.is_finite() && s.acceleration.is_finite());
        let holding = start.holding.filter(|p| p.is_finite());
        let measured = start.measured.filter(|p| p.is_finite());
        let wrench = if start.wrench.is_finite() {
            start.wrench
        } else {
            Wrench::ZERO
        };
        let (target, min_time) = match category {
            StopCategory::MotorsOff => (None, 0.0),
            // A still set-point already holds the arm (Grasp, Validated,
            // the lift's holds): it stays, no move.
            StopCategory::Hold => match finite_set_point {
                Some(s) => (holding.or(Some(s.pose)), start.min_time.max(HOLD_MIN_TIME)),
                None => (holding.or(measured), 0.0),
            },
            StopCategory::RampDown => (
                measured.or(finite_set_point.map(|s| s.pose)),
                RAMP_DOWN_TIME,
            ),
        };
        let motion = match (finite_set_point, target) {
            (Some(from), Some(target)) if min_time > 0.0 => StopMotion::new(
                &from,
                target,
                start.now,
                min_time,
                start.peak_speed,
                start.peak_rate,
                start.coast && category == StopCategory::Hold,
            ),
            _ => None,
        };
        let hold = match (category, motion) {
            (StopCategory::MotorsOff, _) => None,
            (_, Some(motion)) => Some(motion.goal()),
            // A ramp-down that could not move (no set-point, or a clock
            // that is not finite) holds where the set-point was, or the
            // trusted pose.
            (StopCategory::RampDown, None) => finite_set_point.map(|s| s.pose).or(target),
            (StopCategory::Hold, None) => target,
        };
        Self {
            hold,
            reason,
            category,
            at: start.now,
            motion,
            wrench: if category == StopCategory::MotorsOff {
                Wrench::ZERO
            } else {
                wrench
            },
        }
    }

    /// Why the kernel stopped.
    pub fn reason(&self) -> StopReason {
        self.reason
    }

    /// What the stop does to the arm.
    pub fn category(&self) -> StopCategory {
        self.category
    }

    /// Kernel time of the stop [s] (NaN when the clock was not usable).
    pub fn at(&self) -> f64 {
        self.at
    }

    /// The set-point's move to its rest, when it moves.
    pub fn motion(&self) -> Option<&StopMotion> {
        self.motion.as_ref()
    }

    /// The set-point at rest; `None` for a motors-off stop, or when no
    /// finite pose was ever known (the robot then holds its own current
    /// position).
    pub fn hold(&self) -> Option<SetPoint> {
        self.hold.map(SetPoint::hold)
    }

    /// The set-point at kernel time `now`: on its move, then at rest.
    pub fn set_point(&self, now: f64) -> Option<SetPoint> {
        match self.motion {
            Some(motion) => Some(motion.at(now)),
            None => self.hold(),
        }
    }

    /// The wrench commanded at the stop, for a ramp-down: ramped to zero
    /// over the move; zero once it is done, and always for motors off.
    pub fn ramped_wrench(&self, now: f64) -> Wrench {
        match (self.category, self.motion) {
            (StopCategory::RampDown, Some(motion)) => {
                crate::stop::ramped(self.wrench, motion.ramp(now))
            }
            (StopCategory::Hold, _) => self.wrench,
            _ => Wrench::ZERO,
        }
    }

    /// True once the set-point is at rest (at `now`; a NaN time counts as
    /// at rest).
    pub fn is_settled(&self, now: f64) -> bool {
        self.motion.is_none_or(|m| m.is_complete(now))
    }

    /// The operator's reset: back to [`Grasp`], with no model, holding the
    /// stop's set-point at rest (the robot was holding it: no step,
    /// REQ-SM-009), or latching anew when the stop had none (motors off:
    /// the arm rests where it is measured). The kernel allows it only
    /// once the set-point is at rest and the arm still (REQ-STOP-003).
    pub fn reset(self) -> Grasp {
        self.hold.map_or(Grasp::new(), Grasp::holding)
    }
}

/// The kernel's current state.
#[derive(Clone, Copy, Debug, PartialEq)]
// No heap (no_std, no alloc): the larger variant (the estimation's running
// sums, ≈ 1 kB) lives inline; the kernel is one fixed-size value.
#[allow(clippy::large_enum_variant)]
pub enum State {
    /// See [`Grasp`].
    Grasp(Grasp),
    /// See [`Estimate`].
    Estimate(Estimate),
    /// See [`Validated`].
    Validated(Validated),
    /// See [`Manipulate`].
    Manipulate(Manipulate),
    /// See [`SafeStop`].
    SafeStop(SafeStop),
}

impl State {
    /// The state's name.
    pub fn kind(&self) -> StateKind {
        match self {
            State::Grasp(_) => StateKind::Grasp,
            State::Estimate(_) => StateKind::Estimate,
            State::Validated(_) => StateKind::Validated,
            State::Manipulate(_) => StateKind::Manipulate,
            State::SafeStop(_) => StateKind::SafeStop,
        }
    }

    /// The validated model, in the states that hold one.
    pub fn arm(&self) -> Option<&ValidatedArm> {
        match self {
            State::Validated(v) => Some(v.arm()),
            State::Manipulate(m) => Some(m.arm()),
            _ => None,
        }
    }
}

/// An operator's or supervisor's request.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Request {
    /// Grasp → Estimate: start the estimation motion from the held pose
    /// (refused without a fresh measurement).
    StartEstimation,
    /// Validated → Manipulate: move the arm to these joint angles.
    ApproveManipulation(JointAngles),
    /// Manipulate → Validated: end the manipulation and hold.
    FinishManipulation,
    /// Any state → SafeStop.
    Stop,
    /// SafeStop → Grasp.
    Reset,
}

/// Why a request was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum RefusalReason {
    /// The current state has no transition for this request.
    NotAllowedInState,
    /// No fresh, finite measurement to start from.
    NoFreshMeasurement,
    /// `now` is not finite or went backwards.
    InvalidTime,
    /// The manipulation target was refused.
    Target(TargetError),
    /// The estimation motion could not be planned.
    Plan(crate::motion::PlanError),
    /// A reset before the stop's set-point is at rest and the arm still
    /// (a fresh, finite measurement over the whole rate window, speed at
    /// most [`crate::stop::RESET_MAX_SPEED`]; REQ-STOP-003).
    ArmNotStill,
}

impl RefusalReason {
    /// Stable numeric code of the reason.
    pub const fn code(&self) -> u16 {
        match self {
            RefusalReason::NotAllowedInState => 1,
            RefusalReason::NoFreshMeasurement => 2,
            RefusalReason::InvalidTime => 3,
            RefusalReason::Target(_) => 4,
            RefusalReason::Plan(_) => 5,
            RefusalReason::ArmNotStill => 6,
        }
    }
}

/// Why new safety limits were refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LimitUpdateRefusal {
    /// Limits change only while the arm is held still: in Grasp, Validated
    /// or SafeStop, never during the estimation motion or a manipulation.
    NotAllowedInState(StateKind),
    /// The configuration with the new limits fails [`KernelConfig::check`].
    Invalid(ConfigError),
}

/// A refused request: what was asked, in which state, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Refusal {
    /// The request.
    pub request: Request,
    /// The state it was refused in.
    pub state: StateKind,
    /// Why.
    pub reason: RefusalReason,
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
pub(crate) mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    use crate::kani_inputs::{validated_arm, HOLD, MANIPULATION_TARGET};
    use crate::kani_stubs::libm_stubbed;
    use crate::monitor::set::MonitorSet;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    libm_stubbed! { [hypot, atan2, sin, cos]
        /// REQ-SM-003: for any target a manipulation plan exists only for
        /// finite targets whose goal passes the joint-limit and workspace
        /// checks, and it moves from the hold pose. Unwind 24: the validator
        /// that makes the fixed arm checks 22 values for finiteness (22
        /// iterations and the loop's exit; 24 as the validator's own proof).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_003_targets_are_checked() {
            let MonitorSet {
                joint_limits: joints,
                workspace,
                ..
            } = MonitorSet::from_limits(&SafetyLimits::default());
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
    }

    /// REQ-SM-006, REQ-SM-009, REQ-STOP-001: a stop from any state
    /// latches the pose only when it is finite, with its cause's category,
    /// and the only way out, a reset, leads to Grasp holding the stop's
    /// set-point at rest (none when the stop had none).
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_sm_006_stop_holds_only_a_finite_pose() {
        let at = if kani::any() {
            Some(Pose::new(kani::any(), kani::any(), kani::any()))
        } else {
            None
        };
        let reason = if kani::any() {
            StopReason::Operator
        } else {
            StopReason::NonFiniteCommand
        };
        let stop = Grasp::new().stop(reason, StopStart::at_pose(0.0, at));
        assert_eq!(stop.category(), reason.category());
        match (stop.hold(), at) {
            (Some(hold), Some(pose)) => {
                assert!(pose.is_finite() && hold == SetPoint::hold(pose));
                assert!(stop.category().holds());
                kani::cover!(true, "stop: holds the pose");
            }
            (None, Some(pose)) => {
                assert!(!pose.is_finite() || stop.category() == StopCategory::MotorsOff);
                kani::cover!(!pose.is_finite(), "stop: a non-finite pose is not held");
                kani::cover!(pose.is_finite(), "stop: motors off holds nothing");
            }
            (Some(_), None) => panic!("a stop without a pose holds one"),
            (None, None) => {}
        }
        assert_eq!(stop.reason(), reason);
        assert!(stop.ramped_wrench(kani::any()).is_finite());
        let grasp = stop.reset();
        assert_eq!(grasp.held().map(SetPoint::hold), stop.hold());
    }

    /// A fresh estimation by `lift` from `grasp`, as
    /// [`Grasp::start_estimation`] makes it once the motion is planned
    /// (or, for the proofs of a stop during a lift, by the lift a first
    /// step left), for the proofs that start in Estimate: there the planning's result
    /// under the libm stubs is symbolic (a duration is any number the
    /// hypot stub allows, finite or not to symbolic execution), and an
    /// estimate taken out of such a `Result` is merged with the error's
    /// bytes, where only its motion need be symbolic. Built this way, with
    /// the stubs' exact values, the stop from Estimate is verified in
    /// 208 s (552 s before; real Kani, 2026-12-07). The estimate inside the
    /// kernel's state is still not folded by symbolic execution: the
    /// Estimate step's harnesses stub its later parts
    /// (`kernel::verification`'s `first_lift_step_stubbed!`).
    pub(crate) fn lifting(grasp: Pose, lift: ShapedLift) -> Estimate {
        Estimate::lifting(grasp, lift)
    }

    /// Stubs for the harnesses of a lift's first step
    /// (`kernel::verification`): of the estimation's conclusion, where no
    /// conclusion can be (the stage is Lifting and the lift has not
    /// settled: only a later step's [`ShapedLift::settled`] ends it), and
    /// of what other states would read. Each fails the proof if it is
    /// reached where it must not be (Kani reports its assertion
    /// UNREACHABLE, i.e. passed, only when no path of the harness gets
    /// there). Symbolic execution cannot fold the kernel's state out of
    /// its union of variants, so without them every state's branch of the
    /// step was in the formula: the manipulation's set-point, the
    /// stopped step and the validated model's kinematics took half of
    /// its 20.9 M clauses (real Kani, 2026-12-07).
    #[cfg(kani)]
    pub(crate) mod stub {
        use super::*;

        /// Stub of `Conclusion::advance`.
        pub(crate) fn conclusion_advance(
            _: &mut Conclusion,
            _: &[PathSample],
            _: Pose,
            _: &ValidationLimits,
        ) -> Result<EstimateStep, StopReason> {
            kani::assert(false, "a lift's first step reached the refinement");
            Err(StopReason::EstimationFailed(
                EstimateError::UpperArmPhaseTooShort,
            ))
        }

        /// Stub of [`Manipulate::set_point`]: a lift's first step has no
        /// manipulation to read.
        pub(crate) fn manipulate_set_point(manipulate: &Manipulate, _: f64) -> SetPoint {
            kani::assert(false, "a lift's first step read a manipulation's set-point");
            SetPoint::hold(manipulate.motion.goal())
        }

        /// Stub of [`State::arm`] for a lift's first step: asserts that
        /// the state is Estimate and answers as the function then does,
        /// no validated model.
        pub(crate) fn arm(state: &State) -> Option<&ValidatedArm> {
            kani::assert(
                matches!(state, State::Estimate(_)),
                "a lift's first step left Estimate before it read the model",
            );
            None
        }

        /// Stub of `Estimate::conclude`.
        pub(crate) fn conclude(
            _: &mut Estimate,
            _: usize,
            _: Pose,
            _: LiftEnd,
            _: &KernelConfig,
        ) -> Result<(), StopReason> {
            kani::assert(false, "a lift's first step concluded");
            Ok(())
        }
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
