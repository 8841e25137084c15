//! Planned motions of the equilibrium pose x_d(t) (frame S).
//!
//! # Theory of operation
//! Every planned motion is a straight line in (x, z, psi) from a start to a
//! goal with minimum-jerk timing s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, τ = t/T. The
//! duration follows from the peak speed: the peak of ds/dτ is 1.875, so
//! T = 1.875 · |Δ(x, z)| / v_max keeps the grasp point at or below v_max.
//! After T the goal is held.
//!
//! The estimation motion is the paper's eq. 3 (`plant.md`): from the grasp
//! pose x_G to x_R = (x_G + l0 (1 + cos qf), z_G + l0 (1 + sin qf),
//! psi_G + π/2), l0 = 0.30 m, qf = π/4, v_max = 0.05 m/s, then a 2 s hold.

use crate::geometry::{Pose, PoseRate};

/// Peak of the normalised minimum-jerk velocity ds/dτ (at τ = 1/2).
pub const MINIMUM_JERK_PEAK_RATE: f64 = 1.875;

/// Parameters of the estimation motion of `plant.md` (paper eq. 3).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct EstimationMotionParameters {
    /// Lift length l0 [m]; the paper and `plant.md` use 0.30 m.
    pub lift_length: f64,
    /// Lift angle qf [rad]; π/4 in `plant.md`.
    pub lift_angle: f64,
    /// Peak grasp-point speed v_max [m/s]; 0.05 m/s, the paper's 2.5 % of maximum.
    pub peak_speed: f64,
    /// Time the goal is held after the lift [s]; 2 s in `plant.md`.
    pub hold_time: f64,
}

impl Default for EstimationMotionParameters {
    fn default() -> Self {
        Self {
            lift_length: 0.30,
            lift_angle: core::f64::consts::FRAC_PI_4,
            peak_speed: 0.05,
            hold_time: 2.0,
        }
    }
}

/// Equilibrium set-point at one instant: pose, velocity and acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SetPoint {
    /// Virtual equilibrium pose x_d [m, m, rad].
    pub pose: Pose,
    /// Its velocity ẋ_d [m/s, m/s, rad/s].
    pub velocity: PoseRate,
    /// Its acceleration ẍ_d [m/s², m/s², rad/s²].
    pub acceleration: PoseRate,
}

impl SetPoint {
    /// Holding `pose` still.
    pub const fn hold(pose: Pose) -> Self {
        Self {
            pose,
            velocity: PoseRate::ZERO,
            acceleration: PoseRate::ZERO,
        }
    }
}

/// A straight-line minimum-jerk move followed by a hold.
///
/// # Invariants
/// `duration > 0` and finite, start and goal finite (checked by [`Self::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MinimumJerkMove {
    start: Pose,
    goal: Pose,
    duration: f64,
}

/// Why a motion could not be planned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum PlanError {
    /// A pose or parameter was NaN or infinite.
    NonFinite,
    /// The peak speed was not strictly positive.
    NonPositiveSpeed,
}

impl PlanError {
    /// Stable numeric code of the error.
    pub const fn code(&self) -> u16 {
        match self {
            PlanError::NonFinite => 1,
            PlanError::NonPositiveSpeed => 2,
        }
    }
}

impl MinimumJerkMove {
    /// Plans the move from `start` to `goal` with grasp-point peak speed
    /// `peak_speed` [m/s]. A move with no translation takes the minimum
    /// duration of 1 ms.
    pub fn new(start: Pose, goal: Pose, peak_speed: f64) -> Result<Self, PlanError> {
        if !(start.is_finite() && goal.is_finite() && peak_speed.is_finite()) {
            return Err(PlanError::NonFinite);
        }
        if peak_speed <= 0.0 {
            return Err(PlanError::NonPositiveSpeed);
        }
        let distance = start.point().distance(goal.point());
        let duration = (MINIMUM_JERK_PEAK_RATE * distance / peak_speed).max(1e-3);
        if !duration.is_finite() {
            return Err(PlanError::NonFinite);
        }
        Ok(Self {
            start,
            goal,
            duration,
        })
    }

