//! The blind self-check: logs with a withheld effect, diagnosed by a
//! diagnoser that is told only the arm lengths.
//!
//! Each log draws, from one seeded stream: a class uniformly among the
//! ten effects of `plant.md` and `none`; one of the six benchmark arms;
//! the effect's parameters from [`RANGES`]; and the noise seed. The
//! reference plant (`limb-sim`, noise on) writes the log, ground truth
//! is dropped, and [`crate::verdict::diagnose`] answers. The check counts
//! the confusion matrix, top-1 accuracy, the held-out shrink of correct
//! answers, the relative error of their fitted parameters, and `none`
//! answers given for logs whose effect is larger than twice the noise
//! floor (effect size: the largest over signals of the RMS of
//! (sim with effect − nominal sim) / σ, both noise-free).
//!
//! # Parameter ranges
//! [`RANGES`] spans roughly a quarter to four times the magnitude of the
//! labelled example logs of `shared/data/effects/`, inside each effect's
//! valid range; signed effects take either sign. Sampling is uniform in
//! the logarithm where the range spans a decade or more.

use crate::arm::ArmModel;
use crate::engine::Progress;
use crate::model::{Applied, Model};
use crate::verdict::{diagnose, DiagnoseError};
use limb_sim::effects::{Effect, Effects, CATALOGUE};
use limb_sim::log::Record;
use limb_sim::noise::Gaussian;
use limb_sim::{scripted, Plant, PlantParameters, BENCHMARK_ARMS};
use serde::Serialize;

/// How one parameter is drawn: (name, low, high, logarithmic, either sign).
pub type Range = (&'static str, f64, f64, bool, bool);

/// The draw of each effect's parameters, in [`CATALOGUE`] order.
pub const RANGES: [&[Range]; 10] = [
    &[
        ("coulomb", 0.05, 1.0, true, false),
        ("viscous", 0.05, 1.0, true, false),
    ],
    &[("width", 0.006, 0.1, true, false)],
    &[
        ("pos", 0.001, 0.015, true, false),
        ("ang", 0.004, 0.04, true, false),
    ],
    &[("delay", 0.012, 0.2, true, false)],
    &[("k", 200.0, 3000.0, true, false)],
    &[("factor", 0.5, 2.0, true, false)],
    &[("angle", 0.05, 0.5, true, true)],
    &[("k", 300.0, 5000.0, true, false)],
    &[
        ("amp", 0.2, 2.0, true, false),
        ("freq", 0.3, 3.0, true, false),
    ],
    &[
        ("shift", 0.004, 0.04, true, true),
        ("at", 4.0, 22.0, false, false),
    ],
];

/// The classes: the ten effects, then `none`.
pub fn classes() -> Vec<&'static str> {
    CATALOGUE
        .iter()
        .map(|d| d.name)
        .chain(std::iter::once("none"))
        .collect()
}

/// One log of the check.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Case {
    /// Index in the run.
    pub index: usize,
    /// The withheld effect (or `none`).
    pub truth: String,
    /// Its parameters.
    pub params: Vec<(String, f64)>,
    /// Arm lengths [m].
    pub arm: (f64, f64),
    /// Noise seed.
    pub seed: u64,
    /// Effect size: largest per-signal RMS of its noise-free effect [σ].
    pub size: f64,
    /// The diagnoser's answer.
    pub answer: String,
    /// Held-out shrink of the answer.
    pub shrink: f64,
    /// Fitted parameters when the answer is right, relative error each.
    pub parameter_errors: Vec<f64>,
}

/// The check's result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Logs diagnosed.
    pub logs: usize,
    /// Seed of the run.
    pub seed: u64,
    /// Class names, the row and column order of `confusion`.
    pub classes: Vec<String>,
    /// confusion[truth][answer] counts.
    pub confusion: Vec<Vec<usize>>,
    /// Share of logs whose answer is the withheld class.
    pub top1_accuracy: f64,
    /// Median held-out shrink over correct answers with an effect.
    pub median_shrink: f64,
    /// Median relative parameter error over correct answers with an
    /// effect (every parameter).
    pub median_parameter_error: f64,
    /// `none` answered for a log whose effect exceeds twice the noise.
    pub none_for_large_effects: usize,
    /// Logs whose effect is larger than twice the noise floor.
    pub large_effects: usize,
    /// Every log.
    pub cases: Vec<Case>,
}

fn draw(random: &mut Gaussian, range: &Range) -> f64 {
    let (_, low, high, logarithmic, signed) = *range;
    let u = random.uniform();
    let magnitude = if logarithmic {
        (low.ln() + u * (high.ln() - low.ln())).exp()
    } else {
        low + u * (high - low)
    };
    if signed && random.uniform() < 0.5 {
        -magnitude
    } else {
        magnitude
    }
}

fn pick(random: &mut Gaussian, count: usize) -> usize {
    ((random.uniform() * count as f64) as usize).min(count.saturating_sub(1))
}

