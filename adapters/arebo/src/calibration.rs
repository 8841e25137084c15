//! Arm-parameter calibration (paper 2.3.3) and its validator.
//!
//! # Theory of operation
//! 1. ψx: the endpoint path of a flexion/extension movement (φ2 = 0) lies
//!    in the x-z plane of H0, whose normal in R0 is (0, cos ψx, sin ψx).
//!    [`fit_plane`] takes the eigenvector of the smallest eigenvalue of the
//!    path's scatter matrix (bounded Jacobi iterations) as the normal;
//!    ψx = atan2(n_z, n_y).
//! 2. Shoulder origin o and arm length l: during small random movements
//!    the endpoint stays on a sphere |p − o| = l. [`fit_sphere`] solves the
//!    algebraic fit |p|² = 2 p·o + (l² − |o|²) (linear least squares on
//!    centred points) and refines it with a fixed number of Gauss-Newton
//!    steps on the geometric residual |p − o| − l.
//! 3. [`validate`] checks ranges, residuals and spread and is the only
//!    maker of [`ValidatedArmModel`], which converts endpoints to φ.
//!
//! Fits take slices (the caller owns a fixed-size buffer such as
//! [`PathBuffer`]); none allocates or panics; degenerate, too short or
//! non-finite input gives a [`FitError`].

use crate::human::{self, ArmError, ShoulderAngles};
use nalgebra::{Matrix3, Matrix4, SymmetricEigen, Vector3, Vector4};

/// Fixed-capacity endpoint path (frame R0, m): 3000 samples, 15 s at 200 Hz.
pub type PathBuffer = heapless::Vec<Vector3<f64>, 3000>;

/// Length of each calibration movement [s] (paper 2.4.3: 15 s of
/// flexion/extension, then 15 s of small random movements).
pub const CALIBRATION_PHASE: f64 = 15.0;

/// Fewest points a fit accepts.
pub const MIN_POINTS: usize = 20;
/// Jacobi sweeps allowed for the 3×3 eigen-decomposition (converges in
/// well under 10 for a symmetric 3×3; 50 is a generous bound).
const EIGEN_ITERATIONS: usize = 50;
/// Gauss-Newton steps of the geometric sphere refinement.
pub const SPHERE_REFINEMENT_STEPS: usize = 10;

/// Why a fit failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitError {
    /// Fewer than [`MIN_POINTS`] points.
    TooFewPoints,
    /// A point is NaN or infinite.
    NonFinite,
    /// The points do not determine the fit (collinear for a plane,
    /// coplanar for a sphere, or the solver did not converge).
    Degenerate,
}

/// A plane through a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFit {
    /// Unit normal, frame R0, oriented so n_y ≥ 0.
    pub normal: Vector3<f64>,
    /// ψx = atan2(n_z, n_y) [rad].
    pub psi_x: f64,
    /// RMS distance of the points from the plane [m].
    pub residual: f64,
    /// RMS extent along the path's main direction [m] (spread).
    pub spread: f64,
}

/// A sphere through a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereFit {
    /// Centre (shoulder origin), frame R0 [m].
    pub centre: Vector3<f64>,
    /// Radius (arm length l) [m].
    pub radius: f64,
    /// RMS of |p − o| − l [m].
    pub residual: f64,
    /// Smallest RMS extent of the points over the three principal axes [m].
    pub spread: f64,
}

fn check(points: &[Vector3<f64>]) -> Result<Vector3<f64>, FitError> {
    if points.len() < MIN_POINTS {
        return Err(FitError::TooFewPoints);
    }
    if !points.iter().all(|p| p.iter().all(|v| v.is_finite())) {
        return Err(FitError::NonFinite);
    }
    Ok(points.iter().sum::<Vector3<f64>>() / points.len() as f64)
}

