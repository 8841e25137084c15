//! Kernel configuration: gains and limits, as one plain struct with
//! validation. All values SI, frame S.
//!
//! # Invariants
//! [`crate::Kernel::new`] accepts only a configuration for which
//! [`KernelConfig::check`] returns `Ok`: every number finite, every limit
//! positive, every interval non-empty, the planned speeds within the speed
//! limit.

mod error;
mod lift_shaping;
mod validation;

use error::{all_positive, finite, non_negative, positive};
pub use error::{ConfigError, ConfigField, ConfigProblem};
pub use lift_shaping::LiftShaping;
pub use validation::ValidationLimits;

use crate::motion::EstimationMotionParameters;

/// A closed interval [low, high].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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

    /// `Ok` when both bounds are finite and `low <= high`; else the
    /// problem, named as `field`.
    fn check(&self, field: ConfigField) -> Result<(), ConfigError> {
        finite(field, self.low)?;
        finite(field, self.high)?;
        if self.low <= self.high {
            Ok(())
        } else {
            Err(ConfigError::new(field, ConfigProblem::EmptyInterval))
        }
    }
}

/// Cartesian impedance of the command generator (paper eq. 9-12), per axis
/// (x [N/m], z [N/m], psi [N m/rad]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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

impl SafetyLimits {
    /// The widest limits any configuration may set, whoever signs it
    /// (REQ-CFG-001): a limit update can tighten a monitor or loosen it up
    /// to here, never switch it off by a huge value. Design values for a
    /// robot moving a passive adult arm:
    /// - `max_force` 140 N: the lowest quasi-static contact force ISO/TS
    ///   15066 (Table A.2) permits on the hand and forearm regions;
    /// - `max_torque` 20 N m about the wrist, 2.5 × the default;
    /// - `max_force_rate` 2 000 N/s, 8 × the default;
    /// - `max_speed` 0.25 m/s, the reduced speed of ISO 10218-1;
    /// - `rate_window` 0.5 s, `max_model_mismatch` 0.10 m,
    ///   `table_tolerance` 0.02 m, `max_sensor_age` 0.1 s (100 periods of
    ///   the 1 kHz loop);
    /// - joint ranges within shoulder elevation [−0.5, 2.8] rad (−29°,
    ///   160°) and elbow flexion [−0.6, 2.8] rad (34° of hyperextension,
    ///   160° of flexion): beyond any person's passive range, and wide
    ///   enough to replay the recorded open-loop plant.md lifts (26.7° of
    ///   hyperextension, 34° in the provisional model's worst case,
    ///   `kernel/tests/replay.rs`); a clinician's limits are far narrower
    ///   (default 5°);
    /// - the workspace box within ±1.5 m of the base (the arm reaches
    ///   under 0.7 m).
    pub const CEILING: SafetyLimits = SafetyLimits {
        max_force: 140.0,
        max_torque: 20.0,
        max_force_rate: 2000.0,
        max_speed: 0.25,
        rate_window: 0.5,
        shoulder_elevation: Interval::new(-0.5, 2.8),
        elbow_flexion: Interval::new(-0.6, 2.8),
        max_model_mismatch: 0.10,
        table_tolerance: 0.02,
        workspace_x: Interval::new(-1.5, 1.5),
        workspace_z: Interval::new(-1.5, 1.5),
        max_sensor_age: 0.1,
    };

    /// Checks every limit: finite, positive (the table tolerance: not
    /// negative), intervals not empty, and nothing beyond
    /// [`SafetyLimits::CEILING`].
    ///
    /// # Errors
    /// The first unusable field and what is wrong with it.
    pub fn check(&self) -> Result<(), ConfigError> {
        use ConfigField as F;
        let c = &Self::CEILING;
        let scalars = [
            (F::MaxForce, self.max_force, c.max_force),
            (F::MaxTorque, self.max_torque, c.max_torque),
            (F::MaxForceRate, self.max_force_rate, c.max_force_rate),
            (F::MaxSpeed, self.max_speed, c.max_speed),
            (F::RateWindow, self.rate_window, c.rate_window),
            (
                F::MaxModelMismatch,
                self.max_model_mismatch,
                c.max_model_mismatch,
            ),
            (F::MaxSensorAge, self.max_sensor_age, c.max_sensor_age),
            (F::TableTolerance, self.table_tolerance, c.table_tolerance),
        ];
        for (field, value, ceiling) in scalars {
            if field == F::TableTolerance {
                non_negative(field, value)?;
            } else {
                positive(field, value)?;
            }
            if value > ceiling {
                return Err(ConfigError::new(field, ConfigProblem::BeyondCeiling));
            }
        }
        let ranges = [
            (
                F::ShoulderElevation,
                self.shoulder_elevation,
                c.shoulder_elevation,
            ),
            (F::ElbowFlexion, self.elbow_flexion, c.elbow_flexion),
            (F::WorkspaceX, self.workspace_x, c.workspace_x),
            (F::WorkspaceZ, self.workspace_z, c.workspace_z),
        ];
        for (field, range, widest) in ranges {
            range.check(field)?;
            if range.low < widest.low || range.high > widest.high {
                return Err(ConfigError::new(field, ConfigProblem::BeyondCeiling));
            }
        }
        Ok(())
    }

