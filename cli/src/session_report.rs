//! The report of one kernel session on any plant, as `limb run` prints it
//! (the reference plant, `crate::run`; an external plant,
//! `crate::external`): the events with their times, the fitted model
//! against the plant's truth, the step times, the person's joint extremes
//! per state and the canonical digest. [`session`] runs the session under
//! the scripted operator and records it as it runs.

use crate::session_log::Log;
use limb_kernel::geometry::Point;
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::{Command, Kernel, StateKind};
use limb_session::digest::{Digest, EventLine};
use limb_session::kernel_wire::KernelEvent;
use limb_session::operator::describe;
use limb_session::{FittedModel, Frame, Observer, Operator, SessionPlan};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// The truth a session's report compares the model with: what the plant
/// gives at the session's start, each absent when it gives none (an
/// external plant may give any of them or none).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct TruthReport {
    /// Upper-arm length [m] (an anatomical arm: glenohumeral centre to
    /// elbow centre).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub l1: Option<f64>,
    /// Forearm length, elbow centre to grasp [m].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub l2: Option<f64>,
    /// Elbow at t = 0, frame S [m].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elbow: Option<[f64; 2]>,
    /// Shoulder at t = 0, frame S [m].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shoulder: Option<[f64; 2]>,
}

/// What a session's runner reads off its robot beyond the frames.
pub trait TrueJoints {
    /// The person's true joint angles now [rad] (shoulder elevation, elbow
    /// flexion; hyperextension is a negative flexion), when the robot
    /// knows them.
    fn true_joints(&self) -> Option<[f64; 2]>;
}

/// One line of the session's record.
#[derive(Clone, Debug, Serialize)]
pub struct Line {
    /// Kernel time [s].
    pub time: f64,
    /// What happened, in words.
    pub what: String,
    /// What happened, as data: the Zenoh wire's spelling of the kernel's
    /// event (`transition` with its cause, `refused` with the refusal,
    /// `lift_ended`; PROTOCOL.md, `EventMessage.event`).
    pub event: KernelEvent,
}

/// The fitted model against the truth.
#[derive(Clone, Debug, Serialize)]
pub struct ModelReport {
    /// Fitted l1, l2 [m].
    pub l1: f64,
    /// Fitted forearm length [m].
    pub l2: f64,
    /// Fitted shoulder [m].
    pub shoulder: [f64; 2],
    /// Fitted elbow at t = 0 [m].
    pub elbow: [f64; 2],
    /// Error of l1 against the truth [m], when the truth gives l1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_l1: Option<f64>,
    /// Error of l2 [m], when the truth gives l2.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_l2: Option<f64>,
    /// Distance between fitted and true shoulder [m], when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_shoulder: Option<f64>,
    /// Distance between fitted and true elbow at t = 0 [m], when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_elbow: Option<f64>,
    /// Standard uncertainty of l1 and of l2 as the estimator measured it
    /// [m] (`limb_kernel::estimation::LengthUncertainty`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertainty_l1: Option<f64>,
    /// Of l2 [m].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertainty_l2: Option<f64>,
    /// The play in psi the estimator measured and read out [rad].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub play: Option<f64>,
    /// The grasp compliance the estimator measured and read out [m/N].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compliance: Option<f64>,
    /// A yielding trunk's compliance the estimator measured and read out
    /// [m/N].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trunk_compliance: Option<f64>,
    /// The grasp's slide along the forearm the estimator measured at a
    /// slip and read out [m].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grasp_slip: Option<f64>,
    /// The tilt of the arm's plane the estimator read the heights in [rad].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plane_tilt: Option<f64>,
}

/// Wall time of every `Kernel::step` of the session [s].
#[derive(Clone, Debug, Default, Serialize)]
pub struct StepTime {
    /// Median step.
    pub median_s: f64,
    /// 99.9th percentile.
    pub p999_s: f64,
    /// Slowest step.
    pub max_s: f64,
    /// The state the slowest step began in.
    pub max_state: Option<StateKind>,
}

/// The person's joint extremes within one state, from the plant's true
/// joints [rad].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct JointExtremes {
    /// Largest elbow hyperextension, max(0, −q2).
    pub max_hyperextension: f64,
    /// Largest shoulder elevation q1.
    pub max_shoulder_elevation: f64,
}

