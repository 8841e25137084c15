//! Kernel configuration: gains and limits, as one plain struct with
//! validation. All values SI, frame S.
//!
//! # Invariants
//! [`crate::Kernel::new`] accepts only a configuration for which
//! [`KernelConfig::check`] returns `Ok`: every number finite, every limit
//! positive, every interval non-empty, the planned speeds within the speed
//! limit.

use crate::lift::LiftShaping;
use crate::motion::EstimationMotionParameters;
use crate::validate::ValidationLimits;

/// A closed interval [low, high].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Interval {
    /// Lower bound.
    pub low: f64,
    /// Upper bound.
    pub high: f64,
}

impl Interval {
    /// [low, high].
    pub const fn new(low: f64, high: f64) -> Self {
        Self { low, high }
    }

    /// True when `value` is inside (false for NaN).
    pub fn contains(&self, value: f64) -> bool {
        self.low <= value && value <= self.high
    }

    fn is_valid(&self) -> bool {
        self.low.is_finite() && self.high.is_finite() && self.low <= self.high
    }
}

/// Cartesian impedance of the command generator (paper eq. 9-12), per axis
/// (x [N/m], z [N/m], psi [N m/rad]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ImpedanceGains {
    /// Stiffness K: x, z [N/m], psi [N m/rad].
    pub stiffness: [f64; 3],
    /// Desired inertia Λ: x, z [kg], psi [kg m²]; used for inertia shaping
    /// (feed-forward of the set-point acceleration) and for the damping.
    pub inertia: [f64; 3],
    /// Damping ratio ζ; D_i = 2 ζ sqrt(K_i Λ_i). The paper requires an
    /// overdamped robot (ζ > 1) for safety.
    pub damping_ratio: f64,
}

impl Default for ImpedanceGains {
    /// `plant.md`: K = (200, 200, 10), Λ = (2, 2, 0.05), ζ = 2.
    fn default() -> Self {
        Self {
            stiffness: [200.0, 200.0, 10.0],
            inertia: [2.0, 2.0, 0.05],
            damping_ratio: 2.0,
        }
    }
}

/// Limits the monitors enforce.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SafetyLimits {
    /// Largest interaction force magnitude |(fx, fz)| [N]. Also the
    /// saturation of the commanded wrench. The reference lift peaks near
    /// 33 N (`data/nominal/case1.csv`).
    pub max_force: f64,
    /// Largest interaction torque |ty| [N m]; also the torque saturation.
    /// The reference lift peaks near 5.4 N m, the labelled effect logs at 5.9 N m.
    pub max_torque: f64,
    /// Largest rate of change of the force vector [N/s], over
    /// [`SafetyLimits::rate_window`].
    pub max_force_rate: f64,
    /// Largest grasp-point speed [m/s], over [`SafetyLimits::rate_window`].
    pub max_speed: f64,
    /// Window over which speed and force rate are measured [s]. Longer
    /// windows reject sensor noise (0.1 mm pose noise → ≈ 3 mm/s at 50 ms).
    pub rate_window: f64,
    /// Shoulder elevation q1 range [rad].
    pub shoulder_elevation: Interval,
    /// Elbow flexion q2 range [rad]; below `low` is hyperextension.
    pub elbow_flexion: Interval,
    /// Largest mismatch between the measured pose and the validated model
    /// (| |E − S| − l1 |) [m]: a slipped grasp or moved shoulder.
    pub max_model_mismatch: f64,
    /// How far below the table (z = 0) the grasp point or elbow may be
    /// measured before it counts as striking it [m] (noise allowance).
    pub table_tolerance: f64,
    /// Workspace box for the grasp point, x range [m].
    pub workspace_x: Interval,
    /// Workspace box for the grasp point, z range [m].
    pub workspace_z: Interval,
    /// Oldest acceptable sensor frame, `now − frame.time` [s].
    pub max_sensor_age: f64,
}

impl Default for SafetyLimits {
    fn default() -> Self {
        Self {
            max_force: 45.0,
            max_torque: 8.0,
            max_force_rate: 250.0,
            // Three times the planned peak speed (0.05 m/s, the paper's 2.5 %
            // of the iiwa's maximum): the passive arm swings ahead of the
            // compliant robot when the elbow lifts off; the reference logs
            // peak at 0.095 m/s over 50 ms (data/nominal/case6.csv, t = 18.4 s).
            max_speed: 0.15,
            rate_window: 0.05,
            // Passive ranges of an adult arm in the sagittal plane: shoulder
            // flexion up to ≈ 115° before scapular motion dominates, elbow
            // flexion ≈ 150°, hyperextension 0-10° (AAOS norms). The
            // defaults allow 5° of hyperextension and 2.0 rad (115°) of
            // elevation; the kernel's lift keeps the worst case of its
            // provisional model `lift_shaping.joint_margin` inside them
            // (HAZ-08). A clinician narrows them to the person's range.
            shoulder_elevation: Interval::new(-0.05, 2.0),
            elbow_flexion: Interval::new(-0.0873, 2.60),
            max_model_mismatch: 0.03,
            table_tolerance: 0.005,
            workspace_x: Interval::new(-0.10, 0.90),
            workspace_z: Interval::new(-0.01, 0.90),
            max_sensor_age: 0.02,
        }
    }
}

