//! The wire's own spelling of what the kernel reports: states, requests,
//! faults, events, frames and commands. The Zenoh wire (`@v2`), `limb run
//! --json` and the CLI's reports all spell kernel values with it, so it
//! lives here, beside the session loop, not in any one adapter.
//!
//! The kernel's serde names are its Rust names (PascalCase, externally
//! tagged), so a renamed kernel variant would silently change `@v2`. Every
//! kernel value therefore goes through a type of this module, built by an
//! exhaustive `match`: a renamed or added kernel variant stops this crate
//! from compiling, and a changed spelling breaks the golden-message test
//! (`adapters/zenoh/tests/golden.rs`), never a deployed supervisor.
//!
//! Faults (stop reasons, refusals, estimation, plan, target and
//! configuration errors) are one shape, [`Fault`]: the kernel's stable
//! numeric `code`, a snake_case `name`, and what caused it (a nested
//! fault, a monitor violation, or a free-text detail).

use limb_kernel::arm::JointAngles;
use limb_kernel::command::CommandMode;
use limb_kernel::config::ConfigError;
use limb_kernel::estimation::{CircleFitError, EstimateError};
use limb_kernel::geometry::{Point, Pose, PoseRate, Wrench};
use limb_kernel::impedance::Saturation;
use limb_kernel::lift::LiftEnd;
use limb_kernel::monitor::Violation;
use limb_kernel::motion::{PlanError, SetPoint};
use limb_kernel::state::TargetError;
use limb_kernel::trace::{Cause as KernelCause, Event, TraceEvent};
use limb_kernel::validate::Rejection;
use limb_kernel::RefusalReason;
use limb_kernel::{Command, PathSample, Refusal, Request, StateKind, StopReason};
use serde::{Deserialize, Serialize};

/// A kernel state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum State {
    /// Holding the wrist, no model.
    Grasp,
    /// Running the estimation motion.
    Estimate,
    /// Holding still with a validated model.
    Validated,
    /// Moving the arm to an approved target.
    Manipulate,
    /// Latched stop.
    SafeStop,
}

impl From<StateKind> for State {
    fn from(kind: StateKind) -> Self {
        match kind {
            StateKind::Grasp => State::Grasp,
            StateKind::Estimate => State::Estimate,
            StateKind::Validated => State::Validated,
            StateKind::Manipulate => State::Manipulate,
            StateKind::SafeStop => State::SafeStop,
        }
    }
}

/// Joint angles of the arm [rad].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Joints {
    /// Upper-arm elevation above the horizontal, q1 [rad].
    pub shoulder_elevation: f64,
    /// Elbow flexion q2 [rad]; negative is hyperextension.
    pub elbow_flexion: f64,
}

impl From<Joints> for JointAngles {
    fn from(j: Joints) -> Self {
        JointAngles {
            shoulder_elevation: j.shoulder_elevation,
            elbow_flexion: j.elbow_flexion,
        }
    }
}

impl From<JointAngles> for Joints {
    fn from(j: JointAngles) -> Self {
        Joints {
            shoulder_elevation: j.shoulder_elevation,
            elbow_flexion: j.elbow_flexion,
        }
    }
}

/// Which request (a refusal or transition names it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RequestKind {
    /// Grasp → Estimate.
    StartEstimation,
    /// Validated → Manipulate.
    ApproveManipulation,
    /// Manipulate → Validated.
    FinishManipulation,
    /// Any state → SafeStop.
    Stop,
    /// SafeStop → Grasp.
    Reset,
}

impl From<Request> for RequestKind {
    fn from(request: Request) -> Self {
        match request {
            Request::StartEstimation => RequestKind::StartEstimation,
            Request::ApproveManipulation(_) => RequestKind::ApproveManipulation,
            Request::FinishManipulation => RequestKind::FinishManipulation,
            Request::Stop => RequestKind::Stop,
            Request::Reset => RequestKind::Reset,
        }
    }
}

/// A crossed monitor limit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViolationReport {
    /// The limit's stable code (`Limit::code`).
    pub limit: u16,
    /// The limit's name.
    pub limit_name: String,
    /// Measured value, in the limit's unit (null when not finite).
    pub value: Option<f64>,
    /// The bound crossed (null when not finite).
    pub bound: Option<f64>,
}

