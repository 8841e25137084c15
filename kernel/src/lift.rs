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
//!      │ a limit │ filtered force within force_margin of the force limit
//!      │ (the arm resists) │ planned lift and its extension (0.1 m on
//!      │ along the same line, for long arms) complete
//!      ▼
//!   Settling (a minimum-jerk move to the holding pose x − f_ext/K, drawn
//!             back towards x where the joint envelope would leave the
//!             margin there, at hold_speed / hold_rate, then held for
//!             settle_time; recording)
//! ```
//!
//! Once settled ([`ShapedLift::settled`]) the lift is over: the Estimate
//! state concludes (held still; the refinement runs `SAMPLES_PER_STEP`
//! per step, [`crate::state::EstimateStage::Concluding`]).
//!
//! Before any provisional model exists the prior bounds the motion: the
//! set-point stays within `prior_reach` of the grasp (the elbow rests on the
//! table while the forearm turns, so no joint can leave its range there).
//! With a provisional forearm the shoulder is bounded by the validator's
//! l1 range; with a provisional upper arm by its 3σ uncertainty
//! ([`crate::estimation::online::OnlineEstimator::joint_envelope`]). The
//! lift ends when that worst case comes within `joint_margin` of a limit;
//! the joint-limit monitor stops the kernel if it ever crosses one.
//!
//! # Resistance (HAZ-11, REQ-MON-014)
//! An arm that resists the lift (passive stiffness, a reflex, a heavier
//! limb) stalls while the set-point runs on, and the spring's stretch
//! grows the interaction force until the force monitor stops the kernel
//! and releases the arm (MyoArm `cast`, a forearm 50 % heavier: 45.4 N
//! with the forearm upright, the upper arm not yet lifted). The lift
//! measures that force, low-pass filtered over [`FORCE_FILTER_TIME`], and
//! ends once it reaches `limits.max_force − lift_shaping.force_margin`
//! ([`LiftEnd::ForceMargin`]): the arm is held where it is, carrying what
//! it carries, and the estimate concludes on the arcs swept so far (or is
//! refused with its reason). The kernel has no model of the arm's mass:
//! the force is bounded, not predicted.

use crate::config::{KernelConfig, LiftShaping, SafetyLimits, ValidationLimits};
use crate::estimation::online::OnlineEstimator;
use crate::geometry::{Point, Pose, Wrench};
use crate::monitor::joint_limits::JointEnvelope;
use crate::monitor::{Limit, Violation};
use crate::motion::{EstimationMotion, MinimumJerkMove, SetPoint};
use crate::path::PathSample;

/// What the lift reads of the kernel's configuration, and nothing more.
#[derive(Clone, Copy, Debug)]
pub struct LiftSettings<'a> {
    /// How the lift is shaped and ended.
    pub shaping: &'a LiftShaping,
    /// The validator's ranges: the provisional model's prior.
    pub prior: &'a ValidationLimits,
    /// The joint limits the lift keeps its margin to.
    pub limits: &'a SafetyLimits,
    /// The estimation motion's peak grasp-point speed (its extension's) [m/s].
    pub peak_speed: f64,
    /// The impedance stiffness (x, z [N/m], psi [N m/rad]): where a hold
    /// carries the arm.
    pub stiffness: &'a [f64; 3],
}

impl<'a> LiftSettings<'a> {
    /// The lift's settings in `config`.
    pub fn of(config: &'a KernelConfig) -> Self {
        Self {
            shaping: &config.lift_shaping,
            prior: &config.validation,
            limits: &config.limits,
            peak_speed: config.estimation_motion.peak_speed,
            stiffness: &config.impedance.stiffness,
        }
    }
}

/// Time constant of the lift's force filter [s]: a first-order low pass
/// of (f_ext.x, f_ext.z) that takes the force sensor's noise (0.5 N per
/// axis, plant.md) to ≈ 0.04 N at 1 kHz (0.11 N at 100 Hz) and follows the
/// stalled arm's rise (≈ 8 N/s) within 0.8 N.
pub const FORCE_FILTER_TIME: f64 = 0.1;

