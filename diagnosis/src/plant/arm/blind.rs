//! The blind self-check: logs with withheld effects, diagnosed by a
//! diagnoser that is told nothing of the arm (lengths fitted).
//!
//! Each log draws, from one seeded stream: in three logs of four a class
//! uniformly among the effects of the run's [`Focus`] and `none` (plant.md's
//! ten, a person's arm's four, or all fourteen), in the fourth a pair of
//! distinct effects (one of the focus's, any other); a random arm (l1 uniform in
//! [`UPPER_ARMS`], l2 in [`FOREARMS`]); the effects' parameters from
//! [`RANGES`]; and the noise seed. The reference plant (`limb-sim`, noise
//! on) writes the log, ground truth is dropped, and
//! [`super::outcome::diagnose`] answers without the lengths. The check
//! counts, over the single-effect and clean logs, the confusion matrix of
//! the first effect added, top-1 accuracy, clean logs accused, `none`
//! answers for effects larger than twice the noise floor (effect size:
//! the largest over signals of the RMS of (sim with effect − nominal
//! sim) / σ, both noise-free, with the true arm), the corrected arm's
//! error; over the pairs, how often both effects are among those added.
//!
//! The diagnoser fits the lengths, so part of an effect can look like a
//! different arm (a slip before the arm leaves the table is a shorter or
//! longer forearm from the start). Each log also gets the effect's
//! **identifiable size**: the same measure of what the effect leaves once
//! the arm lengths absorb what they can (the noise-free log with the
//! effect less the nominal sim at the lengths that fit it best). The
//! check counts `none` answers both ways. The issue's bar ("`none`
//! never for an effect above twice the noise floor", lengths not given)
//! is counted by the identifiable size: for a diagnosis not told the arm,
//! an effect is what no arm explains (diagnosis README, "How the `none`
//! bar is counted").
//!
//! # Parameter ranges
//! [`RANGES`] spans roughly a quarter to four times the magnitude of the
//! labelled example logs of `shared/data/effects/`, inside each effect's
//! valid range; signed effects take either sign. Sampling is uniform in
//! the logarithm where the range spans a decade or more.

use super::model::{ArmModel, LengthSolve, Lengths};
use super::outcome::{diagnose, DiagnoseError, UNEXPLAINED};
use crate::engine::{parallel_map, Progress};
use crate::model::{Applied, Model, Series};
use limb_sim::effects::{Effect, Effects, CATALOGUE};
use limb_sim::log::Record;
use limb_sim::noise::Gaussian;
use limb_sim::{scripted, ArmBuild, ArmParameters, Plant, PlantParameters};

/// Range the upper-arm length is drawn from [m].
pub const UPPER_ARMS: [f64; 2] = [0.24, 0.36];
/// Range the forearm length is drawn from [m].
pub const FOREARMS: [f64; 2] = [0.16, 0.24];
/// Every this many logs, one carries a pair of effects.
const PAIR_EVERY: usize = 4;
/// Corrected arm error counted as right [m].
pub const ARM_TOLERANCE: f64 = 0.003;
use serde::{Deserialize, Serialize};

/// How one parameter is drawn: (name, low, high, logarithmic, either sign).
pub type Range = (&'static str, f64, f64, bool, bool);

/// The draw of each effect's parameters, in [`CATALOGUE`] order. A
/// person's arm's effects (the last four) reach down to a few times the
/// noise floor at their small end (`spec/human-arm.md`, "Self-check
/// draws").
pub const RANGES: [&[Range]; 14] = [
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
    &[
        ("shoulder", 0.05, 2.0, true, false),
        ("elbow", 0.05, 2.0, true, false),
    ],
    &[
        ("gain", 0.05, 3.0, true, false),
        ("threshold", 0.0, 0.08, false, false),
    ],
    &[
        ("x", 0.002, 0.03, true, true),
        ("z", 0.002, 0.03, true, true),
    ],
    &[
        ("across", 0.004, 0.04, true, true),
        ("along", -0.02, 0.05, false, false),
    ],
];

/// The classes: the fourteen effects the self-check draws (those with a
/// [`RANGES`] entry: the catalogue's `shoulder_height` is no effect the
/// diagnosis names but part of a person's arm, fitted with the lengths),
/// then `none`.
pub fn classes() -> Vec<&'static str> {
    CATALOGUE
        .iter()
        .take(RANGES.len())
        .map(|d| d.name)
        .chain(std::iter::once("none"))
        .collect()
}

