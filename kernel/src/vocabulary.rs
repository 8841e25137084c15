//! The kernel's one vocabulary: for every state, request, refusal, stop
//! reason, monitor limit, estimate rejection and error, its stable numeric
//! `code` (beside each type), its stable snake_case `name` and its display
//! text (here), with the numbers it carries in SI units.
//!
//! Everything a person or a tool reads is spelled from here: the CLI's
//! text and JSON, the session digest the firmware compares with the host,
//! the Zenoh wire (`limb-session`'s `kernel_wire` takes its names from
//! these functions), AREBO's output. No `Debug` formatting of a kernel
//! value reaches a user, a wire or the digest (tested in
//! `cli/tests/vocabulary.rs`). Names never change once released; a new
//! variant gets a new name and code. The table of every code and name is
//! `adapters/zenoh/PROTOCOL.md` ("Faults"); each is pinned by a test here
//! (`every_code_and_name_is_pinned`) and on the wire by the Zenoh golden test.
//!
//! Display text: states by their names in the state diagram (`Grasp`,
//! `SafeStop`, …), everything else by its snake_case name, followed by
//! what it carries (`monitor: force_magnitude 45.0778 N beyond 45.0000 N`,
//! `model_rejected: geometry_inconsistent 0.0116 m`).

use crate::command::CommandMode;
use crate::estimation::{CircleFitError, EstimateError, Method};
use crate::lift::LiftEnd;
use crate::monitor::{Limit, Violation};
use crate::motion::PlanError;
use crate::state::{Refusal, RefusalReason, Request, StateKind, TargetError};
use crate::stop::StopCategory;
use crate::stop::StopReason;
use crate::trace::{Cause, Event, TraceEvent};
use crate::validate::Rejection;
use core::fmt::{self, Display, Formatter};

impl StateKind {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            StateKind::Grasp => "grasp",
            StateKind::Estimate => "estimate",
            StateKind::Validated => "validated",
            StateKind::Manipulate => "manipulate",
            StateKind::SafeStop => "safe_stop",
        }
    }

    /// The state's name in the state diagram (display text).
    pub const fn title(&self) -> &'static str {
        match self {
            StateKind::Grasp => "Grasp",
            StateKind::Estimate => "Estimate",
            StateKind::Validated => "Validated",
            StateKind::Manipulate => "Manipulate",
            StateKind::SafeStop => "SafeStop",
        }
    }
}

impl Display for StateKind {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.title())
    }
}

impl Request {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            Request::StartEstimation => "start_estimation",
            Request::ApproveManipulation(_) => "approve_manipulation",
            Request::FinishManipulation => "finish_manipulation",
            Request::Stop => "stop",
            Request::Reset => "reset",
        }
    }
}

impl Display for Request {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())?;
        if let Request::ApproveManipulation(target) = self {
            write!(
                f,
                " to shoulder elevation {:.4} rad, elbow flexion {:.4} rad",
                target.shoulder_elevation, target.elbow_flexion
            )?;
        }
        Ok(())
    }
}

impl CommandMode {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            CommandMode::Track => "track",
            CommandMode::Hold => "hold",
            CommandMode::Stop => "stop",
        }
    }
}

impl CommandMode {
    /// The mode as the step log writes it (display text).
    pub const fn title(&self) -> &'static str {
        match self {
            CommandMode::Track => "Track",
            CommandMode::Hold => "Hold",
            CommandMode::Stop => "Stop",
        }
    }
}

impl Display for CommandMode {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.title())
    }
}

impl Limit {
    /// Stable snake_case name.
    pub const fn name(self) -> &'static str {
        match self {
            Limit::NonFiniteSensor => "non_finite_sensor",
            Limit::ClockFault => "clock_fault",
            Limit::SensorTimeReversed => "sensor_time_reversed",
            Limit::StaleSensor => "stale_sensor",
            Limit::ForceMagnitude => "force_magnitude",
            Limit::Torque => "torque",
            Limit::ForceRate => "force_rate",
            Limit::Speed => "speed",
            Limit::GraspBelowTable => "grasp_below_table",
            Limit::ElbowBelowTable => "elbow_below_table",
            Limit::WorkspaceX => "workspace_x",
            Limit::WorkspaceZ => "workspace_z",
            Limit::ShoulderElevation => "shoulder_elevation",
            Limit::ElbowFlexion => "elbow_flexion",
            Limit::ModelMismatch => "model_mismatch",
        }
    }

    /// The SI unit of the limit's value and bound (empty: a count or a
    /// time stamp's order).
    pub const fn unit(self) -> &'static str {
        match self {
            Limit::NonFiniteSensor | Limit::SensorTimeReversed => "",
            Limit::ClockFault | Limit::StaleSensor => "s",
            Limit::ForceMagnitude => "N",
            Limit::Torque => "N m",
            Limit::ForceRate => "N/s",
            Limit::Speed => "m/s",
            Limit::GraspBelowTable
            | Limit::ElbowBelowTable
            | Limit::WorkspaceX
            | Limit::WorkspaceZ
            | Limit::ModelMismatch => "m",
            Limit::ShoulderElevation | Limit::ElbowFlexion => "rad",
        }
    }
}

