//! Algebraic circle fits to planar points (frame S): Kåsa (paper eq. 22-27)
//! and Taubin.
//!
//! Both fits are closed-form over the mean-centred moments of the points, so
//! they read the points twice (mean, then moments) and hold no buffer: the
//! points come from any cloneable iterator. Work is O(n), memory O(1).

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

/// Consecutive samples whose mean residual [`ResidualBias`] judges: 0.5 s
/// of the path at its 100 Hz recording rate.
pub const BIAS_BLOCK: usize = 50;

/// The largest |mean geometric residual| over blocks of [`BIAS_BLOCK`]
/// consecutive points [m], streamed: noise averages out of a block
/// (0.15 mm RMS → ≈ 0.02 mm), a path that leaves its circle for a while (a
/// grasp that slipped, play in the angle) does not. A last block of fewer
/// than half [`BIAS_BLOCK`] points is not judged. NaN residuals make it NaN.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResidualBias {
    sum: f64,
    count: usize,
    worst: f64,
    /// Σ of the closed blocks' squared means [m²], and how many closed.
    block_squares: f64,
    blocks: usize,
}

impl ResidualBias {
    /// Adds the next point's residual [m]. A block whose sum meets
    /// infinities of both signs (a sum overflowed to −∞ by residuals near
    /// −`f64::MAX`, then a point at infinity) has an unbounded mean: its
    /// sum is +∞, not the NaN that ∞ − ∞ makes (found by real Kani).
    pub fn add(&mut self, residual: f64) {
        let opposite = self.sum.is_infinite() && residual.is_infinite() && self.sum != residual;
        self.sum = if opposite {
            f64::INFINITY
        } else {
            self.sum + residual
        };
        self.count += 1;
        if self.count >= BIAS_BLOCK {
            self.close_block();
        }
    }

    fn close_block(&mut self) {
        if self.count > 0 && !self.worst.is_nan() {
            let mean = libm::fabs(self.sum / self.count as f64);
            self.block_squares += mean * mean;
            self.blocks += 1;
            // NaN propagates (and stays).
            if mean.is_nan() || mean > self.worst {
                self.worst = mean;
            }
        }
        self.sum = 0.0;
        self.count = 0;
    }

    /// The mean square of the whole blocks' means so far [m²] (0 before
    /// the first block closes): the variance of a block mean about the
    /// circle, which white noise of variance σ² makes σ² / [`BIAS_BLOCK`]
    /// and residuals correlated over many samples make larger.
    pub fn block_mean_square(&self) -> f64 {
        if self.blocks == 0 {
            0.0
        } else {
            self.block_squares / self.blocks as f64
        }
    }

    /// The largest block mean so far, the open block included when it
    /// holds at least half a block [m].
    pub fn worst(mut self) -> f64 {
        if self.count * 2 >= BIAS_BLOCK {
            self.close_block();
        }
        self.worst
    }
}

impl Circle {
    /// [`ResidualBias`] of the geometric residuals over `points` [m].
    pub fn residual_bias<I: Iterator<Item = Point>>(&self, points: I) -> f64 {
        let mut bias = ResidualBias::default();
        for p in points {
            bias.add(p.distance(self.centre) - self.radius);
        }
        bias.worst()
    }

    /// RMS of the geometric residuals |p − c| − r over `points` [m]; 0 for
    /// no points.
    pub fn rms_residual<I: Iterator<Item = Point>>(&self, points: I) -> f64 {
        let (count, sum) = points.fold((0usize, 0.0), |(count, sum), p| {
            let e = p.distance(self.centre) - self.radius;
            (count + 1, sum + e * e)
        });
        if count == 0 {
            0.0
        } else {
            libm::sqrt(sum / count as f64)
        }
    }

    /// Angle between the first and last point seen from the centre
    /// [rad, 0..π]; 0 for fewer than two points, and for an end whose
    /// offset from the centre is not finite (no arc is measured there).
    /// Each offset is scaled to a largest component of ±1 before the
    /// products, so no product overflows and no NaN is made (unscaled,
    /// offsets near `f64::MAX` made ∞ − ∞).
    pub fn arc<I: Iterator<Item = Point>>(&self, points: I) -> f64 {
        let mut ends: Option<(Point, Point)> = None;
        for p in points {
            ends = Some(match ends {
                None => (p, p),
                Some((first, _)) => (first, p),
            });
        }
        match ends {
            Some((a, b)) => {
                let direction = |p: Point| unit_box(p.x - self.centre.x, p.z - self.centre.z);
                match (direction(a), direction(b)) {
                    (Some((ax, az)), Some((bx, bz))) => {
                        libm::fabs(libm::atan2(ax * bz - az * bx, ax * bx + az * bz))
                    }
                    _ => 0.0,
                }
            }
            None => 0.0,
        }
    }

    /// True when centre and radius are finite and the radius is > 0.
    pub fn is_valid(&self) -> bool {
        self.centre.is_finite() && self.radius.is_finite() && self.radius > 0.0
    }
}

