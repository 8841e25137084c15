//! `limb run` on another plant than the embedded reference plant: any
//! simulator that speaks `limb-plant/1` (`../shared/spec/external-plant.md`),
//! reached by `--plant-cmd`, `--plant-tcp` or by name (`--plant myoarm
//! --subject NAME`, `--plant toy`).
//!
//! The session is the reference plant's ([`crate::session_report::session`]: the
//! same loop, operator, recorder and JSON keys); the truth is what the
//! plant's truth gives at its first frame, the joint extremes use the
//! plant's own `shoulder_elevation`/`elbow_flexion` when it gives them,
//! else plant.md's `q1`/`q2`. A plant that breaks the protocol ends the
//! session as a robot failure: the kernel is stopped, the logs hold every
//! frame up to the last good one, `--json` still prints one object
//! (`"completed": false`, `"robot_error"`) and `limb` exits 1 with one
//! line on stderr naming the plant's line and what was wrong.
//!
//! Named plants live in this repository's `plants/` folder (or the folder
//! `LIMB_PLANTS` names): `myoarm` runs `plants/myoarm/plant.py` in the
//! Python environment `plants/myoarm/setup.sh` makes (run once, on first
//! use); `toy` runs `plants/toy/toy_plant.py` with the system `python3`.

use crate::arm_model::ArmModel;
use crate::error::CliError;
use crate::session_log::LogFile;
use crate::session_report::{record_event, session, SessionReport, TrueJoints, TruthReport};
use limb_kernel::{Kernel, KernelConfig, Request};
use limb_plant::{Endpoint, PlantError, PlantRobot};
use limb_session::SessionPlan;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Duration;

/// The plant options of `limb run`.
#[derive(Debug, Clone, clap::Args)]
pub struct PlantArgs {
    /// Run on an external plant started as this command line (it speaks
    /// limb-plant/1 on its stdin/stdout).
    #[arg(long, conflicts_with_all = ["plant_tcp", "plant", "l1", "l2", "effect"])]
    pub plant_cmd: Option<String>,
    /// Run on an external plant listening at HOST:PORT.
    #[arg(long, conflicts_with_all = ["plant", "l1", "l2", "effect"])]
    pub plant_tcp: Option<String>,
    /// Run on a plant of this repository by name (`myoarm` needs --subject).
    #[arg(long, value_enum, conflicts_with_all = ["l1", "l2", "effect"])]
    pub plant: Option<NamedPlant>,
    /// The MyoArm plant's subject (`limb run --plant myoarm --subject NAME`;
    /// the list: plants/myoarm/README.md).
    #[arg(long)]
    pub subject: Option<String>,
    /// Seconds to wait for each line of an external plant, the handshake
    /// included.
    #[arg(long, default_value_t = 10.0)]
    pub plant_timeout: f64,
}

impl PlantArgs {
    /// The arm the estimator assumes by default on this plant
    /// ([`ArmModel`]): `rod` on the reference plant and `--plant toy`,
    /// `person` on any other.
    pub fn default_arm(&self) -> ArmModel {
        let rod = self.plant_cmd.is_none()
            && self.plant_tcp.is_none()
            && self.plant != Some(NamedPlant::Myoarm);
        if rod {
            ArmModel::Rod
        } else {
            ArmModel::Person
        }
    }
}

/// Plants of this repository.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NamedPlant {
    /// MuJoCo + MyoSuite's musculoskeletal arm `myoarm_r` (plants/myoarm).
    Myoarm,
    /// plant.md's arm written again in Python (plants/toy): a protocol example.
    Toy,
}

/// The repository's `plants/` folder.
fn plants_dir() -> PathBuf {
    std::env::var_os("LIMB_PLANTS").map_or_else(
        || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../plants")),
        PathBuf::from,
    )
}

/// `path` quoted for `sh`.
fn quoted(path: &std::path::Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', r"'\''"))
}

