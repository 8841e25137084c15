//! Stop categories: what a stop does to the arm still in the robot's hand.
//!
//! # Theory of operation
//! A stop is decided in the kernel, with its cause ([`StopReason`]), and
//! each cause has one category ([`StopReason::category`]), with the
//! hazard that decides it (`spec/hazards.md`, HAZ-09 and HAZ-10):
//!
//! | category | IEC 60204-1 | set-point | wrench (wrench-overlay robots) |
//! |---|---|---|---|
//! | [`StopCategory::Hold`] | 2 | brought from where it was (its velocity and acceleration kept: no step) to the pose that holds the arm where it is, x − f_ext/K, then held | the impedance law about that set-point |
//! | [`StopCategory::RampDown`] | 1 | brought from where it was to the last trusted measured pose over [`RAMP_DOWN_TIME`]: the spring's force falls to zero, then held | the wrench at the stop, ramped to zero over the same time |
//! | [`StopCategory::MotorsOff`] | 0 | none | zero: the robot's drives off (its own brakes or fallback) |
//!
//! | cause | category | why |
//! |---|---|---|
//! | a stop request (operator, supervisor, emergency stop, the robot not following) | hold | the sensors are trusted; dropping the arm is the hazard (IEC 80601-2-78: no drop on a single fault) |
//! | speed, force rate, workspace box, joint limits, model mismatch | hold | the measurement is trusted and the violation is the motion's: stopping it where the arm is ends it; a force-rate trip is a transient within the force limit |
//! | estimation failed, model rejected, path buffer full, plan failed | hold | a decision of the kernel's software with trusted sensors |
//! | non-finite sensor, clock fault, sensor time reversed, stale sensor | ramp_down | the kernel can no longer see the arm: it neither holds a force it cannot watch nor drops it, it lowers the arm's support over a bounded time |
//! | force or torque beyond its limit, grasp or elbow below the table | ramp_down | holding is itself the hazard: x − f_ext/K would keep pressing with the force that tripped; the robot's force is released in bounded time, the arm comes to rest on its support |
//! | non-finite command | motors_off | the command path itself failed: no set-point it computes can be trusted, so none is sent |
//!
//! The move of the set-point ([`StopMotion`]) is a quintic per axis from
//! the set-point commanded at the stop (pose, velocity, acceleration) to
//! rest at the goal: position, velocity and acceleration are continuous
//! across the stop, the jerk bounded by each axis's duration, which is at
//! least [`HOLD_MIN_TIME`] and long enough for the lift's settling speeds
//! (`LiftShaping::hold_speed`, `hold_rate`). A hold's goal is where the
//! arm is, not where the set-point was going: the running mean of
//! x − f_ext/K over 50 ms, moved on by the arm's velocity over that time
//! constant (`Kernel`), so an arm moving down is stopped where it is.
//!
//! # Requirements
//! REQ-STOP-001 (each cause its category), REQ-STOP-002 (commands
//! continuous across the stop), REQ-STOP-003 (latched stop, still arm for
//! the reset, resume from where the arm is held).

use crate::estimation::EstimateError;
use crate::geometry::{Pose, PoseRate, Wrench};
use crate::monitor::Limit;
use crate::monitor::Violation;
use crate::motion::PlanError;
use crate::motion::{SetPoint, MINIMUM_JERK_PEAK_RATE};
use crate::validate::Rejection;

/// What a stop does to the arm. Codes and names are stable (logs, wire
/// protocols, `limb run --stop-at`'s JSON).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[repr(u8)]
pub enum StopCategory {
    /// Controlled stop, arm held (IEC 60204-1 category 2): the set-point
    /// comes to rest where it carries the arm's weight, x − f_ext/K.
    Hold = 1,
    /// Controlled stop, support released (category 1): the robot's force
    /// ramps to zero over [`RAMP_DOWN_TIME`].
    RampDown = 2,
    /// Uncontrolled stop (category 0): no set-point, no wrench, the
    /// robot's drives off.
    MotorsOff = 3,
}

