//! `limb estimate LOG.csv [--method hough|ls|auto|online] [--arm rod|person] [--json]`
//! (`../shared/spec/cli.md`): fits the arm from an estimation-motion log.
//! Ground-truth columns of the log are never read.

use crate::arm_model::ArmModel;
use crate::error::{emit, print_json, CliError};
use limb_kernel::estimation::outlier::OUTLIER_WINDOW;
use limb_kernel::estimation::tilt::PlaneTilt;
use limb_kernel::estimation::{estimate_arm, estimate_online, FitEvidence, Method};
use limb_kernel::geometry::Point;
use limb_kernel::path::{is_due, PathSample, PATH_CAPACITY};
use limb_kernel::validate::validate;
use limb_kernel::KernelConfig;
use limb_sim::log::Record;
use std::path::Path;

/// The estimator to run (`--method`).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MethodArg {
    /// Bounded Hough transform (paper Algorithm 1, redesigned).
    Hough,
    /// The paper's algebraic least squares (Kåsa, eq. 22-28).
    Ls,
    /// The project's best offline: robust geometric fit, checked against Hough.
    Auto,
    /// The kernel's own online estimator, replayed over the log.
    Online,
}

impl From<MethodArg> for Method {
    fn from(method: MethodArg) -> Self {
        match method {
            MethodArg::Hough => Method::Hough,
            MethodArg::Ls => Method::Ls,
            MethodArg::Auto => Method::Auto,
            MethodArg::Online => Method::Online,
        }
    }
}

/// The JSON document of `limb estimate --json` (frame S, metres).
#[derive(serde::Serialize)]
struct EstimateReport {
    l1: f64,
    l2: f64,
    elbow: [f64; 2],
    shoulder: [f64; 2],
    /// The elbow path's centre and radius (the monitors' fixed shoulder
    /// and upper arm; `shoulder` and `l1` without a shoulder-rhythm prior).
    path_shoulder: [f64; 2],
    path_l1: f64,
    /// Robot pitch minus forearm elevation [rad] (`limb_kernel::arm`).
    grasp_pitch_offset: f64,
    /// The arm assumed (`--arm`).
    arm: ArmModel,
    method: Method,
    samples: usize,
    evidence: FitEvidence,
    /// Would the kernel's validator (default limits) accept it?
    validated: bool,
    /// If not, which check refused it, in words.
    rejection: Option<String>,
    /// The refusing check's stable name (`limb_kernel::vocabulary`).
    rejection_check: Option<&'static str>,
}

/// Runs `limb estimate`.
///
/// # Errors
/// [`CliError::BadInput`] for an unreadable or malformed log, one longer than
/// the kernel's path buffer, or a log the estimator cannot fit.
pub fn run(log: &Path, method: MethodArg, arm: ArmModel, json: bool) -> Result<(), CliError> {
    let records = crate::session_log::read_records(log)?;
    let (path, tilt) = at_path_rate(&records);
    if path.len() > PATH_CAPACITY {
        return Err(CliError::BadInput(format!(
            "{}: {} samples, more than the estimator's capacity of {PATH_CAPACITY}",
            log.display(),
            path.len()
        )));
    }
    let limits = arm.apply(KernelConfig::default()).validation;
    let estimated = match method {
        MethodArg::Online => estimate_online(&path, &limits, &tilt),
        _ => estimate_arm(&path, method.into()),
    };
    let estimate = estimated.map_err(|error| {
        CliError::BadInput(format!(
            "{}: cannot estimate the arm: {error}",
            log.display()
        ))
    })?;
    let rejection = validate(&estimate, grasp_at_rest(&path), &limits).err();
    let report = EstimateReport {
        l1: estimate.upper_arm_length,
        l2: estimate.forearm_length,
        elbow: [estimate.elbow.x, estimate.elbow.z],
        shoulder: [estimate.shoulder.x, estimate.shoulder.z],
        path_shoulder: [estimate.path_shoulder.x, estimate.path_shoulder.z],
        path_l1: estimate.path_upper_arm_length,
        grasp_pitch_offset: estimate.grasp_pitch_offset,
        arm,
        method: estimate.method,
        samples: path.len(),
        evidence: estimate.evidence,
        validated: rejection.is_none(),
        rejection: rejection.map(|r| r.to_string()),
        rejection_check: rejection.map(|r| r.name()),
    };
    if json {
        return print_json(&report);
    }
    emit(&format!(
        "method    {}\nl1        {:.4} m (upper arm)\nl2        {:.4} m (forearm, elbow to grasp)\n\
         elbow     ({:.4}, {:.4}) m, frame S, t = 0\nshoulder  ({:.4}, {:.4}) m, frame S\nsamples   {}\n\
         outliers  {} (isolated samples left out of the fits)\nuncertainty {}\nplay      {}\nvalidator {}\n",
        report.method,
        report.l1,
        report.l2,
        report.elbow[0],
        report.elbow[1],
        report.shoulder[0],
        report.shoulder[1],
        report.samples,
        report.evidence.outliers,
        report
            .evidence
            .uncertainty
            .map_or("not measured by this method".to_string(), |u| format!(
                "l1 {:.3} mm, l2 {:.3} mm (standard, from the fits' residuals)",
                u.upper_arm * 1e3,
                u.forearm * 1e3
            )),
        report.evidence.play.map_or("not measured by this method".to_string(), |w| format!(
            "{:.1} mrad in psi (measured in the upper-arm phase and read out)",
            w * 1e3
        )),
        report.rejection.as_deref().unwrap_or("accepted")
    ))
}

/// The grasp point at rest that the validator checks the model against
/// (frame S): the componentwise median of the first [`OUTLIER_WINDOW`]
/// path samples, so that one glitched first sample (which the outlier test
/// cannot judge: it has no earlier neighbours) does not decide the verdict;
/// the kernel itself takes the mean of its 64-frame Grasp hold. The origin
/// for an empty path (which the estimator has already refused).
fn grasp_at_rest(path: &[PathSample]) -> Point {
    let first = &path[..path.len().min(OUTLIER_WINDOW)];
    let median = |of: fn(&PathSample) -> f64| {
        let mut values: Vec<f64> = first.iter().map(of).collect();
        values.sort_unstable_by(f64::total_cmp);
        values.get(values.len() / 2).copied().unwrap_or_default()
    };
    Point::new(median(|s| s.pose.x), median(|s| s.pose.z))
}

/// The samples the kernel would record from a log: at most one per
/// [`PATH_SAMPLE_PERIOD`] (a `limb run --log` session is logged at the
/// kernel's 1 kHz; `plant.md` logs are already at 100 Hz and pass whole),
/// recorded as the kernel records them, in the arm's plane their lateral
/// positions show (a log without the lateral column: a vertical one), and
/// that plane's tilt.
fn at_path_rate(records: &[Record]) -> (Vec<PathSample>, PlaneTilt) {
    let mut path: Vec<PathSample> = Vec::new();
    let mut tilt = PlaneTilt::new();
    for record in records {
        let sample = record.path_sample();
        if is_due(path.last(), sample.time) {
            path.push(tilt.record(&sample, record.lateral.unwrap_or(0.0)));
        }
    }
    (path, tilt)
}
