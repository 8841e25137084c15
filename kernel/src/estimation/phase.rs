//! Phase detection from the logged grasp path (no ground truth).
//!
//! # Theory of operation
//! Phase 1 starts at lift-off, the first sample whose forearm elevation
//! exceeds [`LIFT_PSI`]. While the elbow rests on the table the grasp point
//! stays on a circle about it; phase 1 ends where the grasp point leaves
//! that circle. The circle is not known in advance, so the split is found by
//! a fixed number of rounds ([`ROUNDS`]): fit a robust circle to the
//! current phase-1 samples (initially lift-off up to psi = [`INITIAL_PSI`]),
//! scan forward for the first sample whose radial residual exceeds
//! [`DEPARTURE_TOLERANCE`] with at least [`DEPARTURE_PERCENT`] % of the
//! [`DEPARTURE_WINDOW`] samples from it doing so too (a lasting departure,
//! not an outlier or a short corrupted stretch), and end phase 1 just after the
//! last sample before that run whose residual was within
//! [`SETTLED_TOLERANCE`] (both tolerances grow to [`NOISE_MULTIPLE`] × and
//! 1 × the fit's robust RMS residual on noisier data). Phase 2 (the upper arm turning about the shoulder)
//! is every sample from there to the end of the path.
//!
//! Work: [`ROUNDS`] × (one robust fit and one scan that evaluates each
//! residual twice) over the path, O(n); memory O(1).

use super::{EstimateError, PointModel, MIN_PHASE_SAMPLES};
use crate::path::PathSample;
use core::ops::Range;

/// Forearm elevation that marks lift-off [rad]: 50 × the psi noise of
/// `plant.md` (1 mrad), so a resting arm never triggers it.
pub const LIFT_PSI: f64 = 0.05;
/// Forearm elevation ending the first guess of phase 1 [rad]. On the six
/// arms of `plant.md` the elbow lifts at psi ≈ 1.35-1.47 rad; a wrong guess
/// only costs a round.
pub(super) const INITIAL_PSI: f64 = 0.5;
/// Radial residual that counts as having left the phase-1 circle [m]:
/// 10 × the position noise of `plant.md`.
pub const DEPARTURE_TOLERANCE: f64 = 1.0e-3;
/// Look-ahead window that confirms a departure [samples] (0.5 s at
/// 100 Hz): the departure must persist, so outliers and a short corrupted
/// stretch do not end phase 1.
pub const DEPARTURE_WINDOW: usize = 50;
/// Share of the look-ahead window that must be beyond
/// [`DEPARTURE_TOLERANCE`] [%].
pub const DEPARTURE_PERCENT: usize = 90;
/// Residual of the last phase-1 sample before the departure [m]: 3σ of the
/// position noise.
pub(super) const SETTLED_TOLERANCE: f64 = 0.3e-3;
/// On noisier data (e.g. coarse quantisation) the tolerances grow with the
/// RMS residual of the current fit: departure at this many RMS, settled at
/// one RMS.
pub const NOISE_MULTIPLE: f64 = 4.0;
/// Fit-and-scan rounds; the split is stable after the second on every log.
pub(super) const ROUNDS: usize = 3;

/// The two phases of the estimation motion, as index ranges of the path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Phases {
    /// Forearm turning about the resting elbow.
    pub forearm: Range<usize>,
    /// Upper arm turning about the shoulder.
    pub upper_arm: Range<usize>,
}

/// Splits `path` into its two phases, reading grasp points through `grasp`
/// (which may correct them).
///
/// # Errors
/// [`EstimateError::ForearmPhaseTooShort`] when there is no lift-off or
/// phase 1 has fewer than [`MIN_PHASE_SAMPLES`];
/// [`EstimateError::UpperArmPhaseTooShort`] when the grasp never leaves the
/// phase-1 circle or phase 2 is too short; a failed phase-1 fit.
pub fn detect_phases(path: &[PathSample], grasp: &PointModel) -> Result<Phases, EstimateError> {
    let lift = path
        .iter()
        .position(|s| s.pose.psi > LIFT_PSI)
        .ok_or(EstimateError::ForearmPhaseTooShort)?;
    detect_phases_from(path, grasp, lift)
}

