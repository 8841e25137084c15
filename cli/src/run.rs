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
use crate::session_report::{human, session, SessionReport, TrueJoints, TruthReport};
use limb_kernel::{Kernel, KernelConfig};
use limb_plant::Endpoint;
pub use limb_session::SessionPlan;
use limb_sim::robot::ReferenceRobot;
use std::time::Duration;

impl TrueJoints for ReferenceRobot<&mut limb_sim::Plant> {
    fn true_joints(&self) -> Option<[f64; 2]> {
        Some(self.plant().state().0)
    }
}

/// The truth of the reference plant's arm: its lengths, the elbow at rest
/// (on the table at the forearm's length from the grasp) and the shoulder
/// now, frame S [m].
fn arm_truth(plant: &limb_sim::Plant) -> TruthReport {
    let a = &plant.params().arm;
    let t = plant.truth();
    TruthReport {
        l1: Some(a.upper_arm_length),
        l2: Some(a.forearm_length),
        elbow: Some([a.forearm_length, 0.0]),
        shoulder: Some([t.shoulder.x, t.shoulder.z]),
    }
}

/// Runs one session of `kernel` on `plant` following `plan`, writing the
/// session log to `log` when given.
pub fn run_session(
    kernel: &mut Kernel,
    plant: &mut limb_sim::Plant,
    plan: &SessionPlan,
    log: Option<&mut Log>,
) -> SessionReport {
    run_session_stopping(kernel, plant, plan, log, None)
}

/// [`run_session`] with an emergency stop at session time `stop_at` [s]
/// when given (`--stop-at`, [`crate::stop_at`]).
pub fn run_session_stopping(
    kernel: &mut Kernel,
    plant: &mut limb_sim::Plant,
    plan: &SessionPlan,
    log: Option<&mut Log>,
    stop_at: Option<f64>,
) -> SessionReport {
    let truth = arm_truth(plant);
    let mut robot = ReferenceRobot::new(plant, plan.rate, plan.timeout);
    let (report, _) = session(kernel, &mut robot, plan, log, stop_at, |_| truth);
    report
}

/// `limb run`: the session on the reference plant.
/// `matches` are the subcommand's (where `--effect` and `--set` stand).
pub fn run(args: &RunArgs, matches: &clap::ArgMatches) -> Result<(), CliError> {
    let config = config(args)?;
    if let Some(endpoint) = crate::external::endpoint(&args.plant, args.seed)? {
        return run_external(args, &endpoint, config);
    }
    let mut params = limb_sim::PlantParameters::new(args.l1, args.l2);
    params.seed = args.seed;
    let effects = crate::simulate::effects(&args.effect, &args.set, matches)?;
    let mut plant = limb_sim::Plant::with_effects(params, effects).map_err(CliError::BadInput)?;
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

/// `limb run` on the external plant at `endpoint`.
///
/// # Errors
/// [`CliError::RobotFailure`] when the plant broke the protocol (after
/// the report is printed), [`CliError::BadInput`] for an unusable
/// configuration or log path.
fn run_external(args: &RunArgs, endpoint: &Endpoint, config: KernelConfig) -> Result<(), CliError> {
    let timeout = Duration::from_secs_f64(args.plant.plant_timeout);
    let outcome = crate::external::plant_session(
        endpoint,
        config,
        timeout,
        args.log.as_deref(),
        args.stop_at,
    )?;
    if args.json {
        print_json(&outcome.json())?;
    } else if args.digest {
        emit(&format!("{}\n", outcome.report.digest))?;
    } else if let Some(plant) = &outcome.plant {
        let header = format!(
            "limb run: external plant \"{}\" (dt {} s), kernel at {:.0} Hz, force limit {:.1} N",
            plant.name,
            plant.dt,
            SessionPlan::default().rate,
            config.limits.max_force
        );
        let mut text = human(&outcome.report, &header);
        if let Some(reason) = &plant.end {
            text.push_str(&format!("the plant ended the session: {reason}\n"));
        }
        if !plant.unknown_keys.is_empty() {
            text.push_str(&format!(
                "ignored unknown keys: {}\n",
                plant.unknown_keys.join(", ")
            ));
        }
        emit(&text)?;
    }
    match outcome.failure {
        Some(error) => Err(CliError::RobotFailure(error.to_string())),
        None => Ok(()),
    }
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