/// The answers a diagnosis gives: the classes, then [`UNEXPLAINED`].
pub fn answers() -> Vec<&'static str> {
    let mut answers = classes();
    answers.push(UNEXPLAINED);
    answers
}

/// confusion[truth][answer] over single-effect and clean logs, rows in
/// [`classes`] order, columns in [`answers`] order (an answer outside
/// them, which the diagnosis never gives, counts as unexplained).
fn confusion(singles: &[&Case]) -> Vec<Vec<usize>> {
    let (rows, columns) = (classes(), answers());
    let mut confusion = vec![vec![0usize; columns.len()]; rows.len()];
    for c in singles {
        let row = rows.iter().position(|n| Some(*n) == c.class());
        let column = columns
            .iter()
            .position(|n| *n == c.answer)
            .unwrap_or(columns.len() - 1);
        if let Some(row) = row {
            confusion[row][column] += 1;
        }
    }
    confusion
}

/// One log of the check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Case {
    /// Index in the run.
    pub index: usize,
    /// The withheld effects (empty: a clean log).
    pub truth: Vec<String>,
    /// Their parameters.
    pub params: Vec<Vec<(String, f64)>>,
    /// Arm lengths [m].
    pub arm: (f64, f64),
    /// Noise seed.
    pub seed: u64,
    /// Effect size of the smallest withheld effect [σ] (0 for none).
    pub size: f64,
    /// Its identifiable size: what is left of it once the arm lengths
    /// absorb what they can [σ] (0 for none).
    pub identifiable_size: f64,
    /// The first effect added, or `none`.
    pub answer: String,
    /// Every effect added, in order.
    pub added: Vec<String>,
    /// Held-out shrink of the answer.
    pub shrink: f64,
    /// Largest error of the corrected arm's lengths [m].
    pub arm_error: f64,
    /// Fitted parameters when a single effect is answered right, relative
    /// error each.
    pub parameter_errors: Vec<f64>,
}

impl Case {
    /// The class of a single-effect or clean log (`none`), `None` for a
    /// pair.
    pub fn class(&self) -> Option<&str> {
        match self.truth.as_slice() {
            [] => Some("none"),
            [one] => Some(one),
            _ => None,
        }
    }
}

/// The check's result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Logs diagnosed.
    pub logs: usize,
    /// Seed of the run.
    pub seed: u64,
    /// Class names, the row order of `confusion`.
    pub classes: Vec<String>,
    /// The answers, the column order of `confusion`: the classes, then
    /// [`UNEXPLAINED`].
    pub answers: Vec<String>,
    /// confusion[truth][answer] counts over single-effect and clean logs.
    pub confusion: Vec<Vec<usize>>,
    /// Single-effect and clean logs.
    pub singles: usize,
    /// Share of them whose answer is the withheld class.
    pub top1_accuracy: f64,
    /// Median held-out shrink over correct answers with an effect.
    pub median_shrink: f64,
    /// Median relative parameter error over correct answers with an
    /// effect (every parameter).
    pub median_parameter_error: f64,
    /// `none` answered for a single-effect log whose effect exceeds twice
    /// the noise.
    pub none_for_large_effects: usize,
    /// Single-effect logs whose effect is larger than twice the noise floor.
    pub large_effects: usize,
    /// `none` answered for a single-effect log whose identifiable size
    /// exceeds twice the noise.
    pub none_for_identifiable_effects: usize,
    /// Single-effect logs whose identifiable size exceeds twice the noise.
    pub identifiable_effects: usize,
    /// Clean logs.
    pub clean: usize,
    /// Clean logs given an effect.
    pub clean_accused: usize,
    /// Single-effect logs.
    pub single_effects: usize,
    /// Of them, those whose corrected arm is within [`ARM_TOLERANCE`].
    pub arm_within_tolerance: usize,
    /// Logs with a pair of effects.
    pub pairs: usize,
    /// Of them, those with both effects among those added.
    pub pairs_both_named: usize,
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
/// [m], noise seed `seed` and `effects`, noise on, ground truth dropped.
///
/// # Errors
/// The plant's refusal of the arm or the effects, in words.
pub fn simulate(l1: f64, l2: f64, seed: u64, effects: &[Effect]) -> Result<Vec<Record>, String> {
    simulate_on(ArmBuild::Rod, l1, l2, seed, effects)
}