impl StopCategory {
    /// Every category, by code.
    pub const ALL: [StopCategory; 3] = [
        StopCategory::Hold,
        StopCategory::RampDown,
        StopCategory::MotorsOff,
    ];

    /// Stable numeric code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// True when the robot keeps carrying the arm's weight.
    pub const fn holds(self) -> bool {
        matches!(self, StopCategory::Hold)
    }
}

/// Shortest move of a hold stop's set-point, per axis [s]: short, so that
/// an arm moving down at the manipulation's 5 cm/s is stopped within
/// ≈ 1 mm of set-point overshoot (0.19 v₀ T), long enough that a 3 mm
/// move accelerates the set-point at most 1.7 m/s² (3.5 N of the
/// impedance's inertia feed-forward). Longer moves are paced by the
/// lift's settling speeds.
pub const HOLD_MIN_TIME: f64 = 0.3;

/// Shortest move of a hold stop's set-point from the lift, per axis [s]:
/// the lift's set-point leads the arm and carries it; slowed down along
/// its line over 0.3 s it keeps carrying the arm up to its rest (a 0.1 s
/// stop let the arm fall back 4 mm from its momentum on the six arms).
pub const LIFT_HOLD_MIN_TIME: f64 = 0.5;

/// Duration of a ramp-down stop [s]: the arm's support falls to zero over
/// 1 s (the ≈ 0.5 s settling of plant.md's overdamped impedance, twice),
/// not in one control period.
pub const RAMP_DOWN_TIME: f64 = 1.0;

/// Fastest grasp-point speed at which a reset is accepted [m/s]: the arm
/// is still. 20 mm/s is seven times the speed noise of the rate window
/// (0.1 mm position noise over 50 ms: 2.8 mm/s).
pub const RESET_MAX_SPEED: f64 = 0.02;

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

impl StopReason {
    /// The stop category of this cause (the table of the module docs).
    pub const fn category(&self) -> StopCategory {
        match self {
            StopReason::Operator
            | StopReason::EstimationFailed(_)
            | StopReason::ModelRejected(_)
            | StopReason::PathBufferFull
            | StopReason::PlanFailed(_) => StopCategory::Hold,
            StopReason::NonFiniteCommand => StopCategory::MotorsOff,
            StopReason::Monitor(violation) => match violation.limit {
                Limit::NonFiniteSensor
                | Limit::ClockFault
                | Limit::SensorTimeReversed
                | Limit::StaleSensor
                | Limit::ForceMagnitude
                | Limit::Torque
                | Limit::GraspBelowTable
                | Limit::ElbowBelowTable => StopCategory::RampDown,
                Limit::ForceRate
                | Limit::Speed
                | Limit::WorkspaceX
                | Limit::WorkspaceZ
                | Limit::ShoulderElevation
                | Limit::ElbowFlexion
                | Limit::ModelMismatch => StopCategory::Hold,
            },
        }
    }
}

/// The set-point's move at a stop: a quintic per axis from the set-point
/// commanded at the stop to rest at `goal`, each axis in its own time.
///
/// # Invariants
/// Every coefficient finite, every duration finite and positive, the
/// longest `duration` (checked by [`StopMotion::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopMotion {
    started_at: f64,
    duration: f64,
    goal: Pose,
    /// Per axis (x, z, psi): its duration and c0..c5 of p(t) = Σ c_k t^k.
    axes: [(f64, [f64; 6]); 3],
}

