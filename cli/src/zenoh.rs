//! `limb zenoh ...`: run a supervised node on the reference plant (a
//! `limb-session` session starting in Grasp), send a supervisory command or
//! an emergency stop, query a node. [`NodeLink`] is the Zenoh side any
//! robot command can take (`limb kuka run --zenoh`). The wire
//! contract is `adapters/zenoh/PROTOCOL.md`.
//!
//! ```sh
//! limb zenoh node  --robot arm1 --listen tcp/127.0.0.1:7447 --key-file key --seconds 60
//! limb zenoh send  --robot arm1 --connect tcp/127.0.0.1:7447 --key-file key approve 0.6 0.8
//! limb zenoh estop --robot arm1 --connect tcp/127.0.0.1:7447
//! limb zenoh query --robot arm1 --connect tcp/127.0.0.1:7447 state
//! ```

use crate::error::{print_json, CliError};
use crate::session_log::LogFile;
use clap::{Args, Subcommand, ValueEnum};
use limb_kernel::{Kernel, KernelConfig};
use limb_session::kernel_wire::{Joints, State};
use limb_sim::robot::ReferenceRobot;
use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::{Link, LinkSettings, SampleQos};
use limb_zenoh::node::Node;
use limb_zenoh::session::peer_config;
use limb_zenoh::supervision::{LivenessPolicy, OnSupervisorLoss, Supervision};
use limb_zenoh::supervisor::SupervisorStation;
use limb_zenoh::wire::{SupervisorCommand, WireFormat};
use limb_zenoh::AdapterError;
use std::path::PathBuf;
use std::time::Duration;

/// How long a command waits for its ack or a query for its answer.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(3);
/// Zenoh lease [ms]: a dead peer is noticed after about this long.
const LEASE_MS: u64 = 1000;

/// `limb zenoh` arguments.
#[derive(Args)]
pub struct ZenohArgs {
    #[command(subcommand)]
    action: Action,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Json,
    Cbor,
}