/// [`simulate`] with the lengths put on `build` (a person's segments, or
/// plant.md's dummy).
///
/// # Errors
/// As [`simulate`].
pub fn simulate_on(
    build: ArmBuild,
    l1: f64,
    l2: f64,
    seed: u64,
    effects: &[Effect],
) -> Result<Vec<Record>, String> {
    let mut params = PlantParameters::new(l1, l2);
    params.arm = ArmParameters::built(build, l1, l2);
    params.seed = seed;
    let effects = Effects::new(effects).map_err(|e| e.to_string())?;
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

/// Largest per-signal RMS of `difference` / σ (rows: samples).
fn largest_rms(difference: &[Vec<f64>], scales: &[f64]) -> f64 {
    (0..scales.len())
        .map(|s| {
            let sum: f64 = difference
                .iter()
                .map(|row| (row[s] / scales[s]).powi(2))
                .sum();
            (sum / difference.len().max(1) as f64).sqrt()
        })
        .fold(0.0, f64::max)
}

/// `a` − `b` per sample and signal.
fn minus(a: &Series, b: &Series) -> Vec<Vec<f64>> {
    (0..a.samples())
        .map(|i| a.row(i).iter().zip(b.row(i)).map(|(x, y)| x - y).collect())
        .collect()
}

/// (with effect − nominal) of `model` (lengths given), noise-free, per
/// sample and signal.
fn difference(model: &ArmModel, applied: &[Applied]) -> Option<Vec<Vec<f64>>> {
    Some(minus(
        &model.predict(applied).ok()?,
        &model.predict(&[]).ok()?,
    ))
}

/// Largest per-signal RMS of (with effect − nominal) / σ, noise-free.
fn effect_size(model: &ArmModel, applied: &[Applied]) -> f64 {
    difference(model, applied).map_or(f64::NAN, |d| largest_rms(&d, model.scales()))
}

/// Step of the central differences of the nominal sim by the lengths [m].
const LENGTH_STEP: f64 = 5e-4;

/// Gauss–Newton iterations of [`identifiable_size`]'s fit of the lengths.
const LENGTH_ITERATIONS: usize = 4;

/// [`effect_size`] of what the effect leaves once the arm lengths absorb
/// what they can: the noise-free log with the effect at the true arm,
/// less the nominal sim at the lengths that fit it best (weights 1/σ²;
/// [`LENGTH_ITERATIONS`] Gauss–Newton steps from the true arm, the
/// derivative by (l1, l2) from central differences of ±[`LENGTH_STEP`]).
/// `truth` is the sim of the true arm `arm` against `records`. NaN when
/// a simulation fails or the fit is singular.
fn identifiable_size(
    truth: &ArmModel,
    records: &[Record],
    arm: (f64, f64),
    applied: &[Applied],
) -> f64 {
    let nominal = |(l1, l2): (f64, f64)| {
        ArmModel::new(Lengths::Given(l1, l2), ArmBuild::Rod, records)
            .ok()
            .and_then(|m| m.predict(&[]).ok())
    };
    let (Ok(with), scales) = (truth.predict(applied), truth.scales()) else {
        return f64::NAN;
    };
    let h = LENGTH_STEP;
    let mut fitted = arm;
    for _ in 0..LENGTH_ITERATIONS {
        let (l1, l2) = fitted;
        let (Some(at), Some(a), Some(b), Some(c), Some(d)) = (
            nominal((l1, l2)),
            nominal((l1 + h, l2)),
            nominal((l1 - h, l2)),
            nominal((l1, l2 + h)),
            nominal((l1, l2 - h)),
        ) else {
            return f64::NAN;
        };
        let mut solve = LengthSolve::new(2);
        for (i, row) in minus(&with, &at).iter().enumerate() {
            for (s, value) in row.iter().enumerate() {
                let j = [
                    (a.row(i)[s] - b.row(i)[s]) / (2.0 * h),
                    (c.row(i)[s] - d.row(i)[s]) / (2.0 * h),
                ];
                solve.add(&j, *value, scales[s]);
            }
        }
        let Some(delta) = solve.solve() else {
            return f64::NAN;
        };
        fitted = (l1 + delta[0], l2 + delta[1]);
    }
    nominal(fitted).map_or(f64::NAN, |at| largest_rms(&minus(&with, &at), scales))
}

/// One effect of class `class` with parameters drawn from [`RANGES`].
fn draw_effect(
    random: &mut Gaussian,
    class: usize,
) -> Result<(Effect, Vec<(String, f64)>), DiagnoseError> {
    let names = classes();
    let ranges = RANGES
        .get(class)
        .ok_or_else(|| DiagnoseError::SelfCheck(format!("no class {class}")))?;
    let params: Vec<(String, f64)> = ranges
        .iter()
        .map(|r| (r.0.to_string(), draw(random, r)))
        .collect();
    let pairs: Vec<(&str, f64)> = params.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    let effect =
        Effect::new(names[class], &pairs).map_err(|e| DiagnoseError::SelfCheck(e.to_string()))?;
    Ok((effect, params))
}

/// One log's draw: the withheld classes, their parameters, the arm and
/// the noise seed.
struct Drawn {
    index: usize,
    classes: Vec<usize>,
    effects: Vec<Effect>,
    params: Vec<Vec<(String, f64)>>,
    arm: (f64, f64),
    seed: u64,
}

/// Which effects a run draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Focus {
    /// The ten effects of `plant.md` (a robot's: friction, backlash, …),
    /// single-effect and clean logs uniformly over those ten and `none`:
    /// the draws of the README's blind seeds, which this reproduces log
    /// for log.
    Robot,
    /// Every effect of the catalogue (single-effect and clean logs
    /// uniformly over the fourteen effects and `none`).
    All,
    /// A person's arm's effects ([`HUMAN_ARM`]): single-effect and clean
    /// logs uniformly over those four and `none`; each pair holds one of
    /// them and any other effect of the catalogue.
    HumanArm,
}

