//! The diagnosis engine: fit every candidate effect on the fit data,
//! score it on the held-out data, rank, and add effects one at a time
//! while each addition earns its parameters.
//!
//! # Theory of operation
//! For a set of effects S with k fitted parameters, the fit minimises the
//! sum of squared scaled residuals on the fit samples ([`crate::optimize`],
//! bounded and deterministic; every point it costs is first refined by
//! the model's own solve, [`Model::polish`], where it has one, and what
//! that solve sets, [`Model::solves`], is not searched); the set is then judged only on held-out
//! samples, by the **held-out information criterion** relative to the
//! set it extends (S₀, the nominal sim at first):
//!
//! ```text
//! known noise (floor > 0):   Δ = (SS₀ − SS) / floor        − k ln n
//! unknown noise (floor = 0): Δ = Σₛ nₛ ln(SS₀ₛ / SSₛ)      − k ln n
//! ```
//!
//! with SS the held-out sum of squares over its n terms (SSₛ, nₛ: signal
//! s's share): the Gaussian log-likelihood gain (σ known, or profiled out
//! separately for each signal, whose noise levels need not be alike) less
//! the BIC penalty.
//! Scoring on held-out data already punishes over-fitting; the penalty
//! makes a parameter pay for itself on top, so pure noise never earns an
//! effect. **Forward selection** adds the candidate with the largest Δ,
//! refits all parameters of the grown set jointly, and repeats while the
//! best Δ is positive, up to a maximum number of effects. The answer is
//! `none` when no candidate has Δ > 0 at the first step. Each step's
//! candidates start from the hints of the residual the chosen set
//! leaves ([`Hints`]); a model may ask more of an addition than Δ > 0
//! ([`Options::min_gain`], [`Options::min_share`], the latter judged
//! over a pair of additions when the first falls short of it alone).

use crate::holdout::{HoldOut, TooShort};
use crate::locate::{locate, Location};
use crate::model::{Applied, Candidate, Hints, Model, ModelError, Series};
use crate::optimize::{minimize, Budget};
use crate::residual::{gap, scaled, signal_sums, sum_of_squares};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// One side of a problem: a model with its data and the samples used.
pub struct Part<'a> {
    /// The model and its data.
    pub model: &'a dyn Model,
    /// `true` for the samples this side uses.
    pub mask: Vec<bool>,
}

/// What is fitted on and what is scored on.
pub struct Problem<'a> {
    /// Samples the fits see.
    pub fit: Part<'a>,
    /// Samples held out from the fits, on which everything is scored.
    pub held: Part<'a>,
}

impl<'a> Problem<'a> {
    /// One log split into alternating fit and held-out blocks.
    ///
    /// # Errors
    /// [`TooShort`] when the log cannot hold anything out.
    pub fn split(model: &'a dyn Model, hold_out: HoldOut) -> Result<Self, TooShort> {
        let masks = hold_out.split(model.times())?;
        Ok(Self {
            fit: Part {
                model,
                mask: masks.fit,
            },
            held: Part {
                model,
                mask: masks.held,
            },
        })
    }

    /// A fit run and a separate held-out run of the same system, each
    /// used whole.
    pub fn two_runs(fit: &'a dyn Model, held: &'a dyn Model) -> Self {
        Self {
            fit: Part {
                model: fit,
                mask: vec![true; fit.times().len()],
            },
            held: Part {
                model: held,
                mask: vec![true; held.times().len()],
            },
        }
    }
}

/// How the engine works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Minimisation budget per fit.
    pub budget: Budget,
    /// Worker threads fitting candidates side by side (at least 1).
    pub threads: usize,
    /// Most effects forward selection adds.
    pub max_effects: usize,
    /// Least an addition must lower the held-out gap by (the model's
    /// metric), besides earning its parameters: on a long log the
    /// criterion detects differences far below any effect worth naming
    /// (a plant that differs from the sim in small ways, a factor of
    /// 1.0002), and those must not be named. 0 (the default): only the
    /// criterion decides.
    pub min_gain: f64,
    /// Least share of the current held-out gap an addition must remove:
    /// an effect outside the candidates leaves a large gap that each
    /// candidate trims by a few per cent, and none may claim it. Two
    /// effects of like size each remove less on their own, so an addition
    /// short of the share is kept on trial: it stays only when the next
    /// addition brings the two together to the share of the gap before
    /// the trial, itself removing at least half the share of the gap it
    /// joins (two effects of like size; without that, a second candidate
    /// that trims a few per cent more carries the first over the share:
    /// MyoArm's `stiff`, a `cuff_offset` on trial confirmed by a heavier
    /// forearm it does not have). See [`select`]. 0 (the default): only
    /// the criterion decides.
    pub min_share: f64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            budget: Budget::default(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            max_effects: 1,
            min_gain: 0.0,
            min_share: 0.0,
        }
    }
}

