//! The scripted operator of a session: the requests a person makes of the
//! kernel while it runs on a robot (the reference plant in `limb run` and
//! the firmware, a KUKA arm behind FRI in `limb kuka run`), as a
//! [`Supervisor`].
//!
//! Theory of operation: once per kernel step, [`Operator::request`] looks
//! at the kernel's state and time and returns at most one request: start
//! the estimation once the grasp has settled, approve the manipulation
//! target once the kernel is in Validated, finish once the target has been
//! held still for [`SessionPlan::hold`]. [`Operator::observe`] records each
//! step's command (the stillness test needs it). The operator asks only
//! while the robot follows commands, and ends the session when it
//! completes or stops ([`Operator::continuing`] leaves that to the robot). [`Described`] puts a trace event into words;
//! [`FittedModel`] is the validated arm in numbers.

use crate::supervisor::Supervisor;
use core::fmt;
use limb_kernel::arm::JointAngles;
use limb_kernel::estimation::LengthUncertainty;
use limb_kernel::geometry::Point;
use limb_kernel::trace::{Event, TraceEvent};
use limb_kernel::validate::ValidatedArm;
use limb_kernel::{Command, Kernel, PathSample, Request, StateKind};

/// How the session is run.
#[derive(Clone, Copy, Debug)]
pub struct SessionPlan {
    /// Kernel rate [Hz].
    pub rate: f64,
    /// Rest before the estimation starts [s].
    pub settle: f64,
    /// Manipulation target.
    pub target: JointAngles,
    /// How long the target is held before finishing [s].
    pub hold: f64,
    /// Give up after this long [s].
    pub timeout: f64,
}

impl Default for SessionPlan {
    fn default() -> Self {
        Self {
            rate: 1000.0,
            settle: 0.1,
            target: JointAngles {
                shoulder_elevation: 1.0,
                elbow_flexion: 0.6,
            },
            hold: 1.0,
            timeout: 120.0,
        }
    }
}

/// The arm model the kernel validated, frame S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedModel {
    /// Upper-arm length l1 [m]: the glenohumeral centre at rest to the
    /// elbow's centre.
    pub upper_arm_length: f64,
    /// Forearm length l2 [m].
    pub forearm_length: f64,
    /// Shoulder [m]: the glenohumeral centre at rest (the monitors use the
    /// centre of the elbow's path, `ArmEstimate::path_shoulder`; the same
    /// point for a fixed shoulder).
    pub shoulder: Point,
    /// Elbow at t = 0 [m].
    pub elbow: Point,
    /// Standard uncertainty of l1 and l2 [m], as the kernel's estimator
    /// measured it (`limb_kernel::estimation::LengthUncertainty`); `None`
    /// when the method does not measure it.
    pub uncertainty: Option<LengthUncertainty>,
    /// The play in psi the estimator measured and read out [rad]
    /// (`limb_kernel::estimation::FitEvidence::play`); `None` when the
    /// method does not measure it.
    pub play: Option<f64>,
    /// The grasp compliance the estimator measured and read out [m/N]
    /// (`limb_kernel::estimation::FitEvidence::compliance`); `None` when
    /// the method does not measure it.
    pub compliance: Option<f64>,
    /// A yielding trunk's compliance the estimator measured and read out
    /// [m/N] (`limb_kernel::estimation::FitEvidence::trunk_compliance`);
    /// `None` when the method does not measure it.
    pub trunk_compliance: Option<f64>,
    /// The grasp's slide along the forearm the estimator measured at a
    /// slip and read out [m] (`limb_kernel::estimation::FitEvidence::
    /// grasp_slip`); `None` when the method does not measure it.
    pub grasp_slip: Option<f64>,
    /// The tilt of the arm's plane the estimator read the heights in [rad]
    /// (`limb_kernel::estimation::FitEvidence::plane_tilt`); `None` when
    /// the method does not measure it.
    pub plane_tilt: Option<f64>,
}

