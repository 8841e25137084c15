//! The stable numeric codes of the kernel's fault enums, pinned in one
//! table: logs and wire protocols (the Zenoh adapter's `code` fields) carry
//! them, so a renumbering breaks this test, not a deployed reader. A new
//! variant gets the next free code and a row here.

use limb_kernel::config::{ConfigError, ConfigField, ConfigProblem};
use limb_kernel::estimation::{CircleFitError, EstimateError};
use limb_kernel::lift::LiftEnd;
use limb_kernel::monitor::{Limit, Violation};
use limb_kernel::motion::PlanError;
use limb_kernel::state::TargetError;
use limb_kernel::validate::Rejection;
use limb_kernel::{RefusalReason, StopReason};

#[test]
fn fault_codes_are_stable() {
    let violation = Violation::new(Limit::Speed, 1.0, 0.5);
    let table = [
        (StopReason::Monitor(violation).code(), 1),
        (StopReason::Operator.code(), 2),
        (
            StopReason::EstimationFailed(EstimateError::PathTooLong).code(),
            3,
        ),
        (StopReason::ModelRejected(Rejection::NonFinite).code(), 4),
        (StopReason::PathBufferFull.code(), 5),
        (StopReason::PlanFailed(PlanError::NonFinite).code(), 6),
        (StopReason::NonFiniteCommand.code(), 7),
        (RefusalReason::NotAllowedInState.code(), 1),
        (RefusalReason::NoFreshMeasurement.code(), 2),
        (RefusalReason::InvalidTime.code(), 3),
        (
            RefusalReason::Target(TargetError::Plan(PlanError::NonFinite)).code(),
            4,
        ),
        (RefusalReason::Plan(PlanError::NonFinite).code(), 5),
        (EstimateError::PathTooLong.code(), 1),
        (EstimateError::NonFiniteSample.code(), 2),
        (EstimateError::ForearmPhaseTooShort.code(), 3),
        (EstimateError::UpperArmPhaseTooShort.code(), 4),
        (
            EstimateError::ForearmFit(CircleFitError::Degenerate).code(),
            5,
        ),
        (
            EstimateError::UpperArmFit(CircleFitError::Degenerate).code(),
            6,
        ),
        (PlanError::NonFinite.code(), 1),
        (PlanError::NonPositiveSpeed.code(), 2),
        (TargetError::JointLimits(violation).code(), 1),
        (TargetError::Workspace(violation).code(), 2),
        (TargetError::Plan(PlanError::NonFinite).code(), 3),
        (CircleFitError::TooFewPoints.code(), 1),
        (CircleFitError::TooManyPoints.code(), 2),
        (CircleFitError::Degenerate.code(), 3),
        (CircleFitError::NonFinite.code(), 4),
        (Rejection::NonFinite.code(), 1),
        (Rejection::UpperArmLengthOutOfRange(0.5).code(), 2),
        (Rejection::ForearmLengthOutOfRange(0.5).code(), 3),
        (Rejection::ForearmArcTooShort(0.1).code(), 4),
        (Rejection::UpperArmArcTooShort(0.1).code(), 5),
        (Rejection::ForearmResidualTooLarge(0.1).code(), 6),
        (Rejection::UpperArmResidualTooLarge(0.1).code(), 7),
        (Rejection::MethodsDisagree(0.1).code(), 8),
        (Rejection::NoIndependentMethod.code(), 9),
        (Rejection::GeometryInconsistent(0.1).code(), 10),
        (Rejection::ShoulderOffTable(0.1).code(), 11),
        (Rejection::ResidualBias(0.1).code(), 12),
        (Rejection::RhythmCorrectionTooLarge(0.1).code(), 13),
        (LiftEnd::ArcReached.code(), 1),
        (LiftEnd::JointMargin(Limit::ElbowFlexion).code(), 2),
        (LiftEnd::MotionComplete.code(), 3),
        (
            LiftEnd::ForceMargin(Violation::new(Limit::ForceMagnitude, 42.5, 42.0)).code(),
            4,
        ),
        (ConfigProblem::NonFinite.code(), 1),
        (ConfigProblem::NotPositive.code(), 2),
        (ConfigProblem::Negative.code(), 3),
        (ConfigProblem::EmptyInterval.code(), 4),
        (ConfigProblem::AboveSpeedLimit.code(), 5),
        (ConfigProblem::BelowMinimum.code(), 6),
        (ConfigProblem::BeyondCeiling.code(), 7),
    ];
    for (row, (code, expected)) in table.into_iter().enumerate() {
        assert_eq!(code, expected, "row {row}");
    }
}

