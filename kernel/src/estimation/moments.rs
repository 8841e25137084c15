//! Running moments of a planar point set and the Kåsa circle they give,
//! updated in O(1) per point (the kernel's online estimation).
//!
//! # Theory of operation
//! With v = (x, z, 1, w), w = x² + z² (coordinates relative to the first
//! point, for conditioning), the Kåsa fit (paper eq. 22-27) minimises
//! Σ (w + a x + b z + d)² = pᵀ M p over p = (a, b, d, 1), M = Σ v vᵀ. So the
//! ten distinct sums of M are all a fit needs: adding a point costs 10
//! multiply-adds, and a fit solves one 3 × 3 system. The centre is
//! (−a/2, −b/2), the radius √((a² + b²)/4 − d).
//!
//! The residual sum S = pᵀ M p at the solution gives the algebraic noise
//! σ² = S/(n − 3); the covariance of (a, b, d) is σ² M₃⁻¹ (M₃ the upper 3 × 3
//! block), propagated to the radius and the centre as 1σ uncertainties. An
//! algebraic residual is ≈ 2R times the geometric one, so S also gives the
//! RMS geometric residual.

use super::circle::{Circle, CircleFitError};
use crate::geometry::Point;
use nalgebra::{Matrix3, Vector3};

/// Running sums Σ v vᵀ of a point set (relative to its first point).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CircleMoments {
    origin: Point,
    count: usize,
    x: f64,
    z: f64,
    w: f64,
    xx: f64,
    xz: f64,
    zz: f64,
    xw: f64,
    zw: f64,
    ww: f64,
}

/// A Kåsa circle with the uncertainty its moments imply.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MomentFit {
    /// The circle [m], frame S.
    pub circle: Circle,
    /// 1σ of the radius [m].
    pub radius_sd: f64,
    /// 1σ of the centre, the larger of its two coordinates [m].
    pub centre_sd: f64,
    /// RMS geometric residual, from the algebraic one [m].
    pub rms_residual: f64,
    /// Points in the fit.
    pub count: usize,
}

impl CircleMoments {
    /// No points.
    pub const fn new() -> Self {
        Self {
            origin: Point::new(0.0, 0.0),
            count: 0,
            x: 0.0,
            z: 0.0,
            w: 0.0,
            xx: 0.0,
            xz: 0.0,
            zz: 0.0,
            xw: 0.0,
            zw: 0.0,
            ww: 0.0,
        }
    }

    /// Points added.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Adds `point`; a non-finite point is ignored (returns false).
    pub fn add(&mut self, point: Point) -> bool {
        if !point.is_finite() {
            return false;
        }
        if self.count == 0 {
            self.origin = point;
        }
        let x = point.x - self.origin.x;
        let z = point.z - self.origin.z;
        let w = x * x + z * z;
        self.count = self.count.saturating_add(1);
        self.x += x;
        self.z += z;
        self.w += w;
        self.xx += x * x;
        self.xz += x * z;
        self.zz += z * z;
        self.xw += x * w;
        self.zw += z * w;
        self.ww += w * w;
        true
    }

    /// Proof stub of [`Self::add`]: counts a finite point as `add` does
    /// and leaves the sums alone. For harnesses that also stub the fit
    /// (which then reads only the count): their properties do not read the
    /// sums, and ten symbolic multiply-adds per point were most of what
    /// CBMC could not solve in the online estimator's harness.
    #[cfg(kani)]
    pub fn count_finite(&mut self, point: Point) -> bool {
        if !point.is_finite() {
            return false;
        }
        self.count = self.count.saturating_add(1);
        true
    }

    /// The Kåsa circle of the points added so far, with its uncertainty.
    ///
    /// # Errors
    /// [`CircleFitError::TooFewPoints`] below four points (the noise needs
    /// one degree of freedom); [`CircleFitError::Degenerate`] for collinear
    /// or coincident points; [`CircleFitError::NonFinite`].
    pub fn fit(&self) -> Result<MomentFit, CircleFitError> {
        if self.count < 4 {
            return Err(CircleFitError::TooFewPoints);
        }
        let n = self.count as f64;
        let m3 = Matrix3::new(
            self.xx, self.xz, self.x, self.xz, self.zz, self.z, self.x, self.z, n,
        );
        let m = Vector3::new(self.xw, self.zw, self.w);
        let inverse = m3.try_inverse().ok_or(CircleFitError::Degenerate)?;
        let p = -(inverse * m);
        let (a, b, d) = (p[0], p[1], p[2]);
        let radius_squared = (a * a + b * b) / 4.0 - d;
        if !(radius_squared.is_finite() && radius_squared > 0.0) {
            return Err(CircleFitError::Degenerate);
        }
        let radius = libm::sqrt(radius_squared);
        // S = ww + 2 p·m + pᵀ M₃ p = ww + p·m at the solution; ≥ 0 up to rounding.
        let residual_sum = (self.ww + p.dot(&m)).max(0.0);
        let sigma_squared = residual_sum / (n - 3.0);
        let covariance = inverse * sigma_squared;
        let gradient = Vector3::new(a / (4.0 * radius), b / (4.0 * radius), -0.5 / radius);
        let radius_variance = (gradient.transpose() * covariance * gradient)[0].max(0.0);
        let centre_variance = (covariance[(0, 0)].max(covariance[(1, 1)]) / 4.0).max(0.0);
        let fit = MomentFit {
            circle: Circle {
                centre: Point::new(self.origin.x - a / 2.0, self.origin.z - b / 2.0),
                radius,
            },
            radius_sd: libm::sqrt(radius_variance),
            centre_sd: libm::sqrt(centre_variance),
            rms_residual: libm::sqrt(residual_sum / n) / (2.0 * radius),
            count: self.count,
        };
        let finite = fit.circle.is_valid()
            && fit.radius_sd.is_finite()
            && fit.centre_sd.is_finite()
            && fit.rms_residual.is_finite();
        if finite {
            Ok(fit)
        } else {
            Err(CircleFitError::NonFinite)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_an_exact_arc_with_zero_uncertainty() {
        let mut moments = CircleMoments::new();
        for i in 0..50 {
            let angle = 0.02 * f64::from(i);
            moments.add(Point::new(
                0.4 - 0.3 * libm::cos(angle),
                0.3 * libm::sin(angle),
            ));
        }
        let fit = moments.fit().unwrap();
        assert!((fit.circle.radius - 0.3).abs() < 1e-9);
        assert!(fit.circle.centre.distance(Point::new(0.4, 0.0)) < 1e-9);
        assert!(fit.radius_sd < 1e-6 && fit.rms_residual < 1e-6);
    }

    #[test]
    fn refuses_collinear_and_too_few_points() {
        let mut moments = CircleMoments::new();
        for i in 0..3 {
            moments.add(Point::new(f64::from(i), 0.0));
        }
        assert_eq!(moments.fit(), Err(CircleFitError::TooFewPoints));
        moments.add(Point::new(3.0, 0.0));
        assert_eq!(moments.fit(), Err(CircleFitError::Degenerate));
        assert!(!moments.add(Point::new(f64::NAN, 0.0)));
        assert_eq!(moments.count(), 4);
    }
}