/// The whole kernel configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct KernelConfig {
    /// Impedance of the command generator.
    pub impedance: ImpedanceGains,
    /// Monitor limits and saturations.
    pub limits: SafetyLimits,
    /// The estimation motion.
    pub estimation_motion: EstimationMotionParameters,
    /// Peak grasp-point speed of manipulation moves [m/s].
    pub manipulation_peak_speed: f64,
    /// How the estimation lift is shaped and ended by the provisional model.
    pub lift_shaping: LiftShaping,
    /// Validator limits.
    pub validation: ValidationLimits,
}

impl Default for KernelConfig {
    fn default() -> Self {
        Self {
            impedance: ImpedanceGains::default(),
            limits: SafetyLimits::default(),
            // plant.md's lift; the kernel ends it early (`lift_shaping`).
            // A longer one (0.35-0.40 m) was tried: short arms then swing
            // past the speed limit as the upper arm rises.
            estimation_motion: EstimationMotionParameters::default(),
            manipulation_peak_speed: 0.05,
            lift_shaping: LiftShaping::default(),
            validation: ValidationLimits::default(),
        }
    }
}

/// Which configuration value is unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ConfigError {
    /// An impedance gain is non-finite or not positive.
    ImpedanceGain,
    /// A force, torque, rate or speed limit is non-finite or not positive.
    Limit,
    /// A range is non-finite or empty.
    Range,
    /// An estimation-motion parameter is non-finite or out of range.
    EstimationMotion,
    /// A planned speed is not positive or exceeds the speed limit.
    PlannedSpeed,
    /// A validation limit is non-finite or inconsistent.
    Validation,
    /// A lift-shaping value is non-finite or not positive.
    LiftShaping,
}

impl ConfigError {
    /// Stable numeric code of the group of values.
    pub const fn code(&self) -> u16 {
        match self {
            ConfigError::ImpedanceGain => 1,
            ConfigError::Limit => 2,
            ConfigError::Range => 3,
            ConfigError::EstimationMotion => 4,
            ConfigError::PlannedSpeed => 5,
            ConfigError::Validation => 6,
            ConfigError::LiftShaping => 7,
        }
    }
}

fn positive(value: f64) -> bool {
    value.is_finite() && value > 0.0
}

impl KernelConfig {
    /// Checks every value.
    ///
    /// # Errors
    /// The first unusable group of values.
    pub fn check(&self) -> Result<(), ConfigError> {
        let g = &self.impedance;
        if !(g
            .stiffness
            .iter()
            .chain(g.inertia.iter())
            .all(|v| positive(*v))
            && positive(g.damping_ratio))
        {
            return Err(ConfigError::ImpedanceGain);
        }
        let l = &self.limits;
        let positives = [
            l.max_force,
            l.max_torque,
            l.max_force_rate,
            l.max_speed,
            l.rate_window,
            l.max_model_mismatch,
            l.max_sensor_age,
        ];
        if !(positives.iter().all(|v| positive(*v))
            && l.table_tolerance.is_finite()
            && l.table_tolerance >= 0.0)
        {
            return Err(ConfigError::Limit);
        }
        let ranges = [
            l.shoulder_elevation,
            l.elbow_flexion,
            l.workspace_x,
            l.workspace_z,
        ];
        if !ranges.iter().all(Interval::is_valid) {
            return Err(ConfigError::Range);
        }
        let m = &self.estimation_motion;
        if !(positive(m.lift_length) && m.lift_angle.is_finite() && m.hold_time.is_finite())
            || m.hold_time < 0.0
        {
            return Err(ConfigError::EstimationMotion);
        }
        for speed in [m.peak_speed, self.manipulation_peak_speed] {
            if !positive(speed) || speed > l.max_speed {
                return Err(ConfigError::PlannedSpeed);
            }
        }
        let v = &self.validation;
        let validation = [
            v.min_upper_arm_length,
            v.max_upper_arm_length,
            v.min_forearm_length,
            v.max_forearm_length,
            v.min_arc,
            v.max_residual,
            v.max_method_disagreement,
            v.max_geometry_mismatch,
            v.max_shoulder_height,
        ];
        if !(validation.iter().all(|x| positive(*x))
            && v.min_upper_arm_length <= v.max_upper_arm_length
            && v.min_forearm_length <= v.max_forearm_length)
        {
            return Err(ConfigError::Validation);
        }
        if !self.lift_shaping.is_valid() {
            return Err(ConfigError::LiftShaping);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid() {
        assert_eq!(KernelConfig::default().check(), Ok(()));
    }

    // Each case changes one field of the default on purpose.
    #[allow(clippy::field_reassign_with_default)]
    #[test]
    fn each_group_is_checked() {
        let mut c = KernelConfig::default();
        c.impedance.stiffness[2] = f64::NAN;
        assert_eq!(c.check(), Err(ConfigError::ImpedanceGain));
        let mut c = KernelConfig::default();
        c.limits.max_force = 0.0;
        assert_eq!(c.check(), Err(ConfigError::Limit));
        let mut c = KernelConfig::default();
        c.limits.elbow_flexion = Interval::new(1.0, 0.0);
        assert_eq!(c.check(), Err(ConfigError::Range));
        let mut c = KernelConfig::default();
        c.estimation_motion.lift_length = -1.0;
        assert_eq!(c.check(), Err(ConfigError::EstimationMotion));
        let mut c = KernelConfig::default();
        c.manipulation_peak_speed = 1.0;
        assert_eq!(c.check(), Err(ConfigError::PlannedSpeed));
        let mut c = KernelConfig::default();
        c.validation.max_residual = f64::INFINITY;
        assert_eq!(c.check(), Err(ConfigError::Validation));
    }
}
