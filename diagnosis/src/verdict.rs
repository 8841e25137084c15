//! The answer of `limb diagnose` (`shared/spec/cli.md`): the arm plant's
//! diagnosis of one log, built from the engine's [`Selection`].
//!
//! The log is split into alternating 1 s fit and held-out blocks
//! ([`HoldOut::default`]); one effect is chosen (the arm logs of
//! `plant.md` carry at most one), `none` when no candidate earns its
//! parameters on the held-out blocks.

use crate::arm::{ArmError, ArmModel};
use crate::engine::{select, EngineError, Gap, Options, Problem, Progress, Ranked, Selection};
use crate::holdout::{HoldOut, TooShort};
use crate::locate::Location;
use limb_sim::log::Record;
use serde::Serialize;
use thiserror::Error;

/// Why a log could not be diagnosed.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum DiagnoseError {
    /// The log cannot be compared with the sim.
    #[error(transparent)]
    Arm(#[from] ArmError),
    /// The log is too short to hold data out.
    #[error(transparent)]
    TooShort(#[from] TooShort),
    /// The engine failed.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// A self-check log could not be made.
    #[error("self-check: {0}")]
    SelfCheck(String),
}

/// The diagnosis of one arm log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnosis {
    /// The effect chosen, or `none`.
    pub effect: String,
    /// Every candidate, best held-out criterion first.
    pub ranking: Vec<Ranked>,
    /// Where the nominal sim's gap lies.
    #[serde(rename = "where")]
    pub location: Location,
    /// The held-out gap before and after adding the chosen effect.
    pub gap: Gap,
    /// Where what the chosen effect leaves lies (empty signals: nothing
    /// beyond noise).
    pub remaining: Location,
    /// How the data were held out.
    pub held_out: String,
    /// Simulations and cost evaluations spent.
    pub evaluations: usize,
}

impl Diagnosis {
    fn from_selection(selection: &Selection, hold_out: HoldOut) -> Self {
        let effect = selection
            .effects
            .first()
            .map_or_else(|| "none".to_string(), |e| e.effect.clone());
        Self {
            effect,
            ranking: selection
                .steps
                .first()
                .map(|s| s.ranking.clone())
                .unwrap_or_default(),
            location: selection.location.clone(),
            gap: selection.gap.clone(),
            remaining: selection.remaining.clone(),
            held_out: format!(
                "alternating {} s blocks: even blocks fit, odd blocks score",
                hold_out.block
            ),
            evaluations: selection.evaluations,
        }
    }
}

/// The model, the engine's selection and the answer, for callers that
/// also plot (the report).
pub struct Diagnosed {
    /// The sim compared with the log.
    pub model: ArmModel,
    /// The engine's full output (predictions included).
    pub selection: Selection,
    /// The answer.
    pub diagnosis: Diagnosis,
}

/// Diagnoses `records` against the reference plant with arm lengths
/// `l1`, `l2` [m]. Ground-truth columns are not read.
///
/// # Errors
/// See [`DiagnoseError`].
pub fn diagnose(
    l1: f64,
    l2: f64,
    records: &[Record],
    threads: usize,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Diagnosed, DiagnoseError> {
    let model = ArmModel::new(l1, l2, records)?;
    let hold_out = HoldOut::default();
    let selection = {
        let problem = Problem::split(&model, hold_out)?;
        let options = Options {
            threads,
            max_effects: 1,
            ..Options::default()
        };
        select(&problem, &options, progress)?
    };
    let diagnosis = Diagnosis::from_selection(&selection, hold_out);
    Ok(Diagnosed {
        model,
        selection,
        diagnosis,
    })
}
