//! `limb`: the command-line face of the kernel. The contract (names, flags,
//! JSON keys, exit codes) is `../shared/spec/cli.md`; each subcommand lives in
//! its own module and returns a [`CliError`] that maps to the exit code.

mod arebo;
mod config;
mod error;

use clap::{Parser, Subcommand};
use error::CliError;

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
    /// Print the embedded default kernel configuration as JSON.
    Config,
    /// AREBO adapter: calibrate or run a device, or simulate one.
    Arebo {
        #[command(subcommand)]
        command: arebo::AreboCommand,
    },
}

fn main() {
    let cli = Cli::parse();
    let result: Result<(), CliError> = match cli.command {
        Command::Config => config::run(),
        Command::Arebo { command } => arebo::run(command),
    };
    if let Err(error) = result {
        eprintln!("limb: {error}");
        std::process::exit(error.exit_code());
    }
}