impl StopMotion {
    /// The move from `from` at kernel time `now` to rest at `target`. Each
    /// axis takes at least `min_time`, long enough for a minimum-jerk move
    /// of its length at `peak_speed` [m/s] (x, z) or `peak_rate` [rad/s]
    /// (psi), and 2 s per m/s (rad/s over `peak_rate`) of its velocity at
    /// the stop (a deceleration of at most ≈ 1 m/s²). `None` when
    /// anything is not finite (the stop then holds without a move).
    pub fn new(
        from: &SetPoint,
        target: Pose,
        now: f64,
        min_time: f64,
        peak_speed: f64,
        peak_rate: f64,
        coast: bool,
    ) -> Option<Self> {
        let p0 = from.pose;
        let v0 = from.velocity;
        let a0 = from.acceleration;
        let axis = |p0: f64, v0: f64, a0: f64, p1: f64, peak: f64, brake: f64| {
            let t = min_time
                .max(MINIMUM_JERK_PEAK_RATE * libm::fabs(p1 - p0) / peak)
                .max(brake * libm::fabs(v0));
            let goal = if coast { p1 + v0 * t / 2.0 } else { p1 };
            let h = goal - p0;
            let coefficients = [
                p0,
                v0,
                a0 / 2.0,
                (20.0 * h - 12.0 * v0 * t - 3.0 * a0 * t * t) / (2.0 * t * t * t),
                (-30.0 * h + 16.0 * v0 * t + 3.0 * a0 * t * t) / (2.0 * t * t * t * t),
                (12.0 * h - 6.0 * v0 * t - a0 * t * t) / (2.0 * t * t * t * t * t),
            ];
            (t, goal, coefficients)
        };
        let rate_brake = 2.0 * peak_speed / peak_rate;
        let axes = [
            axis(p0.x, v0.x, a0.x, target.x, peak_speed, 2.0),
            axis(p0.z, v0.z, a0.z, target.z, peak_speed, 2.0),
            axis(p0.psi, v0.psi, a0.psi, target.psi, peak_rate, rate_brake),
        ];
        let duration = axes[0].0.max(axes[1].0).max(axes[2].0);
        let motion = Self {
            started_at: now,
            duration,
            goal: Pose::new(axes[0].1, axes[1].1, axes[2].1),
            axes: axes.map(|(t, _, c)| (t, c)),
        };
        let finite = now.is_finite()
            && motion.goal.is_finite()
            && motion
                .axes
                .iter()
                .all(|(t, c)| t.is_finite() && *t > 0.0 && c.iter().all(|c| c.is_finite()));
        finite.then_some(motion)
    }

    /// Kernel time the move began [s].
    pub fn started_at(&self) -> f64 {
        self.started_at
    }

    /// Duration of the move, its slowest axis [s].
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The pose the set-point comes to rest at.
    pub fn goal(&self) -> Pose {
        self.goal
    }

    /// Fraction of the move done at `now`, in [0, 1] (1 for a NaN time:
    /// the goal held).
    pub fn progress(&self, now: f64) -> f64 {
        let elapsed = now - self.started_at;
        if elapsed.is_nan() || elapsed >= self.duration {
            1.0
        } else if elapsed <= 0.0 {
            0.0
        } else {
            elapsed / self.duration
        }
    }

    /// True once the set-point is at rest at its goal.
    pub fn is_complete(&self, now: f64) -> bool {
        self.progress(now) >= 1.0
    }

    /// The set-point at kernel time `now`: the start before the move (a
    /// clock that went back), each axis at its goal after its own time,
    /// the goal held after the move or for a NaN time.
    pub fn at(&self, now: f64) -> SetPoint {
        if self.progress(now) >= 1.0 {
            return SetPoint::hold(self.goal);
        }
        let elapsed = self.progress(now) * self.duration;
        let goal = [self.goal.x, self.goal.z, self.goal.psi];
        let mut p = [0.0; 3];
        let mut v = [0.0; 3];
        let mut a = [0.0; 3];
        for (axis, (duration, c)) in self.axes.iter().enumerate() {
            if elapsed >= *duration {
                p[axis] = goal[axis];
                continue;
            }
            let t = elapsed;
            p[axis] = c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))));
            v[axis] =
                c[1] + t * (2.0 * c[2] + t * (3.0 * c[3] + t * (4.0 * c[4] + t * 5.0 * c[5])));
            a[axis] = 2.0 * c[2] + t * (6.0 * c[3] + t * (12.0 * c[4] + t * 20.0 * c[5]));
        }
        SetPoint {
            pose: Pose::new(p[0], p[1], p[2]),
            velocity: PoseRate::new(v[0], v[1], v[2]),
            acceleration: PoseRate::new(a[0], a[1], a[2]),
        }
    }

    /// The minimum-jerk fraction s(τ) of the move at `now` (0 → 1, zero
    /// slope at both ends): the ramp of a ramp-down stop's wrench.
    pub fn ramp(&self, now: f64) -> f64 {
        let tau = self.progress(now);
        tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)
    }
}

