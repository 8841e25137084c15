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
//! Phases are found from the data (`phase.rs`); [`Method::Ls`] is the paper's
//! Kåsa fit, [`Method::Hough`] the bounded Hough transform (`hough.rs`),
//! [`Method::Auto`] the robust forearm-pose model with grasp compliance and
//! slip corrections (`grasp.rs`) and a robust geometric fit (`geometric.rs`),
//! checked against Hough. Details, accuracy and timing tables:
//! `kernel/src/estimation/README.md`.
//!
//! # Bounds
//! Work and memory are bounded: the path holds at most
//! [`crate::path::PATH_CAPACITY`] samples, every loop is over it or over a
//! constant, and no fit copies it (points are streamed from the path); the
//! largest stack object is the 1 002-byte Hough accumulator.

mod circle;
pub mod compliance;
pub mod dequantize;
mod geometric;
mod grasp;
mod hough;
pub mod moments;
pub mod online;
pub mod outlier;
mod phase;
pub mod play;
pub mod refine;
pub mod tilt;

pub use circle::{
    fit_circle_kasa, fit_circle_taubin, Circle, CircleFitError, ResidualBias, BIAS_BLOCK,
};
pub use geometric::{fit_circle_geometric, GeometricFit};
pub use grasp::{
    detect_compliance, detect_slip, fit_forearm_pose, FitPoint, ForearmPose, FreeCorrections,
    GraspCorrection, MIN_SLIP_SAMPLES,
};
pub use hough::{
    hough_circle_chords, hough_circle_normals, ACCUMULATOR_BYTES as HOUGH_ACCUMULATOR_BYTES,
    MAX_VOTES as HOUGH_MAX_VOTES,
};
pub use phase::{detect_phases, detect_phases_from, Phases, DEPARTURE_WINDOW, LIFT_PSI};

use crate::config::ValidationLimits;
use crate::geometry::Point;
use crate::path::{PathSample, PATH_CAPACITY};
use core::ops::Range;

/// Which estimator to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Method {
    /// Hough transform (paper Algorithm 1, bounded).
    Hough,
    /// Algebraic least-squares circle fit (paper eq. 22-28).
    Ls,
    /// The project's best offline method.
    Auto,
    /// The kernel's own: online Kåsa moments and phase split while the path
    /// is recorded, then a bounded geometric refinement (`online.rs`,
    /// `refine.rs`); replayed sample by sample over a recorded path.
    Online,
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
    /// Largest |mean residual| over 0.5 s blocks of either phase
    /// ([`circle::ResidualBias`]) [m]: how far the path leaves its circle
    /// for a while, which noise does not.
    pub residual_bias: f64,
    /// Largest difference in l1 or l2 between independent methods [m];
    /// `None` when only one method ran.
    pub method_disagreement: Option<f64>,
    /// Samples used in phase 1.
    pub forearm_samples: usize,
    /// Samples used in phase 2.
    pub upper_arm_samples: usize,
    /// Samples of either phase left out of the fits as isolated outliers
    /// ([`outlier`]); 0 for the methods that use every sample (the paper's
    /// `Ls` and `Hough`).
    pub outliers: usize,
    /// The sensor's resolution as the fits met it [m]: a quantizer's step
    /// of the grasp point, or of the elbow point under a step of psi (l2 ×
    /// the angle step), whichever is larger ([`dequantize`]). 0 on an
    /// unquantized path, and for the methods other than
    /// [`Method::Online`], which do not measure it. The validator allows
    /// the residual bias and the methods' disagreement half of it
    /// (`crate::validate`).
    pub resolution: f64,
    /// Standard uncertainty of the lengths ([`LengthUncertainty`]); `None`
    /// for the methods other than [`Method::Online`], which do not
    /// measure it.
    pub uncertainty: Option<LengthUncertainty>,
    /// The play (backlash) in psi the upper-arm fits measured and read out
    /// of the falling samples [rad] ([`play`]); `None` for the methods
    /// other than [`Method::Online`], which do not measure it.
    pub play: Option<f64>,
    /// The grasp's compliance 1/k the forearm phase measured and read the
    /// grasp point with [m/N] ([`compliance`]; 0: a rigid grasp); `None`
    /// for the methods other than [`Method::Online`].
    pub compliance: Option<f64>,
    /// A yielding trunk's compliance [m/N] the upper-arm fits measured and
    /// read the elbow points with, E − c f_ext (`refine`, REQ-EST-012; 0:
    /// a fixed shoulder, or a yield not looked for or not shown); `None`
    /// for the methods other than [`Method::Online`].
    pub trunk_compliance: Option<f64>,
    /// The grasp's slide along the forearm [m] the fits measured at a jump
    /// of the path and read out (`refine`, REQ-EST-013; positive: away
    /// from the elbow; 0: none); the estimate is the arm held after it.
    /// `None` for the methods other than [`Method::Online`].
    pub grasp_slip: Option<f64>,
    /// The tilt of the arm's plane about x the lateral channel showed and
    /// the heights were read in [rad] ([`tilt`]; 0: a vertical plane, or
    /// a tilt not shown); `None` for the methods other than
    /// [`Method::Online`].
    pub plane_tilt: Option<f64>,
}

