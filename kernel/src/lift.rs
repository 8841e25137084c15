//! The estimation lift, shaped online by the provisional arm model so that
//! the person's joints stay inside their limits (HAZ-08), and ended as soon
//! as the arcs suffice.
//!
//! # Theory of operation
//! The lift follows the planned [`EstimationMotion`] (plant.md eq. 3) on its
//! own clock, which advances only while [`LiftPhase::Lifting`]:
//!
//! ```text
//!            no provisional forearm and the set-point
//!            beyond LiftShaping::prior_reach of the grasp
//!   Lifting ───────────────────────────────────────────▶ AwaitingForearm
//!      │   ◀─────────────────────── provisional forearm ────┘ (or, after
//!      │                                forearm_wait, EstimationFailed)
//!      │ upper-arm arc ≥ target_arc │ joint envelope within joint_margin of
//!      │ a limit │ planned lift complete
//!      ▼
//!   Settling (set-point frozen, still recording, settle_time)
//!      ▼
//!   Concluding (held still; the refinement runs SAMPLES_PER_STEP per step)
//! ```
//!
//! Before any provisional model exists the prior bounds the motion: the
//! set-point stays within `prior_reach` of the grasp (the elbow rests on the
//! table while the forearm turns, so no joint can leave its range there).
//! With a provisional forearm the shoulder is bounded by the validator's
//! l1 range; with a provisional upper arm by its 3σ uncertainty
//! ([`crate::estimation::online::OnlineEstimator::joint_envelope`]). The
//! lift ends when that worst case comes within `joint_margin` of a limit;
//! the joint-limit monitor stops the kernel if it ever crosses one.

use crate::config::{KernelConfig, SafetyLimits};
use crate::estimation::online::{JointEnvelope, OnlineEstimator};
use crate::estimation::refine::Refinement;
use crate::geometry::Pose;
use crate::monitor::Limit;
use crate::motion::{EstimationMotion, SetPoint};
use crate::path::PathSample;

/// How the kernel shapes and ends its estimation lift.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LiftShaping {
    /// Farthest the set-point may move from the grasp before a provisional
    /// forearm exists [m]. 0.25 m: the forearm sweeps the
    /// [`crate::estimation::online::PROVISIONAL_ARC`] with the set-point
    /// 0.12-0.14 m out on the six arms of `plant.md`.
    pub prior_reach: f64,
    /// Longest wait at `prior_reach` for a provisional forearm [s].
    pub forearm_wait: f64,
    /// Upper-arm arc that ends the lift [rad]. 0.9 rad: the validator needs
    /// 0.5 rad; the upper arm then stands ≈ 52° up, far from the limits.
    pub target_arc: f64,
    /// Margin kept between the joint envelope and the joint limits [rad].
    pub joint_margin: f64,

    /// Time the set-point is held after the lift ends, still recording,
    /// before the conclusion [s].
    pub settle_time: f64,
}

impl Default for LiftShaping {
    fn default() -> Self {
        Self {
            prior_reach: 0.25,
            forearm_wait: 5.0,
            target_arc: 0.9,
            joint_margin: 0.10,
            settle_time: 1.0,
        }
    }
}

impl LiftShaping {
    /// True when every value is finite and positive.
    pub fn is_valid(&self) -> bool {
        [
            self.prior_reach,
            self.forearm_wait,
            self.target_arc,
            self.joint_margin,
            self.settle_time,
        ]
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
    }
}

/// Why the lift ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LiftEnd {
    /// The upper arm swept [`LiftShaping::target_arc`].
    ArcReached,
    /// The joint envelope came within the margin of this limit.
    JointMargin(Limit),
    /// The planned lift was complete.
    MotionComplete,
}

/// Where the lift is.
#[derive(Clone, Copy, Debug, PartialEq)]
// No heap (no_std, no alloc): the larger variant (the estimation's running
// sums, ≈ 1 kB) lives inline; the kernel is one fixed-size value.
#[allow(clippy::large_enum_variant)]
pub enum LiftPhase {
    /// Following the planned lift.
    Lifting,
    /// Paused at the prior reach since this time [s].
    AwaitingForearm {
        /// Kernel time the pause began [s].
        since: f64,
    },
    /// Set-point frozen, arm settling, path still recorded.
    Settling {
        /// Kernel time the lift ended [s].
        since: f64,
        /// The frozen set-point.
        hold: Pose,
        /// Why the lift ended.
        reason: LiftEnd,
    },
    /// Held still while the estimate is refined.
    Concluding {
        /// The frozen set-point.
        hold: Pose,
        /// Why the lift ended.
        reason: LiftEnd,
        /// The refinement in progress.
        refinement: Refinement,
    },
}

/// The shaped lift.
///
/// # Invariants
/// `clock` ∈ [0, planned duration]; it advances only while Lifting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapedLift {
    motion: EstimationMotion,
    clock: f64,
    last_now: f64,
    phase: LiftPhase,
}

/// What the lift commands this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LiftCommand {
    /// Follow this moving set-point.
    Move(SetPoint),
    /// Hold this set-point still.
    Hold(SetPoint),
}

impl ShapedLift {
    /// The planned `motion`, started at kernel time `now`.
    pub fn new(motion: EstimationMotion, now: f64) -> Self {
        Self {
            motion,
            clock: 0.0,
            last_now: now,
            phase: LiftPhase::Lifting,
        }
    }