/// `wrench` scaled by `1 − ramp` (ramp in [0, 1]).
pub fn ramped(wrench: Wrench, ramp: f64) -> Wrench {
    let keep = (1.0 - ramp).clamp(0.0, 1.0);
    if ramp >= 1.0 {
        return Wrench::ZERO;
    }
    Wrench::new(wrench.fx * keep, wrench.fz * keep, wrench.ty * keep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::monitor::Violation;

    fn moving() -> SetPoint {
        SetPoint {
            pose: Pose::new(0.1, 0.2, 0.3),
            velocity: PoseRate::new(0.05, -0.03, 0.2),
            acceleration: PoseRate::new(0.1, 0.2, -0.3),
        }
    }

    /// REQ-STOP-001: each cause has the category of the table in the module
    /// docs (and of spec/hazards.md); changing one fails here.
    #[test]
    fn req_stop_001_each_cause_has_its_category() {
        use StopCategory::{Hold, MotorsOff, RampDown};
        let monitor = |limit| StopReason::Monitor(Violation::new(limit, 1.0, 0.0));
        let table = [
            (StopReason::Operator, Hold),
            (StopReason::PathBufferFull, Hold),
            (
                StopReason::PlanFailed(crate::motion::PlanError::NonFinite),
                Hold,
            ),
            (
                StopReason::EstimationFailed(
                    crate::estimation::EstimateError::UpperArmPhaseTooShort,
                ),
                Hold,
            ),
            (StopReason::NonFiniteCommand, MotorsOff),
            (monitor(Limit::NonFiniteSensor), RampDown),
            (monitor(Limit::ClockFault), RampDown),
            (monitor(Limit::SensorTimeReversed), RampDown),
            (monitor(Limit::StaleSensor), RampDown),
            (monitor(Limit::ForceMagnitude), RampDown),
            (monitor(Limit::Torque), RampDown),
            (monitor(Limit::GraspBelowTable), RampDown),
            (monitor(Limit::ElbowBelowTable), RampDown),
            (monitor(Limit::ForceRate), Hold),
            (monitor(Limit::Speed), Hold),
            (monitor(Limit::WorkspaceX), Hold),
            (monitor(Limit::WorkspaceZ), Hold),
            (monitor(Limit::ShoulderElevation), Hold),
            (monitor(Limit::ElbowFlexion), Hold),
            (monitor(Limit::ModelMismatch), Hold),
        ];
        for (reason, category) in table {
            assert_eq!(reason.category(), category, "{reason:?}");
        }
    }

    /// REQ-STOP-002: the move starts exactly at the set-point commanded at
    /// the stop (pose, velocity, acceleration) and ends at rest at its goal.
    #[test]
    fn req_stop_002_the_move_is_continuous_at_both_ends() {
        let from = moving();
        let target = Pose::new(0.12, 0.19, 0.4);
        let motion = StopMotion::new(&from, target, 2.0, HOLD_MIN_TIME, 0.1, 0.5, true).unwrap();
        let start = motion.at(2.0);
        for (got, want) in [
            (start.pose.x, from.pose.x),
            (start.pose.psi, from.pose.psi),
            (start.velocity.x, from.velocity.x),
            (start.velocity.z, from.velocity.z),
            (start.acceleration.psi, from.acceleration.psi),
        ] {
            assert!((got - want).abs() < 1e-12, "{got} != {want}");
        }
        let end = motion.at(2.0 + motion.duration() - 1e-9);
        assert!((end.pose.x - motion.goal().x).abs() < 1e-9);
        assert!(end.velocity.linear_speed() < 1e-6);
        assert_eq!(motion.at(1e9), SetPoint::hold(motion.goal()));
        assert_eq!(motion.at(f64::NAN), SetPoint::hold(motion.goal()));
        assert!(motion.duration() >= HOLD_MIN_TIME);
        assert!(StopMotion::new(
            &from,
            Pose::new(f64::NAN, 0.0, 0.0),
            2.0,
            0.3,
            0.1,
            0.5,
            true
        )
        .is_none());
        assert!(StopMotion::new(&from, target, f64::INFINITY, 0.3, 0.1, 0.5, true).is_none());
    }

    /// The ramp of a ramp-down stop falls from the whole wrench to zero.
    #[test]
    fn the_ramp_goes_from_the_wrench_to_zero() {
        let motion = StopMotion::new(
            &SetPoint::hold(Pose::default()),
            Pose::default(),
            0.0,
            RAMP_DOWN_TIME,
            0.1,
            0.5,
            false,
        )
        .unwrap();
        let w = Wrench::new(10.0, -20.0, 1.0);
        assert_eq!(ramped(w, motion.ramp(0.0)), w);
        assert_eq!(ramped(w, motion.ramp(RAMP_DOWN_TIME)), Wrench::ZERO);
        let half = ramped(w, motion.ramp(RAMP_DOWN_TIME / 2.0));
        assert!((half.fz + 10.0).abs() < 1e-9, "{half:?}");
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            /// REQ-STOP-002: for any finite set-point at the stop and any
            /// goal within 5 cm, the move is finite, starts at that
            /// set-point and changes by at most what its bounded velocity
            /// allows in one 1 ms period: no step a robot would refuse.
            #[test]
            fn req_stop_002_stop_moves_have_no_step(
                x in -0.3..0.3f64, z in -0.1..0.5f64, psi in -0.5..2.0f64,
                vx in -0.15..0.15f64, vz in -0.15..0.15f64, vpsi in -0.5..0.5f64,
                ax in -1.0..1.0f64, az in -1.0..1.0f64,
                dx in -0.05..0.05f64, dz in -0.05..0.05f64, dpsi in -0.5..0.5f64,
            ) {
                let from = SetPoint {
                    pose: Pose::new(x, z, psi),
                    velocity: PoseRate::new(vx, vz, vpsi),
                    acceleration: PoseRate::new(ax, az, 0.0),
                };
                let target = Pose::new(x + dx, z + dz, psi + dpsi);
                let motion = StopMotion::new(&from, target, 1.0, HOLD_MIN_TIME, 0.1, 0.5, true).unwrap();
                let mut last = motion.at(1.0);
                prop_assert_eq!(last.pose, from.pose);
                let steps = (motion.duration() / 1e-3) as usize + 2;
                for k in 1..=steps {
                    let s = motion.at(1.0 + k as f64 * 1e-3);
                    prop_assert!(s.pose.is_finite() && s.velocity.is_finite());
                    // |Δp| ≤ max speed · dt: the quintic's speed stays below
                    // 3 × (|v0| + 1.875 d / T + |a0| T) (a loose bound that a
                    // step from the old pose to the goal would break).
                    let bound = 3.0 * (0.15 + 0.1 + 1.0 * 0.1) * 1e-3 + 1e-9;
                    prop_assert!((s.pose.x - last.pose.x).abs() <= bound);
                    prop_assert!((s.pose.z - last.pose.z).abs() <= bound);
                    last = s;
                }
                prop_assert_eq!(last, SetPoint::hold(motion.goal()));
            }
        }
    }
}
