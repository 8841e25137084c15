//! Circle fits to planar points (frame S).

use crate::geometry::Point;
use nalgebra::{Matrix3, Vector3};

/// A fitted circle [m].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Circle {
    /// Centre in frame S [m].
    pub centre: Point,
    /// Radius [m].
    pub radius: f64,
}

impl Circle {
    /// RMS of the geometric residuals |p − c| − r over `points` [m].
    pub fn rms_residual(&self, points: &[Point]) -> f64 {
        if points.is_empty() {
            return 0.0;
        }
        let sum: f64 = points
            .iter()
            .map(|p| {
                let e = p.distance(self.centre) - self.radius;
                e * e
            })
            .sum();
        libm::sqrt(sum / points.len() as f64)
    }
}

/// Why a circle could not be fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CircleFitError {
    /// Fewer than three points.
    TooFewPoints,
    /// The points are collinear or coincident: no unique circle.
    Degenerate,
    /// The result was not finite.
    NonFinite,
}

/// Algebraic (Kåsa) least-squares fit, paper eq. 22-27: solves
/// x² + z² = 2a x + 2b z + c in the least-squares sense, on coordinates
/// centred on the mean for conditioning.
pub fn fit_circle_kasa(points: &[Point]) -> Result<Circle, CircleFitError> {
    if points.len() < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    let n = points.len() as f64;
    let (mut mx, mut mz) = (0.0, 0.0);
    for p in points {
        mx += p.x;
        mz += p.z;
    }
    mx /= n;
    mz /= n;
    let mut normal = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    for p in points {
        let (x, z) = (p.x - mx, p.z - mz);
        let row = Vector3::new(2.0 * x, 2.0 * z, 1.0);
        normal += row * row.transpose();
        rhs += row * (x * x + z * z);
    }
    let solution = normal.lu().solve(&rhs).ok_or(CircleFitError::Degenerate)?;
    let (a, b, c) = (solution[0], solution[1], solution[2]);
    let radius_squared = c + a * a + b * b;
    if !(radius_squared.is_finite() && a.is_finite() && b.is_finite()) {
        return Err(CircleFitError::NonFinite);
    }
    if radius_squared <= 0.0 {
        return Err(CircleFitError::Degenerate);
    }
    Ok(Circle {
        centre: Point::new(a + mx, b + mz),
        radius: libm::sqrt(radius_squared),
    })
}