impl From<Violation> for ViolationReport {
    fn from(v: Violation) -> Self {
        Self {
            limit: v.limit.code(),
            limit_name: v.limit.name().to_owned(),
            value: finite(v.value),
            bound: finite(v.bound),
        }
    }
}

/// A kernel fault: stable code, name, and its cause.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fault {
    /// The kernel's stable code of this fault within its kind.
    pub code: u16,
    /// snake_case name.
    pub name: String,
    /// The fault inside it (e.g. an estimation error's fit error).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cause: Option<Box<Fault>>,
    /// The monitor violation (stops by a monitor, refused targets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub violation: Option<Box<ViolationReport>>,
    /// Free text, informative only (model rejections).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detail: Option<String>,
}

impl Fault {
    fn named(code: u16, name: &str) -> Self {
        Self {
            code,
            name: name.to_owned(),
            cause: None,
            violation: None,
            detail: None,
        }
    }

    fn caused_by(mut self, cause: Fault) -> Self {
        self.cause = Some(Box::new(cause));
        self
    }

    fn with_violation(mut self, violation: Violation) -> Self {
        self.violation = Some(Box::new(violation.into()));
        self
    }
}

impl From<PlanError> for Fault {
    fn from(e: PlanError) -> Self {
        Fault::named(e.code(), e.name())
    }
}

impl From<TargetError> for Fault {
    fn from(e: TargetError) -> Self {
        let fault = Fault::named(e.code(), e.name());
        match e {
            TargetError::JointLimits(v) | TargetError::Workspace(v) => fault.with_violation(v),
            TargetError::Plan(p) => fault.caused_by(p.into()),
        }
    }
}

impl From<RefusalReason> for Fault {
    fn from(r: RefusalReason) -> Self {
        let fault = Fault::named(r.code(), r.name());
        match r {
            RefusalReason::Target(t) => fault.caused_by(t.into()),
            RefusalReason::Plan(p) => fault.caused_by(p.into()),
            RefusalReason::NotAllowedInState
            | RefusalReason::NoFreshMeasurement
            | RefusalReason::InvalidTime
            | RefusalReason::ArmNotStill => fault,
        }
    }
}

impl From<CircleFitError> for Fault {
    fn from(e: CircleFitError) -> Self {
        Fault::named(e.code(), e.name())
    }
}

impl From<EstimateError> for Fault {
    fn from(e: EstimateError) -> Self {
        let fault = Fault::named(e.code(), e.name());
        match e {
            EstimateError::ForearmFit(c) | EstimateError::UpperArmFit(c) => {
                fault.caused_by(c.into())
            }
            _ => fault,
        }
    }
}

impl From<StopReason> for Fault {
    fn from(r: StopReason) -> Self {
        let fault = Fault::named(r.code(), r.name());
        match r {
            StopReason::Monitor(v) => fault.with_violation(v),
            StopReason::EstimationFailed(e) => fault.caused_by(e.into()),
            StopReason::ModelRejected(rejection) => fault.caused_by(rejection.into()),
            StopReason::PlanFailed(p) => fault.caused_by(p.into()),
            _ => fault,
        }
    }
}

/// The field (code and path, e.g. 201 `limits.max_force`), caused by
/// the problem with its value (e.g. 2 `not_positive`).
impl From<ConfigError> for Fault {
    fn from(e: ConfigError) -> Self {
        Fault::named(e.code(), e.field.path())
            .caused_by(Fault::named(e.problem.code(), e.problem.name()))
    }
}

/// The failed validation check (stable code and name); the value it found
/// as informative detail.
impl From<Rejection> for Fault {
    fn from(r: Rejection) -> Self {
        let mut fault = Fault::named(r.code(), r.name());
        fault.detail = r.value().map(|v| format!("{v}"));
        fault
    }
}

/// A request the kernel refused: which, in which state, why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KernelRefusal {
    /// The request.
    pub request: RequestKind,
    /// The state it was refused in.
    pub state: State,
    /// Why (a `RefusalReason` fault).
    pub reason: Fault,
}

impl From<Refusal> for KernelRefusal {
    fn from(r: Refusal) -> Self {
        Self {
            request: r.request.into(),
            state: r.state.into(),
            reason: r.reason.into(),
        }
    }
}