/// Eigen-decomposition of the scatter about `mean`, eigenvalues ascending
/// (as variances [m²]) with their eigenvectors.
fn principal_axes(
    points: &[Vector3<f64>],
    mean: &Vector3<f64>,
) -> Result<([f64; 3], [Vector3<f64>; 3]), FitError> {
    let scatter: Matrix3<f64> = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum::<Matrix3<f64>>()
        / points.len() as f64;
    let eigen =
        SymmetricEigen::try_new(scatter, 1e-15, EIGEN_ITERATIONS).ok_or(FitError::Degenerate)?;
    let mut order = [0usize, 1, 2];
    order.sort_unstable_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
    let values = order.map(|i| eigen.eigenvalues[i].max(0.0));
    let vectors = order.map(|i| eigen.eigenvectors.column(i).into_owned());
    Ok((values, vectors))
}

/// Plane through a flexion/extension path, and ψx.
///
/// # Errors
/// [`FitError`]: too few or non-finite points; collinear points (the two
/// largest spreads do not span a plane).
pub fn fit_plane(points: &[Vector3<f64>]) -> Result<PlaneFit, FitError> {
    let mean = check(points)?;
    let (values, vectors) = principal_axes(points, &mean)?;
    if values[1] < 1e-12 {
        return Err(FitError::Degenerate);
    }
    let mut normal = vectors[0].normalize();
    if normal.y < 0.0 {
        normal = -normal;
    }
    Ok(PlaneFit {
        normal,
        psi_x: libm::atan2(normal.z, normal.y),
        residual: libm::sqrt(values[0]),
        spread: libm::sqrt(values[2]),
    })
}

/// Sphere through the endpoints of small random arm movements.
///
/// # Errors
/// [`FitError`]: too few or non-finite points; coplanar points or a
/// singular normal matrix.
pub fn fit_sphere(points: &[Vector3<f64>]) -> Result<SphereFit, FitError> {
    let mean = check(points)?;
    let (values, _) = principal_axes(points, &mean)?;
    if values[0] < 1e-12 {
        return Err(FitError::Degenerate);
    }
    // Algebraic: with q = p − mean, |q|² = 2 q·c + k, c = o − mean.
    let mut normal = Matrix4::<f64>::zeros();
    let mut rhs = Vector4::<f64>::zeros();
    for p in points {
        let q = p - mean;
        let row = Vector4::new(2.0 * q.x, 2.0 * q.y, 2.0 * q.z, 1.0);
        normal += row * row.transpose();
        rhs += row * q.norm_squared();
    }
    let solution = normal.cholesky().ok_or(FitError::Degenerate)?.solve(&rhs);
    let mut centre = Vector3::new(solution.x, solution.y, solution.z);
    let radius_squared = solution.w + centre.norm_squared();
    if radius_squared.is_nan() || radius_squared <= 0.0 {
        return Err(FitError::Degenerate);
    }
    let mut radius = libm::sqrt(radius_squared);
    // Geometric refinement: Gauss-Newton on r_i = |q_i − c| − R.
    for _ in 0..SPHERE_REFINEMENT_STEPS {
        let mut jtj = Matrix4::<f64>::zeros();
        let mut jtr = Vector4::<f64>::zeros();
        for p in points {
            let d = (p - mean) - centre;
            let distance = d.norm();
            if distance < 1e-12 {
                return Err(FitError::Degenerate);
            }
            let row = Vector4::new(-d.x / distance, -d.y / distance, -d.z / distance, -1.0);
            jtj += row * row.transpose();
            jtr += row * (distance - radius);
        }
        let Some(step) = jtj.cholesky().map(|c| c.solve(&jtr)) else {
            break;
        };
        centre -= Vector3::new(step.x, step.y, step.z);
        radius -= step.w;
    }
    let residual = libm::sqrt(
        points
            .iter()
            .map(|p| {
                let e = ((p - mean) - centre).norm() - radius;
                e * e
            })
            .sum::<f64>()
            / points.len() as f64,
    );
    if radius.is_nan() || radius <= 0.0 || !residual.is_finite() {
        return Err(FitError::Degenerate);
    }
    Ok(SphereFit {
        centre: centre + mean,
        radius,
        residual,
        spread: libm::sqrt(values[0]),
    })
}