impl Focus {
    /// The effects (indices in [`CATALOGUE`] order) a single-effect log
    /// draws from, and those a pair's second effect draws from.
    fn draws(self) -> (&'static [usize], usize) {
        const ROBOT: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9];
        const ALL: [usize; 14] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13];
        match self {
            Focus::Robot => (&ROBOT, ROBOT.len()),
            Focus::All => (&ALL, ALL.len()),
            Focus::HumanArm => (&HUMAN_ARM, ALL.len()),
        }
    }

    /// The name a command line gives it.
    pub fn parse(name: &str) -> Option<Focus> {
        match name {
            "robot" => Some(Focus::Robot),
            "all" => Some(Focus::All),
            "human" => Some(Focus::HumanArm),
            _ => None,
        }
    }
}

/// The classes (indices in [`CATALOGUE`] order) of a person's arm's own
/// effects: `passive_stiffness`, `spasticity`, `shoulder_rhythm`,
/// `cuff_offset`.
pub const HUMAN_ARM: [usize; 4] = [10, 11, 12, 13];

/// Draws log `index` from `random` (every draw of a log comes before the
/// next log's, so a run's logs do not depend on how they are diagnosed).
fn draw_case(index: usize, random: &mut Gaussian, focus: Focus) -> Result<Drawn, DiagnoseError> {
    let (singles, pair_pool) = focus.draws();
    let classes: Vec<usize> = if index % PAIR_EVERY == PAIR_EVERY - 1 {
        // One of the focus's effects, then any other of the pool.
        let first = singles[pick(random, singles.len())];
        let mut second = pick(random, pair_pool - 1);
        if second >= first {
            second += 1;
        }
        vec![first, second]
    } else {
        // One of the focus's effects or `none` (the last draw).
        let class = pick(random, singles.len() + 1);
        singles.get(class).copied().into_iter().collect()
    };
    let l1 = UPPER_ARMS[0] + random.uniform() * (UPPER_ARMS[1] - UPPER_ARMS[0]);
    let l2 = FOREARMS[0] + random.uniform() * (FOREARMS[1] - FOREARMS[0]);
    let seed = (random.uniform() * 1e15) as u64;
    let mut effects = Vec::new();
    let mut params = Vec::new();
    for class in &classes {
        let (effect, p) = draw_effect(random, *class)?;
        effects.push(effect);
        params.push(p);
    }
    Ok(Drawn {
        index,
        classes,
        effects,
        params,
        arm: (l1, l2),
        seed,
    })
}

