//! `limb simulate --l1 M --l2 M [--seed N] [--noise on|off]
//! [--effect NAME --set KEY=VALUE ...] --out LOG.csv` (`../shared/spec/cli.md`):
//! runs the reference plant's estimation motion and writes the `plant.md`
//! log with every column, ground truth included.
//!
//! Each `--set` belongs to the nearest `--effect` before it, so several
//! effects can be combined: `--effect backlash --set width=0.02 --effect
//! latency --set delay=0.05`. The same arguments give a byte-identical file.

use crate::error::CliError;
use clap::ArgMatches;
use limb_sim::scripted::estimation_run;
use limb_sim::{Effect, Effects, Plant, PlantParameters};
use std::path::PathBuf;

/// Measurement noise (`--noise`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum NoiseArg {
    /// plant.md sigmas.
    On,
    /// Exact measurements.
    Off,
}

/// Arguments of `limb simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// Upper-arm length l1 [m].
    #[arg(long)]
    pub l1: f64,
    /// Forearm length l2 (elbow to grasp) [m].
    #[arg(long)]
    pub l2: f64,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Measurement noise.
    #[arg(long, value_enum, default_value = "on")]
    pub noise: NoiseArg,
    /// An unmodelled effect of plant.md (repeatable).
    #[arg(long)]
    pub effect: Vec<String>,
    /// A parameter KEY=VALUE of the preceding --effect (SI units).
    #[arg(long)]
    pub set: Vec<String>,
    /// Log file to write (CSV, plant.md format).
    #[arg(long)]
    pub out: PathBuf,
}

/// The plant's effects from `--effect NAME --set KEY=VALUE ...`
/// (`limb simulate` and `limb run`): each `--set` is paired with the
/// `--effect` before it, using the positions clap recorded in `matches`
/// (the subcommand's).
///
/// # Errors
/// [`CliError::BadInput`] for a `--set` before any `--effect`, an unknown
/// effect or parameter, or an invalid combination.
pub fn effects(
    effect: &[String],
    set: &[String],
    matches: &ArgMatches,
) -> Result<Effects, CliError> {
    Effects::new(&group(effect, set, matches)?)
        .map_err(|error| CliError::BadInput(error.to_string()))
}

/// Pairs each `--effect` with the `--set`s that follow it, using the
/// positions clap recorded.
fn group(effect: &[String], set: &[String], matches: &ArgMatches) -> Result<Vec<Effect>, CliError> {
    let positions = |id: &str| -> Vec<usize> {
        matches
            .indices_of(id)
            .map(Iterator::collect)
            .unwrap_or_default()
    };
    let (effect_at, set_at) = (positions("effect"), positions("set"));
    let mut settings: Vec<Vec<&str>> = vec![Vec::new(); effect.len()];
    for (set, at) in set.iter().zip(set_at) {
        let owner = effect_at
            .iter()
            .rposition(|&e| e < at)
            .ok_or_else(|| CliError::BadInput(format!("--set {set} comes before any --effect")))?;
        settings[owner].push(set);
    }
    effect
        .iter()
        .zip(&settings)
        .map(|(name, settings)| {
            Effect::parse(name, settings).map_err(|error| CliError::BadInput(error.to_string()))
        })
        .collect()
}

/// Runs `limb simulate`.
///
/// # Errors
/// [`CliError::BadInput`] for invalid parameters or effects, or an output
/// file that cannot be written; [`CliError::Internal`] if the run fails.
pub fn run(args: &SimulateArgs, matches: &ArgMatches) -> Result<(), CliError> {
    let effects = effects(&args.effect, &args.set, matches)?;
    let mut params = PlantParameters::new(args.l1, args.l2);
    params.seed = args.seed;
    params.noise = args.noise == NoiseArg::On;
    let mut plant = Plant::with_effects(params, effects).map_err(CliError::BadInput)?;
    let rows = estimation_run(&mut plant).map_err(CliError::Internal)?;
    limb_sim::log::write(&args.out, &rows).map_err(|error| CliError::BadInput(error.to_string()))
}