impl FittedModel {
    /// The model of `arm`.
    pub fn of(arm: &ValidatedArm) -> Self {
        let estimate = arm.estimate();
        Self {
            upper_arm_length: estimate.upper_arm_length,
            forearm_length: estimate.forearm_length,
            shoulder: estimate.shoulder,
            elbow: estimate.elbow,
            uncertainty: estimate.evidence.uncertainty,
            play: estimate.evidence.play,
            compliance: estimate.evidence.compliance,
            trunk_compliance: estimate.evidence.trunk_compliance,
            grasp_slip: estimate.evidence.grasp_slip,
            plane_tilt: estimate.evidence.plane_tilt,
        }
    }
}

/// The operator's memory across steps.
#[derive(Clone, Debug)]
pub struct Operator {
    plan: SessionPlan,
    asked_start: bool,
    asked_approve: bool,
    reached_target_at: Option<f64>,
    last: Option<Command>,
    ends_session: bool,
    /// Kernel time of the first step the operator saw [s]: the plan's
    /// settle time counts from it (a robot's clock may start anywhere).
    started_at: Option<f64>,
}

impl Operator {
    /// An operator following `plan` who ends the session when it
    /// completes or stops.
    pub fn new(plan: SessionPlan) -> Self {
        Self {
            plan,
            asked_start: false,
            asked_approve: false,
            reached_target_at: None,
            last: None,
            ends_session: true,
            started_at: None,
        }
    }

    /// An operator following `plan` who leaves the end of the session to
    /// the robot (a real robot keeps being answered, holding, after the
    /// session completed or stopped).
    pub fn continuing(plan: SessionPlan) -> Self {
        Self {
            ends_session: false,
            ..Self::new(plan)
        }
    }

    /// The plan.
    pub fn plan(&self) -> &SessionPlan {
        &self.plan
    }

    /// The request to make at kernel time `now` [s] in `state`, if any
    /// (each of start and approve is asked once; the start once the plan's
    /// settle time has passed since the first call).
    pub fn request(&mut self, state: StateKind, now: f64) -> Option<Request> {
        let started_at = *self.started_at.get_or_insert(now);
        match state {
            StateKind::Grasp if !self.asked_start && now - started_at >= self.plan.settle => {
                self.asked_start = true;
                Some(Request::StartEstimation)
            }
            StateKind::Validated if !self.asked_approve => {
                self.asked_approve = true;
                Some(Request::ApproveManipulation(self.plan.target))
            }
            StateKind::Manipulate => {
                let still = self
                    .last
                    .and_then(|c| c.set_point)
                    .is_some_and(|s| s.velocity.linear_speed() == 0.0 && s.velocity.psi == 0.0);
                let since = *self.reached_target_at.get_or_insert(now);
                if !still {
                    self.reached_target_at = None;
                }
                (still && now - since >= self.plan.hold).then_some(Request::FinishManipulation)
            }
            _ => None,
        }
    }

    /// Records the command of the step just taken.
    pub fn observe(&mut self, command: Command) {
        self.last = Some(command);
    }
}

impl Supervisor for Operator {
    fn before_step(&mut self, kernel: &mut Kernel, now: f64, following: bool) {
        if !following {
            return;
        }
        if let Some(request) = self.request(kernel.state().kind(), now) {
            // A refusal is recorded in the trace and shown as an event.
            let _ = kernel.request(request, now);
        }
    }

    fn after_step(&mut self, _: &Kernel, _: &PathSample, command: &Command, _: f64) {
        self.observe(*command);
    }

    fn finished(&self, state: StateKind, completed: bool) -> bool {
        self.ends_session && (completed || state == StateKind::SafeStop)
    }
}

/// A trace event in words.
#[cfg(feature = "std")]
pub fn describe(event: &TraceEvent) -> String {
    Described(event).to_string()
}

/// A trace event in words, written without allocating (the firmware
/// prints it; [`describe`] collects it).
#[derive(Clone, Copy, Debug)]
pub struct Described<'a>(pub &'a TraceEvent);

impl fmt::Display for Described<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // The kernel's vocabulary (`limb_kernel::vocabulary`).
        fmt::Display::fmt(&self.0.event, f)
    }
}

/// True when `event` ends a whole session: Manipulate → Validated.
pub fn completes_session(event: &TraceEvent) -> bool {
    matches!(
        event.event,
        Event::Transition {
            from: StateKind::Manipulate,
            to: StateKind::Validated,
            ..
        }
    )
}