/// Why the lift ended.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LiftEnd {
    /// The upper arm swept [`LiftShaping::target_arc`].
    ArcReached,
    /// The joint envelope came within the margin of this limit.
    JointMargin(Limit),
    /// The planned lift and its extension were complete.
    MotionComplete,
    /// The filtered interaction force reached the force limit less
    /// `lift_shaping.force_margin`: the arm resists the lift. `value` is
    /// the filtered force magnitude [N], `bound` the limit less the margin.
    ForceMargin(Violation),
}

impl LiftEnd {
    /// Stable numeric code of the reason (the limit has its own,
    /// [`Limit::code`]).
    pub const fn code(&self) -> u16 {
        match self {
            LiftEnd::ArcReached => 1,
            LiftEnd::JointMargin(_) => 2,
            LiftEnd::MotionComplete => 3,
            LiftEnd::ForceMargin(_) => 4,
        }
    }
}

/// Where the lift is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LiftPhase {
    /// Following the planned lift.
    Lifting,
    /// Paused at the prior reach since this time [s].
    AwaitingForearm {
        /// Kernel time the pause began [s].
        since: f64,
    },
    /// Moving to the holding pose, then holding it; arm settling, path still
    /// recorded.
    Settling {
        /// Kernel time the lift ended [s].
        since: f64,
        /// From the lift's last set-point to the holding pose.
        to_hold: MinimumJerkMove,
        /// The holding pose.
        hold: Pose,
        /// Why the lift ended.
        reason: LiftEnd,
    },
}

