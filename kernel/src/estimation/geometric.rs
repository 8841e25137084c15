//! Robust geometric circle fit (frame S).
//!
//! # Theory of operation
//! Minimises Σ ρ(|p_i − c| − r) over the centre c and the radius r, where ρ
//! is the Cauchy loss with scale [`ROBUST_SCALE`] (or [`NOISE_MULTIPLE`] ×
//! the start's RMS residual, if larger): a residual of many scales gets
//! almost no weight, so outliers and a short corrupted stretch barely move
//! the fit, while ordinary noise keeps full weight. Unlike the algebraic
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
pub const ROBUST_SCALE: f64 = 1.0e-3;

/// On noisier data (e.g. coarse quantisation) the Cauchy scale grows to this
/// many RMS residuals of the start circle.
pub const NOISE_MULTIPLE: f64 = 3.0;

/// Gauss–Newton iterations. From an algebraic start within a few mm the step
/// converges quadratically; 15 leave margin for the reweighting to settle.
pub const ITERATIONS: usize = 15;

/// Fits a circle to `points` by robust geometric least squares from `start`
/// (an algebraic fit).
///
/// # Errors
/// Fewer than three points; an invalid start; a singular or non-finite step;
/// a result with a non-finite or non-positive radius.
pub fn fit_circle_geometric<I>(points: I, start: Circle) -> Result<Circle, CircleFitError>
where
    I: Iterator<Item = Point> + Clone,
{
    if points.clone().take(3).count() < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    if !start.is_valid() {
        return Err(CircleFitError::NonFinite);
    }
    let scale = ROBUST_SCALE.max(NOISE_MULTIPLE * start.rms_residual(points.clone()));
    let mut theta = Vector3::new(start.centre.x, start.centre.z, start.radius);
    for _ in 0..ITERATIONS {
        let mut normal = Matrix3::<f64>::zeros();
        let mut gradient = Vector3::<f64>::zeros();
        for p in points.clone() {
            let (dx, dz) = (p.x - theta[0], p.z - theta[1]);
            let distance = libm::hypot(dx, dz);
            if distance <= 0.0 {
                continue;
            }
            let jacobian = Vector3::new(-dx / distance, -dz / distance, -1.0);
            let residual = distance - theta[2];
            let u = residual / scale;
            let weight = 1.0 / (1.0 + u * u);
            normal += jacobian * jacobian.transpose() * weight;
            gradient += jacobian * (residual * weight);
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
        Ok(circle)
    } else {
        Err(CircleFitError::NonFinite)
    }
}
