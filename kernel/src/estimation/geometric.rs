//! Robust geometric circle fit (frame S).
//!
//! # Theory of operation
//! Minimises Σ ρ(|p_i − c| − r) over the centre c and the radius r, where ρ
//! is the Cauchy loss with scale [`ROBUST_SCALE`] or, if larger,
//! [`NOISE_MULTIPLE`] × the weighted RMS residual of the previous iteration
//! ([`INITIAL_SCALE`] at first): a residual of many scales gets almost no
//! weight, so outliers and a short corrupted stretch barely move the fit,
//! while ordinary noise — also coarse quantisation — keeps full weight. With
//! a fraction f of gross outliers the weighted RMS settles near
//! σ / √(1 − 9f), so the scale shrinks back to the noise within a few
//! iterations (f < 10 %). Unlike the algebraic
//! fits it minimises the true geometric distance, so it has no short-arc
//! bias beyond that of the noise itself.
//!
//! Solved by iteratively reweighted Gauss–Newton with a fixed number of
//! iterations ([`ITERATIONS`]) from an algebraic start, each one pass over
//! the points: work O(ITERATIONS · n), memory O(1).

use super::circle::{Circle, CircleFitError};
use crate::geometry::Point;
use nalgebra::{Matrix3, Vector3};

/// Scale of the Cauchy loss [m]: 1 mm, ten times the pose noise of
/// `plant.md` (0.1 mm) and five times the elbow-path noise from the 1 mrad
/// psi noise over a 0.2 m forearm.
pub(super) const ROBUST_SCALE: f64 = 1.0e-3;

/// Cauchy scale of the first iteration [m]: wide enough for coarse
/// quantisation (4 mm steps), narrow enough that gross outliers (centimetres)
/// get little weight even when the start's RMS residual is inflated by them.
pub(super) const INITIAL_SCALE: f64 = 1.0e-2;

/// The Cauchy scale is at least this many weighted RMS residuals.
pub(super) const NOISE_MULTIPLE: f64 = 3.0;

/// Gauss–Newton iterations. From an algebraic start within a few mm the step
/// converges quadratically; 15 leave margin for the reweighting to settle.
pub(super) const ITERATIONS: usize = 15;

/// A robust geometric fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometricFit {
    /// The circle [m].
    pub circle: Circle,
    /// Robust noise level: the weighted RMS residual, at least
    /// [`ROBUST_SCALE`] / [`NOISE_MULTIPLE`] [m].
    pub noise: f64,
}

/// Fits a circle to `points` by robust geometric least squares from `start`
/// (an algebraic fit).
///
/// # Errors
/// Fewer than three points; an invalid start; a singular or non-finite step;
/// a result with a non-finite or non-positive radius.
pub fn fit_circle_geometric<I>(points: I, start: Circle) -> Result<GeometricFit, CircleFitError>
where
    I: Iterator<Item = Point> + Clone,
{
    if points.clone().take(3).count() < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    if !start.is_valid() {
        return Err(CircleFitError::NonFinite);
    }
    let mut scale = INITIAL_SCALE;
    let mut theta = Vector3::new(start.centre.x, start.centre.z, start.radius);
    for _ in 0..ITERATIONS {
        let mut normal = Matrix3::<f64>::zeros();
        let mut gradient = Vector3::<f64>::zeros();
        let (mut weighted_square, mut weight_sum) = (0.0, 0.0);
        for p in points.clone() {
            let (dx, dz) = (p.x - theta[0], p.z - theta[1]);
            // sqrt, not hypot: coordinates are metres, far from overflow, and
            // libm::hypot costs as much as the rest of the iteration.
            let distance = libm::sqrt(dx * dx + dz * dz);
            if distance <= 0.0 {
                continue;
            }
            let jacobian = Vector3::new(-dx / distance, -dz / distance, -1.0);
            let residual = distance - theta[2];
            let u = residual / scale;
            let weight = 1.0 / (1.0 + u * u);
            normal += jacobian * jacobian.transpose() * weight;
            gradient += jacobian * (residual * weight);
            weighted_square += weight * residual * residual;
            weight_sum += weight;
        }
        if weight_sum > 0.0 {
            scale = ROBUST_SCALE.max(NOISE_MULTIPLE * libm::sqrt(weighted_square / weight_sum));
        }
        let step = normal
            .cholesky()
            .ok_or(CircleFitError::Degenerate)?
            .solve(&gradient);
        if !step.iter().all(|s| s.is_finite()) {
            return Err(CircleFitError::NonFinite);
        }
        theta -= step;
    }
    let circle = Circle {
        centre: Point::new(theta[0], theta[1]),
        radius: theta[2],
    };
    if circle.is_valid() {
        Ok(GeometricFit {
            circle,
            noise: scale / NOISE_MULTIPLE,
        })
    } else {
        Err(CircleFitError::NonFinite)
    }
}
