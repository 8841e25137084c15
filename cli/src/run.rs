//! `limb run`: one whole kernel session on the reference plant, the
//! embedded default (no robot, no setup).
//!
//! # Theory of operation
//! The kernel, not a script, drives the session: each control period the
//! plant's measurement goes into [`Kernel::step`] and the kernel's
//! set-point drives the plant's Cartesian impedance for the next period.
//! The runner only makes the operator's requests: start the estimation
//! once the grasp is settled, approve a manipulation target once the kernel
//! is in Validated, finish once the move is held. Every transition and
//! refusal the kernel records is printed with its time and cause; the
//! fitted model is compared with the plant's ground truth.
//!
//! Time: the kernel runs at `--rate` (1 kHz, the FRI rate, by default); the
//! plant integrates at its own 0.5 ms step in between.
//!
//! The loop itself is [`limb_session::run`], the same `no_std` code the
//! firmware runs on a Cortex-M7 and every robot adapter runs; the plant is
//! its robot ([`ReferenceRobot`]), the scripted operator its supervisor.
//! This runner observes it (step wall time, joint extremes, the events)
//! and writes the session log (`--log`). `--digest` prints the session in
//! the canonical text the firmware prints, for comparing the two.

use crate::error::{emit, print_json, CliError};
use crate::session_log::{Log, LogFile};
use limb_kernel::geometry::Point;
use limb_kernel::motion::SetPoint;
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::{Command, Kernel, KernelConfig, StateKind};
use limb_session::digest::{Digest, EventLine};
use limb_session::operator::describe;
pub use limb_session::SessionPlan;
use limb_session::{FittedModel, Frame, Observer, Operator};
use limb_sim::robot::ReferenceRobot;
use limb_sim::Measurement;
use limb_zenoh::kernel_wire::KernelEvent;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// A plant the kernel can close the loop on, with its ground truth.
pub trait ClosedLoopPlant: limb_sim::closed_loop::ClosedLoopPlant {
    /// The person's true joint angles now, exact [rad]: shoulder elevation
    /// q1, elbow flexion q2.
    fn joints(&self) -> [f64; 2];
    /// Ground truth: l1, l2 [m], elbow at t = 0 and shoulder [m], frame S.
    fn arm_truth(&self) -> Truth;
}

impl<P: ClosedLoopPlant + ?Sized> ClosedLoopPlant for &mut P {
    fn joints(&self) -> [f64; 2] {
        (**self).joints()
    }

    fn arm_truth(&self) -> Truth {
        (**self).arm_truth()
    }
}

/// Ground truth of the reference plant's arm.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Truth {
    /// Upper-arm length [m].
    pub l1: f64,
    /// Forearm length [m].
    pub l2: f64,
    /// Elbow at t = 0 [m].
    pub elbow: [f64; 2],
    /// Shoulder [m].
    pub shoulder: [f64; 2],
}

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

impl From<Truth> for TruthReport {
    fn from(t: Truth) -> Self {
        Self {
            l1: Some(t.l1),
            l2: Some(t.l2),
            elbow: Some(t.elbow),
            shoulder: Some(t.shoulder),
        }
    }
}

/// What a session's runner reads off its robot beyond the frames.
pub trait TrueJoints {
    /// The person's true joint angles now [rad] (shoulder elevation, elbow
    /// flexion; hyperextension is a negative flexion), when the robot
    /// knows them.
    fn true_joints(&self) -> Option<[f64; 2]>;
}