/// Acceptance limits for a calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationLimits {
    /// Largest |ψx| [rad] (paper Table 1 searches ±30°; allow ±45°).
    pub max_psi_x: f64,
    /// Largest |n_x| of the flexion plane normal (the model assumes H0 is
    /// rotated about x_R0 only).
    pub max_normal_x: f64,
    /// Largest plane RMS residual [m].
    pub max_plane_residual: f64,
    /// Smallest spread of the flexion path [m].
    pub min_plane_spread: f64,
    /// Arm length range [m] (paper Table 1: 0.15-0.20 m; allow 0.10-0.45).
    pub length: (f64, f64),
    /// Largest sphere RMS residual [m].
    pub max_sphere_residual: f64,
    /// Smallest spread of the sphere data on its thinnest axis [m].
    pub min_sphere_spread: f64,
    /// Largest distance of the shoulder origin from R0's origin [m]
    /// (reach r1 + r2 = 0.714 m plus the arm).
    pub max_origin_distance: f64,
}

impl Default for CalibrationLimits {
    fn default() -> Self {
        Self {
            max_psi_x: 45f64.to_radians(),
            max_normal_x: 0.17,
            max_plane_residual: 0.01,
            min_plane_spread: 0.03,
            length: (0.10, 0.45),
            max_sphere_residual: 0.005,
            min_sphere_spread: 0.001,
            max_origin_distance: 1.2,
        }
    }
}

/// Why a calibration was rejected: which check, the value and the bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rejection {
    /// |ψx| too large [rad].
    PsiX(f64, f64),
    /// Plane normal not perpendicular to x_R0 (|n_x|).
    NormalX(f64, f64),
    /// Plane residual too large [m].
    PlaneResidual(f64, f64),
    /// Flexion path too short [m].
    PlaneSpread(f64, f64),
    /// Arm length outside range [m].
    Length(f64, f64),
    /// Sphere residual too large [m].
    SphereResidual(f64, f64),
    /// Sphere data too thin [m].
    SphereSpread(f64, f64),
    /// Shoulder origin too far from the robot [m].
    OriginDistance(f64, f64),
}

/// An arm model that passed [`validate`]; only [`validate`] makes one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValidatedArmModel {
    psi_x: f64,
    origin: Vector3<f64>,
    length: f64,
}

fn at_most(value: f64, bound: f64, reject: fn(f64, f64) -> Rejection) -> Result<(), Rejection> {
    // NaN fails: `!(value <= bound)`.
    if value <= bound {
        Ok(())
    } else {
        Err(reject(value, bound))
    }
}

/// Accepts a plane fit and a sphere fit as an arm model.
///
/// # Errors
/// The first failed check, as a [`Rejection`] with value and bound.
pub fn validate(
    plane: &PlaneFit,
    sphere: &SphereFit,
    limits: &CalibrationLimits,
) -> Result<ValidatedArmModel, Rejection> {
    at_most(libm::fabs(plane.psi_x), limits.max_psi_x, Rejection::PsiX)?;
    at_most(
        libm::fabs(plane.normal.x),
        limits.max_normal_x,
        Rejection::NormalX,
    )?;
    at_most(
        plane.residual,
        limits.max_plane_residual,
        Rejection::PlaneResidual,
    )?;
    at_most(-plane.spread, -limits.min_plane_spread, |v, b| {
        Rejection::PlaneSpread(-v, -b)
    })?;
    at_most(sphere.radius, limits.length.1, Rejection::Length)?;
    at_most(-sphere.radius, -limits.length.0, |v, b| {
        Rejection::Length(-v, -b)
    })?;
    at_most(
        sphere.residual,
        limits.max_sphere_residual,
        Rejection::SphereResidual,
    )?;
    at_most(-sphere.spread, -limits.min_sphere_spread, |v, b| {
        Rejection::SphereSpread(-v, -b)
    })?;
    at_most(
        sphere.centre.norm(),
        limits.max_origin_distance,
        Rejection::OriginDistance,
    )?;
    Ok(ValidatedArmModel {
        psi_x: plane.psi_x,
        origin: sphere.centre,
        length: sphere.radius,
    })
}