impl Display for Limit {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `value` with its `unit` (none when empty).
struct Quantity(f64, &'static str);

impl Display for Quantity {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(f, "{:.4}", self.0)?;
        if !self.1.is_empty() {
            write!(f, " {}", self.1)?;
        }
        Ok(())
    }
}

impl Display for Violation {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let unit = self.limit.unit();
        write!(
            f,
            "{} {} beyond {}",
            self.limit.name(),
            Quantity(self.value, unit),
            Quantity(self.bound, unit)
        )
    }
}

impl PlanError {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            PlanError::NonFinite => "non_finite",
            PlanError::NonPositiveSpeed => "non_positive_speed",
        }
    }
}

impl Display for PlanError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl TargetError {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            TargetError::JointLimits(_) => "joint_limits",
            TargetError::Workspace(_) => "workspace",
            TargetError::Plan(_) => "plan",
        }
    }
}

impl Display for TargetError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            TargetError::JointLimits(v) | TargetError::Workspace(v) => {
                write!(f, "{}: {v}", self.name())
            }
            TargetError::Plan(p) => write!(f, "{}: {p}", self.name()),
        }
    }
}

impl RefusalReason {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            RefusalReason::NotAllowedInState => "not_allowed_in_state",
            RefusalReason::NoFreshMeasurement => "no_fresh_measurement",
            RefusalReason::InvalidTime => "invalid_time",
            RefusalReason::Target(_) => "target",
            RefusalReason::Plan(_) => "plan",
            RefusalReason::ArmNotStill => "arm_not_still",
        }
    }
}

impl Display for RefusalReason {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            RefusalReason::Target(t) => write!(f, "{}: {t}", self.name()),
            RefusalReason::Plan(p) => write!(f, "{}: {p}", self.name()),
            _ => f.write_str(self.name()),
        }
    }
}

impl Display for Refusal {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "refused {} in {}: {}",
            self.request, self.state, self.reason
        )
    }
}

impl CircleFitError {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            CircleFitError::TooFewPoints => "too_few_points",
            CircleFitError::TooManyPoints => "too_many_points",
            CircleFitError::Degenerate => "degenerate",
            CircleFitError::NonFinite => "non_finite",
        }
    }
}

impl Display for CircleFitError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl EstimateError {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            EstimateError::PathTooLong => "path_too_long",
            EstimateError::NonFiniteSample => "non_finite_sample",
            EstimateError::ForearmPhaseTooShort => "forearm_phase_too_short",
            EstimateError::UpperArmPhaseTooShort => "upper_arm_phase_too_short",
            EstimateError::ForearmFit(_) => "forearm_fit",
            EstimateError::UpperArmFit(_) => "upper_arm_fit",
        }
    }
}

impl Display for EstimateError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            EstimateError::ForearmFit(c) | EstimateError::UpperArmFit(c) => {
                write!(f, "{}: {c}", self.name())
            }
            _ => f.write_str(self.name()),
        }
    }
}

impl Rejection {
    /// Stable snake_case name of the failed check.
    pub const fn name(&self) -> &'static str {
        match self {
            Rejection::NonFinite => "non_finite",
            Rejection::UpperArmLengthOutOfRange(_) => "upper_arm_length_out_of_range",
            Rejection::ForearmLengthOutOfRange(_) => "forearm_length_out_of_range",
            Rejection::ForearmArcTooShort(_) => "forearm_arc_too_short",
            Rejection::UpperArmArcTooShort(_) => "upper_arm_arc_too_short",
            Rejection::ForearmResidualTooLarge(_) => "forearm_residual_too_large",
            Rejection::UpperArmResidualTooLarge(_) => "upper_arm_residual_too_large",
            Rejection::MethodsDisagree(_) => "methods_disagree",
            Rejection::NoIndependentMethod => "no_independent_method",
            Rejection::GeometryInconsistent(_) => "geometry_inconsistent",
            Rejection::ShoulderOffTable(_) => "shoulder_off_table",
            Rejection::ResidualBias(_) => "residual_bias",
            Rejection::RhythmCorrectionTooLarge(_) => "rhythm_correction_too_large",
        }
    }

    /// The SI unit of the value the check found.
    pub const fn unit(&self) -> &'static str {
        match self {
            Rejection::ForearmArcTooShort(_) | Rejection::UpperArmArcTooShort(_) => "rad",
            _ => "m",
        }
    }
}