/// The whole session.
#[derive(Clone, Debug, Serialize)]
pub struct SessionReport {
    /// Transitions, refusals and requests, in order.
    pub events: Vec<Line>,
    /// Stops caused by a monitor, in words.
    pub monitor_events: Vec<Line>,
    /// The plant's truth.
    pub truth: TruthReport,
    /// The validated model, when one was made.
    pub model: Option<ModelReport>,
    /// State at the end.
    pub final_state: StateKind,
    /// True when the session went Grasp → … → Manipulate → Validated.
    pub completed: bool,
    /// Commands whose wrench or set-point was limited.
    pub saturated_commands: u64,
    /// Kernel steps taken.
    pub steps: u64,
    /// Wall time of the kernel's steps.
    pub step_time: StepTime,
    /// Joint extremes per state (lower-case state name).
    pub joint_extremes: BTreeMap<String, JointExtremes>,
    /// Largest measured interaction force |(fx, fz)| over the session [N].
    pub max_force_n: f64,
    /// FNV-1a hash of every command issued, hex (`limb_session::command_hash::CommandHash`).
    pub command_hash: String,
    /// The session in the canonical text of `--digest`.
    #[serde(skip)]
    pub digest: String,
    /// `--stop-at`: the emergency stop and what it did to the arm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop: Option<crate::stop_at::StopReport>,
}

/// What `limb run` records of the session as it runs.
#[derive(Default)]
struct Recorder {
    events: Vec<Line>,
    monitor_events: Vec<Line>,
    digest: String,
    started: Option<Instant>,
    durations: Vec<(f64, StateKind)>,
    joint_extremes: BTreeMap<String, JointExtremes>,
    max_force: f64,
    last_now: f64,
}

impl<R: TrueJoints + ?Sized> Observer<R> for Recorder {
    fn before_step(&mut self, _: &R, _: &Frame, _: StateKind) {
        self.started = Some(Instant::now());
    }

    fn after_step(&mut self, robot: &R, frame: &Frame, state: StateKind, _: &Command) {
        let elapsed = self.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        self.durations.push((elapsed, state));
        let w = &frame.sample.wrench;
        self.max_force = self.max_force.max(w.fx.hypot(w.fz));
        let Some([q1, q2]) = robot.true_joints() else {
            return;
        };
        let extremes = self
            .joint_extremes
            .entry(state.name().to_string())
            .or_default();
        extremes.max_hyperextension = extremes.max_hyperextension.max(-q2);
        extremes.max_shoulder_elevation = extremes.max_shoulder_elevation.max(q1);
    }

    fn stepped(&mut self, step: &limb_session::Step<'_>) {
        self.last_now = step.now;
    }

    fn event(&mut self, event: &TraceEvent) {
        use std::fmt::Write;
        let line = Line {
            time: event.time,
            what: describe(event),
            event: KernelEvent::from(*event),
        };
        if let Event::Transition {
            cause: Cause::Stop(limb_kernel::StopReason::Monitor(_)),
            ..
        } = event.event
        {
            self.monitor_events.push(line.clone());
        }
        self.events.push(line);
        let _ = writeln!(self.digest, "{}", EventLine(event));
    }
}

/// Runs one session of `kernel` on `robot` under the scripted operator
/// following `plan`, writing the session log to `log` when given; `truth`
/// reads the truth off the robot once the session is over. Returns the
/// report and the kernel time of the last step.
pub fn session<R>(
    kernel: &mut Kernel,
    robot: &mut R,
    plan: &SessionPlan,
    log: Option<&mut Log>,
    stop_at: Option<f64>,
    truth: impl FnOnce(&R) -> TruthReport,
) -> (SessionReport, f64)
where
    R: limb_session::Robot<Error = core::convert::Infallible>
        + TrueJoints
        + limb_session::log::Logged,
{
    let mut log = log;
    if let Some(log) = log.as_mut() {
        log.record("/limb/config", "limb.KernelConfig", 0.0, kernel.config());
    }
    let mut observers = (Recorder::default(), log);
    let mut supervisor = crate::stop_at::StopAt::new(Operator::new(*plan), stop_at);
    let Ok(outcome) = limb_session::run(kernel, robot, &mut supervisor, &mut observers);
    let (mut recorder, mut log) = observers;
    let truth = truth(robot);
    let mut digest = recorder.digest;
    digest.push_str(&Digest(&outcome).to_string());
    let report = SessionReport {
        events: recorder.events,
        monitor_events: recorder.monitor_events,
        truth,
        model: outcome.model.map(|m| model_report(&m, &truth)),
        final_state: outcome.final_state,
        completed: outcome.completed,
        saturated_commands: outcome.saturated_commands,
        steps: outcome.steps,
        step_time: step_time(&mut recorder.durations),
        joint_extremes: recorder.joint_extremes,
        max_force_n: recorder.max_force,
        command_hash: format!("{:016x}", outcome.command_hash),
        digest,
        stop: supervisor.report(),
    };
    if let (Some(log), Some(model)) = (log.as_mut(), &report.model) {
        log.record("/limb/model", "limb.Model", recorder.last_now, model);
    }
    (report, recorder.last_now)
}

/// Records `event` in `report` as the session's recorder would have (for
/// the events a runner causes after the loop, e.g. the stop that ends a
/// robot failure).
pub fn record_event(report: &mut SessionReport, event: &TraceEvent) {
    let mut recorder = Recorder::default();
    Observer::<dyn TrueJoints>::event(&mut recorder, event);
    report.events.append(&mut recorder.events);
    report.monitor_events.append(&mut recorder.monitor_events);
}