/// The shaped lift.
///
/// # Invariants
/// `clock` ∈ [0, duration of `segment`]; it advances only while Lifting.
/// `segment` is the planned lift, then (once, if `extended`) its extension.
/// `force` is the measured (f_ext.x, f_ext.z) [N] filtered over
/// [`FORCE_FILTER_TIME`] up to `last_now`, from zero at the start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapedLift {
    motion: EstimationMotion,
    segment: MinimumJerkMove,
    extended: bool,
    clock: f64,
    last_now: f64,
    force: Point,
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
            segment: *motion.lift(),
            extended: false,
            clock: 0.0,
            last_now: now,
            force: Point::new(0.0, 0.0),
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

    /// Advances the lift to kernel time `now` given the online estimate
    /// (already updated with this step's sample) and the measured `frame`.
    /// `judged` is the joint envelope at the frame's pose when the caller
    /// already has it for this estimate (the joint-limit monitor's, on a
    /// step that recorded no sample); `None`: the lift computes it. The
    /// caller starts the conclusion when [`Self::settled`] says so.
    ///
    /// # Errors
    /// No provisional forearm within `forearm_wait`, or a move that cannot
    /// be planned (non-finite).
    pub fn advance(
        &mut self,
        now: f64,
        frame: &PathSample,
        online: &OnlineEstimator,
        judged: Option<Option<JointEnvelope>>,
        settings: &LiftSettings<'_>,
    ) -> Result<LiftCommand, crate::estimation::EstimateError> {
        let shaping = settings.shaping;
        let dt = if now > self.last_now {
            now - self.last_now
        } else {
            0.0
        };
        self.last_now = self.last_now.max(now);
        self.force = filtered_force(self.force, frame.wrench, dt);
        match self.phase {
            LiftPhase::Lifting => {
                let duration = self.segment.duration();
                let next = (self.clock + dt).min(duration);
                let set_point = self.segment.at(next);
                let start = self.motion.lift().start().point();
                if online.forearm().is_none()
                    && set_point.pose.point().distance(start) > shaping.prior_reach
                {
                    self.phase = LiftPhase::AwaitingForearm { since: now };
                    return Ok(LiftCommand::Hold(SetPoint::hold(
                        self.segment.at(self.clock).pose,
                    )));
                }
                self.clock = next;
                let envelope = judged.unwrap_or_else(|| {
                    online.joint_envelope(frame.pose, frame.wrench, settings.prior)
                });
                let mut reason = end_reason(online, envelope, shaping, settings.limits)
                    .or_else(|| force_margin_end(self.force, shaping, settings.limits));
                if reason.is_none() && next >= duration {
                    if self.extended {
                        reason = Some(LiftEnd::MotionComplete);
                    } else {
                        self.extend(settings)?;
                    }
                }
                match reason {
                    Some(reason) => {
                        let hold = lift_hold(frame, online, settings);
                        let to_hold = MinimumJerkMove::bounded(
                            set_point.pose,
                            hold,
                            shaping.hold_speed,
                            shaping.hold_rate,
                            shaping.hold_move_time,
                        )
                        .map_err(|_| crate::estimation::EstimateError::NonFiniteSample)?;
                        self.phase = LiftPhase::Settling {
                            since: now,
                            to_hold,
                            hold,
                            reason,
                        };
                        Ok(LiftCommand::Move(to_hold.at(0.0)))
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
            LiftPhase::Settling { since, to_hold, .. } if now - since < to_hold.duration() => {
                Ok(LiftCommand::Move(to_hold.at(now - since)))
            }
            LiftPhase::Settling { hold, .. } => Ok(LiftCommand::Hold(SetPoint::hold(hold))),
        }
    }

    /// Continues the completed lift along its line by
    /// [`LiftShaping::extension`] at the lift's peak speed (long arms sweep
    /// too little upper-arm arc on plant.md's lift: 0.64 rad for l1 0.38 m,
    /// l2 0.26 m).
    fn extend(
        &mut self,
        settings: &LiftSettings<'_>,
    ) -> Result<(), crate::estimation::EstimateError> {
        let start = self.segment.start();
        let goal = self.segment.goal();
        let (dx, dz) = (goal.x - start.x, goal.z - start.z);
        let length = libm::hypot(dx, dz);
        let reach = settings.shaping.extension / length.max(f64::EPSILON);
        let extended = Pose::new(goal.x + reach * dx, goal.z + reach * dz, goal.psi);
        self.segment = MinimumJerkMove::new(goal, extended, settings.peak_speed)
            .map_err(|_| crate::estimation::EstimateError::NonFiniteSample)?;
        self.clock = 0.0;
        self.extended = true;
        Ok(())
    }

    /// When the holding pose has been reached and held for `settle_time` at
    /// `now`: the pose and why the lift ended.
    pub fn settled(&self, now: f64, settle_time: f64) -> Option<(Pose, LiftEnd)> {
        match self.phase {
            LiftPhase::Settling {
                since,
                to_hold,
                hold,
                reason,
            } if now - since >= to_hold.duration() + settle_time => Some((hold, reason)),
            _ => None,
        }
    }

    /// Why the lift ended, once it has.
    pub fn ended(&self) -> Option<LiftEnd> {
        match self.phase {
            LiftPhase::Settling { reason, .. } => Some(reason),
            _ => None,
        }
    }

    /// The measured force filtered over [`FORCE_FILTER_TIME`]
    /// (f_ext.x, f_ext.z) [N].
    pub fn force(&self) -> Point {
        self.force
    }

    /// The pose held once the lift has ended.
    pub fn hold(&self) -> Option<Pose> {
        match self.phase {
            LiftPhase::Settling { hold, .. } => Some(hold),
            _ => None,
        }
    }
}

/// The force filter's next value: `previous` moved towards the measured
/// `wrench`'s (f_ext.x, f_ext.z) by dt / ([`FORCE_FILTER_TIME`] + dt), dt
/// in seconds (0: unchanged). A non-finite force makes it non-finite,
/// which ends the lift ([`force_margin_end`]).
pub fn filtered_force(previous: Point, wrench: Wrench, dt: f64) -> Point {
    let gain = dt / (FORCE_FILTER_TIME + dt);
    Point::new(
        previous.x + (wrench.fx - previous.x) * gain,
        previous.z + (wrench.fz - previous.z) * gain,
    )
}

/// [`LiftEnd::ForceMargin`] when the filtered `force`'s magnitude is not
/// below `limits.max_force − shaping.force_margin` (a NaN force is not
/// below it); `None` otherwise (REQ-MON-014).
pub fn force_margin_end(
    force: Point,
    shaping: &LiftShaping,
    limits: &SafetyLimits,
) -> Option<LiftEnd> {
    let magnitude = libm::hypot(force.x, force.z);
    let bound = limits.max_force - shaping.force_margin;
    if magnitude < bound {
        None
    } else {
        Some(LiftEnd::ForceMargin(Violation::new(
            Limit::ForceMagnitude,
            magnitude,
            bound,
        )))
    }
}

/// The set-point that holds the arm where `frame` measured it: the
/// measured pose moved by the wrench the robot applies now over the
/// stiffness, x_d = x + F/K = x − f_ext/K, so the spring keeps carrying the
/// arm's weight. The lift's own set-point leads the arm by up to 0.15 m;
/// frozen there it would pull the arm on past its limits. A stop's hold
/// uses it too ([`crate::stop`]).
pub(crate) fn holding_pose(frame: &PathSample, stiffness: &[f64; 3]) -> Pose {
    let w = frame.wrench;
    Pose::new(
        frame.pose.x - w.fx / stiffness[0],
        frame.pose.z - w.fz / stiffness[1],
        frame.pose.psi - w.ty / stiffness[2],
    )
}

/// Halvings of the line from the measured pose to the holding pose that
/// [`lift_hold`] may take: the hold is found to 1/64 of that line (about
/// 1 mm and 0.01 rad for the lift's 5-7 cm, 0.3-0.5 rad stretch), at six
/// joint envelopes' cost once per lift.
pub const HOLD_HALVINGS: usize = 6;

/// The lift's holding pose [world frame; m, rad]: the [`holding_pose`]
/// that carries the arm as the robot carried it at the lift's end, unless
/// the provisional model's joint envelope there leaves less slack to the
/// joint limits ([`joint_slack`]) than the margin and than the measured
/// pose leaves; then the point nearest it on the line from the measured
/// pose that does, to 1/2^[`HOLD_HALVINGS`] of the line.
///
/// Why: at the lift's end the wrench still holds the lift's dynamic part
/// (the set-point leads the arm, and psi's lags it by up to 0.5 rad), so
/// the pose that carries it may lie beyond what the arm can reach with
/// its elbow inside its range: a short arm (l1 0.223 m, l2 0.158 m) held
/// there was pulled straight and on into hyperextension while the
/// estimate was refined (`limb population --arms 500 --seed 2026`, arm
/// 121). Without a provisional forearm there is no envelope to judge by,
/// and the carrying pose is held.
fn lift_hold(frame: &PathSample, online: &OnlineEstimator, settings: &LiftSettings<'_>) -> Pose {
    let carried = holding_pose(frame, settings.stiffness);
    let slack = |pose: Pose| {
        online
            .joint_envelope(pose, frame.wrench, settings.prior)
            .map(|envelope| joint_slack(envelope, settings.shaping, settings.limits))
            .map(|(elbow, shoulder)| elbow.min(shoulder))
    };
    let Some(measured) = slack(frame.pose) else {
        return carried;
    };
    let floor = measured.min(0.0);
    let acceptable = |pose: Pose| slack(pose).is_some_and(|s| s >= floor);
    if acceptable(carried) {
        return carried;
    }
    let at = |t: f64| {
        let from = frame.pose;
        Pose::new(
            from.x + t * (carried.x - from.x),
            from.z + t * (carried.z - from.z),
            from.psi + t * (carried.psi - from.psi),
        )
    };
    let (mut good, mut bad) = (0.0, 1.0);
    for _ in 0..HOLD_HALVINGS {
        let mid = 0.5 * (good + bad);
        if acceptable(at(mid)) {
            good = mid;
        } else {
            bad = mid;
        }
    }
    at(good)
}

/// Slack of a joint envelope to the joint limits less the lift's margin
/// [rad]: (elbow flexion above its low limit + margin, shoulder elevation
/// below its high limit − margin); ≤ 0 is inside the margin.
pub fn joint_slack(
    envelope: JointEnvelope,
    shaping: &LiftShaping,
    limits: &SafetyLimits,
) -> (f64, f64) {
    (
        envelope.min_elbow_flexion - (limits.elbow_flexion.low + shaping.joint_margin),
        limits.shoulder_elevation.high - shaping.joint_margin - envelope.max_shoulder_elevation,
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
        let (elbow, shoulder) = joint_slack(envelope, shaping, limits);
        if elbow <= 0.0 {
            return Some(LiftEnd::JointMargin(Limit::ElbowFlexion));
        }
        if shoulder <= 0.0 {
            return Some(LiftEnd::JointMargin(Limit::ShoulderElevation));
        }
    }
    let (_, upper_arm_arc) = online.arcs();
    (online.upper_arm().is_some() && upper_arm_arc >= shaping.target_arc)
        .then_some(LiftEnd::ArcReached)
}

#[cfg(any(test, kani))]
pub(crate) mod verification {
    use super::*;
    use crate::estimation::EstimateError;
    use crate::kani_inputs::any_frame_the_monitors_pass;
    use crate::kani_stubs::libm_stubbed;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// When the proofs take a lift's first step [s after the lift started
    /// at kernel time 0].
    pub(crate) const FIRST_STEP_AT: f64 = 0.5;

    /// The lift whose first step the proofs take, as planned at kernel
    /// time 0: from the grasp at the origin of frame S straight up by the
    /// default lift's length, the forearm turned by π/2, at the default
    /// peak speed (0.3 m in 11.25 s), then the default hold. Along an axis
    /// its length and duration are exact under the libm stubs (`hypot`
    /// with a leg 0), so its set-points are numbers to symbolic execution.
    /// The default lift's goal is planned through the sine and cosine of
    /// its angle, any values under the stubs: with it the lift's duration
    /// was a formula, and the Estimate step was undecided in 10 min (real
    /// Kani, 2026-12-07).
    pub(crate) fn first_lift() -> ShapedLift {
        let p = KernelConfig::default().estimation_motion;
        let grasp = Pose::new(0.0, 0.0, 0.0);
        let goal = Pose::new(
            grasp.x,
            grasp.z + p.lift_length,
            grasp.psi + core::f64::consts::FRAC_PI_2,
        );
        let lift = MinimumJerkMove::new(grasp, goal, p.peak_speed)
            .expect("a finite move at a positive speed");
        ShapedLift::new(EstimationMotion::of_lift(lift, p.hold_time), 0.0)
    }

    /// A frame at [`FIRST_STEP_AT`] for a step of [`first_lift`]: any
    /// frame the monitors pass under `limits`, or (so that the sampling
    /// stand-in reaches the lift's end too; one of those to Kani) the
    /// grasp pulled by the force limit along both axes, which ends the
    /// lift at its force margin.
    pub(crate) fn any_first_step_frame(limits: &SafetyLimits) -> PathSample {
        let grasp = first_lift().motion().lift().start();
        if kani::any() {
            any_frame_the_monitors_pass(grasp, FIRST_STEP_AT, limits)
        } else {
            PathSample {
                time: FIRST_STEP_AT,
                pose: grasp,
                wrench: Wrench::new(limits.max_force, limits.max_force, 0.0),
            }
        }
    }

    /// REQ-PANIC-001, REQ-CMD-001: what [`first_lift`]'s step at
    /// [`FIRST_STEP_AT`] on a frame the monitors passed may give: the
    /// lift's set-point then; or, the step ending the lift (the force
    /// margin), that set-point's pose held (where the settling move
    /// starts); or a settling move that cannot be planned. Short of the
    /// prior reach (0.25 mm of 0.25 m) and of the lift's end (0.5 s of
    /// 11.25 s) the step can do nothing else. The contract the Estimate
    /// step's proofs assume of the lift ([`stub::advance`]) and
    /// [`verify_req_panic_001_a_first_lift_step_meets_its_contract`]
    /// proves.
    pub(crate) fn first_step_contract(
        result: &Result<LiftCommand, EstimateError>,
    ) -> Result<(), &'static str> {
        let following = first_lift().segment.at(FIRST_STEP_AT);
        match result {
            Ok(LiftCommand::Move(s)) if *s == following || *s == SetPoint::hold(following.pose) => {
                Ok(())
            }
            Ok(_) => Err("a lift's first step commanded another set-point"),
            Err(EstimateError::NonFiniteSample) => Ok(()),
            Err(_) => Err("a lift's first step failed for another reason than its own"),
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        #[cfg_attr(kani, kani::stub(
            OnlineEstimator::record_forearm,
            crate::estimation::online::stub::record_forearm
        ))]
        #[cfg_attr(kani, kani::stub(
            OnlineEstimator::catch_up,
            crate::estimation::online::stub::catch_up
        ))]
        #[cfg_attr(kani, kani::stub(
            OnlineEstimator::joint_envelope,
            crate::estimation::online::stub::joint_envelope
        ))]
        /// REQ-PANIC-001, REQ-CMD-001: [`first_lift`]'s step at
        /// [`FIRST_STEP_AT`] with any frame the monitors pass, the online
        /// estimate fresh or after one sample (any: a first step records
        /// at most one; the lift then judges the joint envelope itself,
        /// else it is handed the monitor's, none without a forearm), never
        /// panics and meets [`first_step_contract`]. The online estimate's
        /// phases and envelope are stubbed as in the Estimate step's
        /// proofs (a fresh estimate has no forearm).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(12))]
        pub(super) fn verify_req_panic_001_a_first_lift_step_meets_its_contract() {
            let config = KernelConfig::default();
            let mut lift = first_lift();
            let frame = any_first_step_frame(&config.limits);
            let mut online = OnlineEstimator::new();
            let recorded: bool = kani::any();
            if recorded {
                online.record(&[kani::any()], &config.validation);
            }
            let judged = if recorded { None } else { Some(None) };
            let result = lift.advance(
                FIRST_STEP_AT,
                &frame,
                &online,
                judged,
                &LiftSettings::of(&config),
            );
            assert_eq!(first_step_contract(&result), Ok(()));
            kani::cover!(
                matches!(result, Ok(LiftCommand::Move(_))) && lift.ended().is_none(),
                "lift's first step: lifts"
            );
            kani::cover!(lift.ended().is_some(), "lift's first step: ends the lift");
        }
    }

    /// Kani stubs of the lift, each any answer its proved contract allows.
    #[cfg(kani)]
    pub(crate) mod stub {
        use super::*;

        /// Stub of [`ShapedLift::advance`] by [`first_step_contract`], for
        /// the Estimate step's proofs (a lift's first step): asserts that
        /// it is called where that contract was proved ([`first_lift`] as
        /// planned, at [`FIRST_STEP_AT`], on a frame the monitors pass) and
        /// gives any of the contract's answers, built from the planned
        /// lift's set-point (numbers; the lift as read from the kernel's
        /// state is not folded by symbolic execution). The lift is left as
        /// it was: after its step a kernel step reads it only into its
        /// trace, and a stop during the step is stubbed by its contract,
        /// proved from the lift before and after a real first step
        /// (`kernel::verification`).
        pub(crate) fn advance(
            lift: &mut ShapedLift,
            now: f64,
            frame: &PathSample,
            _: &OnlineEstimator,
            _: Option<Option<JointEnvelope>>,
            settings: &LiftSettings<'_>,
        ) -> Result<LiftCommand, EstimateError> {
            let planned = first_lift();
            kani::assert(
                now == FIRST_STEP_AT && *lift == planned,
                "the lift's stub stood for another step than its proof's",
            );
            kani::assert(
                crate::kani_inputs::the_monitors_pass(frame, settings.limits),
                "the lift's stub met a frame its proof does not cover",
            );
            let following = planned.segment.at(FIRST_STEP_AT);
            let result = match kani::any::<u8>() {
                0 => Ok(LiftCommand::Move(following)),
                1 => Ok(LiftCommand::Move(SetPoint::hold(following.pose))),
                _ => Err(EstimateError::NonFiniteSample),
            };
            kani::assume(first_step_contract(&result).is_ok());
            result
        }
    }

    /// REQ-MON-014: what [`force_margin_end`] must answer for the filtered
    /// `force`, decided without a square root (the proof stubs `hypot`):
    /// a NaN component, or a component as large as the bound
    /// (`limits.max_force − shaping.force_margin`), ends the lift; components
    /// whose magnitudes sum below the bound do not; an end names the force
    /// limit, carries the bound and a force not below it (or NaN).
    pub(super) fn check_force_margin_end(
        force: Point,
        shaping: &LiftShaping,
        limits: &SafetyLimits,
        end: Option<LiftEnd>,
    ) -> Result<(), &'static str> {
        let bound = limits.max_force - shaping.force_margin;
        let (x, z) = (libm::fabs(force.x), libm::fabs(force.z));
        let clearly_reached = !(x < bound && z < bound);
        let clearly_below = x + z < bound;
        match end {
            None if clearly_reached => Err("a force at the bound did not end the lift"),
            Some(_) if clearly_below => Err("a force below the bound ended the lift"),
            Some(LiftEnd::ForceMargin(v)) => {
                if v.limit != Limit::ForceMagnitude {
                    Err("the end names another limit")
                } else if v.bound.to_bits() != bound.to_bits() {
                    Err("the end carries another bound")
                } else if v.value < bound {
                    Err("the end carries a force below its bound")
                } else {
                    Ok(())
                }
            }
            Some(_) => Err("the force check gave another end"),
            None => Ok(()),
        }
    }

    /// REQ-MON-014: for any filtered force (NaN and infinities included)
    /// and any finite force limit and margin the lift ends exactly when
    /// the force is not below the limit less the margin, and says so with
    /// the force limit's name, the force and the bound. Finite: the
    /// configuration check admits no other limit or margin
    /// ([`LiftShaping::check`], [`SafetyLimits::check`]); an infinite limit
    /// less an infinite margin is NaN, which real Kani reported (NaN on
    /// subtraction) when this harness allowed them.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    pub(super) fn verify_req_mon_014_resistance_ends_the_lift_at_its_margin() {
        let force = Point::new(kani::any(), kani::any());
        let mut shaping = LiftShaping::default();
        let mut limits = SafetyLimits::default();
        shaping.force_margin = kani::any();
        limits.max_force = kani::any();
        kani::assume(shaping.force_margin.is_finite() && limits.max_force.is_finite());
        let end = force_margin_end(force, &shaping, &limits);
        assert_eq!(
            check_force_margin_end(force, &shaping, &limits, end),
            Ok(())
        );
        kani::cover!(end.is_none(), "force margin: lift goes on");
        kani::cover!(end.is_some(), "force margin: lift ends");
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::geometry::Wrench;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "lift force margin",
                20_000,
                verify_req_mon_014_resistance_ends_the_lift_at_its_margin,
            );
            kani::check(
                "a lift's first step",
                2_000,
                verify_req_panic_001_a_first_lift_step_meets_its_contract,
            );
        }

        proptest! {
            /// REQ-MON-014: with the real `hypot` the force check meets the
            /// proof's check and ends the lift exactly outside the circle
            /// of radius max_force − force_margin.
            #[test]
            fn req_mon_014_resistance_ends_the_lift_exactly_at_its_margin(
                fx in -60.0..60.0f64, fz in -60.0..60.0f64, margin in 0.1..10.0f64,
            ) {
                let shaping = LiftShaping {
                    force_margin: margin,
                    ..LiftShaping::default()
                };
                let limits = SafetyLimits::default();
                let force = Point::new(fx, fz);
                let end = force_margin_end(force, &shaping, &limits);
                prop_assert_eq!(check_force_margin_end(force, &shaping, &limits, end), Ok(()));
                let bound = limits.max_force - margin;
                prop_assert_eq!(end.is_some(), libm::hypot(fx, fz) >= bound);
            }

            /// REQ-MON-014: the force filter moves towards each measured
            /// force without passing it (each axis stays between its last
            /// value and the measurement) and, under a constant force,
            /// comes within 1 % of it after 0.5 s (five time constants) at
            /// 1 kHz or at 100 Hz.
            #[test]
            fn req_mon_014_the_force_filter_follows_without_overshoot(
                start in prop::array::uniform2(-60.0..60.0f64),
                measured in prop::array::uniform2(-60.0..60.0f64),
                period in prop_oneof![Just(0.001), Just(0.01)],
            ) {
                let wrench = Wrench::new(measured[0], measured[1], 0.0);
                let mut force = Point::new(start[0], start[1]);
                for _ in 0..libm::round(0.5 / period) as usize {
                    let next = filtered_force(force, wrench, period);
                    for (before, after, target) in [
                        (force.x, next.x, measured[0]),
                        (force.z, next.z, measured[1]),
                    ] {
                        prop_assert!(before.min(target) <= after && after <= before.max(target));
                    }
                    force = next;
                }
                let gap = libm::hypot(force.x - measured[0], force.z - measured[1]);
                let initial = libm::hypot(start[0] - measured[0], start[1] - measured[1]);
                prop_assert!(gap <= 0.01 * initial + 1e-9, "{gap} of {initial}");
            }
        }
    }
}
