//! `limb kuka ...`: tools for the KUKA FRI adapter (`limb-kuka`).

use clap::Subcommand;
use limb_kuka::faults::parse_schedule;
use limb_kuka::messages::{
    ClientCommandMode, ConnectionQuality, FriCommandMessage, FriMonitoringMessage, JointValues,
    MessageHeader, SessionState,
};
use limb_kuka::robot::{ArrivalClock, FriRobot, Overlay};
use limb_kuka::sim_controller::{Pacing, SimController, SimSettings};
use limb_kuka::udp::{
    ClientCounts, FriClient, CLIENT_RECEIVE_TIMEOUT, MAX_JOINT_STEP, UNPACED_CLIENT_RECEIVE_TIMEOUT,
};
use limb_kuka::vectors::{example_command, example_monitoring, SESSION_STATES};
use limb_kuka::{decode_command, decode_monitoring, encode_command, encode_monitoring, FriVersion};
use limb_session::SessionPlan;
use limb_sim::PlantParameters;
use serde_json::{json, Value};
use std::net::SocketAddr;
use std::time::Duration;

use crate::error::{print_json, CliError};
use crate::robot_session::{run_robot, SessionArgs};

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
    /// Run the FRI client with the kernel inside against a robot controller
    /// (the grasp must be closed at start: the first measured flange pose
    /// is frame S); prints a cycle and session summary as JSON.
    Run {
        /// FRI version: 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7.
        #[arg(long = "fri-version")]
        fri_version: String,
        /// UDP port to listen on (all interfaces).
        #[arg(long, default_value_t = 30200)]
        port: u16,
        /// Stop after this many seconds.
        #[arg(long, default_value_t = 60.0)]
        seconds: f64,
        /// How the kernel's output is sent: joint-position or wrench.
        #[arg(long, default_value = "joint-position")]
        overlay: String,
        /// Heading of frame S's x axis (wrist → shoulder) about the robot
        /// base z axis [rad].
        #[arg(long, default_value_t = limb_kuka::sim_controller::DEFAULT_HEADING)]
        heading: f64,
        #[command(flatten)]
        session: SessionArgs,
    },
    /// Run the simulated FRI controller (robot side, reference plant,
    /// optional faults) sending to a client; prints counts and round-trip
    /// latency as JSON.
    SimController {
        /// FRI version: 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7.
        #[arg(long = "fri-version")]
        fri_version: String,
        /// The client's address.
        #[arg(long, default_value = "127.0.0.1:30200")]
        client: SocketAddr,
        /// Local UDP port (0: any).
        #[arg(long, default_value_t = 0)]
        port: u16,
        /// Controller cycles to run (one per send period).
        #[arg(long, default_value_t = 60_000)]
        cycles: u64,
        /// Send period [ms].
        #[arg(long = "send-period", default_value_t = 1)]
        send_period: u32,
        /// Command mode the robot expects: joint-position or wrench.
        #[arg(long, default_value = "joint-position")]
        overlay: String,
        /// Fault schedule, e.g. `burst-loss@2000:50,idle@5000:100` (see
        /// the limb-kuka README).
        #[arg(long, default_value = "")]
        faults: String,
        /// Seed of the faults' random choices.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Do not pace: next cycle as soon as the reply is in.
        #[arg(long)]
        unpaced: bool,
        /// Upper-arm length of the simulated person [m].
        #[arg(long, default_value_t = 0.30)]
        l1: f64,
        /// Forearm length of the simulated person [m].
        #[arg(long, default_value_t = 0.20)]
        l2: f64,
    },
}

fn parse_overlay(text: &str) -> Result<Overlay, CliError> {
    match text {
        "joint-position" => Ok(Overlay::JointPosition),
        "wrench" => Ok(Overlay::Wrench),
        other => Err(CliError::BadInput(format!(
            "--overlay {other}: expected joint-position or wrench"
        ))),
    }
}

/// Options of `limb kuka run`.
struct ClientOptions<'a> {
    fri_version: &'a str,
    port: u16,
    seconds: f64,
    overlay: &'a str,
    heading: f64,
    session: &'a SessionArgs,
}