/// Median, 99.9th percentile and maximum of the step `durations`, with the
/// state the slowest began in.
fn step_time(durations: &mut [(f64, StateKind)]) -> StepTime {
    let Some(&(max_s, max_state)) = durations.iter().max_by(|a, b| a.0.total_cmp(&b.0)) else {
        return StepTime::default();
    };
    durations.sort_by(|a, b| a.0.total_cmp(&b.0));
    let quantile = |q: f64| {
        let index = ((durations.len() - 1) as f64 * q).round() as usize;
        durations[index.min(durations.len() - 1)].0
    };
    StepTime {
        median_s: quantile(0.5),
        p999_s: quantile(0.999),
        max_s,
        max_state: Some(max_state),
    }
}

fn model_report(model: &FittedModel, truth: &TruthReport) -> ModelReport {
    let off = |fitted: Point, truth: Option<[f64; 2]>| {
        truth.map(|[x, z]| fitted.distance(Point::new(x, z)))
    };
    ModelReport {
        l1: model.upper_arm_length,
        l2: model.forearm_length,
        shoulder: [model.shoulder.x, model.shoulder.z],
        elbow: [model.elbow.x, model.elbow.z],
        error_l1: truth.l1.map(|l1| model.upper_arm_length - l1),
        error_l2: truth.l2.map(|l2| model.forearm_length - l2),
        error_shoulder: off(model.shoulder, truth.shoulder),
        error_elbow: off(model.elbow, truth.elbow),
        uncertainty_l1: model.uncertainty.map(|u| u.upper_arm),
        uncertainty_l2: model.uncertainty.map(|u| u.forearm),
        play: model.play,
        compliance: model.compliance,
        trunk_compliance: model.trunk_compliance,
        grasp_slip: model.grasp_slip,
        plane_tilt: model.plane_tilt,
    }
}

/// The report for a person.
pub fn human(report: &SessionReport, header: &str) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(out, "{header}");
    for line in &report.events {
        let _ = writeln!(out, "  {:>8.3} s  {}", line.time, line.what);
    }
    let t = &report.truth;
    let _ = match &report.model {
        Some(m) => {
            let length = |name: &str,
                          fitted: f64,
                          uncertainty: Option<f64>,
                          truth: Option<f64>,
                          error: Option<f64>| {
                let u = uncertainty.map_or(String::new(), |u| format!(", u {:.2} mm", u * 1e3));
                match truth.zip(error) {
                    Some((truth, error)) => format!(
                        "{name} {fitted:.4} m{u} (truth {truth:.4}, {:+.2} mm)",
                        error * 1e3
                    ),
                    None => format!("{name} {fitted:.4} m{u}"),
                }
            };
            let shoulder = match t.shoulder.zip(m.error_shoulder) {
                Some(([x, z], error)) => format!(
                    "shoulder ({:.4}, {:.4}) m (truth ({x:.4}, {z:.4}), {:.2} mm off)",
                    m.shoulder[0],
                    m.shoulder[1],
                    error * 1e3
                ),
                None => format!("shoulder ({:.4}, {:.4}) m", m.shoulder[0], m.shoulder[1]),
            };
            let play = m.play.map_or(String::new(), |w| {
                format!("  play in psi {:.1} mrad", w * 1e3)
            });
            writeln!(
                out,
                "model: {}  {}  {shoulder}{play}",
                length("l1", m.l1, m.uncertainty_l1, t.l1, m.error_l1),
                length("l2", m.l2, m.uncertainty_l2, t.l2, m.error_l2),
            )
        }
        None => writeln!(out, "model: none validated"),
    };
    if let Some(s) = &report.stop {
        let _ = writeln!(
            out,
            "stop at {:.3} s in {}: {}, category {}; over the {:.1} s after it the grasp sagged {:.2} mm, max |f| {:.1} N",
            s.at,
            s.state,
            s.cause,
            s.category,
            s.watched_s,
            s.sag_m * 1e3,
            s.max_force_n
        );
    }
    if report.monitor_events.is_empty() {
        let _ = writeln!(out, "monitor events: none");
    } else {
        let _ = writeln!(out, "monitor events:");
        for line in &report.monitor_events {
            let _ = writeln!(out, "  {:>8.3} s  {}", line.time, line.what);
        }
    }
    let st = &report.step_time;
    let _ = writeln!(
        out,
        "step time (wall): median {:.2} µs, p99.9 {:.2} µs, max {:.1} µs in {}",
        st.median_s * 1e6,
        st.p999_s * 1e6,
        st.max_s * 1e6,
        st.max_state.map_or("no step", |s| s.title()),
    );
    let _ = writeln!(
        out,
        "final state: {} after {} kernel steps ({} with saturation); session {}",
        report.final_state,
        report.steps,
        report.saturated_commands,
        if report.completed {
            "completed"
        } else {
            "ended early"
        }
    );
    out
}