    /// How many numbers the limits hold: 8 scalars and 4 intervals of two.
    pub const NUMBERS: usize = 16;

    /// The `index`-th number of the limits (`index` < [`Self::NUMBERS`],
    /// in [`ConfigField`] code order, an interval's low end before its
    /// high end) with the field [`Self::check`] names for it; `None`
    /// beyond. One list, so a fuzzer or a test that changes "any limit"
    /// reaches every one (`fuzz/src/session.rs` missed `workspace_z.low`
    /// until issue 38).
    pub fn number_mut(&mut self, index: usize) -> Option<(ConfigField, &mut f64)> {
        use ConfigField as F;
        Some(match index {
            0 => (F::MaxForce, &mut self.max_force),
            1 => (F::MaxTorque, &mut self.max_torque),
            2 => (F::MaxForceRate, &mut self.max_force_rate),
            3 => (F::MaxSpeed, &mut self.max_speed),
            4 => (F::RateWindow, &mut self.rate_window),
            5 => (F::MaxModelMismatch, &mut self.max_model_mismatch),
            6 => (F::MaxSensorAge, &mut self.max_sensor_age),
            7 => (F::TableTolerance, &mut self.table_tolerance),
            8 => (F::ShoulderElevation, &mut self.shoulder_elevation.low),
            9 => (F::ShoulderElevation, &mut self.shoulder_elevation.high),
            10 => (F::ElbowFlexion, &mut self.elbow_flexion.low),
            11 => (F::ElbowFlexion, &mut self.elbow_flexion.high),
            12 => (F::WorkspaceX, &mut self.workspace_x.low),
            13 => (F::WorkspaceX, &mut self.workspace_x.high),
            14 => (F::WorkspaceZ, &mut self.workspace_z.low),
            15 => (F::WorkspaceZ, &mut self.workspace_z.high),
            _ => return None,
        })
    }
}

/// The whole kernel configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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

impl KernelConfig {
    /// Checks every value, group by group in the order of the fields.
    ///
    /// # Errors
    /// The first unusable field and what is wrong with it.
    pub fn check(&self) -> Result<(), ConfigError> {
        use ConfigField as F;
        let g = &self.impedance;
        for v in g.stiffness {
            positive(F::ImpedanceStiffness, v)?;
        }
        for v in g.inertia {
            positive(F::ImpedanceInertia, v)?;
        }
        positive(F::ImpedanceDampingRatio, g.damping_ratio)?;
        let l = &self.limits;
        l.check()?;
        let m = &self.estimation_motion;
        positive(F::LiftLength, m.lift_length)?;
        finite(F::LiftAngle, m.lift_angle)?;
        non_negative(F::HoldTime, m.hold_time)?;
        for (field, speed) in [
            (F::EstimationPeakSpeed, m.peak_speed),
            (F::ManipulationPeakSpeed, self.manipulation_peak_speed),
        ] {
            positive(field, speed)?;
            if speed > l.max_speed {
                return Err(ConfigError::new(field, ConfigProblem::AboveSpeedLimit));
            }
        }
        self.lift_shaping.check()?;
        let v = &self.validation;
        all_positive(&[
            (F::MinUpperArmLength, v.min_upper_arm_length),
            (F::MaxUpperArmLength, v.max_upper_arm_length),
            (F::MinForearmLength, v.min_forearm_length),
            (F::MaxForearmLength, v.max_forearm_length),
            (F::MinArc, v.min_arc),
            (F::MaxResidual, v.max_residual),
            (F::MaxMethodDisagreement, v.max_method_disagreement),
            (F::MaxGeometryMismatch, v.max_geometry_mismatch),
            (F::MaxShoulderHeight, v.max_shoulder_height),
            (F::MaxResidualBias, v.max_residual_bias),
            (F::MaxRhythmCorrection, v.max_rhythm_correction),
        ])?;
        for component in v.shoulder_rhythm {
            finite(F::ShoulderRhythm, component)?;
            if libm::fabs(component) > ValidationLimits::MAX_SHOULDER_RHYTHM {
                return Err(ConfigError::new(
                    F::ShoulderRhythm,
                    ConfigProblem::BeyondCeiling,
                ));
            }
        }
        for (field, min, max) in [
            (
                F::MaxUpperArmLength,
                v.min_upper_arm_length,
                v.max_upper_arm_length,
            ),
            (
                F::MaxForearmLength,
                v.min_forearm_length,
                v.max_forearm_length,
            ),
        ] {
            if min > max {
                return Err(ConfigError::new(field, ConfigProblem::BelowMinimum));
            }
        }
        Ok(())
    }
}