fn run_client(options: &ClientOptions<'_>) -> Result<(), CliError> {
    let version = parse_version(options.fri_version)?;
    let overlay = parse_overlay(options.overlay)?;
    let duration = Duration::try_from_secs_f64(options.seconds)
        .map_err(|error| CliError::BadInput(format!("--seconds {}: {error}", options.seconds)))?;
    let heading = options.heading;
    if !heading.is_finite() {
        return Err(CliError::BadInput(format!(
            "--heading {heading}: not finite"
        )));
    }
    let clock = options.session.clock()?;
    let receive_timeout = match clock {
        ArrivalClock::Host => CLIENT_RECEIVE_TIMEOUT,
        ArrivalClock::Robot => UNPACED_CLIENT_RECEIVE_TIMEOUT,
    };
    let address = SocketAddr::from(([0, 0, 0, 0], options.port));
    let client = FriClient::bind(address, version, MAX_JOINT_STEP, receive_timeout)
        .map_err(|error| CliError::BadInput(format!("{address}: {error}")))?;
    let mut robot = FriRobot::new(client, overlay, heading, Some(duration));
    robot.arrival_clock(clock);
    let session = run_robot(&mut robot, options.session, SessionPlan::default())?;
    let outcome = session
        .outcome
        .map_err(|error| CliError::Internal(error.to_string()))?;
    let (kernel, events) = (session.kernel, session.events);
    let record = robot.record();
    print_json(&json!({
        "fri_version": version.to_string(),
        "overlay": overlay.name(),
        "client": counts_json(&record.client),
        "kernel_state": kernel.state().kind().title(),
        "kernel_steps": outcome.steps,
        "stale_steps": outcome.stale_steps,
        "missing_measurements": record.missing_measurements,
        "inverse_failures": record.inverse_failures,
        "overlay_lost_stops": outcome.unfollowed_stops,
        "events": events.json(),
        "model": outcome.model.map(|m| json!({
            "l1": m.upper_arm_length, "l2": m.forearm_length,
            "shoulder": [m.shoulder.x, m.shoulder.z], "elbow": [m.elbow.x, m.elbow.z],
        })),
    }))
}

fn counts_json(counts: &ClientCounts) -> Value {
    json!({
        "handled": counts.handled,
        "answered": counts.answered,
        "rejected": counts.rejected,
        "timeouts": counts.timeouts,
        "duplicates": counts.duplicates,
        "stale_datagrams": counts.stale_datagrams,
        "gaps": counts.gaps,
        "resynchronisations": counts.resynchronisations,
        "session_faults": counts.session_faults,
    })
}

/// Options of `limb kuka sim-controller`.
struct SimOptions<'a> {
    fri_version: &'a str,
    client: SocketAddr,
    port: u16,
    cycles: u64,
    send_period: u32,
    overlay: &'a str,
    faults: &'a str,
    seed: u64,
    unpaced: bool,
    l1: f64,
    l2: f64,
}

fn run_sim_controller(options: &SimOptions<'_>) -> Result<(), CliError> {
    let version = parse_version(options.fri_version)?;
    if !(1..=100).contains(&options.send_period) {
        return Err(CliError::BadInput(format!(
            "--send-period {}: 1..100 ms",
            options.send_period
        )));
    }
    let mut settings = SimSettings::new(version);
    settings.send_period_ms = options.send_period;
    settings.overlay = parse_overlay(options.overlay)?;
    settings.pacing = if options.unpaced {
        Pacing::AsFastAsPossible
    } else {
        Pacing::RealTime
    };
    settings.faults = parse_schedule(options.faults, options.seed)
        .map_err(|error| CliError::BadInput(error.to_string()))?;
    let mut plant = PlantParameters::new(options.l1, options.l2);
    plant.check().map_err(CliError::BadInput)?;
    plant.seed = options.seed;
    let address = SocketAddr::from(([0, 0, 0, 0], options.port));
    let mut sim = SimController::bind(address, options.client, settings, plant)
        .map_err(|error| CliError::BadInput(format!("{address}: {error}")))?;
    for _ in 0..options.cycles {
        sim.run_cycle()
            .map_err(|error| CliError::Internal(error.to_string()))?;
    }
    let stats = sim.stats();
    let latency = stats.latency();
    let truth = sim.plant().truth();
    print_json(&json!({
        "fri_version": version.to_string(),
        "cycles": stats.cycles,
        "state_cycles": {
            "idle": stats.state_cycles[0],
            "monitoring_wait": stats.state_cycles[1],
            "monitoring_ready": stats.state_cycles[2],
            "commanding_wait": stats.state_cycles[3],
            "commanding_active": stats.state_cycles[4],
        },
        "datagrams_sent": stats.datagrams_sent,
        "datagrams_dropped": stats.datagrams_dropped,
        "garbage_sent": stats.garbage_sent,
        "replies_on_time": stats.replies_on_time,
        "missed_cycles": stats.missed_cycles,
        "missed_with_delivery": stats.missed_with_delivery,
        "stray_replies": stats.stray_replies,
        "non_finite_replies": stats.non_finite_replies,
        "overlay_aborts": stats.overlay_aborts,
        "commanding_entries": stats.commanding_entries,
        "max_entry_jump_rad": stats.max_entry_jump,
        "round_trip_us": {
            "samples": latency.samples,
            "p50": latency.p50_us,
            "p99": latency.p99_us,
            "max": latency.max_us,
        },
        "truth": {
            "l1": options.l1,
            "l2": options.l2,
            "shoulder": [truth.shoulder.x, truth.shoulder.z],
        },
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
            overlay,
            heading,
            session,
        } => run_client(&ClientOptions {
            fri_version: &fri_version,
            port,
            seconds,
            overlay: &overlay,
            heading,
            session: &session,
        }),
        KukaCommand::SimController {
            fri_version,
            client,
            port,
            cycles,
            send_period,
            overlay,
            faults,
            seed,
            unpaced,
            l1,
            l2,
        } => run_sim_controller(&SimOptions {
            fri_version: &fri_version,
            client,
            port,
            cycles,
            send_period,
            overlay: &overlay,
            faults: &faults,
            seed,
            unpaced,
            l1,
            l2,
        }),
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
