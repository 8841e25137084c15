//! What the engine diagnoses: a [`Model`] is "the sim" of one system
//! together with the "real" data it is compared with.
//!
//! A model names its measured [`Signal`]s, the scale each residual is
//! divided by (the measurement noise σ where it is known), the candidate
//! unmodelled effects it can add (each with bounded parameters) and
//! predicts every signal at every sample for any set of effects. The
//! engine never looks inside: the same code serves the arm plant of
//! `plant.md` ([`crate::plant::arm`]) and any other plant.

pub use limb_sim::effects::{Parameter, Scale};
use std::sync::Arc;
use thiserror::Error;

/// One measured signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Signal {
    /// Name as in the log header (`x`, `psi`, `fz`, `tau`, ...).
    pub name: &'static str,
    /// SI unit of the signal.
    pub unit: &'static str,
}

/// A candidate unmodelled effect: its name in the output and its
/// parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// Name as the output uses it (`backlash`, `viscous_friction`, ...).
    pub name: &'static str,
    /// Its fitted parameters.
    pub parameters: Vec<Parameter>,
}

/// One effect added to the sim: the index of its [`Candidate`] and its
/// parameter values in the candidate's order and units.
#[derive(Clone, Debug, PartialEq)]
pub struct Applied {
    /// Index into [`Model::candidates`].
    pub candidate: usize,
    /// Values, one per parameter.
    pub values: Vec<f64>,
}

/// Samples × signals, row-major: `values[sample * signals + signal]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    signals: usize,
    values: Vec<f64>,
}

impl Series {
    /// An empty series of `signals` columns with room for `samples` rows.
    pub fn with_capacity(signals: usize, samples: usize) -> Self {
        Self {
            signals,
            values: Vec::with_capacity(signals * samples),
        }
    }

    /// Appends one sample; `row` must hold one value per signal (a shorter
    /// or longer row is an error, not truncated).
    ///
    /// # Errors
    /// [`ModelError::Shape`] when the row length is wrong.
    pub fn push(&mut self, row: &[f64]) -> Result<(), ModelError> {
        if row.len() != self.signals {
            return Err(ModelError::Shape {
                expected: self.signals,
                found: row.len(),
            });
        }
        self.values.extend_from_slice(row);
        Ok(())
    }

    /// Number of signals (columns).
    pub fn signals(&self) -> usize {
        self.signals
    }

    /// Number of samples (rows).
    pub fn samples(&self) -> usize {
        self.values.len().checked_div(self.signals).unwrap_or(0)
    }

    /// One sample's values.
    pub fn row(&self, sample: usize) -> &[f64] {
        let start = (sample * self.signals).min(self.values.len());
        let end = (start + self.signals).min(self.values.len());
        &self.values[start..end]
    }

    /// One signal over all samples.
    pub fn column(&self, signal: usize) -> Vec<f64> {
        (0..self.samples())
            .map(|i| self.row(i).get(signal).copied().unwrap_or(f64::NAN))
            .collect()
    }
}

/// Why a model could not predict or be built.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ModelError {
    /// A row did not have one value per signal.
    #[error("a sample has {found} values for {expected} signals")]
    Shape {
        /// Signals of the series.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// The effect set is not one the model can apply.
    #[error("cannot apply effects: {0}")]
    Effects(String),
    /// The simulation failed (diverged or could not start).
    #[error("simulation failed: {0}")]
    Simulation(String),
}

/// Where the residual a candidate is to explain points (the residual of
/// the effects it joins: the nominal sim's in the first selection step),
/// for choosing where its fit starts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hints {
    /// First time the residual leaves the noise [s], when it does.
    pub onset: Option<f64>,
    /// Last time it is beyond the noise [s], when it is.
    pub end: Option<f64>,
    /// Frequency of the residual's spectral peak [Hz], when one stands out.
    pub frequency: Option<f64>,
    /// The band around that peak holding its power [Hz], when the
    /// residual concentrates in one (the location's `band_hz`).
    pub band: Option<[f64; 2]>,
    /// That residual itself, scaled ((observed − predicted) / scale, every
    /// sample); set by the engine.
    pub residual: Option<Arc<Series>>,
}

