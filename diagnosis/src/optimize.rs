//! Bounded, deterministic minimisation in the unit cube.
//!
//! Every parameter is searched in unit coordinates u ∈ [0, 1] (mapped to
//! its range by [`crate::model::Parameter::value`]). The search evaluates
//! every start point, then runs Nelder–Mead from the best
//! [`Budget::refine`] of them for exactly [`Budget::iterations`]
//! iterations each. A vertex outside the cube is costed at its projection
//! onto the cube plus a penalty growing with its distance outside (the
//! simplex keeps its shape instead of collapsing onto a face); the answer
//! is always inside the cube. Costs must be non-negative.
//! No randomness and no tolerance-dependent stopping: the same inputs
//! always take the same number of evaluations and give the same answer.

/// How much work one minimisation may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// Start points refined by Nelder–Mead (the best ones).
    pub refine: usize,
    /// Nelder–Mead iterations per refined start.
    pub iterations: usize,
    /// Initial simplex edge in unit coordinates.
    pub step_per_mille: u32,
}

impl Default for Budget {
    fn default() -> Self {
        Self {
            refine: 1,
            iterations: 40,
            step_per_mille: 80,
        }
    }
}

/// Nelder–Mead runs per refined start, each with a simplex a quarter the
/// size of the one before: half the iterations to the first, the rest
/// shared.
const RESTARTS: usize = 5;

/// The best point found and its cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Minimum {
    /// Unit coordinates.
    pub point: Vec<f64>,
    /// Cost there (`+inf` when every point failed).
    pub cost: f64,
    /// Cost evaluations spent.
    pub evaluations: usize,
}

fn project(point: &mut [f64]) {
    for u in point.iter_mut() {
        *u = if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) };
    }
}

/// Minimises `cost` over the unit cube of the starts' dimension.
/// A cost that is NaN counts as `+inf`.
pub fn minimize(cost: impl Fn(&[f64]) -> f64, starts: &[Vec<f64>], budget: Budget) -> Minimum {
    let mut evaluations = 0usize;
    let mut eval = |p: &[f64]| {
        evaluations += 1;
        let mut inside = p.to_vec();
        project(&mut inside);
        let outside = p
            .iter()
            .zip(&inside)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let c = cost(&inside);
        if !c.is_finite() {
            // NaN (and the NaN an infinite cost times a zero distance
            // would make) sorts as the worst point, never the best.
            f64::INFINITY
        } else if outside > 0.0 {
            c + (c.abs() + 1.0) * 10.0 * outside
        } else {
            c
        }
    };
    let mut scored: Vec<(f64, Vec<f64>)> = starts
        .iter()
        .map(|s| {
            let mut p = s.clone();
            project(&mut p);
            (eval(&p), p)
        })
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = scored
        .first()
        .map_or((f64::INFINITY, Vec::new()), |s| s.clone());
    let step = f64::from(budget.step_per_mille) / 1000.0;
    for (cost0, start) in scored.iter().take(budget.refine) {
        if start.is_empty() {
            continue;
        }
        // Restarting from the best vertex with a fresh, smaller simplex
        // undoes a simplex that has collapsed (typically against a face).
        let (mut c, mut p) = (*cost0, start.clone());
        // Half the iterations go to the first (largest) simplex, which
        // travels; the smaller ones share the rest and polish.
        let first = budget.iterations / 2;
        let later = (budget.iterations - first) / (RESTARTS - 1);
        for round in 0..RESTARTS {
            let size = step / f64::from(1u32 << (2 * round));
            let iterations = if round == 0 { first } else { later };
            (c, p) = nelder_mead(&mut eval, &p, c, size, iterations);
        }
        if c < best.0 {
            best = (c, p);
        }
    }
    Minimum {
        point: best.1,
        cost: best.0,
        evaluations,
    }
}