/// The plant `args` name, if any (`seed`: the session's noise seed, passed
/// to named plants).
///
/// # Errors
/// [`CliError::BadInput`] for `--plant myoarm` without `--subject`, a
/// subject on another plant, or a timeout that is not a positive number;
/// [`CliError::Internal`] when the MyoArm environment cannot be set up.
pub fn endpoint(args: &PlantArgs, seed: u64) -> Result<Option<Endpoint>, CliError> {
    if !(args.plant_timeout.is_finite() && args.plant_timeout > 0.0) {
        return Err(CliError::BadInput(format!(
            "--plant-timeout {}: not a positive number of seconds",
            args.plant_timeout
        )));
    }
    if args.subject.is_some() && args.plant != Some(NamedPlant::Myoarm) {
        return Err(CliError::BadInput("--subject needs --plant myoarm".into()));
    }
    if let Some(line) = &args.plant_cmd {
        return Ok(Some(Endpoint::Command(line.clone())));
    }
    if let Some(address) = &args.plant_tcp {
        return Ok(Some(Endpoint::Tcp(address.clone())));
    }
    match args.plant {
        None => Ok(None),
        Some(NamedPlant::Toy) => Ok(Some(Endpoint::Command(format!(
            "python3 {} --seed {seed}",
            quoted(&plants_dir().join("toy/toy_plant.py"))
        )))),
        Some(NamedPlant::Myoarm) => {
            let subject = args.subject.as_deref().ok_or_else(|| {
                CliError::BadInput(
                    "--plant myoarm needs --subject NAME (plants/myoarm/README.md)".into(),
                )
            })?;
            Ok(Some(Endpoint::Command(myoarm_command(&format!(
                "--subject {} --seed {seed}",
                quoted(std::path::Path::new(subject)),
            ))?)))
        }
    }
}

/// The MyoArm plant's command line with `options` (its environment set up
/// on first use).
///
/// # Errors
/// [`CliError::Internal`] when the environment cannot be set up.
pub fn myoarm_command(options: &str) -> Result<String, CliError> {
    let dir = plants_dir();
    let python = myoarm_python(&dir)?;
    Ok(format!(
        "{} {} {options}",
        quoted(&python),
        quoted(&dir.join("myoarm/plant.py")),
    ))
}

/// The MyoArm plant's Python, its environment set up on first use.
fn myoarm_python(dir: &std::path::Path) -> Result<PathBuf, CliError> {
    let python = dir.join("myoarm/.venv/bin/python");
    if python.exists() {
        return Ok(python);
    }
    eprintln!(
        "limb: setting up the MyoArm plant's Python environment (once): plants/myoarm/setup.sh"
    );
    let status = std::process::Command::new("bash")
        .arg(dir.join("myoarm/setup.sh"))
        .stdout(std::process::Stdio::null())
        .status()
        .map_err(|e| CliError::Internal(format!("plants/myoarm/setup.sh: {e}")))?;
    if status.success() && python.exists() {
        Ok(python)
    } else {
        Err(CliError::Internal(format!(
            "plants/myoarm/setup.sh failed ({status}): the MyoArm plant cannot run"
        )))
    }
}

impl TrueJoints for PlantRobot {
    fn true_joints(&self) -> Option<[f64; 2]> {
        let frame = self.last_frame()?;
        let own = self
            .truth_of(frame, "shoulder_elevation")
            .zip(self.truth_of(frame, "elbow_flexion"));
        let plant_md = || self.truth_of(frame, "q1").zip(self.truth_of(frame, "q2"));
        own.or_else(plant_md)
            .map(|(shoulder, elbow)| [shoulder, elbow])
    }
}

/// The truth at the plant's first frame.
fn truth_of(robot: &PlantRobot) -> TruthReport {
    let Some(frame) = robot.first_frame() else {
        return TruthReport::default();
    };
    let value = |name| robot.truth_of(frame, name);
    let point = |x, z| value(x).zip(value(z)).map(|(x, z)| [x, z]);
    TruthReport {
        l1: value("l1"),
        l2: value("l2"),
        elbow: point("elbow_x", "elbow_z"),
        shoulder: point("shoulder_x", "shoulder_z"),
    }
}

/// The plant as the report shows it.
#[derive(Debug, Clone, Serialize)]
pub struct PlantReport {
    /// The plant's name for itself (handshake).
    pub name: String,
    /// Its period [s].
    pub dt: f64,
    /// Frames the kernel stepped on.
    pub frames: u64,
    /// The reason the plant gave when it ended the session itself.
    pub end: Option<String>,
    /// Keys the plant sent that limb does not know (ignored, as the
    /// protocol says).
    pub unknown_keys: Vec<String>,
}

/// A robot failure as the report shows it.
#[derive(Debug, Clone, Serialize)]
pub struct RobotError {
    /// Stable code of the fault (`limb_plant::Fault::code`).
    pub code: &'static str,
    /// The plant's line it was seen on (1 = the handshake).
    pub line: u64,
    /// What was wrong, in words.
    pub message: String,
}

