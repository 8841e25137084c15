//! Scaled residuals between the data and a prediction, and the gap
//! statistics built on them.
//!
//! A residual is (observed − predicted) / scale per signal, so with the
//! noise σ as scale pure measurement noise has mean square 1 (the model's
//! noise floor). The **gap** is the part of the residual's RMS beyond the
//! noise: sqrt(max(0, mean square − floor)), in units of the scale (σ for
//! the arm). With an unknown noise (floor 0) it is the scaled RMS itself.

use crate::model::{Model, Series};

/// Sum of squared scaled residuals over the masked samples, and how many
/// terms it has. A non-finite prediction makes the sum `+inf`.
pub fn sum_of_squares(model: &dyn Model, predicted: &Series, mask: &[bool]) -> (f64, usize) {
    let sums = signal_sums(model, predicted, mask);
    (
        sums.iter().map(|s| s.0).sum(),
        sums.iter().map(|s| s.1).sum(),
    )
}

/// [`sum_of_squares`] of each signal separately: (sum, terms) per signal,
/// in signal order. A non-finite prediction makes every sum `+inf`.
pub fn signal_sums(model: &dyn Model, predicted: &Series, mask: &[bool]) -> Vec<(f64, usize)> {
    let observed = model.observed();
    let scales = model.scales();
    let mut sums = vec![(0.0, 0usize); scales.len()];
    for (sample, used) in mask.iter().enumerate() {
        if !used {
            continue;
        }
        for (((o, p), s), sum) in observed
            .row(sample)
            .iter()
            .zip(predicted.row(sample))
            .zip(scales)
            .zip(sums.iter_mut())
        {
            let r = (o - p) / s;
            sum.0 += r * r;
            sum.1 += 1;
        }
    }
    let finite = sums.iter().all(|s| s.0.is_finite());
    if !(finite && predicted.samples() == observed.samples()) {
        sums.iter_mut().for_each(|s| s.0 = f64::INFINITY);
    }
    sums
}

/// The gap of a mean square `mean_square` above `floor`.
pub fn gap(mean_square: f64, floor: f64) -> f64 {
    (mean_square - floor).max(0.0).sqrt()
}

/// Scaled residual of every signal at every sample.
pub fn scaled(model: &dyn Model, predicted: &Series) -> Series {
    let observed = model.observed();
    let scales = model.scales();
    let mut out = Series::with_capacity(observed.signals(), observed.samples());
    let mut row = vec![0.0; observed.signals()];
    for sample in 0..observed.samples() {
        for (((r, o), p), s) in row
            .iter_mut()
            .zip(observed.row(sample))
            .zip(predicted.row(sample))
            .zip(scales)
        {
            *r = (o - p) / s;
        }
        // Lengths agree by construction: `row` has one value per signal.
        let _ = out.push(&row);
    }
    out
}