/// `(x, z)` scaled so that its larger |component| is 1 (the direction
/// kept; zero stays zero); `None` when a component is not finite.
fn unit_box(x: f64, z: f64) -> Option<(f64, f64)> {
    let largest = libm::fabs(x).max(libm::fabs(z));
    if !(x.is_finite() && z.is_finite()) {
        None
    } else if largest == 0.0 {
        Some((0.0, 0.0))
    } else {
        Some((x / largest, z / largest))
    }
}

/// Why a circle could not be fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CircleFitError {
    /// Fewer than three points.
    TooFewPoints,
    /// More points than a bounded fit accepts ([`crate::path::PATH_CAPACITY`]).
    TooManyPoints,
    /// The points are collinear or coincident: no unique circle.
    Degenerate,
    /// The result was not finite.
    NonFinite,
}

impl CircleFitError {
    /// Stable numeric code of the error.
    pub const fn code(&self) -> u16 {
        match self {
            CircleFitError::TooFewPoints => 1,
            CircleFitError::TooManyPoints => 2,
            CircleFitError::Degenerate => 3,
            CircleFitError::NonFinite => 4,
        }
    }
}

/// Mean-centred moments of a point set (Chernov's notation, with
/// w = x² + z² of the centred coordinates) [m^k].
struct Moments {
    mean: Point,
    xx: f64,
    zz: f64,
    xz: f64,
    xw: f64,
    zw: f64,
    ww: f64,
}

/// Smallest spread of the points (trace of their covariance) a fit accepts
/// [m²]: (1 µm)². Below it the points are coincident.
const MIN_SPREAD: f64 = 1e-12;

fn moments<I: Iterator<Item = Point> + Clone>(points: I) -> Result<Moments, CircleFitError> {
    let (count, sx, sz) = points.clone().fold((0usize, 0.0, 0.0), |(n, sx, sz), p| {
        (n + 1, sx + p.x, sz + p.z)
    });
    if count < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    let n = count as f64;
    let mean = Point::new(sx / n, sz / n);
    let mut m = Moments {
        mean,
        xx: 0.0,
        zz: 0.0,
        xz: 0.0,
        xw: 0.0,
        zw: 0.0,
        ww: 0.0,
    };
    for p in points {
        let (x, z) = (p.x - mean.x, p.z - mean.z);
        let w = x * x + z * z;
        m.xx += x * x;
        m.zz += z * z;
        m.xz += x * z;
        m.xw += x * w;
        m.zw += z * w;
        m.ww += w * w;
    }
    for value in [
        &mut m.xx, &mut m.zz, &mut m.xz, &mut m.xw, &mut m.zw, &mut m.ww,
    ] {
        *value /= n;
    }
    if !(m.xx + m.zz + m.ww + m.xw + m.zw).is_finite() || !mean.is_finite() {
        return Err(CircleFitError::NonFinite);
    }
    if m.xx + m.zz < MIN_SPREAD {
        return Err(CircleFitError::Degenerate);
    }
    Ok(m)
}

/// Largest radius a fit returns [m]: beyond it the points are, for this
/// application, a straight line (arm segments are < 0.5 m, paper eq. 17).
const MAX_RADIUS: f64 = 1.0e3;

fn circle_from_centred(
    m: &Moments,
    a: f64,
    b: f64,
    radius_squared: f64,
) -> Result<Circle, CircleFitError> {
    if !(radius_squared.is_finite() && a.is_finite() && b.is_finite()) {
        return Err(CircleFitError::NonFinite);
    }
    if radius_squared <= 0.0 || radius_squared > MAX_RADIUS * MAX_RADIUS {
        return Err(CircleFitError::Degenerate);
    }
    Ok(Circle {
        centre: Point::new(a + m.mean.x, b + m.mean.z),
        radius: libm::sqrt(radius_squared),
    })
}

/// Algebraic (Kåsa) least-squares fit, paper eq. 22-27: solves
/// x² + z² = 2a x + 2b z + c in the least-squares sense, on coordinates
/// centred on the mean for conditioning. Biased toward small radii on short,
/// noisy arcs; see [`fit_circle_taubin`].
///
/// # Errors
/// Fewer than three points, coincident or collinear points, non-finite data.
pub fn fit_circle_kasa<I: Iterator<Item = Point> + Clone>(
    points: I,
) -> Result<Circle, CircleFitError> {
    let m = moments(points)?;
    // Normal equations of rows (2x, 2z, 1) against w; the centred sums of x
    // and z vanish.
    let normal = Matrix3::new(
        4.0 * m.xx,
        4.0 * m.xz,
        0.0,
        4.0 * m.xz,
        4.0 * m.zz,
        0.0,
        0.0,
        0.0,
        1.0,
    );
    let rhs = Vector3::new(2.0 * m.xw, 2.0 * m.zw, m.xx + m.zz);
    let solution = crate::linear::solve(normal.transpose().into(), rhs.into())
        .ok_or(CircleFitError::Degenerate)?;
    let (a, b, c) = (solution[0], solution[1], solution[2]);
    circle_from_centred(&m, a, b, c + a * a + b * b)
}