/// Standard uncertainty (one standard deviation) of the fitted lengths
/// [m], each from its circle's last Gauss-Newton pass: the covariance of
/// the radius under the pass's residual variance, inflated by how far the
/// residuals' 0.5 s block means say they are correlated (batch means).
/// It is the noise's share of the error and the part of a model error that
/// shows in the residuals; an error the circle absorbs (a bias every
/// sample shares) it cannot see.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct LengthUncertainty {
    /// Of the upper-arm length l1 (the glenohumeral centre at rest to the
    /// elbow, with a shoulder-rhythm prior; else the elbow path's radius) [m].
    pub upper_arm: f64,
    /// Of the forearm length l2 [m].
    pub forearm: f64,
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
    /// Shoulder centre [m]: the glenohumeral centre at rest (with a
    /// shoulder-rhythm prior; otherwise the fixed shoulder). l1 is measured
    /// from it to the elbow's centre.
    pub shoulder: Point,
    /// Centre of the elbow's path in the upper-arm phase [m]: the fixed
    /// shoulder that best explains the lift, which the monitors use
    /// (equal to `shoulder` without a shoulder-rhythm prior).
    pub path_shoulder: Point,
    /// Radius of the elbow's path about [`ArmEstimate::path_shoulder`] [m]
    /// (equal to l1 without a shoulder-rhythm prior).
    pub path_upper_arm_length: f64,
    /// Grasp pitch offset δ [rad] (`crate::arm`): the robot's pitch minus
    /// the forearm's elevation. Measured by [`Method::Online`]; the paper's
    /// methods and `Auto` take the grasp on the forearm's joint line (0).
    pub grasp_pitch_offset: f64,
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

impl EstimateError {
    /// Stable numeric code of the error.
    pub const fn code(&self) -> u16 {
        match self {
            EstimateError::PathTooLong => 1,
            EstimateError::NonFiniteSample => 2,
            EstimateError::ForearmPhaseTooShort => 3,
            EstimateError::UpperArmPhaseTooShort => 4,
            EstimateError::ForearmFit(_) => 5,
            EstimateError::UpperArmFit(_) => 6,
        }
    }
}

/// Minimum samples a phase needs for a fit.
pub const MIN_PHASE_SAMPLES: usize = 10;

/// How a path sample becomes a point of a fit: the grasp point
/// (`forearm_length` = 0) or the elbow, eq. 19-21 in frame S:
/// E = G + l2 (cos psi, −sin psi), with optional grasp corrections.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointModel {
    /// Distance from the grasp to the point along the forearm [m].
    pub forearm_length: f64,
    /// Grasp corrections applied to every point.
    pub correction: GraspCorrection,
    /// Path index from which the grasp has slipped (`usize::MAX`: never).
    pub slip_index: usize,
}

impl PointModel {
    /// The grasp point itself, uncorrected.
    pub const GRASP: PointModel = PointModel {
        forearm_length: 0.0,
        correction: GraspCorrection {
            compliance: 0.0,
            slide: 0.0,
            offset: Point::new(0.0, 0.0),
        },
        slip_index: usize::MAX,
    };

