//! The drive diagnosis: a fit log, held-out data (a second run, or
//! alternating blocks of the fit log), the engine's forward selection, and
//! the answer in the shape `limb diagnose-drive` prints.

use super::log::DriveLog;
use super::model::{DriveModel, DriveModelError};
use crate::engine::{select, EngineError, Options, Problem, Selection};
use crate::holdout::{HoldOut, TooShort};
use crate::locate::Location;
use serde::Serialize;
use std::collections::BTreeMap;

/// Most effects forward selection adds to a drive (a friction law has up
/// to three parts; one more for a transmission or timing effect).
pub const MAX_EFFECTS: usize = 4;

/// One named log.
#[derive(Clone, Copy, Debug)]
pub struct Run<'a> {
    /// File name (for messages).
    pub name: &'a str,
    /// Its contents.
    pub log: &'a DriveLog,
}

/// Why a drive diagnosis could not be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DriveError {
    /// A log cannot be compared with the rigid model.
    #[error("{file}: {source}")]
    Model {
        /// The log's file.
        file: String,
        /// Why.
        source: DriveModelError,
    },
    /// The fit log is too short to hold data out of.
    #[error("{file}: {source}")]
    TooShort {
        /// The log's file.
        file: String,
        /// Why.
        source: TooShort,
    },
    /// The two runs do not log the same columns.
    #[error("{held}: logs {what} but {fit} does not (or the other way round): both runs must log the same columns")]
    Mismatch {
        /// Fit log.
        fit: String,
        /// Held-out log.
        held: String,
        /// The column that differs.
        what: &'static str,
    },
    /// The engine failed.
    #[error("{0}")]
    Engine(#[from] EngineError),
}

impl DriveError {
    /// `true` when the input is at fault (a bad log), not the program.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, DriveError::Engine(_))
    }
}

/// One effect added, in the order forward selection added it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AddedEffect {
    /// Its name (`none` when nothing earned its parameters).
    pub effect: String,
    /// Fitted parameters (as refitted with every effect added), SI.
    pub params: BTreeMap<String, f64>,
    /// Units of the parameters.
    pub units: BTreeMap<String, String>,
    /// Held-out gap once it was added.
    pub held_out_after: f64,
}

/// The answer of a drive diagnosis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnosis {
    /// The effects added, in order (`none` alone when none earned its
    /// parameters).
    pub effects: Vec<AddedEffect>,
    /// The nominal rigid model's parameters as refitted with the effects
    /// (`mass` [kg], `offset` [N], …).
    pub nominal: BTreeMap<String, f64>,
    /// The held-out gap before and after.
    pub gap: crate::engine::Gap,
    /// Where the nominal model's gap lies.
    #[serde(rename = "where")]
    pub location: Location,
    /// Where what the effects leave lies.
    pub remaining: Location,
    /// What remains, in words.
    pub unexplained: String,
    /// What the gap was scored on.
    pub held_out_data: String,
    /// Zero-phase cut-off of positions and force [Hz].
    pub cutoff_hz: f64,
}

/// The drive diagnosis with what a report plots: the model of the scored
/// run and the engine's full selection.
pub struct Diagnosed {
    /// The model whose data were scored: the held-out run, or the fit run
    /// when its own blocks were held out.
    pub scored: DriveModel,
    /// The engine's output (predictions on the scored run included).
    pub selection: Selection,
    /// The answer.
    pub diagnosis: Diagnosis,
}

/// Diagnoses `fit` against `held` (a second run of the same drive) or,
/// without one, against alternating 1 s blocks of `fit` itself.
///
/// # Errors
/// See [`DriveError`].
pub fn diagnose(
    fit: Run,
    held: Option<Run>,
    cutoff: f64,
    options: &Options,
) -> Result<Diagnosed, DriveError> {
    let model_of = |run: Run| {
        DriveModel::new(run.log, cutoff).map_err(|source| DriveError::Model {
            file: run.name.to_string(),
            source,
        })
    };
    let fit_model = model_of(fit)?;
    let (scored, selection, held_out_data) = match held {
        Some(held) => {
            if fit.log.q_load.is_some() != held.log.q_load.is_some() {
                return Err(DriveError::Mismatch {
                    fit: fit.name.to_string(),
                    held: held.name.to_string(),
                    what: "q_load",
                });
            }
            let held_model = model_of(held)?;
            let selection = select(
                &Problem::two_runs(&fit_model, &held_model),
                options,
                &|_| {},
            )?;
            (held_model, selection, format!("the whole of {}", held.name))
        }
        None => {
            let hold_out = HoldOut {
                block: 1.0,
                min_samples: 100,
            };
            let problem =
                Problem::split(&fit_model, hold_out).map_err(|source| DriveError::TooShort {
                    file: fit.name.to_string(),
                    source,
                })?;
            let selection = select(&problem, options, &|_| {})?;
            let text = format!(
                "alternating {} s blocks of {} held out from the fit (no --validate run given)",
                hold_out.block, fit.name
            );
            (fit_model, selection, text)
        }
    };
    let diagnosis = answer(&selection, held_out_data, scored.cutoff());
    Ok(Diagnosed {
        scored,
        selection,
        diagnosis,
    })
}

/// The answer from the engine's selection (its predictions stay with the
/// caller, for the report).
fn answer(selection: &Selection, held_out_data: String, cutoff_hz: f64) -> Diagnosis {
    let mut effects: Vec<AddedEffect> = selection
        .effects
        .iter()
        .map(|e| AddedEffect {
            effect: e.effect.clone(),
            params: e.params.clone(),
            units: e.units.clone(),
            held_out_after: e.held_out_after,
        })
        .collect();
    if effects.is_empty() {
        effects.push(AddedEffect {
            effect: "none".into(),
            params: BTreeMap::new(),
            units: BTreeMap::new(),
            held_out_after: selection.gap.after,
        });
    }
    Diagnosis {
        effects,
        nominal: selection.nominal.clone(),
        unexplained: unexplained(selection, cutoff_hz),
        location: selection.location.clone(),
        remaining: selection.remaining.clone(),
        gap: selection.gap.clone(),
        held_out_data,
        cutoff_hz,
    }
}

/// What remains after the chosen effects, and where, in one sentence.
fn unexplained(selection: &Selection, cutoff_hz: f64) -> String {
    let gap = &selection.gap;
    let place = &selection.remaining;
    let mut text = format!(
        "held-out {} {:.3} remains ({:.0} % of the nominal {:.3}); the force noise is unknown, so all of it is counted",
        gap.metric,
        gap.after,
        100.0 * (1.0 - gap.shrink),
        gap.before
    );
    if !place.signals.is_empty() {
        text += &format!(", in {}", place.signals.join(" and "));
    }
    if let (Some(start), Some(end)) = (place.t_start, place.t_end) {
        text += &format!(", from t = {start:.2} s to {end:.2} s");
    }
    text += &match place.band_hz {
        Some([lo, hi]) => format!(", concentrated in {lo:.2}–{hi:.2} Hz"),
        None => format!(", spread over 0–{cutoff_hz} Hz with no dominant band"),
    };
    text
}