impl From<&PlantError> for RobotError {
    fn from(error: &PlantError) -> Self {
        Self {
            code: error.fault.code(),
            line: error.line,
            message: error.to_string(),
        }
    }
}

/// `limb run --json` on an external plant.
#[derive(Debug, Serialize)]
struct ExternalReport<'a> {
    #[serde(flatten)]
    session: Option<&'a SessionReport>,
    /// False when the handshake failed (the `session` keys are absent).
    #[serde(skip_serializing_if = "Option::is_none")]
    completed: Option<bool>,
    plant: Option<PlantReport>,
    robot_error: Option<RobotError>,
}

/// One session on an external plant: its report, the plant, and the robot
/// failure that ended it, if one did.
pub struct PlantSession {
    /// The session as on the reference plant.
    pub report: SessionReport,
    /// The plant (none when its handshake failed).
    pub plant: Option<PlantReport>,
    /// The robot failure, if one ended the session.
    pub failure: Option<PlantError>,
}

impl PlantSession {
    /// The JSON object of `limb run --json` on an external plant.
    pub fn json(&self) -> serde_json::Value {
        let report = ExternalReport {
            session: self.plant.as_ref().map(|_| &self.report),
            completed: self.plant.is_none().then_some(false),
            plant: self.plant.clone(),
            robot_error: self.failure.as_ref().map(RobotError::from),
        };
        serde_json::to_value(report).unwrap_or_default()
    }
}

/// Runs one session of a kernel configured by `config` on the plant at
/// `endpoint` (each wait for a line bounded by `timeout`), writing the
/// session log at `log_path` when given, with an emergency stop at session
/// time `stop_at` [s] when given.
///
/// # Errors
/// [`CliError::BadInput`] for an unusable configuration or log path. A
/// robot failure is not an error here: it is in [`PlantSession::failure`].
pub fn plant_session(
    endpoint: &Endpoint,
    config: KernelConfig,
    timeout: Duration,
    log_path: Option<&std::path::Path>,
    stop_at: Option<f64>,
) -> Result<PlantSession, CliError> {
    let plan = crate::stop_at::plan(SessionPlan::default(), stop_at);
    let mut kernel = Box::new(
        Kernel::new(config)
            .map_err(|e| CliError::BadInput(format!("kernel configuration: {e}")))?,
    );
    let mut log = LogFile::create(log_path)?;
    let mut robot = match PlantRobot::connect(endpoint, timeout, plan.timeout) {
        Ok(robot) => robot,
        Err(error) => {
            LogFile::finish(log, log_path)?;
            let (report, _) = session(&mut kernel, &mut Idle, &plan, None, None, |_| {
                TruthReport::default()
            });
            return Ok(PlantSession {
                report,
                plant: None,
                failure: Some(error),
            });
        }
    };
    let (mut report, last_now) = session(
        &mut kernel,
        &mut robot,
        &plan,
        log.as_mut(),
        stop_at,
        truth_of,
    );
    if robot.failure().is_some() {
        // The robot failed: the kernel stops (its trace says so).
        let _ = kernel.request(Request::Stop, last_now);
        while let Some(event) = kernel.pop_event() {
            record_event(&mut report, &event);
        }
        report.final_state = kernel.state().kind();
        report.completed = false;
    }
    let handshake = robot.handshake().clone();
    let ending = robot.finish(if report.completed {
        "session completed"
    } else {
        "session ended"
    });
    LogFile::finish(log, log_path)?;
    if ending.failure.is_some() {
        report.completed = false;
    }
    Ok(PlantSession {
        report,
        plant: Some(PlantReport {
            name: handshake.name,
            dt: handshake.dt,
            frames: ending.frames,
            end: ending.plant_end,
            unknown_keys: ending.unknown_keys,
        }),
        failure: ending.failure,
    })
}

/// A robot that never sends a frame (the session of a plant whose
/// handshake failed: the kernel's report with no step).
struct Idle;

impl limb_session::Robot for Idle {
    type Error = core::convert::Infallible;

    fn sense(&mut self) -> Result<limb_session::Sensed, Self::Error> {
        Ok(limb_session::Sensed::Ended)
    }

    fn actuate(&mut self, _: &limb_kernel::Command) -> Result<(), Self::Error> {
        Ok(())
    }
}

impl TrueJoints for Idle {
    fn true_joints(&self) -> Option<[f64; 2]> {
        None
    }
}

impl limb_session::log::Logged for Idle {}