/// Nelder–Mead with the standard coefficients (reflection 1, expansion 2,
/// contraction ½, shrink ½) for a fixed number of iterations.
fn nelder_mead(
    eval: &mut impl FnMut(&[f64]) -> f64,
    start: &[f64],
    start_cost: f64,
    step: f64,
    iterations: usize,
) -> (f64, Vec<f64>) {
    let n = start.len();
    let mut simplex: Vec<(f64, Vec<f64>)> = vec![(start_cost, start.to_vec())];
    for i in 0..n {
        let mut p = start.to_vec();
        // Step inward so the vertex stays inside the cube.
        p[i] += if p[i] + step <= 1.0 { step } else { -step };
        project(&mut p);
        simplex.push((eval(&p), p));
    }
    let along = |from: &[f64], to: &[f64], t: f64| -> Vec<f64> {
        let mut p: Vec<f64> = from.iter().zip(to).map(|(a, b)| a + t * (b - a)).collect();
        project(&mut p);
        p
    };
    for _ in 0..iterations {
        simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut centroid = vec![0.0; n];
        for (_, p) in &simplex[..n] {
            for (c, v) in centroid.iter_mut().zip(p) {
                *c += v / n as f64;
            }
        }
        let worst = simplex[n].clone();
        let reflected = along(&worst.1, &centroid, 2.0);
        let fr = eval(&reflected);
        if fr < simplex[0].0 {
            let expanded = along(&worst.1, &centroid, 3.0);
            let fe = eval(&expanded);
            simplex[n] = if fe < fr {
                (fe, expanded)
            } else {
                (fr, reflected)
            };
        } else if fr < simplex[n - 1].0 {
            simplex[n] = (fr, reflected);
        } else {
            let contracted = if fr < worst.0 {
                along(&centroid, &reflected, 0.5)
            } else {
                along(&centroid, &worst.1, 0.5)
            };
            let fc = eval(&contracted);
            if fc < worst.0.min(fr) {
                simplex[n] = (fc, contracted);
            } else {
                let best = simplex[0].1.clone();
                for vertex in simplex.iter_mut().skip(1) {
                    let p = along(&best, &vertex.1, 0.5);
                    *vertex = (eval(&p), p);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (cost, mut point) = simplex.swap_remove(0);
    project(&mut point);
    (cost, point)
}

#[cfg(test)]
mod tests {
    use super::{minimize, Budget};
    use crate::model::grid;
    use proptest::prelude::*;

    proptest! {
        /// A convex bowl anywhere in the cube is found to 1e-3 from a
        /// coarse grid; the answer never leaves the cube.
        #[test]
        fn finds_the_bottom_of_a_bowl(a in 0.0f64..1.0, b in 0.0f64..1.0) {
            let cost = |p: &[f64]| (p[0] - a).powi(2) + 3.0 * (p[1] - b).powi(2);
            let m = minimize(cost, &grid(2, 5), Budget { refine: 1, iterations: 80, step_per_mille: 100 });
            prop_assert!(m.point.iter().all(|u| (0.0..=1.0).contains(u)));
            prop_assert!((m.point[0] - a).abs() < 1e-3 && (m.point[1] - b).abs() < 1e-3, "{:?}", m.point);
        }
    }

    /// An infinite cost at the first start (a diverged simulation) must
    /// not be taken for the best point.
    #[test]
    fn infinite_costs_rank_last() {
        let cost = |p: &[f64]| {
            if p[0] < 0.1 {
                f64::INFINITY
            } else {
                (p[0] - 0.3).powi(2)
            }
        };
        let m = minimize(cost, &grid(1, 9), Budget::default());
        assert!((m.point[0] - 0.3).abs() < 0.01, "{:?}", m.point);
    }

    #[test]
    fn is_deterministic_and_survives_nan_costs() {
        let cost = |p: &[f64]| {
            if p[0] > 0.7 {
                f64::NAN
            } else {
                (p[0] - 0.3).abs()
            }
        };
        let one = minimize(cost, &grid(1, 9), Budget::default());
        let two = minimize(cost, &grid(1, 9), Budget::default());
        assert_eq!(one, two);
        assert!((one.point[0] - 0.3).abs() < 0.01 && one.cost.is_finite());
    }
}