/// What caused a transition.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "cause", rename_all = "snake_case")]
pub enum Cause {
    /// A request.
    Request {
        /// Which.
        request: RequestKind,
    },
    /// The estimate passed validation at the end of the motion.
    ModelValidated,
    /// A stop.
    Stop {
        /// Why (a `StopReason` fault).
        reason: Fault,
    },
}

/// One decision of the kernel, at kernel time `time` [s].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum KernelEvent {
    /// The state changed.
    Transition {
        /// Kernel time [s] (null when the clock was not finite).
        time: Option<f64>,
        /// State left.
        from: State,
        /// State entered.
        to: State,
        /// Why.
        #[serde(flatten)]
        cause: Cause,
    },
    /// A request was refused; the state did not change.
    Refused {
        /// Kernel time [s] (null when the clock was not finite).
        time: Option<f64>,
        /// What and why.
        refusal: KernelRefusal,
    },
    /// The estimation lift ended (Estimate goes on: settling, then the
    /// refinement).
    LiftEnded {
        /// Kernel time [s] (null when the clock was not finite).
        time: Option<f64>,
        /// Why it ended.
        end: LiftEndReport,
    },
}

/// Why the estimation lift ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum LiftEndReport {
    /// The upper arm swept the target arc.
    ArcReached,
    /// The joint envelope came within the margin of a joint limit.
    JointMargin {
        /// The limit's stable code (`Limit::code`).
        limit: u16,
        /// The limit's name.
        limit_name: String,
    },
    /// The planned lift and its extension were complete.
    MotionComplete,
    /// The filtered interaction force reached the force limit less the
    /// lift's force margin: the arm resists the lift.
    ForceMargin {
        /// The filtered force magnitude [N].
        force_n: f64,
        /// The force limit less the margin [N].
        bound_n: f64,
    },
}

impl From<LiftEnd> for LiftEndReport {
    fn from(end: LiftEnd) -> Self {
        match end {
            LiftEnd::ArcReached => LiftEndReport::ArcReached,
            LiftEnd::JointMargin(limit) => LiftEndReport::JointMargin {
                limit: limit.code(),
                limit_name: limit.name().to_owned(),
            },
            LiftEnd::MotionComplete => LiftEndReport::MotionComplete,
            LiftEnd::ForceMargin(force) => LiftEndReport::ForceMargin {
                force_n: force.value,
                bound_n: force.bound,
            },
        }
    }
}

fn finite(value: f64) -> Option<f64> {
    value.is_finite().then_some(value)
}

impl From<TraceEvent> for KernelEvent {
    fn from(e: TraceEvent) -> Self {
        let time = finite(e.time);
        match e.event {
            Event::Transition { from, to, cause } => KernelEvent::Transition {
                time,
                from: from.into(),
                to: to.into(),
                cause: match cause {
                    KernelCause::Request(r) => Cause::Request { request: r.into() },
                    KernelCause::ModelValidated => Cause::ModelValidated,
                    KernelCause::Stop(reason) => Cause::Stop {
                        reason: reason.into(),
                    },
                },
            },
            Event::Refused(refusal) => KernelEvent::Refused {
                time,
                refusal: refusal.into(),
            },
            Event::LiftEnded(end) => KernelEvent::LiftEnded {
                time,
                end: end.into(),
            },
        }
    }
}

/// x, z [m] and an angle or their rates, frame S.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Planar {
    /// Horizontal, toward the shoulder [m] (or m/s, m/s²).
    pub x: f64,
    /// Vertical, up; the table is z = 0 [m] (or m/s, m/s²).
    pub z: f64,
    /// Forearm elevation [rad] (or rad/s, rad/s²).
    pub psi: f64,
}

impl From<Pose> for Planar {
    fn from(p: Pose) -> Self {
        Self {
            x: p.x,
            z: p.z,
            psi: p.psi,
        }
    }
}

impl From<PoseRate> for Planar {
    fn from(p: PoseRate) -> Self {
        Self {
            x: p.x,
            z: p.z,
            psi: p.psi,
        }
    }
}

/// A point x, z [m], frame S.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanarPoint {
    /// Horizontal [m].
    pub x: f64,
    /// Vertical [m].
    pub z: f64,
}

impl From<Point> for PlanarPoint {
    fn from(p: Point) -> Self {
        Self { x: p.x, z: p.z }
    }
}