/// Every configuration field's code, with its path: a field is named by
/// both in `ConfigError` (logs, the Zenoh `invalid_limits` refusal).
#[test]
fn config_field_codes_are_stable() {
    use ConfigField as F;
    let table = [
        (F::ImpedanceStiffness, 101, "impedance.stiffness"),
        (F::ImpedanceInertia, 102, "impedance.inertia"),
        (F::ImpedanceDampingRatio, 103, "impedance.damping_ratio"),
        (F::MaxForce, 201, "limits.max_force"),
        (F::MaxTorque, 202, "limits.max_torque"),
        (F::MaxForceRate, 203, "limits.max_force_rate"),
        (F::MaxSpeed, 204, "limits.max_speed"),
        (F::RateWindow, 205, "limits.rate_window"),
        (F::MaxModelMismatch, 206, "limits.max_model_mismatch"),
        (F::MaxSensorAge, 207, "limits.max_sensor_age"),
        (F::TableTolerance, 208, "limits.table_tolerance"),
        (F::ShoulderElevation, 209, "limits.shoulder_elevation"),
        (F::ElbowFlexion, 210, "limits.elbow_flexion"),
        (F::WorkspaceX, 211, "limits.workspace_x"),
        (F::WorkspaceZ, 212, "limits.workspace_z"),
        (F::LiftLength, 301, "estimation_motion.lift_length"),
        (F::LiftAngle, 302, "estimation_motion.lift_angle"),
        (F::EstimationPeakSpeed, 303, "estimation_motion.peak_speed"),
        (F::HoldTime, 304, "estimation_motion.hold_time"),
        (F::ManipulationPeakSpeed, 401, "manipulation_peak_speed"),
        (F::PriorReach, 501, "lift_shaping.prior_reach"),
        (F::ForearmWait, 502, "lift_shaping.forearm_wait"),
        (F::TargetArc, 503, "lift_shaping.target_arc"),
        (F::JointMargin, 504, "lift_shaping.joint_margin"),
        (F::SettleTime, 505, "lift_shaping.settle_time"),
        (F::HoldSpeed, 506, "lift_shaping.hold_speed"),
        (F::HoldRate, 507, "lift_shaping.hold_rate"),
        (F::HoldMoveTime, 508, "lift_shaping.hold_move_time"),
        (F::Extension, 509, "lift_shaping.extension"),
        (F::ForceMargin, 510, "lift_shaping.force_margin"),
        (F::MinUpperArmLength, 601, "validation.min_upper_arm_length"),
        (F::MaxUpperArmLength, 602, "validation.max_upper_arm_length"),
        (F::MinForearmLength, 603, "validation.min_forearm_length"),
        (F::MaxForearmLength, 604, "validation.max_forearm_length"),
        (F::MinArc, 605, "validation.min_arc"),
        (F::MaxResidual, 606, "validation.max_residual"),
        (
            F::MaxMethodDisagreement,
            607,
            "validation.max_method_disagreement",
        ),
        (
            F::MaxGeometryMismatch,
            608,
            "validation.max_geometry_mismatch",
        ),
        (F::MaxShoulderHeight, 609, "validation.max_shoulder_height"),
        (F::ShoulderRhythm, 610, "validation.shoulder_rhythm"),
        (F::MaxResidualBias, 611, "validation.max_residual_bias"),
        (
            F::MaxRhythmCorrection,
            612,
            "validation.max_rhythm_correction",
        ),
    ];
    for (field, code, path) in table {
        assert_eq!((field.code(), field.path()), (code, path));
        assert_eq!(
            ConfigError::new(field, ConfigProblem::NonFinite).code(),
            code
        );
    }
}

/// The value a rejection carries is the one its check found; the checks
/// without a value carry none.
#[test]
fn rejections_carry_the_value_they_found() {
    assert_eq!(Rejection::NonFinite.value(), None);
    assert_eq!(Rejection::NoIndependentMethod.value(), None);
    assert_eq!(Rejection::ForearmArcTooShort(0.25).value(), Some(0.25));
    assert_eq!(Rejection::ShoulderOffTable(-0.031).value(), Some(-0.031));
}