/// Newton iterations of the Taubin characteristic polynomial. Chernov's
/// reference implementation allows 99; from the start at 0 the iteration is
/// monotone and converges in < 10 on any arc, so 20 is ample.
const TAUBIN_ITERATIONS: usize = 20;

/// Taubin's algebraic fit (Taubin 1991; Chernov's Newton form): the
/// gradient-weighted algebraic fit, nearly unbiased on short arcs and
/// invariant to translation and rotation.
///
/// # Errors
/// Fewer than three points, coincident or collinear points, non-finite data.
pub fn fit_circle_taubin<I: Iterator<Item = Point> + Clone>(
    points: I,
) -> Result<Circle, CircleFitError> {
    let m = moments(points)?;
    let mz = m.xx + m.zz;
    let cov = m.xx * m.zz - m.xz * m.xz;
    let var_w = m.ww - mz * mz;
    let a3 = 4.0 * mz;
    let a2 = -3.0 * mz * mz - m.ww;
    let a1 = var_w * mz + 4.0 * cov * mz - m.xw * m.xw - m.zw * m.zw;
    let a0 = m.xw * (m.xw * m.zz - m.zw * m.xz) + m.zw * (m.zw * m.xx - m.xw * m.xz) - var_w * cov;
    let (mut x, mut y) = (0.0f64, a0);
    for _ in 0..TAUBIN_ITERATIONS {
        let slope = a1 + x * (2.0 * a2 + 3.0 * a3 * x);
        let next = x - y / slope;
        if !next.is_finite() || next == x {
            break;
        }
        let value = a0 + next * (a1 + next * (a2 + next * a3));
        if libm::fabs(value) >= libm::fabs(y) {
            break;
        }
        x = next;
        y = value;
    }
    let det = x * x - x * mz + cov;
    if !(det.is_finite() && libm::fabs(det) > 0.0) {
        return Err(CircleFitError::Degenerate);
    }
    let a = (m.xw * (m.zz - x) - m.zw * m.xz) / det / 2.0;
    let b = (m.zw * (m.xx - x) - m.xw * m.xz) / det / 2.0;
    circle_from_centred(&m, a, b, a * a + b * b + mz)
}

#[cfg(test)]
mod tests {
    use super::*;

    type Fit = fn(core::slice::Iter<'_, Point>) -> Result<Circle, CircleFitError>;
    const FITS: [(&str, Fit); 2] = [
        ("Kåsa", |p| fit_circle_kasa(p.copied())),
        ("Taubin", |p| fit_circle_taubin(p.copied())),
    ];

    /// Three points fix a circle: the fewest either fit takes.
    #[test]
    fn three_points_on_a_circle_are_fitted_exactly() {
        let points = [
            Point::new(0.3, 0.1),
            Point::new(0.1, 0.3),
            Point::new(-0.1, 0.1),
        ];
        for (name, fit) in FITS {
            let circle = fit(points.iter()).unwrap_or_else(|e| panic!("{name}: {e:?}"));
            assert!(
                circle.centre.distance(Point::new(0.1, 0.1)) < 1e-12
                    && (circle.radius - 0.2).abs() < 1e-12,
                "{name}: {circle:?}"
            );
        }
    }

    /// Exactly collinear points are a degenerate circle (a line), for
    /// Taubin too, whose root is then exactly 0: not a non-finite one.
    #[test]
    fn exactly_collinear_points_are_degenerate() {
        let points = [
            Point::new(0.0, 0.2),
            Point::new(0.1, 0.2),
            Point::new(0.2, 0.2),
            Point::new(0.4, 0.2),
        ];
        for (name, fit) in FITS {
            assert_eq!(
                fit(points.iter()),
                Err(CircleFitError::Degenerate),
                "{name}"
            );
        }
    }

    /// A radius whose square overflowed is non-finite even when the centre
    /// is finite; each of the three numbers is checked on its own.
    #[test]
    fn each_non_finite_number_of_a_centred_circle_is_refused() {
        let m = moments(
            [
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.0, 1.0),
            ]
            .into_iter(),
        )
        .unwrap_or_else(|e| panic!("{e:?}"));
        for (a, b, r2) in [
            (0.1, 0.1, f64::INFINITY),
            (0.1, 0.1, f64::NAN),
            (f64::NAN, 0.1, 0.5),
            (0.1, f64::INFINITY, 0.5),
        ] {
            assert_eq!(
                circle_from_centred(&m, a, b, r2),
                Err(CircleFitError::NonFinite),
                "a {a}, b {b}, r² {r2}"
            );
        }
        assert!(circle_from_centred(&m, 0.1, 0.1, 0.5).is_ok());
    }
}