impl Display for Rejection {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())?;
        match self.value() {
            Some(v) => write!(f, " {}", Quantity(v, self.unit())),
            None => Ok(()),
        }
    }
}

impl StopReason {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            StopReason::Monitor(_) => "monitor",
            StopReason::Operator => "operator",
            StopReason::EstimationFailed(_) => "estimation_failed",
            StopReason::ModelRejected(_) => "model_rejected",
            StopReason::PathBufferFull => "path_buffer_full",
            StopReason::PlanFailed(_) => "plan_failed",
            StopReason::NonFiniteCommand => "non_finite_command",
        }
    }
}

impl Display for StopReason {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let name = self.name();
        match self {
            StopReason::Monitor(v) => write!(f, "{name}: {v}"),
            StopReason::EstimationFailed(e) => write!(f, "{name}: {e}"),
            StopReason::ModelRejected(r) => write!(f, "{name}: {r}"),
            StopReason::PlanFailed(p) => write!(f, "{name}: {p}"),
            _ => f.write_str(name),
        }
    }
}

impl StopCategory {
    /// Stable snake_case name.
    pub const fn name(self) -> &'static str {
        match self {
            StopCategory::Hold => "hold",
            StopCategory::RampDown => "ramp_down",
            StopCategory::MotorsOff => "motors_off",
        }
    }
}

impl Display for StopCategory {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl LiftEnd {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            LiftEnd::ArcReached => "arc_reached",
            LiftEnd::JointMargin(_) => "joint_margin",
            LiftEnd::MotionComplete => "motion_complete",
            LiftEnd::ForceMargin(_) => "force_margin",
        }
    }
}

impl Display for LiftEnd {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            LiftEnd::JointMargin(limit) => write!(f, "{}: {limit}", self.name()),
            LiftEnd::ForceMargin(force) => write!(f, "{}: {force}", self.name()),
            _ => f.write_str(self.name()),
        }
    }
}

impl Cause {
    /// Stable snake_case name.
    pub const fn name(&self) -> &'static str {
        match self {
            Cause::Request(_) => "request",
            Cause::ModelValidated => "model_validated",
            Cause::Stop(_) => "stop",
        }
    }
}

impl Display for Cause {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Cause::Request(request) => write!(f, "request {request}"),
            Cause::ModelValidated => f.write_str("model validated"),
            Cause::Stop(reason) => write!(f, "stop: {reason}"),
        }
    }
}

impl Display for Event {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Event::Transition { from, to, cause } => write!(f, "{from} → {to} ({cause})"),
            Event::Refused(refusal) => write!(f, "{refusal}"),
            Event::LiftEnded(reason) => write!(
                f,
                "lift ended: {reason}; holding while the estimate is refined"
            ),
        }
    }
}

impl Display for TraceEvent {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        self.event.fmt(f)
    }
}

impl Method {
    /// Stable snake_case name (as the CLI's `--method` spells it).
    pub const fn name(&self) -> &'static str {
        match self {
            Method::Hough => "hough",
            Method::Ls => "ls",
            Method::Auto => "auto",
            Method::Online => "online",
        }
    }
}

impl Display for Method {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::JointAngles;
    use crate::monitor::Violation;

    fn violation(limit: Limit) -> Violation {
        Violation {
            limit,
            value: 1.0,
            bound: 0.5,
        }
    }