/// Proof of REQ-CFG-001: no accepted limits lie beyond the ceilings.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-CFG-001: what an accepted set of limits must satisfy: every
    /// scalar positive (the table tolerance not negative) and at most its
    /// ceiling, every range non-empty and inside the widest range.
    pub(super) fn check_within_ceilings(l: &SafetyLimits) -> Result<(), &'static str> {
        let c = &SafetyLimits::CEILING;
        let scalars = [
            (l.max_force, c.max_force),
            (l.max_torque, c.max_torque),
            (l.max_force_rate, c.max_force_rate),
            (l.max_speed, c.max_speed),
            (l.rate_window, c.rate_window),
            (l.max_model_mismatch, c.max_model_mismatch),
            (l.max_sensor_age, c.max_sensor_age),
        ];
        if !scalars.iter().all(|&(v, top)| 0.0 < v && v <= top) {
            return Err("a scalar limit not in (0, ceiling]");
        }
        if !(0.0 <= l.table_tolerance && l.table_tolerance <= c.table_tolerance) {
            return Err("table tolerance not in [0, ceiling]");
        }
        let ranges = [
            (l.shoulder_elevation, c.shoulder_elevation),
            (l.elbow_flexion, c.elbow_flexion),
            (l.workspace_x, c.workspace_x),
            (l.workspace_z, c.workspace_z),
        ];
        if !ranges
            .iter()
            .all(|(r, w)| w.low <= r.low && r.low <= r.high && r.high <= w.high)
        {
            return Err("a range empty or beyond its widest");
        }
        Ok(())
    }

    /// REQ-CFG-001: any force, speed and sensor-age limit and any elbow
    /// range (the other fields go through the same two loops) are accepted
    /// only within the ceilings; the ceilings themselves are accepted. No
    /// loop depends on the inputs: the loops run over fixed arrays of 8
    /// scalars and 4 ranges (unwind 9).
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(9))]
    pub(super) fn verify_req_cfg_001_no_limits_beyond_the_ceilings() {
        let mut limits = if kani::any() {
            SafetyLimits::CEILING
        } else {
            SafetyLimits::default()
        };
        if kani::any() {
            limits.max_force = kani::any();
            limits.max_speed = kani::any();
            limits.max_sensor_age = kani::any();
            limits.elbow_flexion = Interval::new(kani::any(), kani::any());
        }
        let verdict = limits.check();
        if verdict.is_ok() {
            assert_eq!(check_within_ceilings(&limits), Ok(()));
        }
        if limits == SafetyLimits::CEILING {
            assert_eq!(verdict, Ok(()));
        }
        kani::cover!(verdict.is_ok(), "limits: accepted");
        kani::cover!(
            verdict.is_err_and(|e| e.problem == ConfigProblem::BeyondCeiling),
            "limits: beyond a ceiling"
        );
        kani::cover!(
            verdict.is_err_and(|e| e.problem == ConfigProblem::NonFinite),
            "limits: not finite"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "limit ceilings",
                20_000,
                verify_req_cfg_001_no_limits_beyond_the_ceilings,
            );
        }

        proptest! {
            /// REQ-CFG-001: limits drawn across and beyond the ceilings are
            /// accepted exactly when they lie within them.
            #[test]
            fn req_cfg_001_limits_are_accepted_exactly_within_the_ceilings(
                force in -10.0..300.0f64, speed in -0.1..0.5f64,
                age in -0.05..0.2f64, low in -1.0..0.5f64, high in -0.5..3.5f64,
                tolerance in -0.01..0.05f64,
            ) {
                let limits = SafetyLimits {
                    max_force: force,
                    max_speed: speed,
                    max_sensor_age: age,
                    elbow_flexion: Interval::new(low, high),
                    table_tolerance: tolerance,
                    ..SafetyLimits::default()
                };
                prop_assert_eq!(
                    limits.check().is_ok(),
                    check_within_ceilings(&limits).is_ok()
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    /// Every number of the limits is listed once, under the field `check`
    /// names when that number alone is NaN: 16 distinct numbers, and the
    /// limits are 16 numbers in all.
    #[test]
    fn every_limit_number_is_listed_once_under_its_checked_field() {
        let mut addresses = [0usize; SafetyLimits::NUMBERS];
        for (index, address) in addresses.iter_mut().enumerate() {
            let mut limits = SafetyLimits::default();
            let (field, number) = limits.number_mut(index).expect("listed");
            *number = f64::NAN;
            assert_eq!(limits.check().map_err(|e| e.field), Err(field), "{index}");
            let mut fresh = SafetyLimits::default();
            let base = &fresh as *const SafetyLimits as usize;
            *address = fresh
                .number_mut(index)
                .map_or(0, |(_, n)| n as *const f64 as usize - base);
        }
        addresses.sort_unstable();
        assert!(addresses.windows(2).all(|w| w[0] < w[1]), "{addresses:?}");
        assert!(SafetyLimits::default()
            .number_mut(SafetyLimits::NUMBERS)
            .is_none());
        assert_eq!(
            core::mem::size_of::<SafetyLimits>(),
            SafetyLimits::NUMBERS * core::mem::size_of::<f64>()
        );
    }

    use super::*;

    #[test]
    fn default_is_valid() {
        assert_eq!(KernelConfig::default().check(), Ok(()));
    }

    /// A range of one value (a known arm) is a range: min = max is valid.
    #[allow(clippy::field_reassign_with_default)]
    #[test]
    fn a_length_range_of_one_value_is_valid() {
        let mut config = KernelConfig::default();
        config.validation.max_upper_arm_length = config.validation.min_upper_arm_length;
        config.validation.min_forearm_length = config.validation.max_forearm_length;
        assert_eq!(config.check(), Ok(()));
        config.validation.max_upper_arm_length *= 0.999;
        assert_eq!(
            config.check(),
            Err(ConfigError::new(
                ConfigField::MaxUpperArmLength,
                ConfigProblem::BelowMinimum
            ))
        );
    }

    // Each case changes one field of the default on purpose.
    #[allow(clippy::field_reassign_with_default)]
    #[test]
    fn the_first_unusable_field_is_named() {
        use ConfigField as F;
        use ConfigProblem as P;
        type Case = (fn(&mut KernelConfig), ConfigField, ConfigProblem);
        let cases: [Case; 12] = [
            (
                |c| c.limits.max_force = 4.1e224,
                F::MaxForce,
                P::BeyondCeiling,
            ),
            (
                |c| c.limits.elbow_flexion.low = -0.7,
                F::ElbowFlexion,
                P::BeyondCeiling,
            ),
            (
                |c| c.impedance.stiffness[2] = f64::NAN,
                F::ImpedanceStiffness,
                P::NonFinite,
            ),
            (
                |c| c.impedance.damping_ratio = 0.0,
                F::ImpedanceDampingRatio,
                P::NotPositive,
            ),
            (|c| c.limits.max_force = 0.0, F::MaxForce, P::NotPositive),
            (
                |c| c.limits.table_tolerance = -1e-3,
                F::TableTolerance,
                P::Negative,
            ),
            (
                |c| c.limits.elbow_flexion = Interval::new(1.0, 0.0),
                F::ElbowFlexion,
                P::EmptyInterval,
            ),
            (
                |c| c.limits.workspace_z.high = f64::INFINITY,
                F::WorkspaceZ,
                P::NonFinite,
            ),
            (
                |c| c.estimation_motion.lift_length = -1.0,
                F::LiftLength,
                P::NotPositive,
            ),
            (
                |c| c.manipulation_peak_speed = 1.0,
                F::ManipulationPeakSpeed,
                P::AboveSpeedLimit,
            ),
            (
                |c| c.lift_shaping.extension = 0.0,
                F::Extension,
                P::NotPositive,
            ),
            (
                |c| c.validation.min_forearm_length = 0.5,
                F::MaxForearmLength,
                P::BelowMinimum,
            ),
        ];
        for (change, field, problem) in cases {
            let mut c = KernelConfig::default();
            change(&mut c);
            assert_eq!(c.check(), Err(ConfigError::new(field, problem)));
        }
        let mut c = KernelConfig::default();
        c.validation.max_residual = f64::INFINITY;
        let error = c.check().unwrap_err();
        assert_eq!(error.code(), 606);
        let mut text = heapless::String::<64>::new();
        core::fmt::Write::write_fmt(&mut text, format_args!("{error}")).unwrap();
        assert_eq!(text.as_str(), "validation.max_residual: non_finite");
    }
}