impl From<Format> for WireFormat {
    fn from(format: Format) -> Self {
        match format {
            Format::Json => WireFormat::Json,
            Format::Cbor => WireFormat::Cbor,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum Policy {
    Stop,
    Continue,
}

/// Where and as whom.
#[derive(Args)]
struct Peer {
    /// Robot id (key prefix `limb/<robot>/@v2`).
    #[arg(long)]
    robot: String,
    /// Endpoints to connect to, e.g. tcp/127.0.0.1:7447.
    #[arg(long)]
    connect: Vec<String>,
    /// Payload encoding.
    #[arg(long, value_enum, default_value = "json")]
    format: Format,
    /// Zenoh's own JSON5 configuration file (user/password, TLS, access
    /// control, mode, scouting); `--connect` endpoints are added to it.
    #[arg(long)]
    zenoh_config: Option<PathBuf>,
}

/// The Zenoh session configuration: Zenoh's own JSON5 file when given
/// (its endpoints replaced by `listen`/`connect` where those are given),
/// else limb's peer configuration (peer mode, explicit endpoints, no
/// scouting).
fn session_config(
    file: Option<&PathBuf>,
    listen: &[String],
    connect: &[String],
) -> Result<limb_zenoh::zenoh::Config, CliError> {
    let Some(file) = file else {
        return peer_config(listen, connect, LEASE_MS).map_err(bad_input);
    };
    let mut config = limb_zenoh::zenoh::Config::from_file(file)
        .map_err(|e| CliError::BadInput(format!("{}: {e}", file.display())))?;
    for (key, endpoints) in [("listen/endpoints", listen), ("connect/endpoints", connect)] {
        if !endpoints.is_empty() {
            let list = serde_json::to_string(endpoints)
                .map_err(|e| CliError::Internal(format!("endpoints: {e}")))?;
            config
                .insert_json5(key, &list)
                .map_err(|e| CliError::BadInput(format!("{}: {key}: {e}", file.display())))?;
        }
    }
    Ok(config)
}

/// The Zenoh side of a robot's session: who supervises it and how
/// (`--robot` and `--key-file` are required where it is used).
#[derive(Args)]
pub struct NodeLink {
    /// Robot id (key prefix `limb/<robot>/@v2`).
    #[arg(long)]
    robot: Option<String>,
    /// Endpoints to connect to, e.g. tcp/127.0.0.1:7447.
    #[arg(long)]
    connect: Vec<String>,
    /// Payload encoding.
    #[arg(long, value_enum, default_value = "json")]
    format: Format,
    /// Endpoints to listen on, e.g. tcp/127.0.0.1:7447.
    #[arg(long)]
    listen: Vec<String>,
    /// File holding the shared command secret (at least 16 bytes).
    #[arg(long)]
    key_file: Option<PathBuf>,
    /// What to do when the supervisor's heartbeat stops.
    #[arg(long, value_enum, default_value = "stop")]
    on_supervisor_loss: Policy,
    /// Supervisor heartbeat timeout [s].
    #[arg(long, default_value_t = 0.25)]
    liveness_timeout: f64,
    /// Zenoh's own JSON5 configuration file (access control, user/password
    /// dictionary, TLS, mode); `--listen`/`--connect` endpoints are added
    /// to it.
    #[arg(long)]
    zenoh_config: Option<PathBuf>,
}

impl NodeLink {
    /// Opens the link for a kernel configured with `config`.
    ///
    /// # Errors
    /// [`CliError::BadInput`] for a bad setting, key file or endpoint.
    pub fn open(&self, config: KernelConfig) -> Result<(Link, Supervision), CliError> {
        let (zenoh_config, settings) = self.settings()?;
        Link::open(zenoh_config, &settings, config).map_err(bad_input)
    }

    fn settings(&self) -> Result<(limb_zenoh::zenoh::Config, LinkSettings), CliError> {
        let required = |flag: &str| CliError::BadInput(format!("{flag} is required"));
        let settings = LinkSettings {
            robot_id: self.robot.clone().ok_or_else(|| required("--robot"))?,
            format: self.format.into(),
            command_key: read_key(
                self.key_file
                    .as_ref()
                    .ok_or_else(|| required("--key-file"))?,
            )?,
            sample_decimation: 1,
            sample_qos: SampleQos::BATCHED,
            status_period: 0.1,
            liveness: LivenessPolicy {
                timeout: positive_duration(self.liveness_timeout, "--liveness-timeout")?,
                on_loss: match self.on_supervisor_loss {
                    Policy::Stop => OnSupervisorLoss::Stop,
                    Policy::Continue => OnSupervisorLoss::Continue,
                },
            },
        };
        let config = session_config(self.zenoh_config.as_ref(), &self.listen, &self.connect)?;
        Ok((config, settings))
    }
}

#[derive(Subcommand)]
enum Action {
    /// Run a node: the reference plant in Grasp, supervised, for a while.
    Node {
        #[command(flatten)]
        link: NodeLink,
        /// Control rate [Hz].
        #[arg(long, default_value_t = 1000.0)]
        rate: f64,
        /// Run time [s].
        #[arg(long, default_value_t = 60.0)]
        seconds: f64,
        /// Upper-arm length of the simulated person [m].
        #[arg(long, default_value_t = 0.30)]
        l1: f64,
        /// Forearm length of the simulated person [m].
        #[arg(long, default_value_t = 0.20)]
        l2: f64,
        /// Measurement-noise seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write the session log (plant.md CSV, with the plant's truth) to
        /// this file, and every kernel step to FILE.steps.csv beside it.
        #[arg(long)]
        log: Option<PathBuf>,
    },
    /// Send one signed command and print its ack.
    Send {
        #[command(flatten)]
        peer: Peer,
        /// File holding the shared command secret.
        #[arg(long)]
        key_file: PathBuf,
        #[command(subcommand)]
        command: CommandArg,
    },
    /// Send an emergency stop (unsigned) and print its ack.
    Estop {
        #[command(flatten)]
        peer: Peer,
    },
    /// Query a node's state, configuration or arm model.
    Query {
        #[command(flatten)]
        peer: Peer,
        /// What to ask for.
        #[arg(value_enum)]
        what: QueryArg,
    },
}

#[derive(Subcommand)]
enum CommandArg {
    /// Grasp → Estimate.
    StartEstimation,
    /// Validated → Manipulate to these joint angles [rad].
    Approve {
        shoulder_elevation: f64,
        elbow_flexion: f64,
    },
    /// Manipulate → Validated.
    Finish,
    /// Any state → SafeStop (signed operator stop).
    Stop,
    /// SafeStop → Grasp.
    Reset,
}

#[derive(Clone, Copy, ValueEnum)]
enum QueryArg {
    State,
    Config,
    Arm,
}

fn internal(error: AdapterError) -> CliError {
    CliError::Internal(error.to_string())
}

fn bad_input(error: AdapterError) -> CliError {
    CliError::BadInput(error.to_string())
}

fn read_key(path: &PathBuf) -> Result<CommandKey, CliError> {
    let bytes =
        std::fs::read(path).map_err(|e| CliError::BadInput(format!("{}: {e}", path.display())))?;
    CommandKey::new(bytes.trim_ascii())
        .map_err(|e| CliError::BadInput(format!("{}: {e}", path.display())))
}

fn supervisor(peer: &Peer, key: CommandKey) -> Result<SupervisorStation, CliError> {
    let config = session_config(peer.zenoh_config.as_ref(), &[], &peer.connect)?;
    let supervisor = SupervisorStation::connect(config, &peer.robot, peer.format.into(), key)
        .map_err(bad_input)?;
    supervisor.wait_for_node(ANSWER_TIMEOUT).map_err(internal)?;
    Ok(supervisor)
}

/// Runs `limb zenoh ...`.
pub fn run(args: ZenohArgs) -> Result<(), CliError> {
    match args.action {
        Action::Node {
            link,
            rate,
            seconds,
            l1,
            l2,
            seed,
            log,
        } => {
            let period = positive_duration(1.0 / rate, "--rate")?;
            let run_time = positive_duration(seconds, "--seconds")?;
            let (config, settings) = link.settings()?;
            let mut params = limb_sim::PlantParameters::new(l1, l2);
            params.seed = seed;
            let plant = limb_sim::Plant::new(params).map_err(CliError::BadInput)?;
            let kernel = Box::new(
                Kernel::new(KernelConfig::default())
                    .map_err(|e| CliError::BadInput(format!("kernel configuration: {e}")))?,
            );
            let robot = ReferenceRobot::new(plant, rate, f64::INFINITY);
            let observer = LogFile::create(log.as_deref())?;
            let node =
                Node::spawn_observed(config, &settings, Some(period), kernel, robot, observer)
                    .map_err(bad_input)?;
            std::thread::sleep(run_time);
            let (kernel, observer) = node.finish().map_err(internal)?;
            LogFile::finish(observer, log.as_deref())?;
            print_json(&serde_json::json!({ "state": State::from(kernel.state().kind()) }))
        }
        Action::Send {
            peer,
            key_file,
            command,
        } => {
            let command = match command {
                CommandArg::StartEstimation => SupervisorCommand::StartEstimation,
                CommandArg::Approve {
                    shoulder_elevation,
                    elbow_flexion,
                } => SupervisorCommand::ApproveManipulation {
                    target: Joints {
                        shoulder_elevation,
                        elbow_flexion,
                    },
                },
                CommandArg::Finish => SupervisorCommand::FinishManipulation,
                CommandArg::Stop => SupervisorCommand::Stop,
                CommandArg::Reset => SupervisorCommand::Reset,
            };
            let mut supervisor = supervisor(&peer, read_key(&key_file)?)?;
            let ack = supervisor
                .request(command, ANSWER_TIMEOUT)
                .map_err(internal)?;
            supervisor.close().map_err(internal)?;
            print_json(&ack)
        }
        Action::Estop { peer } => {
            let mut supervisor = supervisor(&peer, unsigned_key()?)?;
            let sequence = supervisor.emergency_stop().map_err(internal)?;
            let ack = supervisor
                .wait_ack(|a| a.sequence == Some(sequence), ANSWER_TIMEOUT)
                .map_err(internal)?;
            supervisor.close().map_err(internal)?;
            print_json(&ack)
        }
        Action::Query { peer, what } => {
            let supervisor = supervisor(&peer, unsigned_key()?)?;
            let keys = supervisor.keys();
            let key = match what {
                QueryArg::State => keys.state(),
                QueryArg::Config => keys.config(),
                QueryArg::Arm => keys.arm(),
            };
            let answer = supervisor.query::<serde_json::Value>(&key, ANSWER_TIMEOUT);
            let answer = answer.map_err(internal)?;
            supervisor.close().map_err(internal)?;
            print_json(&answer)
        }
    }
}

/// A placeholder key for sessions that sign nothing (e-stops and queries
/// are not signed).
fn unsigned_key() -> Result<CommandKey, CliError> {
    CommandKey::new(&[0; 16]).map_err(internal)
}

fn positive_duration(seconds: f64, flag: &str) -> Result<Duration, CliError> {
    Duration::try_from_secs_f64(seconds)
        .ok()
        .filter(|d| !d.is_zero())
        .ok_or_else(|| CliError::BadInput(format!("{flag} must be a positive number")))
}
