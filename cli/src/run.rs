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
//! The loop itself is [`limb_sim::session::run`], the same `no_std` code
//! the firmware runs on a Cortex-M7; `--digest` prints the session in the
//! canonical text the firmware prints, for comparing the two.

use crate::error::{emit, print_json, CliError};
use limb_kernel::geometry::Point;
use limb_kernel::motion::SetPoint;
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::{Kernel, KernelConfig, PathSample, StateKind};
pub use limb_sim::operator::SessionPlan;
use limb_sim::operator::{describe, FittedModel};
use limb_sim::session::{self, Digest, EventLine, Observer, Outcome};
use serde::Serialize;

/// A plant the kernel can close the loop on, with its ground truth.
pub trait ClosedLoopPlant: session::ClosedLoopPlant {
    /// Ground truth: l1, l2 [m], elbow at t = 0 and shoulder [m], frame S.
    fn truth(&self) -> Truth;
}

/// Ground truth of the plant's arm.
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

/// One line of the session's record.
#[derive(Clone, Debug, Serialize)]
pub struct Line {
    /// Kernel time [s].
    pub time: f64,
    /// What happened, in words.
    pub what: String,
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
    /// Errors: l1, l2 and shoulder distance [m].
    pub error_l1: f64,
    /// Error of l2 [m].
    pub error_l2: f64,
    /// Distance between fitted and true shoulder [m].
    pub error_shoulder: f64,
}

/// The whole session.
#[derive(Clone, Debug, Serialize)]
pub struct SessionReport {
    /// Transitions, refusals and requests, in order.
    pub events: Vec<Line>,
    /// Stops caused by a monitor, in words.
    pub monitor_events: Vec<Line>,
    /// The plant's truth.
    pub truth: Truth,
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
    /// FNV-1a hash of every command issued, hex (`limb_sim::session::CommandHash`).
    pub command_hash: String,
    /// The session in the canonical text of `--digest`.
    #[serde(skip)]
    pub digest: String,
}

/// Collects the session's record for the report.
#[derive(Default)]
struct Recorder {
    events: Vec<Line>,
    monitor_events: Vec<Line>,
    digest: String,
}

impl<P: ?Sized> Observer<P> for Recorder {
    fn event(&mut self, event: &TraceEvent) {
        use std::fmt::Write;
        let line = Line {
            time: event.time,
            what: describe(event),
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

/// Runs one session of `kernel` on `plant` following `plan`.
pub fn run_session(
    kernel: &mut Kernel,
    plant: &mut dyn ClosedLoopPlant,
    plan: &SessionPlan,
) -> SessionReport {
    let truth = plant.truth();
    let mut recorder = Recorder::default();
    let outcome: Outcome = session::run(kernel, plant, plan, &mut recorder);
    let mut digest = recorder.digest;
    digest.push_str(&Digest(&outcome).to_string());
    SessionReport {
        events: recorder.events,
        monitor_events: recorder.monitor_events,
        truth,
        model: outcome.model.map(|m| model_report(&m, &truth)),
        final_state: outcome.final_state,
        completed: outcome.completed,
        saturated_commands: outcome.saturated_commands,
        steps: outcome.steps,
        command_hash: format!("{:016x}", outcome.command_hash),
        digest,
    }
}

fn model_report(model: &FittedModel, truth: &Truth) -> ModelReport {
    ModelReport {
        l1: model.upper_arm_length,
        l2: model.forearm_length,
        shoulder: [model.shoulder.x, model.shoulder.z],
        elbow: [model.elbow.x, model.elbow.z],
        error_l1: model.upper_arm_length - truth.l1,
        error_l2: model.forearm_length - truth.l2,
        error_shoulder: model
            .shoulder
            .distance(Point::new(truth.shoulder[0], truth.shoulder[1])),
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
        Some(m) => writeln!(
            out,
            "model: l1 {:.4} m (truth {:.4}, {:+.2} mm)  l2 {:.4} m (truth {:.4}, {:+.2} mm)  \
             shoulder ({:.4}, {:.4}) m (truth ({:.4}, {:.4}), {:.2} mm off)",
            m.l1,
            t.l1,
            m.error_l1 * 1e3,
            m.l2,
            t.l2,
            m.error_l2 * 1e3,
            m.shoulder[0],
            m.shoulder[1],
            t.shoulder[0],
            t.shoulder[1],
            m.error_shoulder * 1e3
        ),
        None => writeln!(out, "model: none validated"),
    };
    if report.monitor_events.is_empty() {
        let _ = writeln!(out, "monitor events: none");
    } else {
        let _ = writeln!(out, "monitor events:");
        for line in &report.monitor_events {
            let _ = writeln!(out, "  {:>8.3} s  {}", line.time, line.what);
        }
    }
    let _ = writeln!(
        out,
        "final state: {:?} after {} kernel steps ({} with saturation); session {}",
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

impl session::ClosedLoopPlant for ReferencePlant {
    fn time(&self) -> f64 {
        self.0.time()
    }

    fn measure(&mut self) -> PathSample {
        session::ClosedLoopPlant::measure(&mut self.0)
    }

    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64) {
        session::ClosedLoopPlant::advance(&mut self.0, set_point, duration);
    }
}

impl ClosedLoopPlant for ReferencePlant {
    fn truth(&self) -> Truth {
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
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let config = config(args)?;
    let mut params = limb_sim::PlantParameters::new(args.l1, args.l2);
    params.seed = args.seed;
    let plant = limb_sim::Plant::new(params).map_err(CliError::BadInput)?;
    let mut plant = ReferencePlant(plant);
    let mut kernel = Box::new(
        Kernel::new(config)
            .map_err(|e| CliError::BadInput(format!("kernel configuration: {e:?}")))?,
    );
    let plan = SessionPlan::default();
    let report = run_session(&mut kernel, &mut plant, &plan);
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
    /// Upper-arm length of the simulated person [m].
    #[arg(long, default_value_t = 0.30)]
    pub l1: f64,
    /// Forearm length (elbow to grasp) of the simulated person [m].
    #[arg(long, default_value_t = 0.20)]
    pub l2: f64,
    /// Measurement-noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Overrides the kernel's force limit [N] (e.g. below the lift force, to see a safe stop).
    #[arg(long)]
    pub max_force: Option<f64>,
    /// Print one JSON object instead of the human report.
    #[arg(long)]
    pub json: bool,
    /// Print only the session's canonical digest (events, exact model,
    /// command hash): the text the firmware prints on the target.
    #[arg(long, conflicts_with = "json")]
    pub digest: bool,
}

/// The kernel configuration for `args`, checked.
pub fn config(args: &RunArgs) -> Result<KernelConfig, CliError> {
    let mut config = KernelConfig::default();
    if let Some(max_force) = args.max_force {
        config.limits.max_force = max_force;
    }
    config
        .check()
        .map_err(|error| CliError::BadInput(format!("invalid kernel configuration: {error:?}")))?;
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