/// Progress of a diagnosis: a candidate fit finished.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    /// Fits finished in this selection step.
    pub done: usize,
    /// Fits in this selection step.
    pub total: usize,
    /// The candidate just fitted.
    pub candidate: &'a str,
}

/// One candidate effect fitted and scored.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ranked {
    /// Its name.
    pub effect: String,
    /// Share of the held-out gap it explains: 1 − after / before.
    pub score: f64,
    /// Held-out information criterion Δ (positive: the effect is real).
    pub criterion: f64,
    /// Fitted parameters, SI units (see `units`).
    pub params: BTreeMap<String, f64>,
    /// Unit of each parameter.
    pub units: BTreeMap<String, String>,
    /// Held-out gap with the effect added (after the effects chosen
    /// before it).
    pub held_out_after: f64,
}

impl Ranked {
    /// The fitted parameters as `name = value unit`, comma-separated.
    pub fn parameters_text(&self) -> String {
        self.params
            .iter()
            .map(|(k, v)| {
                format!(
                    "{k} = {v:.4} {}",
                    self.units.get(k).map_or("", String::as_str)
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The gap before and after the chosen effects, on held-out data.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Gap {
    /// What `before` and `after` measure.
    pub metric: String,
    /// Held-out gap of the nominal sim.
    pub before: f64,
    /// Held-out gap with the chosen effects.
    pub after: f64,
    /// 1 − after / before (0 when there is no gap).
    pub shrink: f64,
    /// Always `true`: both are measured on data the fits never saw.
    pub held_out: bool,
}

/// One step of forward selection: every remaining candidate, best first.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// The candidates fitted at this step, best criterion first.
    pub ranking: Vec<Ranked>,
    /// The one added, if any earned its parameters.
    pub added: Option<String>,
}

/// The engine's answer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Selection {
    /// The effects added, in order, each with its parameters as refitted
    /// with all effects added (the last step's values).
    pub effects: Vec<Ranked>,
    /// Every selection step.
    pub steps: Vec<Step>,
    /// The nominal sim's own fitted parameters (see [`Model::base`]).
    pub nominal: BTreeMap<String, f64>,
    /// The same parameters refitted with the chosen effects (equal to
    /// `nominal` when none was chosen).
    pub corrected: BTreeMap<String, f64>,
    /// Where the nominal sim's gap lies (held-out side, all its samples).
    pub location: Location,
    /// Where what the chosen effects leave lies.
    pub remaining: Location,
    /// The held-out gap before and after.
    pub gap: Gap,
    /// The chosen effects' predictions on the held-out side.
    #[serde(skip)]
    pub predictions: Predictions,
    /// The chosen set as the model takes it: the base's values first
    /// (when the model has one), then each added effect's.
    #[serde(skip)]
    pub chosen: Vec<Applied>,
    /// Cost evaluations (simulations) spent.
    pub evaluations: usize,
}

/// Predictions kept for plotting: the held-out side's nominal sim and
/// the sim with the chosen effects.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Predictions {
    /// Nominal sim.
    pub nominal: Option<Series>,
    /// Sim with the chosen effects.
    pub chosen: Option<Series>,
}

/// Why a diagnosis could not be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EngineError {
    /// The nominal sim could not be computed.
    #[error("the nominal sim failed: {0}")]
    Nominal(ModelError),
    /// The fit and held-out models do not describe the same signals or
    /// candidates.
    #[error("the fit and held-out data differ in {0}")]
    Mismatch(&'static str),
}

/// A set of effects fitted on one side and scored on the other.
#[derive(Clone, Debug)]
struct Fitted {
    effects: Vec<Applied>,
    /// Held-out (sum of squares, terms) per signal.
    held: Vec<(f64, usize)>,
    evaluations: usize,
}

/// Total of per-signal sums of squares.
fn total(sums: &[(f64, usize)]) -> f64 {
    sums.iter().map(|s| s.0).sum()
}

/// Held-out information criterion of `sums` against `reference` (both
/// per signal), for `parameters` added parameters (module docs).
fn criterion(
    reference: &[(f64, usize)],
    sums: &[(f64, usize)],
    parameters: usize,
    floor: f64,
) -> f64 {
    let n = reference.iter().map(|s| s.1).sum::<usize>().max(1) as f64;
    let gain = if floor > 0.0 {
        (total(reference) - total(sums)) / floor
    } else {
        reference
            .iter()
            .zip(sums)
            .filter(|(r, s)| r.0 > 0.0 && s.0 > 0.0)
            .map(|(r, s)| r.1 as f64 * (r.0 / s.0).ln())
            .sum()
    };
    if gain.is_finite() {
        gain - parameters as f64 * n.ln()
    } else {
        f64::NEG_INFINITY
    }
}

/// Maps unit coordinates to effects: `base` with its parameters replaced
/// by the first units, then `candidate` (if any) with the rest.
fn effects_at(model: &dyn Model, layout: &[usize], units: &[f64]) -> Vec<Applied> {
    let mut rest = units;
    layout
        .iter()
        .map(|&candidate| {
            let parameters = &model.candidates()[candidate].parameters;
            let (mine, others) = rest.split_at(parameters.len().min(rest.len()));
            rest = others;
            Applied {
                candidate,
                values: parameters
                    .iter()
                    .zip(mine)
                    .map(|(p, u)| p.value(*u))
                    .collect(),
            }
        })
        .collect()
}

/// Unit coordinates of `effects`' values, in order.
fn units_of(model: &dyn Model, effects: &[Applied]) -> Vec<f64> {
    let candidates = model.candidates();
    effects
        .iter()
        .flat_map(|a| {
            candidates[a.candidate]
                .parameters
                .iter()
                .zip(&a.values)
                .map(|(p, v)| p.unit_of(*v))
        })
        .collect()
}

/// Minimises the fit samples' cost over the parameters of the effects
/// `layout` from `starts` (unit coordinates); every point is refined by
/// the model's own solve, where it has one. The parameters of candidates
/// the model solves ([`Model::solves`]) are not searched: they keep the
/// first start's values until the solve replaces them, and starts that
/// differ only in them are one start. Returns the effects at the minimum
/// and the evaluations spent.
fn minimize_over(
    problem: &Problem,
    layout: &[usize],
    starts: &[Vec<f64>],
    options: &Options,
) -> (Vec<Applied>, usize) {
    let model = problem.fit.model;
    let searched: Vec<bool> = layout
        .iter()
        .flat_map(|&c| {
            let count = model.candidates()[c].parameters.len();
            std::iter::repeat_n(!model.solves(c), count)
        })
        .collect();
    let held = starts.first().cloned().unwrap_or_default();
    let full = |units: &[f64]| -> Vec<f64> {
        let mut searched_units = units.iter();
        held.iter()
            .zip(&searched)
            .map(|(h, s)| {
                if *s {
                    searched_units.next().copied().unwrap_or(*h)
                } else {
                    *h
                }
            })
            .collect()
    };
    let mut reduced: Vec<Vec<f64>> = Vec::with_capacity(starts.len());
    for start in starts {
        let point: Vec<f64> = start
            .iter()
            .zip(&searched)
            .filter_map(|(u, s)| s.then_some(*u))
            .collect();
        if !reduced.contains(&point) {
            reduced.push(point);
        }
    }
    let effects_for = |units: &[f64]| {
        let effects = effects_at(model, layout, &full(units));
        model.polish(&effects, &problem.fit.mask).unwrap_or(effects)
    };
    let cost = |units: &[f64]| match model.predict(&effects_for(units)) {
        Ok(predicted) => sum_of_squares(model, &predicted, &problem.fit.mask).0,
        Err(_) => f64::INFINITY,
    };
    let minimum = minimize(cost, &reduced, options.budget);
    (effects_for(&minimum.point), minimum.evaluations)
}

fn fit(
    problem: &Problem,
    base: &[Applied],
    candidate: usize,
    hints: &Hints,
    options: &Options,
) -> Fitted {
    let model = problem.fit.model;
    let base_units = units_of(model, base);
    let layout: Vec<usize> = base
        .iter()
        .map(|a| a.candidate)
        .chain(std::iter::once(candidate))
        .collect();
    let starts: Vec<Vec<f64>> = model
        .starts(candidate, hints)
        .into_iter()
        .map(|s| base_units.iter().copied().chain(s).collect())
        .collect();
    let (effects, evaluations) = minimize_over(problem, &layout, &starts, options);
    let signals = problem.held.model.signals().len();
    let held = held_sums(problem, &effects).unwrap_or_else(|_| vec![(f64::INFINITY, 0); signals]);
    Fitted {
        effects,
        held,
        evaluations: evaluations + 1,
    }
}

fn held_sums(problem: &Problem, effects: &[Applied]) -> Result<Vec<(f64, usize)>, ModelError> {
    let predicted = problem.held.model.predict(effects)?;
    Ok(signal_sums(
        problem.held.model,
        &predicted,
        &problem.held.mask,
    ))
}

/// The selection before an addition kept on trial (see
/// [`Options::min_share`]).
struct Trial {
    chosen: Vec<Applied>,
    /// Held-out sums per signal of `chosen`.
    current: Vec<(f64, usize)>,
    /// Index of the step that added it.
    step: usize,
    /// Held-out gap of `chosen`.
    gap: f64,
}

/// Where the residual of `prediction` lies, and the hints it gives with
/// the residual attached.
fn located(model: &dyn Model, prediction: &Series) -> (Location, Hints) {
    let residual = scaled(model, prediction);
    let (location, mut hints) = locate(model, &residual);
    hints.residual = Some(Arc::new(residual));
    (location, hints)
}

/// Gauss–Newton iterations that settle a linearised base (see
/// [`Model::recentre`]) after each selection step.
const SETTLE_ITERATIONS: usize = 4;

/// Moves a linearised model's reference to the base values of `chosen`
/// and re-solves them there, until they stop moving (Gauss–Newton on the
/// base with the effects held): the chosen set's predictions are then
/// exact at its reported values. Models without a linearisation return
/// `chosen` untouched.
fn settle(problem: &Problem, mut chosen: Vec<Applied>) -> Vec<Applied> {
    let recentre = |effects: &[Applied]| {
        let moved = problem.fit.model.recentre(effects);
        let same = std::ptr::addr_eq(problem.fit.model, problem.held.model);
        (same || problem.held.model.recentre(effects)) && moved
    };
    for _ in 0..SETTLE_ITERATIONS {
        if !recentre(&chosen) {
            return chosen;
        }
        match problem.fit.model.polish(&chosen, &problem.fit.mask) {
            Some(polished) if polished != chosen => chosen = polished,
            _ => return chosen,
        }
    }
    recentre(&chosen);
    chosen
}

/// Refits every parameter of `chosen` jointly from its current values
/// (one start, the full budget) and settles the base again: on a
/// linearised model the added effect was fitted around the reference of
/// before, and what that leaves must not be credited to the next
/// addition. Returns the set and the evaluations spent.
fn refit(problem: &Problem, chosen: Vec<Applied>, options: &Options) -> (Vec<Applied>, usize) {
    let layout: Vec<usize> = chosen.iter().map(|a| a.candidate).collect();
    let start = units_of(problem.fit.model, &chosen);
    let (effects, evaluations) = minimize_over(problem, &layout, &[start], options);
    (settle(problem, effects), evaluations)
}

/// Most refit rounds after an addition. A round is one Nelder–Mead from
/// the set's values, whose fixed iterations go mostly to shrinking the
/// simplex onto a sharply fixed parameter (a slip's time, to the
/// millisecond) before it travels along a shallow one; a 3 cm slip at
/// 6.9 s, whose shift trades with the forearm before it, moved 0.2-1.1 mm
/// a round and took nine rounds to settle (with three it stopped 3.4 mm
/// short; blind seed 161803, case 48). Rounds stop as soon as the base
/// stays still, so a set that settles at once costs one.
const REFITS: usize = 10;
/// A base that moves less than this in unit coordinates in a refit
/// round has settled.
const BASE_STILL: f64 = 1e-4;

/// `f(0..count)` on `threads` workers; results in index order.
pub(crate) fn parallel_map<T: Send>(
    count: usize,
    threads: usize,
    f: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..count).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads.clamp(1, count.max(1)) {
            scope.spawn(|| loop {
                let index = next.fetch_add(1, Ordering::Relaxed);
                if index >= count {
                    break;
                }
                let value = f(index);
                if let Ok(mut slots) = results.lock() {
                    slots[index] = Some(value);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}

fn check_alike(problem: &Problem) -> Result<(), EngineError> {
    let (a, b) = (problem.fit.model, problem.held.model);
    if a.signals() != b.signals() || a.scales().len() != b.scales().len() {
        return Err(EngineError::Mismatch("signals"));
    }
    if a.candidates() != b.candidates() {
        return Err(EngineError::Mismatch("candidates"));
    }
    Ok(())
}

/// The nominal sim: with its own parameters fitted (settled), where its
/// model has any; and the evaluations that fit spent.
fn nominal_base(problem: &Problem, options: &Options) -> (Vec<Applied>, usize) {
    match problem.fit.model.base() {
        Some(base) => {
            let fitted = fit(problem, &[], base, &Hints::default(), options);
            (settle(problem, fitted.effects), fitted.evaluations)
        }
        None => (Vec::new(), 0),
    }
}

/// An addition still on `trial` that the next step did not confirm: the
/// steps end at the one that added it (which now adds nothing), and the
/// selection goes back to what it was before it, settled there again,
/// with its held-out sums per signal.
fn withdraw(
    problem: &Problem,
    trial: Trial,
    steps: &mut Vec<Step>,
) -> (Vec<Applied>, Vec<(f64, usize)>) {
    steps.truncate(trial.step + 1);
    if let Some(step) = steps.last_mut() {
        step.added = None;
    }
    let chosen = settle(problem, trial.chosen);
    let current = held_sums(problem, &chosen).unwrap_or(trial.current);
    (chosen, current)
}

/// `candidate`'s parameters by name with `values` (in its order and units).
fn values_of(candidate: &Candidate, values: &[f64]) -> BTreeMap<String, f64> {
    candidate
        .parameters
        .iter()
        .zip(values)
        .map(|(p, v)| (p.name.to_string(), *v))
        .collect()
}

/// One step's ranking: each fit's candidate (the last effect it added)
/// with its share of the gap `before` closed (`share` of the held-out gap
/// after, `gap_of` of a held-out sum), its information criterion against
/// the `current` held-out sums (noise `floor`), its fitted values and
/// units; best criterion first (stable sort: ties keep candidate order).
fn rank<'f>(
    fits: &'f [Fitted],
    candidates: &[Candidate],
    current: &[(f64, usize)],
    floor: f64,
    gap_of: &dyn Fn(f64) -> f64,
    share: &dyn Fn(f64) -> f64,
) -> Vec<(Ranked, &'f Fitted)> {
    let mut ranked: Vec<(Ranked, &Fitted)> = fits
        .iter()
        .map(|f| {
            let mine = f.effects.last().cloned().unwrap_or(Applied {
                candidate: 0,
                values: Vec::new(),
            });
            let candidate = &candidates[mine.candidate];
            let parameters = &candidate.parameters;
            let after = gap_of(total(&f.held));
            (
                Ranked {
                    effect: candidate.name.to_string(),
                    score: share(after),
                    criterion: criterion(current, &f.held, parameters.len(), floor),
                    params: values_of(candidate, &mine.values),
                    units: parameters
                        .iter()
                        .map(|p| (p.name.to_string(), p.unit.to_string()))
                        .collect(),
                    held_out_after: after,
                },
                f,
            )
        })
        .collect();
    ranked.sort_by(|a, b| b.0.criterion.total_cmp(&a.0.criterion));
    ranked
}

/// Takes the step's winning fit into the selection: its effects settled
/// (the base's parameters kept in range) and, when settling moved them,
/// refitted and settled again until the first `base_count` parameters stop
/// moving (at most [`REFITS`] rounds: a base far from the reference of the
/// step's fits, an arm fitted to the arm after a slip, needs more than
/// one). Returns the new selection, its held-out sums per signal and the
/// evaluations the refits spent.
fn accept(
    problem: &Problem,
    fitted: Fitted,
    base_count: usize,
    options: &Options,
) -> (Vec<Applied>, Vec<(f64, usize)>, usize) {
    let held = problem.held.model;
    let settled = settle(problem, fitted.effects.clone());
    if settled == fitted.effects {
        return (settled, fitted.held, 0);
    }
    let mut spent_all = 0;
    let mut set = settled;
    for _ in 0..REFITS {
        let (refitted, spent) = refit(problem, set.clone(), options);
        spent_all += spent;
        let moved = units_of(held, &refitted)
            .iter()
            .zip(units_of(held, &set))
            .take(base_count)
            .any(|(a, b)| (a - b).abs() > BASE_STILL);
        set = refitted;
        if !moved {
            break;
        }
    }
    let current = held_sums(problem, &set).unwrap_or(fitted.held);
    (set, current, spent_all)
}

/// The selection's `added` effects (after the nominal base), each as the
/// step that added it ranked it (`steps[i]` for the i-th), with its final
/// values; `after` is the held-out gap of an effect no step ranked.
fn added_effects(
    added: &[Applied],
    steps: &[Step],
    candidates: &[Candidate],
    after: f64,
) -> Vec<Ranked> {
    added
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let candidate = &candidates[a.candidate];
            let mut ranked = steps[i]
                .ranking
                .iter()
                .find(|r| r.effect == candidate.name)
                .cloned()
                .unwrap_or_else(|| Ranked {
                    effect: candidate.name.to_string(),
                    score: 0.0,
                    criterion: 0.0,
                    params: BTreeMap::new(),
                    units: BTreeMap::new(),
                    held_out_after: after,
                });
            ranked.params = values_of(candidate, &a.values);
            ranked
        })
        .collect()
}

/// Diagnoses `problem`: ranks every candidate and adds effects by forward
/// selection (see the module docs). `progress` is told of every finished
/// fit.
///
/// # Errors
/// The nominal sim fails, or the two sides are not the same system.
pub fn select(
    problem: &Problem,
    options: &Options,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Selection, EngineError> {
    check_alike(problem)?;
    let held = problem.held.model;
    let floor = held.noise_floor();
    let candidates = problem.fit.model.candidates();
    let (mut chosen, spent) = nominal_base(problem, options);
    let mut evaluations = 1 + spent;
    let nominal_effects = chosen.clone();
    let base_count: usize = nominal_effects
        .iter()
        .map(|a| candidates[a.candidate].parameters.len())
        .sum();
    let nominal = held.predict(&chosen).map_err(EngineError::Nominal)?;
    let nominal_sums = signal_sums(held, &nominal, &problem.held.mask);
    let (nominal_sum, terms) = (
        total(&nominal_sums),
        nominal_sums.iter().map(|s| s.1).sum::<usize>(),
    );
    let (location, mut hints) = located(held, &nominal);
    let gap_of = |sum: f64| gap(sum / terms.max(1) as f64, floor);
    let before = gap_of(nominal_sum);
    let share = |after: f64| {
        if before > 0.0 {
            1.0 - after / before
        } else {
            0.0
        }
    };
    let mut current = nominal_sums;
    let mut steps = Vec::new();
    let mut trial: Option<Trial> = None;
    for _ in 0..options.max_effects.min(candidates.len()) {
        let remaining: Vec<usize> = (0..candidates.len())
            .filter(|c| chosen.iter().all(|a| a.candidate != *c))
            .collect();
        // No addition can gain more than the whole gap left: once that is
        // below the least gain, later steps cannot add anything (the
        // first step is always run, for its ranking).
        let hopeless = !steps.is_empty() && gap_of(total(&current)) < options.min_gain;
        if remaining.is_empty() || hopeless {
            break;
        }
        // Later candidates start from what the chosen effects leave (a
        // slip's change point or a torque's frequency hidden under a
        // larger first effect shows only once that is taken out).
        if !steps.is_empty() {
            let prediction = held.predict(&chosen).map_err(EngineError::Nominal)?;
            hints = located(held, &prediction).1;
        }
        let done = AtomicUsize::new(0);
        let fits = parallel_map(remaining.len(), options.threads, |i| {
            let fitted = fit(problem, &chosen, remaining[i], &hints, options);
            progress(Progress {
                done: done.fetch_add(1, Ordering::Relaxed) + 1,
                total: remaining.len(),
                candidate: candidates[remaining[i]].name,
            });
            fitted
        });
        evaluations += fits.iter().map(|f| f.evaluations).sum::<usize>();
        let ranked = rank(&fits, candidates, &current, floor, &gap_of, &share);
        let gap_now = gap_of(total(&current));
        // The share counts from the gap before an addition on trial.
        let share_of = trial.as_ref().map_or(gap_now, |t| t.gap);
        let best = ranked
            .first()
            .filter(|(r, _)| r.criterion > 0.0 && gap_now - r.held_out_after >= options.min_gain);
        // An addition confirming a trial must be of like size: itself
        // remove half the share of the gap it joins.
        let alike =
            |after: f64| trial.is_none() || gap_now - after >= options.min_share / 2.0 * gap_now;
        let winner = match best {
            Some((r, _))
                if share_of - r.held_out_after >= options.min_share * share_of
                    && alike(r.held_out_after) =>
            {
                trial = None;
                best
            }
            Some(_) if trial.is_none() => {
                trial = Some(Trial {
                    chosen: chosen.clone(),
                    current: current.clone(),
                    step: steps.len(),
                    gap: gap_now,
                });
                best
            }
            _ => None,
        }
        .map(|(r, f)| (r.effect.clone(), (*f).clone()));
        steps.push(Step {
            ranking: ranked.iter().map(|(r, _)| r.clone()).collect(),
            added: winner.as_ref().map(|w| w.0.clone()),
        });
        let Some((_, fitted)) = winner else { break };
        let spent;
        (chosen, current, spent) = accept(problem, fitted, base_count, options);
        evaluations += spent;
    }
    if let Some(t) = trial {
        (chosen, current) = withdraw(problem, t, &mut steps);
    }
    let chosen_prediction = if chosen == nominal_effects {
        nominal.clone()
    } else {
        held.predict(&chosen).map_err(EngineError::Nominal)?
    };
    let (remaining, _) = locate(held, &scaled(held, &chosen_prediction));
    let after = gap_of(total(&current));
    let base = nominal_effects.len();
    let effects = added_effects(&chosen[base.min(chosen.len())..], &steps, candidates, after);
    let parameters_of = |effects: &[Applied]| {
        effects
            .first()
            .filter(|_| base > 0)
            .map(|a| values_of(&candidates[a.candidate], &a.values))
            .unwrap_or_default()
    };
    Ok(Selection {
        effects,
        nominal: parameters_of(&nominal_effects),
        corrected: parameters_of(&chosen),
        steps,
        location,
        remaining,
        gap: Gap {
            metric: held.gap_metric().to_string(),
            before,
            after,
            shrink: share(after),
            held_out: true,
        },
        predictions: Predictions {
            nominal: Some(nominal),
            chosen: Some(chosen_prediction),
        },
        evaluations,
        chosen,
    })
}

#[cfg(test)]
mod tests {
    use super::criterion;

    #[test]
    fn criterion_charges_each_parameter_ln_n() {
        // Known noise: a gain of exactly k ln n is worth nothing.
        let n = 1000usize;
        let c = criterion(
            &[(2000.0, n)],
            &[(2000.0 - 2.0 * (n as f64).ln(), n)],
            2,
            1.0,
        );
        assert!(c.abs() < 1e-9);
        // Unknown noise: halving the residual is worth n ln 2 − k ln n.
        let c = criterion(&[(2.0, n)], &[(1.0, n)], 1, 0.0);
        assert!((c - (n as f64 * 2f64.ln() - (n as f64).ln())).abs() < 1e-9);
        assert_eq!(
            criterion(&[(1.0, n)], &[(f64::INFINITY, n)], 1, 1.0),
            f64::NEG_INFINITY
        );
        // Unknown noise, two signals: each is judged against its own
        // noise, so halving a quiet signal's residual counts as much as
        // halving a loud one's.
        let quiet = criterion(&[(1e6, n), (2.0, n)], &[(1e6, n), (1.0, n)], 0, 0.0);
        let loud = criterion(&[(2e6, n), (1.0, n)], &[(1e6, n), (1.0, n)], 0, 0.0);
        assert!((quiet - loud).abs() < 1e-6 && (quiet - n as f64 * 2f64.ln()).abs() < 1e-6);
    }
}