/// One case: simulate the drawn log, diagnose it without the lengths
/// (one thread).
fn case(drawn: &Drawn) -> Result<Case, DiagnoseError> {
    let names = classes();
    let ((l1, l2), seed) = (drawn.arm, drawn.seed);
    let (classes, effects) = (&drawn.classes, &drawn.effects);
    let records = simulate(l1, l2, seed, effects).map_err(DiagnoseError::SelfCheck)?;
    let diagnosed = diagnose(
        Lengths::Fitted,
        ArmBuild::Rod,
        &records,
        1,
        &|_: Progress| {},
    )?;
    let truth_model = ArmModel::new(Lengths::Given(l1, l2), ArmBuild::Rod, &records)?;
    let applied: Vec<[Applied; 1]> = classes
        .iter()
        .zip(effects)
        .map(|(class, e)| {
            [Applied {
                candidate: *class,
                values: e.values(),
            }]
        })
        .collect();
    let smallest = |size: &dyn Fn(&[Applied]) -> f64| {
        let least = applied
            .iter()
            .map(|a| size(a))
            .fold(f64::INFINITY, f64::min);
        if least.is_finite() {
            least
        } else {
            0.0
        }
    };
    let size = smallest(&|a| effect_size(&truth_model, a));
    let identifiable = smallest(&|a| identifiable_size(&truth_model, &records, (l1, l2), a));
    let d = &diagnosed.diagnosis;
    let truth: Vec<String> = classes.iter().map(|c| names[*c].to_string()).collect();
    let parameter_errors = match (truth.as_slice(), d.effects.first(), drawn.params.first()) {
        ([one], Some(first), Some(p)) if *one == first.effect => p
            .iter()
            .filter_map(|(k, v)| first.params.get(k).map(|f| ((f - v) / v).abs()))
            .collect(),
        _ => Vec::new(),
    };
    Ok(Case {
        index: drawn.index,
        truth,
        params: drawn.params.clone(),
        arm: (l1, l2),
        seed,
        size,
        identifiable_size: identifiable,
        answer: d.effect.clone(),
        added: d.effects.iter().map(|e| e.effect.clone()).collect(),
        shrink: d.gap.shrink,
        arm_error: (d.arm.l1 - l1).abs().max((d.arm.l2 - l2).abs()),
        parameter_errors,
    })
}

/// Runs the check over `logs` logs drawn from `seed`, diagnosing
/// `threads` logs side by side (each on one thread: the candidates of one
/// diagnosis differ in cost by a factor of ten, whole logs balance
/// better); `progress` is told of every finished case, in the order they
/// finish. The figures do not depend on `threads`.
///
/// # Errors
/// A case whose simulation or diagnosis failed (a defect, not a miss).
pub fn run(
    logs: usize,
    seed: u64,
    threads: usize,
    progress: &(dyn Fn(&Case) + Sync),
) -> Result<Summary, DiagnoseError> {
    run_focused(logs, seed, threads, Focus::Robot, progress)
}