    /// Every code and name of the vocabulary, pinned: a renamed or
    /// renumbered variant fails here (and PROTOCOL.md's table lists the
    /// same, "Faults"); the stop categories' codes and names too
    /// (REQ-STOP-001).
    #[test]
    fn every_code_and_name_is_pinned() {
        let limits = [
            (Limit::NonFiniteSensor, 1, "non_finite_sensor"),
            (Limit::ClockFault, 2, "clock_fault"),
            (Limit::SensorTimeReversed, 3, "sensor_time_reversed"),
            (Limit::StaleSensor, 4, "stale_sensor"),
            (Limit::ForceMagnitude, 10, "force_magnitude"),
            (Limit::Torque, 11, "torque"),
            (Limit::ForceRate, 12, "force_rate"),
            (Limit::Speed, 20, "speed"),
            (Limit::GraspBelowTable, 30, "grasp_below_table"),
            (Limit::ElbowBelowTable, 31, "elbow_below_table"),
            (Limit::WorkspaceX, 32, "workspace_x"),
            (Limit::WorkspaceZ, 33, "workspace_z"),
            (Limit::ShoulderElevation, 40, "shoulder_elevation"),
            (Limit::ElbowFlexion, 41, "elbow_flexion"),
            (Limit::ModelMismatch, 42, "model_mismatch"),
        ];
        for (limit, code, name) in limits {
            assert_eq!((limit.code(), limit.name()), (code, name));
        }
        let v = violation(Limit::ForceMagnitude);
        let stops = [
            (StopReason::Monitor(v), 1, "monitor"),
            (StopReason::Operator, 2, "operator"),
            (
                StopReason::EstimationFailed(EstimateError::PathTooLong),
                3,
                "estimation_failed",
            ),
            (
                StopReason::ModelRejected(Rejection::NonFinite),
                4,
                "model_rejected",
            ),
            (StopReason::PathBufferFull, 5, "path_buffer_full"),
            (
                StopReason::PlanFailed(PlanError::NonFinite),
                6,
                "plan_failed",
            ),
            (StopReason::NonFiniteCommand, 7, "non_finite_command"),
        ];
        for (reason, code, name) in stops {
            assert_eq!((reason.code(), reason.name()), (code, name));
        }
        let refusals = [
            (RefusalReason::NotAllowedInState, 1, "not_allowed_in_state"),
            (RefusalReason::NoFreshMeasurement, 2, "no_fresh_measurement"),
            (RefusalReason::InvalidTime, 3, "invalid_time"),
            (
                RefusalReason::Target(TargetError::Workspace(v)),
                4,
                "target",
            ),
            (RefusalReason::Plan(PlanError::NonFinite), 5, "plan"),
            (RefusalReason::ArmNotStill, 6, "arm_not_still"),
        ];
        for (reason, code, name) in refusals {
            assert_eq!((reason.code(), reason.name()), (code, name));
        }
        let targets = [
            (TargetError::JointLimits(v), 1, "joint_limits"),
            (TargetError::Workspace(v), 2, "workspace"),
            (TargetError::Plan(PlanError::NonPositiveSpeed), 3, "plan"),
        ];
        for (error, code, name) in targets {
            assert_eq!((error.code(), error.name()), (code, name));
        }
        for (error, code, name) in [
            (PlanError::NonFinite, 1, "non_finite"),
            (PlanError::NonPositiveSpeed, 2, "non_positive_speed"),
        ] {
            assert_eq!((error.code(), error.name()), (code, name));
        }
        let fits = [
            (CircleFitError::TooFewPoints, 1, "too_few_points"),
            (CircleFitError::TooManyPoints, 2, "too_many_points"),
            (CircleFitError::Degenerate, 3, "degenerate"),
            (CircleFitError::NonFinite, 4, "non_finite"),
        ];
        for (error, code, name) in fits {
            assert_eq!((error.code(), error.name()), (code, name));
        }
        let estimates = [
            (EstimateError::PathTooLong, 1, "path_too_long"),
            (EstimateError::NonFiniteSample, 2, "non_finite_sample"),
            (
                EstimateError::ForearmPhaseTooShort,
                3,
                "forearm_phase_too_short",
            ),
            (
                EstimateError::UpperArmPhaseTooShort,
                4,
                "upper_arm_phase_too_short",
            ),
            (
                EstimateError::ForearmFit(CircleFitError::Degenerate),
                5,
                "forearm_fit",
            ),
            (
                EstimateError::UpperArmFit(CircleFitError::Degenerate),
                6,
                "upper_arm_fit",
            ),
        ];
        for (error, code, name) in estimates {
            assert_eq!((error.code(), error.name()), (code, name));
        }
        let rejections = [
            (Rejection::NonFinite, 1, "non_finite"),
            (
                Rejection::UpperArmLengthOutOfRange(0.1),
                2,
                "upper_arm_length_out_of_range",
            ),
            (
                Rejection::ForearmLengthOutOfRange(0.1),
                3,
                "forearm_length_out_of_range",
            ),
            (
                Rejection::ForearmArcTooShort(0.1),
                4,
                "forearm_arc_too_short",
            ),
            (
                Rejection::UpperArmArcTooShort(0.1),
                5,
                "upper_arm_arc_too_short",
            ),
            (
                Rejection::ForearmResidualTooLarge(0.1),
                6,
                "forearm_residual_too_large",
            ),
            (
                Rejection::UpperArmResidualTooLarge(0.1),
                7,
                "upper_arm_residual_too_large",
            ),
            (Rejection::MethodsDisagree(0.1), 8, "methods_disagree"),
            (Rejection::NoIndependentMethod, 9, "no_independent_method"),
            (
                Rejection::GeometryInconsistent(0.1),
                10,
                "geometry_inconsistent",
            ),
            (Rejection::ShoulderOffTable(0.1), 11, "shoulder_off_table"),
            (Rejection::ResidualBias(0.1), 12, "residual_bias"),
            (
                Rejection::RhythmCorrectionTooLarge(0.1),
                13,
                "rhythm_correction_too_large",
            ),
        ];
        for (rejection, code, name) in rejections {
            assert_eq!((rejection.code(), rejection.name()), (code, name));
        }
        let ends = [
            (LiftEnd::ArcReached, 1, "arc_reached"),
            (LiftEnd::JointMargin(Limit::ElbowFlexion), 2, "joint_margin"),
            (LiftEnd::MotionComplete, 3, "motion_complete"),
            (
                LiftEnd::ForceMargin(Violation::new(Limit::ForceMagnitude, 42.5, 42.0)),
                4,
                "force_margin",
            ),
        ];
        for (end, code, name) in ends {
            assert_eq!((end.code(), end.name()), (code, name));
        }
        let categories = [
            (StopCategory::Hold, 1, "hold"),
            (StopCategory::RampDown, 2, "ramp_down"),
            (StopCategory::MotorsOff, 3, "motors_off"),
        ];
        for (category, code, name) in categories {
            assert_eq!((category.code(), category.name()), (code, name));
        }
        assert_eq!(StopCategory::ALL.map(StopCategory::code), [1, 2, 3]);
    }

