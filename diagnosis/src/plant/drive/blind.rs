//! The blind self-check of the drive diagnosis: simulated drives
//! ([`super::sim`]) with withheld effects drawn at random — a single
//! effect (or none) in even trials, a pair in odd ones — each diagnosed
//! from a fit run and a separate validation run (different reference and
//! noise), without being told what was withheld.
//!
//! Scores: **top-1** for single effects (the first effect added is the
//! withheld one, `none` for none) and **set recovery** for pairs (the
//! effects added are exactly the pair; also counted: both of the pair are
//! among those added).

use super::outcome::{diagnose, Run, MAX_EFFECTS};
use super::sim::{reference, simulate, Truth, Uniform};
use super::CUTOFF;
use crate::engine::Options;
use serde::Serialize;

/// Length of each simulated run [s].
pub const DURATION: f64 = 10.0;
/// The withheld effects drawn from, with `none` for singles.
pub const EFFECTS: [&str; 8] = [
    "viscous_friction",
    "coulomb_friction",
    "asymmetric_friction",
    "stribeck_friction",
    "latency",
    "quantization",
    "compliance",
    "backlash",
];

/// One trial.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Trial {
    /// Trial seed.
    pub seed: u64,
    /// What was withheld (empty: none), with the true parameters.
    pub withheld: Vec<String>,
    /// What the diagnosis added, in order (empty: none).
    pub found: Vec<String>,
    /// Held-out gap shrink.
    pub shrink: f64,
    /// Right: top-1 for a single, exact set for a pair.
    pub correct: bool,
}

/// The self-check's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// Trials with one withheld effect (or none).
    pub singles: usize,
    /// Of those, the first effect added was the withheld one.
    pub single_top1: usize,
    /// Trials with a withheld pair.
    pub pairs: usize,
    /// Of those, the effects added were exactly the pair.
    pub pair_exact: usize,
    /// Of those, both of the pair were among the effects added.
    pub pair_both_found: usize,
    /// Every trial.
    pub trials: Vec<Trial>,
}

/// A withheld effect of kind `name` with parameters drawn so the effect is
/// visible in an EMPS-like run but not dominant.
fn draw(name: &str, u: &mut Uniform) -> Option<Truth> {
    let sign = if u.unit() < 0.5 { -1.0 } else { 1.0 };
    Some(match name {
        "viscous_friction" => Truth::Viscous(u.between(50.0, 300.0)),
        "coulomb_friction" => Truth::Coulomb(u.between(5.0, 30.0)),
        "asymmetric_friction" => {
            Truth::Asymmetric(sign * u.between(3.0, 10.0), sign * u.between(20.0, 80.0))
        }
        "stribeck_friction" => Truth::Stribeck(u.between(5.0, 20.0), u.log_between(2e-3, 2e-2)),
        "latency" => Truth::Latency(u.between(0.003, 0.02)),
        "quantization" => Truth::Quantization(u.log_between(2e-6, 2e-5)),
        "compliance" => Truth::Compliance(u.log_between(1e5, 1e6)),
        "backlash" => Truth::Backlash(u.log_between(2e-5, 2e-4)),
        _ => return None,
    })
}

/// Runs `count` trials from `seed` (trial i uses seed·10007 + i).
pub fn run(count: usize, seed: u64, options: &Options) -> Report {
    let mut trials = Vec::with_capacity(count);
    for i in 0..count {
        let trial_seed = seed.wrapping_mul(10_007).wrapping_add(i as u64);
        let mut u = Uniform::new(trial_seed);
        let pick =
            |u: &mut Uniform, slots: usize| ((u.unit() * slots as f64) as usize).min(slots - 1);
        let truth: Vec<Truth> = if i % 2 == 0 {
            // One of the eight effects or none, evenly.
            let k = pick(&mut u, EFFECTS.len() + 1);
            EFFECTS
                .get(k)
                .and_then(|name| draw(name, &mut u))
                .into_iter()
                .collect()
        } else {
            let first = pick(&mut u, EFFECTS.len());
            let second = (first + 1 + pick(&mut u, EFFECTS.len() - 1)) % EFFECTS.len();
            [first, second]
                .iter()
                .filter_map(|k| draw(EFFECTS[*k], &mut u))
                .collect()
        };
        trials.push(trial(trial_seed, &truth, options));
    }
    let singles: Vec<&Trial> = trials.iter().step_by(2).collect();
    let pairs: Vec<&Trial> = trials.iter().skip(1).step_by(2).collect();
    Report {
        singles: singles.len(),
        single_top1: singles.iter().filter(|t| t.correct).count(),
        pairs: pairs.len(),
        pair_exact: pairs.iter().filter(|t| t.correct).count(),
        pair_both_found: pairs
            .iter()
            .filter(|t| {
                t.withheld
                    .iter()
                    .all(|w| t.found.iter().any(|f| w.starts_with(f.as_str())))
            })
            .count(),
        trials,
    }
}

/// One trial: fit and validation runs with `truth`, diagnosed.
fn trial(seed: u64, truth: &[Truth], options: &Options) -> Trial {
    let fit = simulate(
        &reference(seed ^ 0x5EED, DURATION),
        truth,
        seed.wrapping_add(1),
    );
    let held = simulate(
        &reference(seed ^ 0xBEEF, DURATION),
        truth,
        seed.wrapping_add(2),
    );
    let names: Vec<&str> = truth.iter().map(Truth::name).collect();
    let withheld: Vec<String> = truth
        .iter()
        .map(|t| format!("{} {:?}", t.name(), t))
        .collect();
    let options = Options {
        max_effects: MAX_EFFECTS,
        ..*options
    };
    let answer = diagnose(
        Run {
            name: "fit",
            log: &fit,
        },
        Some(Run {
            name: "held",
            log: &held,
        }),
        CUTOFF,
        &options,
    );
    let (found, shrink) = match answer.map(|d| d.diagnosis) {
        Ok(a) => (
            a.effects
                .iter()
                .map(|e| e.effect.clone())
                .filter(|e| e != "none")
                .collect::<Vec<String>>(),
            a.gap.shrink,
        ),
        Err(e) => (vec![format!("error: {e}")], 0.0),
    };
    let correct = if names.len() <= 1 {
        found.first().map(String::as_str) == names.first().copied()
    } else {
        found.len() == names.len() && names.iter().all(|n| found.iter().any(|f| f == n))
    };
    Trial {
        seed,
        withheld,
        found,
        shrink,
        correct,
    }
}

#[cfg(test)]
mod tests {
    use super::{draw, EFFECTS};
    use crate::plant::drive::sim::Uniform;

    #[test]
    fn every_effect_can_be_drawn() {
        let mut u = Uniform::new(3);
        for name in EFFECTS {
            assert_eq!(draw(name, &mut u).map(|t| t.name()), Some(name));
        }
        assert!(draw("none", &mut u).is_none());
    }
}