impl<P: ClosedLoopPlant> TrueJoints for ReferenceRobot<P> {
    fn true_joints(&self) -> Option<[f64; 2]> {
        Some(self.plant().joints())
    }
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

/// Runs one session of `kernel` on `plant` following `plan`, writing the
/// session log to `log` when given.
pub fn run_session(
    kernel: &mut Kernel,
    plant: &mut dyn ClosedLoopPlant,
    plan: &SessionPlan,
    log: Option<&mut Log>,
) -> SessionReport {
    run_session_stopping(kernel, plant, plan, log, None)
}

/// [`run_session`] with an emergency stop at session time `stop_at` [s]
/// when given (`--stop-at`, [`crate::stop_at`]).
pub fn run_session_stopping(
    kernel: &mut Kernel,
    plant: &mut dyn ClosedLoopPlant,
    plan: &SessionPlan,
    log: Option<&mut Log>,
    stop_at: Option<f64>,
) -> SessionReport {
    let truth = TruthReport::from(plant.arm_truth());
    let mut robot = ReferenceRobot::new(plant, plan.rate, plan.timeout);
    let (report, _) = session(kernel, &mut robot, plan, log, stop_at, |_| truth);
    report
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
    Observer::<ReferenceRobot<ReferencePlant>>::event(&mut recorder, event);
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
            let length =
                |name: &str, fitted: f64, truth: Option<f64>, error: Option<f64>| match truth
                    .zip(error)
                {
                    Some((truth, error)) => format!(
                        "{name} {fitted:.4} m (truth {truth:.4}, {:+.2} mm)",
                        error * 1e3
                    ),
                    None => format!("{name} {fitted:.4} m"),
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
            writeln!(
                out,
                "model: {}  {}  {shoulder}",
                length("l1", m.l1, t.l1, m.error_l1),
                length("l2", m.l2, t.l2, m.error_l2),
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

/// The reference plant of `limb-sim` behind [`ClosedLoopPlant`].
pub struct ReferencePlant(pub limb_sim::Plant);

impl limb_sim::closed_loop::ClosedLoopPlant for ReferencePlant {
    fn time(&self) -> f64 {
        self.0.time()
    }

    fn measure(&mut self) -> Measurement {
        self.0.measure()
    }

    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64) {
        limb_sim::closed_loop::advance(&mut self.0, set_point, duration);
    }

    fn truth(&self) -> limb_sim::Truth {
        self.0.truth()
    }
}

impl ClosedLoopPlant for ReferencePlant {
    fn joints(&self) -> [f64; 2] {
        self.0.state().0
    }

    fn arm_truth(&self) -> Truth {
        let a = &self.0.params().arm;
        let t = self.0.truth();
        Truth {
            l1: a.upper_arm_length,
            l2: a.forearm_length,
            elbow: [a.forearm_length, 0.0],
            shoulder: [t.shoulder.x, t.shoulder.z],
        }
    }
}

/// `limb run`: the session on the reference plant.
/// `matches` are the subcommand's (where `--effect` and `--set` stand).
pub fn run(args: &RunArgs, matches: &clap::ArgMatches) -> Result<(), CliError> {
    let config = config(args)?;
    if let Some(endpoint) = crate::external::endpoint(&args.plant, args.seed)? {
        return crate::external::run(args, &endpoint, config);
    }
    let mut params = limb_sim::PlantParameters::new(args.l1, args.l2);
    params.seed = args.seed;
    let effects = crate::simulate::effects(&args.effect, &args.set, matches)?;
    let plant = limb_sim::Plant::with_effects(params, effects).map_err(CliError::BadInput)?;
    let mut plant = ReferencePlant(plant);
    let mut kernel = Box::new(
        Kernel::new(config)
            .map_err(|e| CliError::BadInput(format!("kernel configuration: {e}")))?,
    );
    let plan = crate::stop_at::plan(SessionPlan::default(), args.stop_at);
    let mut log = LogFile::create(args.log.as_deref())?;
    let report = run_session_stopping(&mut kernel, &mut plant, &plan, log.as_mut(), args.stop_at);
    LogFile::finish(log, args.log.as_deref())?;
    let header = format!(
        "limb run: reference plant, arm l1 = {:.3} m, l2 = {:.3} m, noise seed {}, kernel at {:.0} Hz, \
         force limit {:.1} N",
        args.l1, args.l2, args.seed, plan.rate, config.limits.max_force
    );
    output(&report, args, &header)
}

/// `limb run` options.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Upper-arm length of the simulated person [m] (reference plant).
    #[arg(long, default_value_t = 0.30)]
    pub l1: f64,
    /// Forearm length (elbow to grasp) of the simulated person [m].
    #[arg(long, default_value_t = 0.20)]
    pub l2: f64,
    /// Measurement-noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// An unmodelled effect of plant.md switched on in the plant
    /// (repeatable, as for `limb simulate`).
    #[arg(long)]
    pub effect: Vec<String>,
    /// A parameter KEY=VALUE of the preceding --effect (SI units).
    #[arg(long)]
    pub set: Vec<String>,
    /// Another plant than the reference plant (`external-plant.md`).
    #[command(flatten)]
    pub plant: crate::external::PlantArgs,
    /// Overrides the kernel's force limit [N] (e.g. below the lift force, to see a safe stop).
    #[arg(long)]
    pub max_force: Option<f64>,
    /// The arm the estimator assumes: `rod` (a fixed shoulder) or `person`
    /// (a shoulder that moves with elevation). Default: `rod` on the
    /// reference plant and `--plant toy`, `person` on any other plant.
    #[arg(long, value_enum)]
    pub arm: Option<crate::arm_model::ArmModel>,
    /// Print one JSON object instead of the human report.
    #[arg(long)]
    pub json: bool,
    /// Write the session (every frame's measurement, commanded set-point
    /// and the plant's truth) to this CSV in the plant.md format, and every
    /// kernel step to FILE.steps.csv beside it.
    #[arg(long)]
    pub log: Option<std::path::PathBuf>,
    /// Print only the session's canonical digest (events, exact model,
    /// command hash): the text the firmware prints on the target.
    #[arg(long, conflicts_with = "json")]
    pub digest: bool,
    /// Emergency stop at T seconds of session time, whatever the state;
    /// the session runs on 2 s to measure it (`stop` in the JSON).
    #[arg(long, value_name = "T", value_parser = crate::stop_at::parse_time)]
    pub stop_at: Option<f64>,
}

/// The kernel configuration for `args`, checked.
pub fn config(args: &RunArgs) -> Result<KernelConfig, CliError> {
    let arm = args.arm.unwrap_or_else(|| args.plant.default_arm());
    let mut config = arm.apply(KernelConfig::default());
    if let Some(max_force) = args.max_force {
        config.limits.max_force = max_force;
    }
    config
        .check()
        .map_err(|error| CliError::BadInput(format!("invalid kernel configuration: {error}")))?;
    Ok(config)
}

/// Prints `report` as JSON or for a person.
pub fn output(report: &SessionReport, args: &RunArgs, header: &str) -> Result<(), CliError> {
    if args.json {
        print_json(report)
    } else if args.digest {
        emit(&format!("{}\n", report.digest))
    } else {
        emit(&human(report, header))
    }
}
