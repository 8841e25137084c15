//! Arm estimation from the grasp path (paper 000, section III-C).
//!
//! # Theory of operation
//! During the estimation motion the forearm first turns about the elbow
//! resting on the table (phase 1), then the upper arm turns about the
//! shoulder (phase 2). A circle fitted to the phase-1 grasp path gives the
//! forearm length l2 and the elbow; the elbow path follows from each grasp
//! pose and l2 (eq. 19-21), and a circle fitted to the phase-2 elbow path
//! gives the upper-arm length l1 and the shoulder (eq. 28).
//!
//! Work and memory are bounded: the path holds at most
//! [`crate::path::PATH_CAPACITY`] samples and every loop is over it.

mod circle;

pub use circle::{fit_circle_kasa, Circle, CircleFitError};

use crate::geometry::Point;
use crate::path::{PathSample, PATH_CAPACITY};

/// Which estimator to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Method {
    /// Hough transform (paper Algorithm 1, bounded).
    Hough,
    /// Algebraic least-squares circle fit (paper eq. 22-28).
    Ls,
    /// The project's best method.
    Auto,
}

/// What the fits saw, for the validator to judge.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FitEvidence {
    /// Arc swept by the forearm about the elbow in phase 1 [rad].
    pub forearm_arc: f64,
    /// Arc swept by the upper arm about the shoulder in phase 2 [rad].
    pub upper_arm_arc: f64,
    /// RMS geometric residual of the phase-1 fit [m].
    pub forearm_residual: f64,
    /// RMS geometric residual of the phase-2 fit [m].
    pub upper_arm_residual: f64,
    /// Largest difference in l1 or l2 between independent methods [m];
    /// `None` when only one method ran.
    pub method_disagreement: Option<f64>,
    /// Samples used in phase 1.
    pub forearm_samples: usize,
    /// Samples used in phase 2.
    pub upper_arm_samples: usize,
}

/// An unvalidated arm estimate (frame S). Turned into a
/// [`crate::validate::ValidatedArm`] only by the validator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ArmEstimate {
    /// Upper-arm length l1 [m].
    pub upper_arm_length: f64,
    /// Forearm length l2 [m].
    pub forearm_length: f64,
    /// Elbow at the start of the motion [m].
    pub elbow: Point,
    /// Shoulder centre [m].
    pub shoulder: Point,
    /// The method that produced it.
    pub method: Method,
    /// What the fits saw.
    pub evidence: FitEvidence,
}

/// Why no estimate could be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum EstimateError {
    /// More samples than [`PATH_CAPACITY`].
    PathTooLong,
    /// A sample held NaN or infinity.
    NonFiniteSample,
    /// Too few samples in the forearm phase.
    ForearmPhaseTooShort,
    /// Too few samples in the upper-arm phase.
    UpperArmPhaseTooShort,
    /// The forearm circle fit failed.
    ForearmFit(CircleFitError),
    /// The upper-arm circle fit failed.
    UpperArmFit(CircleFitError),
}

/// Minimum samples a phase needs for a fit.
pub const MIN_PHASE_SAMPLES: usize = 10;

/// Forearm elevation that ends phase 1 in this first-pass phase split [rad].
const PHASE_ONE_END_PSI: f64 = 1.2;
/// Grasp height that starts phase 1 [m]: the forearm has left the table.
const LIFT_OFF_HEIGHT: f64 = 0.002;
/// Elbow height that starts phase 2 [m]: the upper arm has left the table.
const ELBOW_LIFT_OFF_HEIGHT: f64 = 0.005;

/// Estimates the arm from the recorded grasp path with `method`.
///
/// # Errors
/// A typed [`EstimateError`]; never panics for any input.
pub fn estimate_arm(path: &[PathSample], method: Method) -> Result<ArmEstimate, EstimateError> {
    if path.len() > PATH_CAPACITY {
        return Err(EstimateError::PathTooLong);
    }
    if path
        .iter()
        .any(|s| !(s.time.is_finite() && s.pose.is_finite() && s.wrench.is_finite()))
    {
        return Err(EstimateError::NonFiniteSample);
    }
    let mut points = [Point::default(); PATH_CAPACITY];
    // Phase 1: from lift-off until the forearm is well up.
    let mut n = 0;
    for sample in path {
        if sample.pose.psi >= PHASE_ONE_END_PSI {
            break;
        }
        if sample.pose.z > LIFT_OFF_HEIGHT {
            points[n] = sample.pose.point();
            n += 1;
        }
    }
    if n < MIN_PHASE_SAMPLES {
        return Err(EstimateError::ForearmPhaseTooShort);
    }
    let forearm = fit_circle_kasa(&points[..n]).map_err(EstimateError::ForearmFit)?;
    let forearm_arc = arc_about(&points[..n], forearm.centre);
    let (forearm_samples, forearm_residual) = (n, forearm.rms_residual(&points[..n]));
    // Phase 2: elbow path (eq. 19-21) once the elbow has left the table.
    let l2 = forearm.radius;
    n = 0;
    for sample in path {
        let elbow = Point::new(
            sample.pose.x + l2 * libm::cos(sample.pose.psi),
            sample.pose.z - l2 * libm::sin(sample.pose.psi),
        );
        if elbow.z > ELBOW_LIFT_OFF_HEIGHT {
            points[n] = elbow;
            n += 1;
        }
    }
    if n < MIN_PHASE_SAMPLES {
        return Err(EstimateError::UpperArmPhaseTooShort);
    }
    let upper_arm = fit_circle_kasa(&points[..n]).map_err(EstimateError::UpperArmFit)?;
    Ok(ArmEstimate {
        upper_arm_length: upper_arm.radius,
        forearm_length: l2,
        elbow: forearm.centre,
        shoulder: upper_arm.centre,
        method,
        evidence: FitEvidence {
            forearm_arc,
            upper_arm_arc: arc_about(&points[..n], upper_arm.centre),
            forearm_residual,
            upper_arm_residual: upper_arm.rms_residual(&points[..n]),
            method_disagreement: None,
            forearm_samples,
            upper_arm_samples: n,
        },
    })
}

/// Angle between the first and last point seen from `centre` [rad, 0..π].
fn arc_about(points: &[Point], centre: Point) -> f64 {
    match (points.first(), points.last()) {
        (Some(a), Some(b)) => {
            let (ax, az) = (a.x - centre.x, a.z - centre.z);
            let (bx, bz) = (b.x - centre.x, b.z - centre.z);
            libm::fabs(libm::atan2(ax * bz - az * bx, ax * bx + az * bz))
        }
        _ => 0.0,
    }
}