    /// Plans the move from `start` to `goal` with grasp-point peak speed
    /// `peak_speed` [m/s], forearm peak rate `peak_rate` [rad/s] and at least
    /// `min_duration` [s]: the longest of the three needs. The floor bounds
    /// the acceleration of short moves (peak 5.77 d/T²), which the
    /// impedance's inertia feed-forward turns into force.
    ///
    /// # Errors
    /// As [`Self::new`]; a rate that is not strictly positive is
    /// [`PlanError::NonPositiveSpeed`], a non-finite duration
    /// [`PlanError::NonFinite`].
    pub fn bounded(
        start: Pose,
        goal: Pose,
        peak_speed: f64,
        peak_rate: f64,
        min_duration: f64,
    ) -> Result<Self, PlanError> {
        let mut planned = Self::new(start, goal, peak_speed)?;
        if !(peak_rate.is_finite() && min_duration.is_finite()) {
            return Err(PlanError::NonFinite);
        }
        if peak_rate <= 0.0 {
            return Err(PlanError::NonPositiveSpeed);
        }
        let turn = MINIMUM_JERK_PEAK_RATE * libm::fabs(goal.psi - start.psi) / peak_rate;
        planned.duration = planned.duration.max(turn).max(min_duration);
        Ok(planned)
    }

    /// Duration of the moving part T [s].
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Start pose.
    pub fn start(&self) -> Pose {
        self.start
    }

    /// Goal pose.
    pub fn goal(&self) -> Pose {
        self.goal
    }

    /// The set-point `elapsed` seconds after the start. Before the start
    /// (or for a NaN time) it is the start held; after T, the goal held.
    pub fn at(&self, elapsed: f64) -> SetPoint {
        if elapsed.is_nan() || elapsed <= 0.0 {
            return SetPoint::hold(self.start);
        }
        if elapsed >= self.duration {
            return SetPoint::hold(self.goal);
        }
        let tau = elapsed / self.duration;
        let tau2 = tau * tau;
        let tau3 = tau2 * tau;
        let s = tau3 * (10.0 - 15.0 * tau + 6.0 * tau2);
        let ds = 30.0 * tau2 * (1.0 - 2.0 * tau + tau2) / self.duration;
        let dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * tau2) / (self.duration * self.duration);
        let dx = self.goal.x - self.start.x;
        let dz = self.goal.z - self.start.z;
        let dpsi = self.goal.psi - self.start.psi;
        SetPoint {
            pose: Pose::new(
                self.start.x + s * dx,
                self.start.z + s * dz,
                self.start.psi + s * dpsi,
            ),
            velocity: PoseRate::new(ds * dx, ds * dz, ds * dpsi),
            acceleration: PoseRate::new(dds * dx, dds * dz, dds * dpsi),
        }
    }
}

/// The estimation motion: lift from the grasp pose, then hold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimationMotion {
    lift: MinimumJerkMove,
    hold_time: f64,
}

impl EstimationMotion {
    /// Plans the estimation motion from the grasp pose `grasp` (x_G).
    pub fn new(grasp: Pose, parameters: &EstimationMotionParameters) -> Result<Self, PlanError> {
        let p = parameters;
        if !(p.lift_length.is_finite() && p.lift_angle.is_finite() && p.hold_time.is_finite()) {
            return Err(PlanError::NonFinite);
        }
        let goal = Pose::new(
            grasp.x + p.lift_length * (1.0 + libm::cos(p.lift_angle)),
            grasp.z + p.lift_length * (1.0 + libm::sin(p.lift_angle)),
            grasp.psi + core::f64::consts::FRAC_PI_2,
        );
        Ok(Self {
            lift: MinimumJerkMove::new(grasp, goal, p.peak_speed)?,
            hold_time: p.hold_time.max(0.0),
        })
    }

    /// The motion of a `lift` already planned, then a hold of
    /// `hold_time` [s]: the proofs plan their own lift
    /// (`lift::verification::first_lift`).
    #[cfg(any(test, kani))]
    pub(crate) fn of_lift(lift: MinimumJerkMove, hold_time: f64) -> Self {
        Self { lift, hold_time }
    }

    /// The set-point `elapsed` seconds after the motion started.
    pub fn at(&self, elapsed: f64) -> SetPoint {
        self.lift.at(elapsed)
    }

    /// The lift part (start x_G, goal x_R, duration T).
    pub fn lift(&self) -> &MinimumJerkMove {
        &self.lift
    }

    /// Total duration, lift plus hold [s].
    pub fn total_duration(&self) -> f64 {
        self.lift.duration() + self.hold_time
    }

    /// True once the lift and the hold are over.
    pub fn is_finished(&self, elapsed: f64) -> bool {
        elapsed >= self.total_duration()
    }
}