    /// The display text carries the numbers with their units and no Rust
    /// `Debug` shape.
    #[test]
    fn display_text_names_values_and_units() {
        use core::fmt::Write;
        // The display text in a fixed buffer (the kernel has no allocator).
        struct Text(heapless::String<160>);
        impl PartialEq<&str> for Text {
            fn eq(&self, other: &&str) -> bool {
                self.0.as_str() == *other
            }
        }
        impl core::fmt::Debug for Text {
            fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
                f.write_str(&self.0)
            }
        }
        trait Written {
            fn to_string(&self) -> Text;
        }
        impl<T: Display> Written for T {
            fn to_string(&self) -> Text {
                let mut text = heapless::String::new();
                let _ = write!(text, "{self}");
                Text(text)
            }
        }
        let stop = StopReason::Monitor(Violation {
            limit: Limit::ForceMagnitude,
            value: 45.07774,
            bound: 45.0,
        });
        assert_eq!(
            stop.to_string(),
            "monitor: force_magnitude 45.0777 N beyond 45.0000 N"
        );
        assert_eq!(
            StopReason::ModelRejected(Rejection::GeometryInconsistent(0.0116)).to_string(),
            "model_rejected: geometry_inconsistent 0.0116 m"
        );
        assert_eq!(
            StopReason::EstimationFailed(EstimateError::UpperArmFit(CircleFitError::Degenerate))
                .to_string(),
            "estimation_failed: upper_arm_fit: degenerate"
        );
        let approve = Request::ApproveManipulation(JointAngles {
            shoulder_elevation: 1.0,
            elbow_flexion: 0.6,
        });
        assert_eq!(
            approve.to_string(),
            "approve_manipulation to shoulder elevation 1.0000 rad, elbow flexion 0.6000 rad"
        );
        let refusal = Refusal {
            request: Request::StartEstimation,
            state: StateKind::SafeStop,
            reason: RefusalReason::NotAllowedInState,
        };
        assert_eq!(
            refusal.to_string(),
            "refused start_estimation in SafeStop: not_allowed_in_state"
        );
        assert_eq!(
            LiftEnd::JointMargin(Limit::ShoulderElevation).to_string(),
            "joint_margin: shoulder_elevation"
        );
        assert_eq!(
            LiftEnd::ForceMargin(Violation::new(Limit::ForceMagnitude, 42.5, 42.0)).to_string(),
            "force_margin: force_magnitude 42.5000 N beyond 42.0000 N"
        );
        assert_eq!(
            Rejection::ForearmArcTooShort(0.4).to_string(),
            "forearm_arc_too_short 0.4000 rad"
        );
    }
}
