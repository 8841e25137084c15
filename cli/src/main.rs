//! `limb`: the command-line face of the kernel. The contract (names, flags,
//! JSON keys, exit codes) is `../shared/spec/cli.md`; each subcommand lives in
//! its own module and returns a [`CliError`] that maps to the exit code.

mod arebo;
mod arm_model;
mod config;
mod diagnose;
mod diagnose_drive;
mod error;
mod estimate;
mod external;
mod kuka;
mod plant_population;
mod population;
mod robot_session;
mod run;
mod session_log;
mod session_report;
mod simulate;
mod soak;
mod stop_at;
mod zenoh;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use error::CliError;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "limb",
    version,
    about = "Control kernel for robots that move a person's arm"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// One whole kernel session on the reference plant (the embedded default, no robot).
    Run(run::RunArgs),
    /// Kernel sessions on many random arms: joint limits during Estimate, model errors, refusals.
    Population(population::PopulationArgs),
    /// Print the embedded default kernel configuration as JSON.
    Config,
    /// Fit the arm (l1, l2, elbow, shoulder) from an estimation-motion log.
    Estimate {
        /// Log in the CSV format of plant.md.
        log: PathBuf,
        /// Estimator.
        #[arg(long, value_enum, default_value = "auto")]
        method: estimate::MethodArg,
        /// Print one JSON object on stdout.
        #[arg(long)]
        json: bool,
        /// The arm the estimator (`online`: its shoulder-rhythm prior) and
        /// the validator assume: `rod` (default, plant.md) or `person`.
        #[arg(long, value_enum, default_value = "rod")]
        arm: arm_model::ArmModel,
    },
    /// Run the reference plant (optionally with unmodelled effects) and write its log.
    Simulate(simulate::SimulateArgs),
    /// Diagnose the sim-to-real gap of a log: where, which effect, how far it shrinks.
    Diagnose(diagnose::DiagnoseArgs),
    /// Supervise a kernel over Zenoh: run a node, send commands, query.
    Zenoh(zenoh::ZenohArgs),
    /// AREBO adapter: calibrate or run a device, or simulate one.
    Arebo {
        #[command(subcommand)]
        command: arebo::AreboCommand,
    },
    /// Gap diagnosis of one actuated axis (spec/drive.md): which effects beyond the rigid model.
    DiagnoseDrive(diagnose_drive::DiagnoseDriveArgs),
    /// KUKA LBR iiwa FRI adapter tools.
    #[command(subcommand)]
    Kuka(kuka::KukaCommand),
    /// Soak runs that count what was lost: sessions with seeded faults or
    /// emergency stops over real loopback sockets for a wall-clock time.
    Soak(soak::SoakArgs),
}

/// What is logged when `RUST_LOG` is not set: the adapters' warnings
/// (refused commands, supervisor losses, unpublished telemetry) and every
/// other crate's errors.
const DEFAULT_LOG: &str = "error,limb_zenoh=warn,limb_arebo=warn";

/// Logs `tracing` events as lines on stderr, filtered by `RUST_LOG` (the
/// `tracing-subscriber` `EnvFilter` syntax, e.g. `limb_zenoh=debug`), or by
/// [`DEFAULT_LOG`]. An unreadable `RUST_LOG` is a usage error.
fn install_logging() -> Result<(), CliError> {
    use tracing_subscriber::EnvFilter;
    let filter = match std::env::var("RUST_LOG") {
        Ok(spec) => EnvFilter::try_new(&spec)
            .map_err(|e| CliError::BadInput(format!("RUST_LOG={spec}: {e}")))?,
        Err(_) => EnvFilter::new(DEFAULT_LOG),
    };
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(false)
        .try_init()
        .map_err(|e| CliError::Internal(format!("logging: {e}")))
}

fn main() {
    // Usage errors are bad input: one line, exit 2 (help and version print
    // in full and exit 0).
    let matches = Cli::command()
        .try_get_matches()
        .and_then(|matches| Ok((Cli::from_arg_matches(&matches)?, matches)));
    let (cli, matches) = match matches {
        Ok(parsed) => parsed,
        Err(error) if error.use_stderr() => {
            // clap names the missing or conflicting arguments on the lines
            // after the first: they are joined into the one line.
            let text = error.to_string();
            let words: Vec<&str> = text
                .lines()
                .take_while(|line| !line.starts_with("Usage:"))
                .map(str::trim)
                .filter(|line| !line.is_empty())
                .collect();
            let line = if words.is_empty() {
                "bad arguments".to_string()
            } else {
                words.join(" ")
            };
            eprintln!("limb: {line}");
            std::process::exit(2);
        }
        Err(error) => error.exit(),
    };
    if let Err(error) = install_logging() {
        eprintln!("limb: {error}");
        std::process::exit(error.exit_code());
    }
    let result: Result<(), CliError> = match cli.command {
        Command::Run(args) => match matches.subcommand_matches("run") {
            Some(sub) => run::run(&args, sub),
            None => Err(CliError::Internal("run: no argument matches".into())),
        },
        Command::Population(args) => population::run(&args),
        Command::Config => config::run(),
        Command::Estimate {
            log,
            method,
            json,
            arm,
        } => estimate::run(&log, method, arm, json),
        Command::Simulate(args) => match matches.subcommand_matches("simulate") {
            Some(sub) => simulate::run(&args, sub),
            None => Err(CliError::Internal("simulate: no argument matches".into())),
        },
        Command::Diagnose(args) => diagnose::run(&args),
        Command::Zenoh(args) => zenoh::run(args),
        Command::Arebo { command } => arebo::run(command),
        Command::Kuka(command) => kuka::run(command),
        Command::DiagnoseDrive(args) => diagnose_drive::run(&args),
        Command::Soak(args) => soak::run(args),
    };
    if let Err(error) = result {
        eprintln!("limb: {error}");
        std::process::exit(error.exit_code());
    }
}
