//! Why a configuration was refused: the field, by its path in
//! [`super::KernelConfig`], and what is wrong with its value.
//!
//! Both carry stable numeric codes (logs, wire protocols; pinned by
//! `kernel/tests/codes.rs`): a field's code is its group × 100 + its place in
//! the group, so a new field takes the next free number of its group.

/// A configuration field, named by its path (`limits.max_force`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u16)]
pub enum ConfigField {
    /// `impedance.stiffness` (any axis).
    ImpedanceStiffness = 101,
    /// `impedance.inertia` (any axis).
    ImpedanceInertia = 102,
    /// `impedance.damping_ratio`.
    ImpedanceDampingRatio = 103,
    /// `limits.max_force`.
    MaxForce = 201,
    /// `limits.max_torque`.
    MaxTorque = 202,
    /// `limits.max_force_rate`.
    MaxForceRate = 203,
    /// `limits.max_speed`.
    MaxSpeed = 204,
    /// `limits.rate_window`.
    RateWindow = 205,
    /// `limits.max_model_mismatch`.
    MaxModelMismatch = 206,
    /// `limits.max_sensor_age`.
    MaxSensorAge = 207,
    /// `limits.table_tolerance`.
    TableTolerance = 208,
    /// `limits.shoulder_elevation`.
    ShoulderElevation = 209,
    /// `limits.elbow_flexion`.
    ElbowFlexion = 210,
    /// `limits.workspace_x`.
    WorkspaceX = 211,
    /// `limits.workspace_z`.
    WorkspaceZ = 212,
    /// `estimation_motion.lift_length`.
    LiftLength = 301,
    /// `estimation_motion.lift_angle`.
    LiftAngle = 302,
    /// `estimation_motion.peak_speed`.
    EstimationPeakSpeed = 303,
    /// `estimation_motion.hold_time`.
    HoldTime = 304,
    /// `manipulation_peak_speed`.
    ManipulationPeakSpeed = 401,
    /// `lift_shaping.prior_reach`.
    PriorReach = 501,
    /// `lift_shaping.forearm_wait`.
    ForearmWait = 502,
    /// `lift_shaping.target_arc`.
    TargetArc = 503,
    /// `lift_shaping.joint_margin`.
    JointMargin = 504,
    /// `lift_shaping.settle_time`.
    SettleTime = 505,
    /// `lift_shaping.hold_speed`.
    HoldSpeed = 506,
    /// `lift_shaping.hold_rate`.
    HoldRate = 507,
    /// `lift_shaping.hold_move_time`.
    HoldMoveTime = 508,
    /// `lift_shaping.extension`.
    Extension = 509,
    /// `lift_shaping.force_margin`.
    ForceMargin = 510,
    /// `validation.min_upper_arm_length`.
    MinUpperArmLength = 601,
    /// `validation.max_upper_arm_length`.
    MaxUpperArmLength = 602,
    /// `validation.min_forearm_length`.
    MinForearmLength = 603,
    /// `validation.max_forearm_length`.
    MaxForearmLength = 604,
    /// `validation.min_arc`.
    MinArc = 605,
    /// `validation.max_residual`.
    MaxResidual = 606,
    /// `validation.max_method_disagreement`.
    MaxMethodDisagreement = 607,
    /// `validation.max_geometry_mismatch`.
    MaxGeometryMismatch = 608,
    /// `validation.max_shoulder_height`.
    MaxShoulderHeight = 609,
    /// `validation.shoulder_rhythm`.
    ShoulderRhythm = 610,
    /// `validation.max_residual_bias`.
    MaxResidualBias = 611,
    /// `validation.max_rhythm_correction`.
    MaxRhythmCorrection = 612,
}

