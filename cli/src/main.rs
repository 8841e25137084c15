//! `limb`: the command-line face of the kernel. The contract (names, flags,
//! JSON keys, exit codes) is `../shared/spec/cli.md`; each subcommand lives in
//! its own module and returns a [`CliError`] that maps to the exit code.

mod error;
mod kuka;

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
    /// KUKA LBR iiwa FRI adapter tools.
    #[command(subcommand)]
    Kuka(kuka::KukaCommand),
}

fn main() {
    let cli = Cli::parse();
    let result: Result<(), CliError> = match cli.command {
        Command::Kuka(command) => kuka::run(command),
    };
    if let Err(error) = result {
        eprintln!("limb: {error}");
        std::process::exit(error.exit_code());
    }
}