/// [`run`] drawing the effects of `focus`.
///
/// # Errors
/// As [`run`].
pub fn run_focused(
    logs: usize,
    seed: u64,
    threads: usize,
    focus: Focus,
    progress: &(dyn Fn(&Case) + Sync),
) -> Result<Summary, DiagnoseError> {
    let names = classes();
    let mut random = Gaussian::new(seed);
    let drawn = (0..logs)
        .map(|index| draw_case(index, &mut random, focus))
        .collect::<Result<Vec<_>, _>>()?;
    let cases = parallel_map(logs, threads, |index| {
        let c = case(&drawn[index])?;
        progress(&c);
        Ok(c)
    })
    .into_iter()
    .collect::<Result<Vec<Case>, DiagnoseError>>()?;
    let singles: Vec<&Case> = cases.iter().filter(|c| c.class().is_some()).collect();
    let confusion = confusion(&singles);
    let correct = singles
        .iter()
        .filter(|c| c.class() == Some(&c.answer))
        .count();
    let right_effects = || {
        singles
            .iter()
            .filter(|c| c.class() == Some(&c.answer) && c.answer != "none")
    };
    let single_effects: Vec<&&Case> = singles.iter().filter(|c| c.truth.len() == 1).collect();
    let large: Vec<&&&Case> = single_effects.iter().filter(|c| c.size > 2.0).collect();
    let identifiable: Vec<&&&Case> = single_effects
        .iter()
        .filter(|c| c.identifiable_size > 2.0)
        .collect();
    let clean: Vec<&&Case> = singles.iter().filter(|c| c.truth.is_empty()).collect();
    let pairs: Vec<&Case> = cases.iter().filter(|c| c.truth.len() == 2).collect();
    Ok(Summary {
        logs,
        seed,
        classes: names.iter().map(|n| n.to_string()).collect(),
        answers: answers().iter().map(|n| n.to_string()).collect(),
        confusion,
        singles: singles.len(),
        top1_accuracy: correct as f64 / singles.len().max(1) as f64,
        median_shrink: median(right_effects().map(|c| c.shrink).collect()),
        median_parameter_error: median(
            right_effects()
                .flat_map(|c| c.parameter_errors.iter().copied())
                .collect(),
        ),
        none_for_large_effects: large.iter().filter(|c| c.answer == "none").count(),
        large_effects: large.len(),
        none_for_identifiable_effects: identifiable.iter().filter(|c| c.answer == "none").count(),
        identifiable_effects: identifiable.len(),
        clean: clean.len(),
        clean_accused: clean.iter().filter(|c| c.answer != "none").count(),
        single_effects: single_effects.len(),
        arm_within_tolerance: single_effects
            .iter()
            .filter(|c| c.arm_error < ARM_TOLERANCE)
            .count(),
        pairs: pairs.len(),
        pairs_both_named: pairs
            .iter()
            .filter(|c| c.truth.iter().all(|t| c.added.contains(t)))
            .count(),
        cases,
    })
}

#[cfg(test)]
mod tests {
    use super::{answers, classes, confusion, Case};

    fn case(truth: &[&str], answer: &str) -> Case {
        Case {
            index: 0,
            truth: truth.iter().map(|t| t.to_string()).collect(),
            params: Vec::new(),
            arm: (0.3, 0.2),
            seed: 0,
            size: 0.0,
            identifiable_size: 0.0,
            answer: answer.to_string(),
            added: Vec::new(),
            shrink: 0.0,
            arm_error: 0.0,
            parameter_errors: Vec::new(),
        }
    }

    /// `unexplained` is a column of its own, not counted as `none`; a
    /// pair has no row.
    #[test]
    fn unexplained_answers_are_not_counted_as_none() {
        let cases = [
            case(&["grasp_slip"], "unexplained"),
            case(&["grasp_slip"], "none"),
            case(&[], "none"),
            case(&["backlash", "latency"], "backlash"),
        ];
        let singles: Vec<&Case> = cases.iter().collect();
        let table = confusion(&singles);
        let (rows, columns) = (classes(), answers());
        let at = |name: &str, list: &[&str]| list.iter().position(|n| *n == name).unwrap();
        assert_eq!(table.len(), rows.len());
        assert!(table.iter().all(|row| row.len() == columns.len()));
        let slip = &table[at("grasp_slip", &rows)];
        assert_eq!(slip[at("unexplained", &columns)], 1);
        assert_eq!(slip[at("none", &columns)], 1);
        assert_eq!(table[at("none", &rows)][at("none", &columns)], 1);
        assert_eq!(table.iter().flatten().sum::<usize>(), 3);
    }
}