/// The log of one case: the reference plant with arm lengths `l1`, `l2`
/// [m], noise seed `seed` and `effect`, noise on, ground truth dropped.
///
/// # Errors
/// The plant's refusal of the arm or the effect, in words.
pub fn simulate(
    l1: f64,
    l2: f64,
    seed: u64,
    effect: Option<Effect>,
) -> Result<Vec<Record>, String> {
    let mut params = PlantParameters::new(l1, l2);
    params.seed = seed;
    let effects = Effects::new(effect.as_slice()).map_err(|e| e.to_string())?;
    let mut plant = Plant::with_effects(params, effects)?;
    let rows = scripted::estimation_run(&mut plant)?;
    Ok(rows
        .iter()
        .map(|row| Record {
            truth: None,
            ..Record::from_row(row)
        })
        .collect())
}

fn median(mut values: Vec<f64>) -> f64 {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Largest per-signal RMS of (with effect − nominal) / σ, noise-free.
fn effect_size(model: &ArmModel, applied: &[Applied]) -> f64 {
    let (Ok(with), Ok(without)) = (model.predict(applied), model.predict(&[])) else {
        return f64::NAN;
    };
    (0..with.signals())
        .map(|s| {
            let (a, b) = (with.column(s), without.column(s));
            let sum: f64 = a
                .iter()
                .zip(&b)
                .map(|(x, y)| ((x - y) / model.scales()[s]).powi(2))
                .sum();
            (sum / a.len().max(1) as f64).sqrt()
        })
        .fold(0.0, f64::max)
}

/// One case: draw, simulate, diagnose.
fn case(index: usize, random: &mut Gaussian, threads: usize) -> Result<Case, DiagnoseError> {
    let names = classes();
    let class = pick(random, names.len());
    let (l1, l2) = BENCHMARK_ARMS[pick(random, BENCHMARK_ARMS.len())];
    let seed = (random.uniform() * 1e15) as u64;
    let (effect, params) = match RANGES.get(class) {
        Some(ranges) => {
            let params: Vec<(String, f64)> = ranges
                .iter()
                .map(|r| (r.0.to_string(), draw(random, r)))
                .collect();
            let pairs: Vec<(&str, f64)> = params.iter().map(|(k, v)| (k.as_str(), *v)).collect();
            let effect = Effect::new(names[class], &pairs)
                .map_err(|e| DiagnoseError::SelfCheck(e.to_string()))?;
            (Some(effect), params)
        }
        None => (None, Vec::new()),
    };
    let records = simulate(l1, l2, seed, effect).map_err(DiagnoseError::SelfCheck)?;
    let diagnosed = diagnose(l1, l2, &records, threads, &|_: Progress| {})?;
    let applied: Vec<Applied> = effect
        .iter()
        .map(|e| Applied {
            candidate: class,
            values: e.values(),
        })
        .collect();
    let size = effect_size(&diagnosed.model, &applied);
    let d = &diagnosed.diagnosis;
    let right = d.effect == names[class] && effect.is_some();
    let parameter_errors = if right {
        d.ranking
            .first()
            .map(|r| {
                params
                    .iter()
                    .filter_map(|(k, v)| r.params.get(k).map(|f| ((f - v) / v).abs()))
                    .collect()
            })
            .unwrap_or_default()
    } else {
        Vec::new()
    };
    Ok(Case {
        index,
        truth: names[class].to_string(),
        params,
        arm: (l1, l2),
        seed,
        size,
        answer: d.effect.clone(),
        shrink: d.gap.shrink,
        parameter_errors,
    })
}

/// Runs the check over `logs` logs drawn from `seed`; `progress` is told
/// of every finished case.
///
/// # Errors
/// A case whose simulation or diagnosis failed (a defect, not a miss).
pub fn run(
    logs: usize,
    seed: u64,
    threads: usize,
    progress: &dyn Fn(&Case),
) -> Result<Summary, DiagnoseError> {
    let names = classes();
    let mut random = Gaussian::new(seed);
    let mut cases = Vec::with_capacity(logs);
    for index in 0..logs {
        let c = case(index, &mut random, threads)?;
        progress(&c);
        cases.push(c);
    }
    let position = |name: &str| {
        names
            .iter()
            .position(|n| *n == name)
            .unwrap_or(names.len() - 1)
    };
    let mut confusion = vec![vec![0usize; names.len()]; names.len()];
    for c in &cases {
        confusion[position(&c.truth)][position(&c.answer)] += 1;
    }
    let correct = cases.iter().filter(|c| c.truth == c.answer).count();
    let right_effects = || {
        cases
            .iter()
            .filter(|c| c.truth == c.answer && c.truth != "none")
    };
    let large = |c: &&Case| c.truth != "none" && c.size > 2.0;
    Ok(Summary {
        logs,
        seed,
        classes: names.iter().map(|n| n.to_string()).collect(),
        confusion,
        top1_accuracy: correct as f64 / logs.max(1) as f64,
        median_shrink: median(right_effects().map(|c| c.shrink).collect()),
        median_parameter_error: median(
            right_effects()
                .flat_map(|c| c.parameter_errors.iter().copied())
                .collect(),
        ),
        none_for_large_effects: cases
            .iter()
            .filter(large)
            .filter(|c| c.answer == "none")
            .count(),
        large_effects: cases.iter().filter(large).count(),
        cases,
    })
}