    /// The same corrections, stepping `forearm_length` along the forearm.
    pub const fn along_forearm(self, forearm_length: f64) -> PointModel {
        PointModel {
            forearm_length,
            ..self
        }
    }

    /// The point of path sample `index` with its correction derivatives,
    /// before the corrections are applied.
    pub fn fit_point(&self, index: usize, sample: &PathSample) -> FitPoint {
        let forearm = Point::new(libm::cos(sample.pose.psi), -libm::sin(sample.pose.psi));
        FitPoint {
            base: Point::new(
                sample.pose.x + self.forearm_length * forearm.x,
                sample.pose.z + self.forearm_length * forearm.z,
            ),
            force: Point::new(sample.wrench.fx, sample.wrench.fz),
            forearm,
            slipped: index >= self.slip_index,
        }
    }

    /// Fit points of `path[range]` (empty where the range is out of bounds).
    pub fn fit_points<'a>(
        &'a self,
        path: &'a [PathSample],
        range: Range<usize>,
    ) -> impl Iterator<Item = FitPoint> + Clone + 'a {
        let first = range.start;
        path.get(range)
            .unwrap_or(&[])
            .iter()
            .enumerate()
            .map(move |(offset, sample)| self.fit_point(first + offset, sample))
    }

    /// Corrected point of path sample `index`: the same as
    /// `fit_point(index, sample).at(correction)`, without the trigonometry
    /// when the point lies at the grasp (no step along the forearm).
    pub fn point(&self, index: usize, sample: &PathSample) -> Point {
        let c = self.correction;
        let slipped = index >= self.slip_index;
        let (along, offset) = if slipped {
            (self.forearm_length + c.slide, c.offset)
        } else {
            (self.forearm_length, Point::default())
        };
        let wrist = Point::new(
            sample.pose.x + c.compliance * sample.wrench.fx - offset.x,
            sample.pose.z + c.compliance * sample.wrench.fz - offset.z,
        );
        if along == 0.0 {
            return wrist;
        }
        Point::new(
            wrist.x + along * libm::cos(sample.pose.psi),
            wrist.z - along * libm::sin(sample.pose.psi),
        )
    }

    /// Corrected point of path sample `index`, if there is one.
    pub fn point_at(&self, path: &[PathSample], index: usize) -> Option<Point> {
        path.get(index).map(|sample| self.point(index, sample))
    }

    /// Robust circle through the corrected points of `path[range]` that
    /// are not isolated outliers ([`outlier`]): the bounded Hough transform
    /// (chords) as a start that outliers and corrupted stretches cannot
    /// pull, refined by the robust geometric fit.
    ///
    /// # Errors
    /// Either fit failed.
    pub fn robust_circle(
        &self,
        path: &[PathSample],
        range: Range<usize>,
    ) -> Result<GeometricFit, CircleFitError> {
        let first = range.start;
        let start = hough_circle_chords(range.len(), |offset| {
            let index = first.checked_add(offset)?;
            if outlier::is_isolated_outlier(path, index) {
                return None;
            }
            self.point_at(path, index)
        })?;
        let kept = outlier::kept(path, range).filter_map(|index| self.point_at(path, index));
        fit_circle_geometric(kept, start)
    }

    /// Corrected points of `path[range]` (empty where the range is out of
    /// bounds).
    pub fn points<'a>(
        &'a self,
        path: &'a [PathSample],
        range: Range<usize>,
    ) -> impl Iterator<Item = Point> + Clone + 'a {
        let first = range.start;
        path.get(range)
            .unwrap_or(&[])
            .iter()
            .enumerate()
            .map(move |(offset, sample)| self.point(first + offset, sample))
    }
}

