//! `limb kuka ...`: tools for the KUKA FRI adapter (`limb-kuka`).

use clap::Subcommand;
use limb_kuka::messages::{
    ClientCommandMode, ConnectionQuality, FriCommandMessage, FriMonitoringMessage, JointValues,
    MessageHeader, SessionState,
};
use limb_kuka::session::{CommandIntent, Controller, MonitoringView};
use limb_kuka::udp::{CycleOutcome, FriClient};
use limb_kuka::vectors::{example_command, example_monitoring, SESSION_STATES};
use limb_kuka::{decode_command, decode_monitoring, encode_command, encode_monitoring, FriVersion};
use serde_json::{json, Value};
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use crate::error::{print_json, CliError};

/// KUKA FRI subcommands.
#[derive(Subcommand)]
pub enum KukaCommand {
    /// Decode one FRI datagram (monitoring or command) into JSON.
    Decode {
        /// Raw datagram file.
        file: std::path::PathBuf,
        /// FRI version: 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7.
        #[arg(long = "fri-version")]
        fri_version: String,
        /// Print JSON (the only output format).
        #[arg(long)]
        json: bool,
    },
    /// Write example monitoring and command datagrams (`.bin`) and their
    /// contents (`.json`) for each session state into DIR.
    Vectors {
        /// Output directory (created if missing).
        dir: std::path::PathBuf,
        /// FRI version: 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7.
        #[arg(long = "fri-version")]
        fri_version: String,
    },
    /// Run the FRI client with a placeholder controller that holds position
    /// (the kernel is not plugged in yet); prints a cycle summary as JSON.
    Run {
        /// FRI version: 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7.
        #[arg(long = "fri-version")]
        fri_version: String,
        /// UDP port to listen on (all interfaces).
        #[arg(long, default_value_t = 30200)]
        port: u16,
        /// Stop after this many seconds.
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
    },
}

/// Placeholder controller: always holds (IPO / last target).
struct HoldController {
    stale_calls: u64,
}

impl Controller for HoldController {
    fn on_monitoring(&mut self, _view: &MonitoringView, _now: f64) -> CommandIntent {
        CommandIntent::Hold
    }
    fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {
        self.stale_calls += 1;
    }
}

/// Largest target change per reply of the placeholder run (rad).
const RUN_MAX_JOINT_STEP: f64 = 0.001;

fn run_client(fri_version: &str, port: u16, seconds: f64) -> Result<(), CliError> {
    let version = parse_version(fri_version)?;
    let duration = Duration::try_from_secs_f64(seconds)
        .map_err(|error| CliError::BadInput(format!("--seconds {seconds}: {error}")))?;
    let address = SocketAddr::from(([0, 0, 0, 0], port));
    let mut client = FriClient::bind(
        address,
        version,
        RUN_MAX_JOINT_STEP,
        Duration::from_millis(100),
    )
    .map_err(|error| CliError::BadInput(format!("{address}: {error}")))?;
    let mut controller = HoldController { stale_calls: 0 };
    let (mut answered, mut rejected, mut faults) = (0u64, 0u64, 0u64);
    let start = Instant::now();
    while start.elapsed() < duration {
        match client
            .run_cycle(&mut controller)
            .map_err(|error| CliError::Internal(error.to_string()))?
        {
            CycleOutcome::Handled {
                answered: sent,
                fault,
                ..
            } => {
                answered += u64::from(sent);
                faults += u64::from(fault.is_some());
            }
            CycleOutcome::Rejected(_) => rejected += 1,
            CycleOutcome::Stale => {}
        }
    }
    print_json(&json!({
        "fri_version": version.to_string(),
        "answered": answered,
        "rejected": rejected,
        "faults": faults,
        "stale": controller.stale_calls,
    }))
}

/// Runs one `limb kuka` subcommand.
pub fn run(command: KukaCommand) -> Result<(), CliError> {
    match command {
        KukaCommand::Decode {
            file,
            fri_version,
            json: _,
        } => decode(&file, &fri_version),
        KukaCommand::Vectors { dir, fri_version } => vectors(&dir, &fri_version),
        KukaCommand::Run {
            fri_version,
            port,
            seconds,
        } => run_client(&fri_version, port, seconds),
    }
}

fn parse_version(text: &str) -> Result<FriVersion, CliError> {
    text.parse()
        .map_err(|error| CliError::BadInput(format!("{error}")))
}

