//! `limb estimate LOG.csv [--method hough|ls|auto] [--json]`
//! (`../shared/spec/cli.md`): fits the arm from an estimation-motion log.
//! Ground-truth columns of the log are never read.

use crate::error::{emit, print_json, CliError};
use limb_kernel::estimation::{estimate_arm, FitEvidence, Method};
use limb_kernel::path::{is_due, PathSample, PATH_CAPACITY};
use limb_kernel::validate::{validate, ValidationLimits};
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
    method: Method,
    samples: usize,
    evidence: FitEvidence,
    /// Would the kernel's validator (default limits) accept it?
    validated: bool,
    /// If not, which check refused it, in words.
    rejection: Option<String>,
}

/// Runs `limb estimate`.
///
/// # Errors
/// [`CliError::BadInput`] for an unreadable or malformed log, one longer than
/// the kernel's path buffer, or a log the estimator cannot fit.
pub fn run(log: &Path, method: MethodArg, json: bool) -> Result<(), CliError> {
    let records =
        limb_sim::log::read(log).map_err(|error| CliError::BadInput(error.to_string()))?;
    let path = at_path_rate(records.iter().map(limb_sim::log::Record::path_sample));
    if path.len() > PATH_CAPACITY {
        return Err(CliError::BadInput(format!(
            "{}: {} samples, more than the estimator's capacity of {PATH_CAPACITY}",
            log.display(),
            path.len()
        )));
    }
    let estimate = estimate_arm(&path, method.into()).map_err(|error| {
        CliError::BadInput(format!(
            "{}: cannot estimate the arm: {error:?}",
            log.display()
        ))
    })?;
    let rejection = validate(
        &estimate,
        path.first().map(|s| s.pose.point()).unwrap_or_default(),
        &ValidationLimits::default(),
    )
    .err()
    .map(|rejection| format!("{rejection:?}"));
    let report = EstimateReport {
        l1: estimate.upper_arm_length,
        l2: estimate.forearm_length,
        elbow: [estimate.elbow.x, estimate.elbow.z],
        shoulder: [estimate.shoulder.x, estimate.shoulder.z],
        method: estimate.method,
        samples: path.len(),
        evidence: estimate.evidence,
        validated: rejection.is_none(),
        rejection,
    };
    if json {
        return print_json(&report);
    }
    emit(&format!(
        "method    {:?}\nl1        {:.4} m (upper arm)\nl2        {:.4} m (forearm, elbow to grasp)\n\
         elbow     ({:.4}, {:.4}) m, frame S, t = 0\nshoulder  ({:.4}, {:.4}) m, frame S\nsamples   {}\n\
         validator {}\n",
        report.method,
        report.l1,
        report.l2,
        report.elbow[0],
        report.elbow[1],
        report.shoulder[0],
        report.shoulder[1],
        report.samples,
        report.rejection.as_deref().unwrap_or("accepted")
    ))
}

/// The samples the kernel would record from a log: at most one per
/// [`PATH_SAMPLE_PERIOD`] (a `limb run --log` session is logged at the
/// kernel's 1 kHz; `plant.md` logs are already at 100 Hz and pass whole).
fn at_path_rate(samples: impl Iterator<Item = PathSample>) -> Vec<PathSample> {
    let mut path: Vec<PathSample> = Vec::new();
    for sample in samples {
        if is_due(path.last(), sample.time) {
            path.push(sample);
        }
    }
    path
}