/// A wrench at the grasp, frame S.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WrenchReport {
    /// Horizontal force [N].
    pub fx: f64,
    /// Vertical force [N].
    pub fz: f64,
    /// Torque about +y [N m].
    pub ty: f64,
}

impl From<Wrench> for WrenchReport {
    fn from(w: Wrench) -> Self {
        Self {
            fx: w.fx,
            fz: w.fz,
            ty: w.ty,
        }
    }
}

/// One sensor frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Measurement time stamp [s, kernel clock].
    pub time: f64,
    /// Measured grasp pose.
    pub pose: Planar,
    /// Measured external wrench at the grasp.
    pub wrench: WrenchReport,
}

impl From<PathSample> for Frame {
    fn from(s: PathSample) -> Self {
        Self {
            time: s.time,
            pose: s.pose.into(),
            wrench: s.wrench.into(),
        }
    }
}

/// How the robot treats a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Follow the set-point.
    Track,
    /// Zero motion.
    Hold,
    /// Latched stop: the set-point and wrench of its category (`stop`).
    Stop,
}

/// A set-point of the robot's impedance controller.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SetPointReport {
    /// Equilibrium pose [m, m, rad].
    pub pose: Planar,
    /// Its velocity [m/s, m/s, rad/s].
    pub velocity: Planar,
    /// Its acceleration [m/s², m/s², rad/s²].
    pub acceleration: Planar,
}

impl From<SetPoint> for SetPointReport {
    fn from(s: SetPoint) -> Self {
        Self {
            pose: s.pose.into(),
            velocity: s.velocity.into(),
            acceleration: s.acceleration.into(),
        }
    }
}

/// Saturations that acted on a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SaturationReport {
    /// The force magnitude was limited.
    pub force: bool,
    /// The torque was limited.
    pub torque: bool,
    /// The set-point speed was limited.
    pub speed: bool,
    /// An input was not finite; the wrench was replaced by zero.
    pub non_finite: bool,
}

impl From<Saturation> for SaturationReport {
    fn from(s: Saturation) -> Self {
        Self {
            force: s.force,
            torque: s.torque,
            speed: s.speed,
            non_finite: s.non_finite,
        }
    }
}

/// The kernel's command of one step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CommandReport {
    /// State after the step.
    pub state: State,
    /// How to treat it.
    pub mode: Mode,
    /// Set-point (null: hold the current position).
    pub set_point: Option<SetPointReport>,
    /// Wrench overlay at the grasp.
    pub wrench: WrenchReport,
    /// Saturations that acted.
    pub saturation: SaturationReport,
    /// In SafeStop, the stop's category (`hold`, `ramp_down`,
    /// `motors_off`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop: Option<limb_kernel::StopCategory>,
}

impl From<Command> for CommandReport {
    fn from(c: Command) -> Self {
        Self {
            state: c.state.into(),
            mode: match c.mode {
                CommandMode::Track => Mode::Track,
                CommandMode::Hold => Mode::Hold,
                CommandMode::Stop => Mode::Stop,
            },
            set_point: c.set_point.map(Into::into),
            wrench: c.wrench.into(),
            saturation: c.saturation.into(),
            stop: c.stop,
        }
    }
}

#[cfg(test)]
mod vocabulary {
    use super::*;
    use limb_kernel::arm::JointAngles;

    /// The wire's state and request names are the kernel's vocabulary
    /// (`StateKind::name`, `Request::name`), for every variant.
    #[test]
    fn states_and_requests_are_spelled_as_the_kernel_names_them() {
        let states = [
            StateKind::Grasp,
            StateKind::Estimate,
            StateKind::Validated,
            StateKind::Manipulate,
            StateKind::SafeStop,
        ];
        for kind in states {
            assert_eq!(
                serde_json::to_value(State::from(kind)).unwrap(),
                kind.name()
            );
        }
        let target = JointAngles {
            shoulder_elevation: 0.5,
            elbow_flexion: 0.5,
        };
        let requests = [
            Request::StartEstimation,
            Request::ApproveManipulation(target),
            Request::FinishManipulation,
            Request::Stop,
            Request::Reset,
        ];
        for request in requests {
            let wire = serde_json::to_value(RequestKind::from(request)).unwrap();
            assert_eq!(wire, request.name());
        }
    }
}
