//! `limb estimate LOG.csv [--method hough|ls|auto] [--json]`
//! (`../shared/spec/cli.md`): fits the arm from an estimation-motion log.
//! Ground-truth columns of the log are never read.

use crate::error::{emit, print_json, CliError};
use limb_kernel::estimation::{estimate_arm, FitEvidence, Method};
use limb_kernel::path::PATH_CAPACITY;
use std::path::Path;

/// The estimator to run (`--method`).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MethodArg {
    /// Bounded Hough transform (paper Algorithm 1, redesigned).
    Hough,
    /// The paper's algebraic least squares (Kåsa, eq. 22-28).
    Ls,
    /// The project's best: robust geometric fit, checked against Hough.
    Auto,
}

impl From<MethodArg> for Method {
    fn from(method: MethodArg) -> Self {
        match method {
            MethodArg::Hough => Method::Hough,
            MethodArg::Ls => Method::Ls,
            MethodArg::Auto => Method::Auto,
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
}

/// Runs `limb estimate`.
///
/// # Errors
/// [`CliError::BadInput`] for an unreadable or malformed log, one longer than
/// the kernel's path buffer, or a log the estimator cannot fit.
pub fn run(log: &Path, method: MethodArg, json: bool) -> Result<(), CliError> {
    let path: Vec<_> = limb_sim::log::read(log)
        .map_err(|error| CliError::BadInput(error.to_string()))?
        .iter()
        .map(limb_sim::log::Record::path_sample)
        .collect();
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
    let report = EstimateReport {
        l1: estimate.upper_arm_length,
        l2: estimate.forearm_length,
        elbow: [estimate.elbow.x, estimate.elbow.z],
        shoulder: [estimate.shoulder.x, estimate.shoulder.z],
        method: estimate.method,
        samples: path.len(),
        evidence: estimate.evidence,
    };
    if json {
        return print_json(&report);
    }
    emit(&format!(
        "method    {:?}\nl1        {:.4} m (upper arm)\nl2        {:.4} m (forearm, elbow to grasp)\n\
         elbow     ({:.4}, {:.4}) m, frame S, t = 0\nshoulder  ({:.4}, {:.4}) m, frame S\nsamples   {}\n",
        report.method,
        report.l1,
        report.l2,
        report.elbow[0],
        report.elbow[1],
        report.shoulder[0],
        report.shoulder[1],
        report.samples
    ))
}
