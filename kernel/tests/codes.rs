//! The stable numeric codes of the kernel's fault enums, pinned in one
//! table: logs and wire protocols (the Zenoh adapter's `code` fields) carry
//! them, so a renumbering breaks this test, not a deployed reader. A new
//! variant gets the next free code and a row here.

use limb_kernel::config::ConfigError;
use limb_kernel::estimation::{CircleFitError, EstimateError};
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
        (ConfigError::ImpedanceGain.code(), 1),
        (ConfigError::Limit.code(), 2),
        (ConfigError::Range.code(), 3),
        (ConfigError::EstimationMotion.code(), 4),
        (ConfigError::PlannedSpeed.code(), 5),
        (ConfigError::Validation.code(), 6),
        (ConfigError::LiftShaping.code(), 7),
    ];
    for (row, (code, expected)) in table.into_iter().enumerate() {
        assert_eq!(code, expected, "row {row}");
    }
}