    /// The planned motion.
    pub fn motion(&self) -> &EstimationMotion {
        &self.motion
    }

    /// The phase.
    pub fn phase(&self) -> &LiftPhase {
        &self.phase
    }

    /// Mutable phase, for the conclusion's refinement.
    pub(crate) fn phase_mut(&mut self) -> &mut LiftPhase {
        &mut self.phase
    }

    /// True while the path is still being recorded (not Concluding).
    pub fn is_recording(&self) -> bool {
        !matches!(self.phase, LiftPhase::Concluding { .. })
    }

    /// Advances the lift to kernel time `now` given the online estimate
    /// (already updated with this step's sample) and the measured `pose`.
    /// Returns the command, or `Err(Some(refinement start))`-free: the
    /// caller starts the conclusion when [`Self::settled`] says so.
    pub fn advance(
        &mut self,
        now: f64,
        frame: &PathSample,
        online: &OnlineEstimator,
        config: &KernelConfig,
    ) -> Result<LiftCommand, crate::estimation::EstimateError> {
        let shaping = &config.lift_shaping;
        let dt = if now > self.last_now {
            now - self.last_now
        } else {
            0.0
        };
        self.last_now = self.last_now.max(now);
        match self.phase {
            LiftPhase::Lifting => {
                let duration = self.motion.lift().duration();
                let next = (self.clock + dt).min(duration);
                let set_point = self.motion.at(next);
                let start = self.motion.lift().start().point();
                if online.forearm().is_none()
                    && set_point.pose.point().distance(start) > shaping.prior_reach
                {
                    self.phase = LiftPhase::AwaitingForearm { since: now };
                    return Ok(LiftCommand::Hold(SetPoint::hold(
                        self.motion.at(self.clock).pose,
                    )));
                }
                self.clock = next;
                let envelope = online.joint_envelope(frame.pose, &config.validation);
                let reason = end_reason(online, envelope, shaping, &config.limits)
                    .or((next >= duration).then_some(LiftEnd::MotionComplete));
                match reason {
                    Some(reason) => {
                        let hold = holding_pose(frame, &config.impedance.stiffness);
                        self.phase = LiftPhase::Settling {
                            since: now,
                            hold,
                            reason,
                        };
                        Ok(LiftCommand::Hold(SetPoint::hold(hold)))
                    }
                    None => Ok(LiftCommand::Move(set_point)),
                }
            }
            LiftPhase::AwaitingForearm { since } => {
                if online.forearm().is_some() {
                    self.phase = LiftPhase::Lifting;
                } else if now - since > shaping.forearm_wait {
                    return Err(crate::estimation::EstimateError::ForearmPhaseTooShort);
                }
                Ok(LiftCommand::Hold(SetPoint::hold(
                    self.motion.at(self.clock).pose,
                )))
            }
            LiftPhase::Settling { hold, .. } | LiftPhase::Concluding { hold, .. } => {
                Ok(LiftCommand::Hold(SetPoint::hold(hold)))
            }
        }
    }

    /// When Settling for at least `settle_time` at `now`: the frozen pose and
    /// why the lift ended.
    pub fn settled(&self, now: f64, settle_time: f64) -> Option<(Pose, LiftEnd)> {
        match self.phase {
            LiftPhase::Settling {
                since,
                hold,
                reason,
            } if now - since >= settle_time => Some((hold, reason)),
            _ => None,
        }
    }

    /// Why the lift ended, once it has.
    pub fn ended(&self) -> Option<LiftEnd> {
        match self.phase {
            LiftPhase::Settling { reason, .. } | LiftPhase::Concluding { reason, .. } => {
                Some(reason)
            }
            _ => None,
        }
    }

    /// The pose held once the lift has ended.
    pub fn hold(&self) -> Option<Pose> {
        match self.phase {
            LiftPhase::Settling { hold, .. } | LiftPhase::Concluding { hold, .. } => Some(hold),
            _ => None,
        }
    }
}

/// The set-point that holds the arm where `frame` measured it: the
/// measured pose moved by the wrench the robot applies now over the
/// stiffness, x_d = x + F/K = x − f_ext/K, so the spring keeps carrying the
/// arm's weight. The lift's own set-point leads the arm by up to 0.15 m;
/// frozen there it would pull the arm on past its limits.
fn holding_pose(frame: &PathSample, stiffness: &[f64; 3]) -> Pose {
    let w = frame.wrench;
    Pose::new(
        frame.pose.x - w.fx / stiffness[0],
        frame.pose.z - w.fz / stiffness[1],
        frame.pose.psi - w.ty / stiffness[2],
    )
}

/// Why the lift must end now, if it must.
fn end_reason(
    online: &OnlineEstimator,
    envelope: Option<JointEnvelope>,
    shaping: &LiftShaping,
    limits: &SafetyLimits,
) -> Option<LiftEnd> {
    if let Some(envelope) = envelope {
        if envelope.min_elbow_flexion <= limits.elbow_flexion.low + shaping.joint_margin {
            return Some(LiftEnd::JointMargin(Limit::ElbowFlexion));
        }
        if envelope.max_shoulder_elevation >= limits.shoulder_elevation.high - shaping.joint_margin
        {
            return Some(LiftEnd::JointMargin(Limit::ShoulderElevation));
        }
    }
    let (_, upper_arm_arc) = online.arcs();
    (online.upper_arm().is_some() && upper_arm_arc >= shaping.target_arc)
        .then_some(LiftEnd::ArcReached)
}
