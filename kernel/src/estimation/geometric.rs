//! Robust geometric circle fit (frame S) with optional grasp corrections.
//!
//! # Theory of operation
//! Minimises Σ ρ(|p_i(θ) − c| − r) over the centre c, the radius r and, when
//! freed, two grasp corrections shared by all points:
//!
//! ```text
//! p_i(θ) = base_i + compliance · force_i + slip · slip_direction_i
//! ```
//!
//! * `compliance` [m/N] = 1/k of a compliant grasp: the logged end-effector
//!   leads the wrist by F/k, so the wrist is the logged point plus
//!   f_ext · compliance (`force_i` = logged f_ext).
//! * `slip` [m]: the grasp slid once along the forearm; `slip_direction_i` is
//!   the forearm direction grasp → elbow for samples after the slip, zero
//!   before it.
//!
//! ρ is the Cauchy loss with scale [`ROBUST_SCALE`]: a residual of many
//! scales gets almost no weight, so outliers and a short corrupted stretch
//! barely move the fit. Solved by iteratively reweighted Levenberg–Marquardt
//! with a fixed number of iterations ([`ITERATIONS`]), each one pass over the
//! points: work O(ITERATIONS · n), memory O(1). Parameters not freed keep
//! their start values (their rows of the normal equations are identity).

use super::circle::{Circle, CircleFitError};
use crate::geometry::Point;
use nalgebra::{Matrix5, Vector5};

/// One point of a geometric fit with the derivatives of its position with
/// respect to the grasp corrections [m, m/(m/N) = N, m/m].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FitPoint {
    /// Position with both corrections at zero [m].
    pub base: Point,
    /// ∂p/∂compliance: the logged force f_ext [N].
    pub force: Point,
    /// ∂p/∂slip: unit forearm direction after the slip, zero before [1].
    pub slip_direction: Point,
}

impl FitPoint {
    /// A plain point with no correction.
    pub const fn plain(base: Point) -> Self {
        Self {
            base,
            force: Point::new(0.0, 0.0),
            slip_direction: Point::new(0.0, 0.0),
        }
    }

    /// Its position under `corrections`.
    pub fn at(&self, corrections: GraspCorrection) -> Point {
        Point::new(
            self.base.x
                + corrections.compliance * self.force.x
                + corrections.slip * self.slip_direction.x,
            self.base.z
                + corrections.compliance * self.force.z
                + corrections.slip * self.slip_direction.z,
        )
    }
}

/// Grasp corrections shared by all points of a fit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct GraspCorrection {
    /// Grasp compliance 1/k [m/N].
    pub compliance: f64,
    /// Grasp slip along the forearm toward the elbow [m].
    pub slip: f64,
}

/// Which grasp corrections a fit may change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FreeCorrections {
    /// Fit the compliance.
    pub compliance: bool,
    /// Fit the slip.
    pub slip: bool,
}

/// Result of a geometric fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometricFit {
    /// The circle [m].
    pub circle: Circle,
    /// The corrections [m/N, m].
    pub correction: GraspCorrection,
}

/// Scale of the Cauchy loss [m]: 1 mm, ten times the pose noise of
/// `plant.md` (0.1 mm) and five times the elbow-path noise from the 1 mrad
/// psi noise over a 0.2 m forearm.
pub const ROBUST_SCALE: f64 = 1.0e-3;

/// Levenberg–Marquardt iterations. From an algebraic start within a few mm
/// the undamped step converges quadratically; 15 leave margin for the
/// reweighting to settle (measured: < 1 µm change after 8 on all logs).
pub const ITERATIONS: usize = 15;

/// Relative Levenberg damping added to the diagonal: keeps the normal
/// equations solvable when a correction is not identifiable (e.g. constant
/// force along the arc), without biasing well-posed fits.
const DAMPING: f64 = 1e-9;

/// Fits a circle to `points` by robust geometric least squares, starting
/// from `start` and `correction`.
///
/// # Errors
/// Fewer than three points; a singular or non-finite step; a result with a
/// non-finite or non-positive radius.
pub fn fit_circle_geometric<I>(
    points: I,
    start: Circle,
    correction: GraspCorrection,
    free: FreeCorrections,
) -> Result<GeometricFit, CircleFitError>
where
    I: Iterator<Item = FitPoint> + Clone,
{
    if points.clone().take(3).count() < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    if !(start.is_valid() && correction.compliance.is_finite() && correction.slip.is_finite()) {
        return Err(CircleFitError::NonFinite);
    }
    let mut theta = Vector5::new(
        start.centre.x,
        start.centre.z,
        start.radius,
        correction.compliance,
        correction.slip,
    );
    for _ in 0..ITERATIONS {
        let mut normal = Matrix5::<f64>::zeros();
        let mut gradient = Vector5::<f64>::zeros();
        let current = GraspCorrection {
            compliance: theta[3],
            slip: theta[4],
        };
        for fit_point in points.clone() {
            let p = fit_point.at(current);
            let (dx, dz) = (p.x - theta[0], p.z - theta[1]);
            let distance = libm::hypot(dx, dz);
            if distance <= 0.0 {
                continue;
            }
            let (nx, nz) = (dx / distance, dz / distance);
            let residual = distance - theta[2];
            let u = residual / ROBUST_SCALE;
            let weight = 1.0 / (1.0 + u * u);
            let jacobian = Vector5::new(
                -nx,
                -nz,
                -1.0,
                nx * fit_point.force.x + nz * fit_point.force.z,
                nx * fit_point.slip_direction.x + nz * fit_point.slip_direction.z,
            );
            normal += jacobian * jacobian.transpose() * weight;
            gradient += jacobian * (residual * weight);
        }
        for (index, is_free) in [(3, free.compliance), (4, free.slip)] {
            if !is_free {
                normal.row_mut(index).fill(0.0);
                normal.column_mut(index).fill(0.0);
                normal[(index, index)] = 1.0;
                gradient[index] = 0.0;
            }
        }
        for index in 0..5 {
            normal[(index, index)] *= 1.0 + DAMPING;
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
    if !(circle.is_valid() && theta[3].is_finite() && theta[4].is_finite()) {
        return Err(CircleFitError::NonFinite);
    }
    Ok(GeometricFit {
        circle,
        correction: GraspCorrection {
            compliance: theta[3],
            slip: theta[4],
        },
    })
}