/// The two circles of an estimate and the model that produced the elbow path.
struct PhaseFits {
    forearm: Circle,
    upper_arm: Circle,
    elbow_path: PointModel,
}

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
    let (phases, fits, method_disagreement) = match method {
        Method::Online => {
            return estimate_online(path, &ValidationLimits::default(), &tilt::PlaneTilt::new())
        }
        Method::Ls => {
            let phases = detect_phases(path, &PointModel::GRASP)?;
            let fits = fit_ls(path, &phases, PointModel::GRASP)?;
            (phases, fits, None)
        }
        Method::Hough => {
            let phases = detect_phases(path, &PointModel::GRASP)?;
            let fits = fit_hough(path, &phases, PointModel::GRASP)?;
            (phases, fits, None)
        }
        Method::Auto => {
            let (phases, best) = fit_robust(path)?;
            let grasp = best.elbow_path.along_forearm(0.0);
            let disagreement = fit_hough(path, &phases, grasp).ok().map(|hough| {
                libm::fabs(hough.forearm.radius - best.forearm.radius)
                    .max(libm::fabs(hough.upper_arm.radius - best.upper_arm.radius))
            });
            (phases, best, disagreement)
        }
    };
    let grasp = fits.elbow_path.along_forearm(0.0);
    // Auto leaves isolated outliers out of its fits, so its evidence is
    // over the samples it kept; the paper's methods keep every sample.
    let gated = method == Method::Auto;
    let used = |range: Range<usize>| {
        range.filter(move |&index| !(gated && outlier::is_isolated_outlier(path, index)))
    };
    let forearm_points = || used(phases.forearm.clone()).filter_map(|i| grasp.point_at(path, i));
    let elbow_points =
        || used(phases.upper_arm.clone()).filter_map(|i| fits.elbow_path.point_at(path, i));
    let forearm_samples = used(phases.forearm.clone()).count();
    let upper_arm_samples = used(phases.upper_arm.clone()).count();
    Ok(ArmEstimate {
        upper_arm_length: fits.upper_arm.radius,
        forearm_length: fits.forearm.radius,
        elbow: fits.forearm.centre,
        shoulder: fits.upper_arm.centre,
        path_shoulder: fits.upper_arm.centre,
        path_upper_arm_length: fits.upper_arm.radius,
        grasp_pitch_offset: 0.0,
        method,
        evidence: FitEvidence {
            forearm_arc: fits.forearm.arc(forearm_points()),
            upper_arm_arc: fits.upper_arm.arc(elbow_points()),
            forearm_residual: fits.forearm.rms_residual(forearm_points()),
            upper_arm_residual: fits.upper_arm.rms_residual(elbow_points()),
            residual_bias: refine::max_or_nan(
                fits.forearm.residual_bias(forearm_points()),
                fits.upper_arm.residual_bias(elbow_points()),
            ),
            method_disagreement,
            forearm_samples,
            upper_arm_samples,
            outliers: phases.forearm.len().saturating_sub(forearm_samples)
                + phases.upper_arm.len().saturating_sub(upper_arm_samples),
            resolution: 0.0,
            uncertainty: None,
            play: None,
            compliance: None,
            trunk_compliance: None,
            grasp_slip: None,
            plane_tilt: None,
        },
    })
}

/// The paper's least squares (eq. 22-28): Kåsa on both phases.
fn fit_ls(
    path: &[PathSample],
    phases: &Phases,
    grasp: PointModel,
) -> Result<PhaseFits, EstimateError> {
    let forearm = fit_circle_kasa(grasp.points(path, phases.forearm.clone()))
        .map_err(EstimateError::ForearmFit)?;
    let elbow_path = grasp.along_forearm(forearm.radius);
    let upper_arm = fit_circle_kasa(elbow_path.points(path, phases.upper_arm.clone()))
        .map_err(EstimateError::UpperArmFit)?;
    Ok(PhaseFits {
        forearm,
        upper_arm,
        elbow_path,
    })
}