/// What a model compares: its signals and their scales, the measured
/// data, and its candidate effects. Invariant: `scales` has one entry per
/// signal, `observed` one column per signal and one row per entry of
/// `times` (strictly increasing, seconds).
#[derive(Clone, Debug, PartialEq)]
pub struct Data {
    /// The signals compared, in [`Series`] column order.
    pub signals: Vec<Signal>,
    /// What each signal's residual is divided by (same order), in the
    /// signal's unit.
    pub scales: Vec<f64>,
    /// Sample times [s].
    pub times: Vec<f64>,
    /// The measured ("real") data.
    pub observed: Series,
    /// The candidate effects.
    pub candidates: Vec<Candidate>,
}

/// "The sim" of one system with the data it is compared with.
pub trait Model: Sync {
    /// The data compared (see the accessors below).
    fn data(&self) -> &Data;
    /// The signals compared, in [`Series`] column order.
    fn signals(&self) -> &[Signal] {
        &self.data().signals
    }
    /// What each signal's residual is divided by (same order): the
    /// measurement noise σ where it is known, in the signal's unit.
    fn scales(&self) -> &[f64] {
        &self.data().scales
    }
    /// Expected mean square of a scaled residual that is pure measurement
    /// noise: 1 where [`Model::scales`] are the noise σ, 0 where the noise
    /// is unknown (the gap is then the whole residual).
    fn noise_floor(&self) -> f64;
    /// Name of the gap metric (the `metric` of the output).
    fn gap_metric(&self) -> &'static str;
    /// Sample times [s], strictly increasing.
    fn times(&self) -> &[f64] {
        &self.data().times
    }
    /// The measured ("real") data.
    fn observed(&self) -> &Series {
        &self.data().observed
    }
    /// The candidate effects.
    fn candidates(&self) -> &[Candidate] {
        &self.data().candidates
    }
    /// The candidate that is part of the nominal sim itself (its
    /// parameters, e.g. a drive's mass and offset, are fitted first and
    /// refitted with every effect; it is never ranked). `None` for a sim
    /// with no fitted parameters of its own.
    fn base(&self) -> Option<usize> {
        None
    }
    /// The sim's prediction of every signal at every sample with `effects`
    /// added (none: the nominal sim).
    ///
    /// # Errors
    /// An effect set the model cannot apply, or a failed simulation.
    fn predict(&self, effects: &[Applied]) -> Result<Series, ModelError>;
    /// The model's own closed-form refinement of `effects` on the samples
    /// where `mask` is `true` (e.g. a least-squares solve of the
    /// parameters its prediction is linear in, the others held), or `None`
    /// (the default) to leave every parameter to the optimiser. The engine
    /// refines every point it costs, so the optimiser then searches only
    /// what the model cannot solve. Values returned must lie in their
    /// parameters' ranges.
    fn polish(&self, _effects: &[Applied], _mask: &[bool]) -> Option<Vec<Applied>> {
        None
    }
    /// `true` when [`Model::polish`] solves every parameter of `candidate`
    /// from the others whatever values it is handed: the optimiser then
    /// leaves them out of its search (a direction along which the cost
    /// cannot change only misleads a simplex). The default: `false`.
    fn solves(&self, _candidate: usize) -> bool {
        false
    }
    /// For a model whose prediction is linearised in its base parameters
    /// around a reference (so [`Model::polish`] solves them by least
    /// squares): moves the reference to the base values in `effects`,
    /// linearising there the prediction with the other effects in
    /// `effects`, and returns `true`. The default (no linearisation) does
    /// nothing and returns `false`. The engine calls it between selection steps only,
    /// never while candidates are fitted side by side.
    fn recentre(&self, _effects: &[Applied]) -> bool {
        false
    }
    /// Start points for fitting `candidate`, in unit coordinates (one per
    /// parameter, each in [0, 1]). The default is an even grid.
    fn starts(&self, candidate: usize, _hints: &Hints) -> Vec<Vec<f64>> {
        let dimension = self
            .candidates()
            .get(candidate)
            .map_or(0, |c| c.parameters.len());
        grid(dimension, if dimension <= 1 { 9 } else { 5 })
    }
}

/// Every point of an even grid of `per_axis` points on each of `dimension`
/// unit axes (cell centres, so no point sits on a bound).
pub fn grid(dimension: usize, per_axis: usize) -> Vec<Vec<f64>> {
    let per_axis = per_axis.max(1);
    let count = per_axis.pow(dimension as u32);
    (0..count)
        .map(|mut index| {
            (0..dimension)
                .map(|_| {
                    let k = index % per_axis;
                    index /= per_axis;
                    (k as f64 + 0.5) / per_axis as f64
                })
                .collect()
        })
        .collect()
}