impl ConfigField {
    /// Stable numeric code (group × 100 + place).
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The field's path in the configuration, as `limb config` prints it.
    pub const fn path(self) -> &'static str {
        use ConfigField as F;
        match self {
            F::ImpedanceStiffness => "impedance.stiffness",
            F::ImpedanceInertia => "impedance.inertia",
            F::ImpedanceDampingRatio => "impedance.damping_ratio",
            F::MaxForce => "limits.max_force",
            F::MaxTorque => "limits.max_torque",
            F::MaxForceRate => "limits.max_force_rate",
            F::MaxSpeed => "limits.max_speed",
            F::RateWindow => "limits.rate_window",
            F::MaxModelMismatch => "limits.max_model_mismatch",
            F::MaxSensorAge => "limits.max_sensor_age",
            F::TableTolerance => "limits.table_tolerance",
            F::ShoulderElevation => "limits.shoulder_elevation",
            F::ElbowFlexion => "limits.elbow_flexion",
            F::WorkspaceX => "limits.workspace_x",
            F::WorkspaceZ => "limits.workspace_z",
            F::LiftLength => "estimation_motion.lift_length",
            F::LiftAngle => "estimation_motion.lift_angle",
            F::EstimationPeakSpeed => "estimation_motion.peak_speed",
            F::HoldTime => "estimation_motion.hold_time",
            F::ManipulationPeakSpeed => "manipulation_peak_speed",
            F::PriorReach => "lift_shaping.prior_reach",
            F::ForearmWait => "lift_shaping.forearm_wait",
            F::TargetArc => "lift_shaping.target_arc",
            F::JointMargin => "lift_shaping.joint_margin",
            F::SettleTime => "lift_shaping.settle_time",
            F::HoldSpeed => "lift_shaping.hold_speed",
            F::HoldRate => "lift_shaping.hold_rate",
            F::HoldMoveTime => "lift_shaping.hold_move_time",
            F::Extension => "lift_shaping.extension",
            F::ForceMargin => "lift_shaping.force_margin",
            F::MinUpperArmLength => "validation.min_upper_arm_length",
            F::MaxUpperArmLength => "validation.max_upper_arm_length",
            F::MinForearmLength => "validation.min_forearm_length",
            F::MaxForearmLength => "validation.max_forearm_length",
            F::MinArc => "validation.min_arc",
            F::MaxResidual => "validation.max_residual",
            F::MaxMethodDisagreement => "validation.max_method_disagreement",
            F::MaxGeometryMismatch => "validation.max_geometry_mismatch",
            F::MaxShoulderHeight => "validation.max_shoulder_height",
            F::ShoulderRhythm => "validation.shoulder_rhythm",
            F::MaxResidualBias => "validation.max_residual_bias",
            F::MaxRhythmCorrection => "validation.max_rhythm_correction",
        }
    }
}

/// What is wrong with a field's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u16)]
pub enum ConfigProblem {
    /// NaN or infinite.
    NonFinite = 1,
    /// Zero or negative where only a positive value is usable.
    NotPositive = 2,
    /// Negative where zero is the least usable value.
    Negative = 3,
    /// An interval whose low bound is above its high bound.
    EmptyInterval = 4,
    /// A planned speed above `limits.max_speed`.
    AboveSpeedLimit = 5,
    /// A minimum above its maximum (the maximum is named).
    BelowMinimum = 6,
    /// A limit beyond [`super::SafetyLimits::CEILING`] (REQ-CFG-001).
    BeyondCeiling = 7,
}

impl ConfigProblem {
    /// Stable numeric code.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// snake_case name.
    pub const fn name(self) -> &'static str {
        match self {
            ConfigProblem::NonFinite => "non_finite",
            ConfigProblem::NotPositive => "not_positive",
            ConfigProblem::Negative => "negative",
            ConfigProblem::EmptyInterval => "empty_interval",
            ConfigProblem::AboveSpeedLimit => "above_speed_limit",
            ConfigProblem::BelowMinimum => "below_minimum",
            ConfigProblem::BeyondCeiling => "beyond_ceiling",
        }
    }
}

/// The first unusable value of a configuration: which field and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ConfigError {
    /// The field.
    pub field: ConfigField,
    /// What is wrong with it.
    pub problem: ConfigProblem,
}

impl ConfigError {
    /// `field` is unusable because of `problem`.
    pub const fn new(field: ConfigField, problem: ConfigProblem) -> Self {
        Self { field, problem }
    }

    /// Stable numeric code: the field's (the problem has its own,
    /// [`ConfigProblem::code`]).
    pub const fn code(&self) -> u16 {
        self.field.code()
    }
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}", self.field.path(), self.problem.name())
    }
}

/// `Ok` when `value` is finite and positive.
pub(crate) fn positive(field: ConfigField, value: f64) -> Result<(), ConfigError> {
    if !value.is_finite() {
        Err(ConfigError::new(field, ConfigProblem::NonFinite))
    } else if value > 0.0 {
        Ok(())
    } else {
        Err(ConfigError::new(field, ConfigProblem::NotPositive))
    }
}

/// `Ok` when every value is finite and positive; else the first that is
/// not, by its field.
pub(crate) fn all_positive(values: &[(ConfigField, f64)]) -> Result<(), ConfigError> {
    values
        .iter()
        .try_for_each(|&(field, value)| positive(field, value))
}

/// `Ok` when `value` is finite and not negative.
pub(crate) fn non_negative(field: ConfigField, value: f64) -> Result<(), ConfigError> {
    if !value.is_finite() {
        Err(ConfigError::new(field, ConfigProblem::NonFinite))
    } else if value >= 0.0 {
        Ok(())
    } else {
        Err(ConfigError::new(field, ConfigProblem::Negative))
    }
}

/// `Ok` when `value` is finite.
pub(crate) fn finite(field: ConfigField, value: f64) -> Result<(), ConfigError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ConfigError::new(field, ConfigProblem::NonFinite))
    }
}