impl ValidatedArmModel {
    /// ψx [rad].
    pub fn psi_x(&self) -> f64 {
        self.psi_x
    }

    /// Shoulder centre, frame R0 [m].
    pub fn origin(&self) -> Vector3<f64> {
        self.origin
    }

    /// Arm length l [m].
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Shoulder angles of a robot endpoint `endpoint` [m, frame R0].
    ///
    /// # Errors
    /// [`ArmError`] for a non-finite endpoint or one at the shoulder.
    pub fn angles(&self, endpoint: &Vector3<f64>) -> Result<ShoulderAngles, ArmError> {
        let relative = human::base_rotation(self.psi_x).inverse() * (endpoint - self.origin);
        human::angles(&relative)
    }

    /// Robot endpoint [m, frame R0] for shoulder angles φ.
    pub fn endpoint(&self, phi: ShoulderAngles) -> Vector3<f64> {
        self.origin + human::base_rotation(self.psi_x) * human::direction(phi) * self.length
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn true_model(psi: f64, origin: Vector3<f64>, l: f64) -> ValidatedArmModel {
        ValidatedArmModel {
            psi_x: psi,
            origin,
            length: l,
        }
    }

    proptest! {
        /// Noise-free flexion paths give ψx exactly; small random moves give
        /// the sphere exactly.
        #[test]
        fn fits_recover_the_arm(psi in -0.6f64..0.6, ox in -0.2f64..0.2, oy in 0.1f64..0.4, oz in -0.3f64..0.1, l in 0.15f64..0.35) {
            let model = true_model(psi, Vector3::new(ox, oy, oz), l);
            let mut path = PathBuffer::new();
            for i in 0..200 {
                let f = 1.5 * (i as f64 / 199.0);
                path.push(model.endpoint(ShoulderAngles { flexion: f, abduction: 0.0 })).unwrap();
            }
            let plane = fit_plane(&path).unwrap();
            prop_assert!(libm::fabs(plane.psi_x - psi) < 1e-9);
            let mut small = PathBuffer::new();
            for i in 0..300 {
                let t = i as f64 * 0.05;
                let phi = ShoulderAngles { flexion: 0.6 + 0.3 * libm::sin(1.3 * t), abduction: 0.2 * libm::sin(0.7 * t + 1.0) };
                small.push(model.endpoint(phi)).unwrap();
            }
            let sphere = fit_sphere(&small).unwrap();
            prop_assert!((sphere.centre - model.origin).norm() < 1e-8);
            prop_assert!(libm::fabs(sphere.radius - l) < 1e-8);
            let validated = validate(&plane, &sphere, &CalibrationLimits::default()).unwrap();
            let phi = ShoulderAngles { flexion: 0.4, abduction: -0.2 };
            let back = validated.angles(&model.endpoint(phi)).unwrap();
            prop_assert!(libm::fabs(back.flexion - 0.4) < 1e-7 && libm::fabs(back.abduction + 0.2) < 1e-7);
        }

        /// Fits are total: any finite or non-finite input gives a fit or a
        /// typed error, never a panic.
        #[test]
        fn fits_are_total(points in proptest::collection::vec(proptest::array::uniform3(proptest::num::f64::ANY), 0..40)) {
            let points: heapless::Vec<Vector3<f64>, 64> = points.iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect();
            let _ = fit_plane(&points);
            let _ = fit_sphere(&points);
        }
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        let line: heapless::Vec<Vector3<f64>, 64> =
            (0..30).map(|i| Vector3::new(i as f64, 0.0, 0.0)).collect();
        assert_eq!(fit_plane(&line), Err(FitError::Degenerate));
        assert_eq!(fit_sphere(&line), Err(FitError::Degenerate));
        assert_eq!(fit_plane(&line[..5]), Err(FitError::TooFewPoints));
        let mut bad = line.clone();
        bad[3].y = f64::NAN;
        assert_eq!(fit_sphere(&bad), Err(FitError::NonFinite));
    }
}