fn vectors(dir: &std::path::Path, fri_version: &str) -> Result<(), CliError> {
    let version = parse_version(fri_version)?;
    std::fs::create_dir_all(dir)
        .map_err(|error| CliError::BadInput(format!("{}: {error}", dir.display())))?;
    let mut written = Vec::new();
    for state in SESSION_STATES {
        let name = screaming_snake(&format!("{state:?}")).to_lowercase();
        let monitoring = example_monitoring(state, version);
        let bytes = encode_monitoring(&monitoring, version)
            .map_err(|error| CliError::Internal(error.to_string()))?;
        written.push(write_pair(
            dir,
            &format!("monitoring_{name}"),
            &bytes,
            &monitoring_json(&monitoring),
        )?);
        if let Some(command) = example_command(state, version) {
            let bytes = encode_command(&command, version)
                .map_err(|error| CliError::Internal(error.to_string()))?;
            written.push(write_pair(
                dir,
                &format!("command_{name}"),
                &bytes,
                &command_json(&command),
            )?);
        }
    }
    print_json(&json!({ "fri_version": version.to_string(), "written": written }))
}

fn write_pair(
    dir: &std::path::Path,
    stem: &str,
    bytes: &[u8],
    contents: &Value,
) -> Result<String, CliError> {
    let write = |path: std::path::PathBuf, data: &[u8]| {
        std::fs::write(&path, data)
            .map_err(|error| CliError::BadInput(format!("{}: {error}", path.display())))
    };
    write(dir.join(format!("{stem}.bin")), bytes)?;
    let text = serde_json::to_string_pretty(contents)
        .map_err(|error| CliError::Internal(format!("serialising JSON: {error}")))?;
    write(dir.join(format!("{stem}.json")), text.as_bytes())?;
    Ok(stem.to_string())
}

fn decode(file: &std::path::Path, fri_version: &str) -> Result<(), CliError> {
    let version = parse_version(fri_version)?;
    let bytes = std::fs::read(file)
        .map_err(|error| CliError::BadInput(format!("{}: {error}", file.display())))?;
    let value = match decode_monitoring(&bytes, version) {
        Ok(message) => monitoring_json(&message),
        Err(monitoring_error) => match decode_command(&bytes, version) {
            Ok(message) => command_json(&message),
            Err(command_error) => {
                return Err(CliError::BadInput(format!(
                    "{}: not an FRI {version} datagram (as monitoring: {monitoring_error}; as command: {command_error})",
                    file.display()
                )))
            }
        },
    };
    print_json(&value)
}

fn header_json(header: &MessageHeader) -> Value {
    json!({
        "message_identifier": header.message_identifier,
        "sequence_counter": header.sequence_counter,
        "reflected_sequence_counter": header.reflected_sequence_counter,
    })
}

fn joints_json(values: Option<&JointValues>) -> Value {
    values.map_or(Value::Null, |values| json!(values.value))
}

fn enum_name<E: core::fmt::Debug>(raw: i32, convert: impl Fn(i32) -> Option<E>) -> Value {
    match convert(raw) {
        Some(known) => json!(screaming_snake(&format!("{known:?}"))),
        None => json!(raw),
    }
}

/// `MonitoringWait` → `MONITORING_WAIT`.
fn screaming_snake(camel: &str) -> String {
    let mut out = String::new();
    for (index, character) in camel.chars().enumerate() {
        if character.is_uppercase() && index > 0 {
            out.push('_');
        }
        out.push(character.to_ascii_uppercase());
    }
    out
}

fn monitoring_json(message: &FriMonitoringMessage) -> Value {
    let info = message.connection_info.unwrap_or_default();
    let monitor = message.monitor_data.clone().unwrap_or_default();
    let ipo = message.ipo_data.clone().unwrap_or_default();
    json!({
        "message": "FRIMonitoringMessage",
        "header": header_json(&message.header),
        "connection_info": {
            "session_state": enum_name(info.session_state, |raw| SessionState::try_from(raw).ok()),
            "quality": enum_name(info.quality, |raw| ConnectionQuality::try_from(raw).ok()),
            "send_period": info.send_period,
            "receive_multiplier": info.receive_multiplier,
        },
        "monitor_data": {
            "measured_joint_position": joints_json(monitor.measured_joint_position.as_ref()),
            "measured_torque": joints_json(monitor.measured_torque.as_ref()),
            "commanded_joint_position": joints_json(monitor.commanded_joint_position.as_ref()),
            "external_torque": joints_json(monitor.external_torque.as_ref()),
        },
        "ipo_data": {
            "joint_position": joints_json(ipo.joint_position.as_ref()),
            "client_command_mode": ipo.client_command_mode
                .map(|raw| enum_name(raw, |raw| ClientCommandMode::try_from(raw).ok())),
            "tracking_performance": ipo.tracking_performance,
        },
    })
}

fn command_json(message: &FriCommandMessage) -> Value {
    let data = message.command_data.clone().unwrap_or_default();
    json!({
        "message": "FRICommandMessage",
        "header": header_json(&message.header),
        "command_data": {
            "joint_position": joints_json(data.joint_position.as_ref()),
            "joint_torque": joints_json(data.joint_torque.as_ref()),
            "cartesian_wrench_feed_forward": data.cartesian_wrench_feed_forward
                .map(|vector| json!(vector.element)),
        },
    })
}