/// The bounded Hough transform on both phases (see `hough.rs`).
fn fit_hough(
    path: &[PathSample],
    phases: &Phases,
    grasp: PointModel,
) -> Result<PhaseFits, EstimateError> {
    let sample_at = |first: usize, model: PointModel| {
        move |offset: usize| {
            let index = first.checked_add(offset)?;
            let sample = path.get(index)?;
            Some((
                model.fit_point(index, sample).at(model.correction),
                sample.pose.psi,
            ))
        }
    };
    let forearm =
        hough_circle_normals(phases.forearm.len(), sample_at(phases.forearm.start, grasp))
            .map_err(EstimateError::ForearmFit)?;
    let elbow_path = grasp.along_forearm(forearm.radius);
    let elbow_at = sample_at(phases.upper_arm.start, elbow_path);
    let upper_arm = hough_circle_chords(phases.upper_arm.len(), |offset| {
        elbow_at(offset).map(|(p, _)| p)
    })
    .map_err(EstimateError::UpperArmFit)?;
    Ok(PhaseFits {
        forearm,
        upper_arm,
        elbow_path,
    })
}

/// The grasp model of a log: compliance and slip detected from the data
/// (see `grasp.rs`), and the phases under that model.
fn grasp_model(path: &[PathSample]) -> Result<(Phases, PointModel), EstimateError> {
    let mut model = PointModel::GRASP;
    let mut phases = detect_phases(path, &model)?;
    model.correction.compliance = detect_compliance(path, phases.forearm.clone())?;
    if model.correction.compliance != 0.0 {
        phases = detect_phases(path, &model)?;
    }
    if let Some(slipped) = detect_slip(path, &phases, &model)? {
        model = slipped;
        phases = detect_phases(path, &model)?;
    }
    Ok((phases, model))
}

/// The project's best fit: phase 1 by the robust forearm-pose model (grasp
/// points, psi and wrench, with compliance and slip corrected, see
/// `grasp.rs`), phase 2 by a Taubin start and a robust geometric refinement
/// on the corrected elbow path.
fn fit_robust(path: &[PathSample]) -> Result<(Phases, PhaseFits), EstimateError> {
    let (phases, grasp) = grasp_model(path)?;
    let pose = fit_forearm_pose(
        path,
        phases.forearm.clone(),
        &grasp,
        FreeCorrections::default(),
    )?;
    let forearm = Circle {
        centre: pose.elbow,
        radius: pose.forearm_length,
    };
    let elbow_path = grasp.along_forearm(forearm.radius);
    let upper_arm = elbow_path
        .robust_circle(path, phases.upper_arm.clone())
        .map_err(EstimateError::UpperArmFit)?
        .circle;
    Ok((
        phases,
        PhaseFits {
            forearm,
            upper_arm,
            elbow_path,
        },
    ))
}

/// The kernel's estimator replayed over a recorded path: each sample
/// recorded in turn by an [`online::OnlineEstimator`], then the whole
/// [`refine::Refinement`] at once.
///
/// # Errors
/// No lift-off or no split ([`EstimateError::ForearmPhaseTooShort`],
/// [`EstimateError::UpperArmPhaseTooShort`]), or a failed fit.
/// `prior` gives the shoulder-rhythm prior [m/rad]
/// (`ValidationLimits::shoulder_rhythm`; `estimate_arm` uses the default
/// limits, whose rhythm is none) and the plausible forearm range of the
/// provisional forearm; `tilt` the sums the path was recorded in the
/// arm's plane with ([`tilt::PlaneTilt::record`]), whose slope the
/// estimate reports (`estimate_arm` has none: a vertical plane).
pub fn estimate_online(
    path: &[PathSample],
    prior: &ValidationLimits,
    tilt: &tilt::PlaneTilt,
) -> Result<ArmEstimate, EstimateError> {
    let mut online = online::OnlineEstimator::new();
    for end in 1..=path.len().min(PATH_CAPACITY) {
        online.record(path.get(..end).unwrap_or(&[]), prior);
    }
    let mut refinement = refine::Refinement::after(&online, path.len(), prior, tilt)
        .ok_or(EstimateError::UpperArmPhaseTooShort)?;
    // Each call ends at least one pass; the last call reports the outcome.
    for _ in 0..=refine::MAX_PASSES {
        if let refine::Progress::Done(outcome) = refinement.advance(path, PATH_CAPACITY) {
            return outcome;
        }
    }
    Err(EstimateError::UpperArmPhaseTooShort)
}

#[cfg(any(test, kani))]
mod verification;