/// Where the path departs from phase 1's circle: the scan of
/// [`detect_phases_from`] over a path of `len` samples from index `lift`,
/// given each sample's `residual` from the circle [m] (any number; NaN
/// counts as neither departed nor settled). A sample departs when its
/// residual exceeds `departure_tolerance` and at least
/// [`DEPARTURE_PERCENT`] % of a look-ahead window of up to
/// [`DEPARTURE_WINDOW`] samples (and at least [`MIN_PHASE_SAMPLES`]) do
/// too; the result is then the end of the samples settled on the circle
/// (residual ≤ `settled_tolerance`) before it, in `lift..=len`. `None`:
/// no departure.
pub(super) fn departure_from(
    len: usize,
    lift: usize,
    residual: impl Fn(usize) -> f64,
    departure_tolerance: f64,
    settled_tolerance: f64,
) -> Option<usize> {
    let departed = |index: usize| residual(index) > departure_tolerance;
    // Samples beyond tolerance in the look-ahead window [index, index + W).
    let mut ahead = (lift..len.min(lift + DEPARTURE_WINDOW))
        .filter(|&i| departed(i))
        .count();
    let mut settled = lift;
    for index in lift..len {
        let width = DEPARTURE_WINDOW.min(len - index);
        let value = residual(index);
        if value > departure_tolerance
            && width >= MIN_PHASE_SAMPLES
            && ahead * 100 >= width * DEPARTURE_PERCENT
        {
            return Some(settled);
        }
        if value <= settled_tolerance {
            settled = index + 1;
        }
        // `ahead` counts `index` when it departed, so this never goes
        // below 0; saturating, the scan is total without that invariant
        // (which a proof over any residuals would have to count out).
        ahead = ahead.saturating_sub(usize::from(departed(index)));
        ahead += usize::from(index + DEPARTURE_WINDOW < len && departed(index + DEPARTURE_WINDOW));
    }
    None
}

/// [`detect_phases`] with phase 1 starting at path index `lift`; the first
/// guess of phase 1 ends where psi has grown by [`INITIAL_PSI`] − [`LIFT_PSI`].
///
/// # Errors
/// As [`detect_phases`].
pub fn detect_phases_from(
    path: &[PathSample],
    grasp: &PointModel,
    lift: usize,
) -> Result<Phases, EstimateError> {
    let start_psi = path
        .get(lift)
        .ok_or(EstimateError::ForearmPhaseTooShort)?
        .pose
        .psi;
    let mut end = path
        .iter()
        .skip(lift)
        .position(|s| s.pose.psi > start_psi + (INITIAL_PSI - LIFT_PSI))
        .map_or(path.len(), |offset| lift + offset);
    for _ in 0..ROUNDS {
        if end.saturating_sub(lift) < MIN_PHASE_SAMPLES {
            return Err(EstimateError::ForearmPhaseTooShort);
        }
        let fit = grasp
            .robust_circle(path, lift..end)
            .map_err(EstimateError::ForearmFit)?;
        let departure_tolerance = DEPARTURE_TOLERANCE.max(NOISE_MULTIPLE * fit.noise);
        let settled_tolerance = SETTLED_TOLERANCE.max(fit.noise);
        let residual = |index: usize| {
            grasp.point_at(path, index).map_or(0.0, |point| {
                libm::fabs(point.distance(fit.circle.centre) - fit.circle.radius)
            })
        };
        let departure = departure_from(
            path.len(),
            lift,
            residual,
            departure_tolerance,
            settled_tolerance,
        );
        end = departure.ok_or(EstimateError::UpperArmPhaseTooShort)?;
    }
    if end.saturating_sub(lift) < MIN_PHASE_SAMPLES {
        return Err(EstimateError::ForearmPhaseTooShort);
    }
    if path.len().saturating_sub(end) < MIN_PHASE_SAMPLES {
        return Err(EstimateError::UpperArmPhaseTooShort);
    }
    Ok(Phases {
        forearm: lift..end,
        upper_arm: end..path.len(),
    })
}
