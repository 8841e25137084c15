//! `limb population`: whole kernel sessions on many random arms of the
//! reference plant, noise on, and what they show about the Estimate state:
//! did the person's joints stay inside the configured limits, how far is
//! each validated model from the truth, which arms the validator refused
//! and why, how long the lift took.
//!
//! Arms are drawn uniformly, l1 in [0.22, 0.38] m and l2 in [0.15, 0.26] m
//! (adult upper arms and wrist-to-elbow grasps, with margin), from `--seed`
//! with the plant's seeded generator; arm i gets noise seed `seed + i`. The
//! kernel runs with its default configuration: nothing is tuned per arm and
//! no ground truth reaches it.

use crate::error::{emit, print_json, CliError};
use crate::run::{run_session, SessionPlan};
use crate::session_report::JointExtremes;
use limb_kernel::{Kernel, KernelConfig, StateKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// `limb population` options.
#[derive(Debug, clap::Args)]
pub struct PopulationArgs {
    /// Number of random arms.
    #[arg(long, default_value_t = 500)]
    pub arms: usize,
    /// Seed of the arm draw (and, plus the arm's index, of its noise).
    #[arg(long, default_value_t = 2026)]
    pub seed: u64,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Sessions on external plants instead of the reference plant's arms.
    #[command(flatten)]
    pub plants: crate::plant_population::PlantPopulationArgs,
}

/// One arm's session.
#[derive(Clone, Debug, Serialize)]
pub struct ArmOutcome {
    /// True upper-arm length [m].
    pub l1: f64,
    /// True forearm length [m].
    pub l2: f64,
    /// Noise seed.
    pub seed: u64,
    /// Joint extremes during Estimate, from the plant's true joints [rad].
    pub estimate_joints: JointExtremes,
    /// True when they stayed inside the configured limits.
    pub within_limits: bool,
    /// |l1 − truth|, |l2 − truth| [m] of the validated model.
    pub error: Option<[f64; 2]>,
    /// The standard uncertainty of l1 and l2 the estimator reported [m]
    /// (`limb_kernel::estimation::LengthUncertainty`).
    pub uncertainty: Option<[f64; 2]>,
    /// Why the kernel stopped instead of validating, in words.
    pub refusal: Option<String>,
    /// The same in the kernel's vocabulary (`stop reason: what`, e.g.
    /// `monitor: elbow_flexion`): the key of `refused`.
    pub refusal_reason: Option<String>,
    /// Time from the start of the estimation to Validated [s].
    pub estimate_duration: Option<f64>,
    /// True when the whole session (manipulation included) completed.
    pub completed: bool,
}

/// Quantiles of a sample: median, 95th percentile, maximum.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

impl Spread {
    fn of(mut values: Vec<f64>) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        values.sort_by(f64::total_cmp);
        let at = |q: f64| values[((values.len() - 1) as f64 * q).round() as usize];
        Self {
            median: at(0.5),
            p95: at(0.95),
            max: at(1.0),
        }
    }
}

/// The population's figures.
#[derive(Clone, Debug, Serialize)]
pub struct PopulationReport {
    /// Arms run.
    pub arms: usize,
    /// Seed of the draw.
    pub seed: u64,
    /// Arms whose joints stayed inside the limits during Estimate.
    pub within_limits: usize,
    /// Largest hyperextension during Estimate over all arms [rad].
    pub max_hyperextension: f64,
    /// Largest shoulder elevation during Estimate over all arms [rad].
    pub max_shoulder_elevation: f64,
    /// Arms the validator accepted.
    pub validated: usize,
    /// |l1 error| of the validated models [m].
    pub error_l1: Spread,
    /// |l2 error| of the validated models [m].
    pub error_l2: Spread,
    /// Validated models more than 1 mm off in l1 or l2.
    pub over_1mm: usize,
    /// Validated models whose l1 and l2 errors are each within k = 1, 2, 3
    /// of their reported standard uncertainties (a model without one is
    /// counted outside).
    pub within_uncertainty: [usize; 3],
    /// Arms stopped instead of validated, by reason.
    pub refused: BTreeMap<String, usize>,
    /// Estimation duration, start to Validated [s].
    pub estimate_duration: Spread,
    /// Whole sessions completed.
    pub completed: usize,
    /// Every arm.
    pub outcomes: Vec<ArmOutcome>,
}

/// Runs arm `index` of the draw.
fn run_arm(l1: f64, l2: f64, seed: u64, config: &KernelConfig) -> Result<ArmOutcome, CliError> {
    let mut params = limb_sim::PlantParameters::new(l1, l2);
    params.seed = seed;
    let mut plant = limb_sim::Plant::new(params).map_err(CliError::Internal)?;
    let mut kernel = Box::new(
        Kernel::new(*config).map_err(|e| CliError::Internal(format!("configuration: {e}")))?,
    );
    let report = run_session(&mut kernel, &mut plant, &SessionPlan::default(), None);
    let estimate_joints = report
        .joint_extremes
        .get("estimate")
        .copied()
        .unwrap_or_default();
    let limits = &config.limits;
    let within_limits = -estimate_joints.max_hyperextension >= limits.elbow_flexion.low
        && estimate_joints.max_shoulder_elevation <= limits.shoulder_elevation.high;
    let time_of = |what: &str| {
        report
            .events
            .iter()
            .find(|line| line.what.contains(what))
            .map(|line| line.time)
    };
    let estimate_duration = time_of("Estimate → Validated")
        .zip(time_of("Grasp → Estimate"))
        .map(|(end, start)| end - start);
    let refusal = crate::plant_population::refusal(&report);
    let refusal_reason = crate::plant_population::refusal_reason(&report);
    Ok(ArmOutcome {
        l1,
        l2,
        seed,
        estimate_joints,
        within_limits,
        error: report
            .model
            .as_ref()
            .and_then(|m| Some([m.error_l1?.abs(), m.error_l2?.abs()])),
        uncertainty: report
            .model
            .as_ref()
            .and_then(|m| Some([m.uncertainty_l1?, m.uncertainty_l2?])),
        refusal,
        refusal_reason,
        estimate_duration,
        completed: report.completed && report.final_state == StateKind::Validated,
    })
}

/// Runs the population on both cores.
pub fn population(arms: usize, seed: u64) -> Result<PopulationReport, CliError> {
    let config = KernelConfig::default();
    let mut draw = limb_sim::noise::Gaussian::new(seed);
    let specs: Vec<(f64, f64, u64)> = (0..arms)
        .map(|i| {
            let l1 = 0.22 + 0.16 * draw.uniform();
            let l2 = 0.15 + 0.11 * draw.uniform();
            (l1, l2, seed.wrapping_add(i as u64))
        })
        .collect();
    let halves: Vec<Result<Vec<ArmOutcome>, CliError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = specs
            .chunks(arms.div_ceil(2).max(1))
            .map(|chunk| {
                scope.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(l1, l2, seed)| run_arm(l1, l2, seed, &config))
                        .collect()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(CliError::Internal("a session thread panicked".into())))
            })
            .collect()
    });
    let mut outcomes = Vec::with_capacity(arms);
    for half in halves {
        outcomes.extend(half?);
    }
    let errors: Vec<[f64; 2]> = outcomes.iter().filter_map(|o| o.error).collect();
    let mut refused = BTreeMap::new();
    for reason in outcomes.iter().filter_map(|o| o.refusal_reason.as_ref()) {
        *refused.entry(reason.clone()).or_insert(0) += 1;
    }
    let max_of = |f: fn(&ArmOutcome) -> f64| outcomes.iter().map(f).fold(0.0, f64::max);
    Ok(PopulationReport {
        arms,
        seed,
        within_limits: outcomes.iter().filter(|o| o.within_limits).count(),
        max_hyperextension: max_of(|o| o.estimate_joints.max_hyperextension),
        max_shoulder_elevation: max_of(|o| o.estimate_joints.max_shoulder_elevation),
        validated: errors.len(),
        error_l1: Spread::of(errors.iter().map(|e| e[0]).collect()),
        error_l2: Spread::of(errors.iter().map(|e| e[1]).collect()),
        over_1mm: errors.iter().filter(|e| e[0] > 1e-3 || e[1] > 1e-3).count(),
        within_uncertainty: [1.0, 2.0, 3.0].map(|k| {
            outcomes
                .iter()
                .filter(|o| match (o.error, o.uncertainty) {
                    (Some(e), Some(u)) => e[0] <= k * u[0] && e[1] <= k * u[1],
                    _ => false,
                })
                .count()
        }),
        refused,
        estimate_duration: Spread::of(
            outcomes
                .iter()
                .filter_map(|o| o.estimate_duration)
                .collect(),
        ),
        completed: outcomes.iter().filter(|o| o.completed).count(),
        outcomes,
    })
}

/// `limb population`.
pub fn run(args: &PopulationArgs) -> Result<(), CliError> {
    if args.plants.given() {
        return crate::plant_population::run(&args.plants, args.seed, args.json);
    }
    if args.arms == 0 {
        return Err(CliError::BadInput("--arms must be at least 1".into()));
    }
    let report = population(args.arms, args.seed)?;
    if args.json {
        return print_json(&report);
    }
    let mm = |s: Spread| {
        format!(
            "median {:.3} mm, p95 {:.3} mm, max {:.3} mm",
            s.median * 1e3,
            s.p95 * 1e3,
            s.max * 1e3
        )
    };
    let mut text = format!(
        "limb population: {} random arms (l1 0.22-0.38 m, l2 0.15-0.26 m), seed {}, noise on\n\
         joints within limits during Estimate: {}/{} (max hyperextension {:.2}°, max shoulder elevation {:.1}°)\n\
         validated: {}/{}; |Δl1| {}; |Δl2| {}; over 1 mm: {}\n\
         both errors within 1, 2, 3 standard uncertainties: {}, {}, {} of {}\n\
         estimation duration: median {:.1} s, max {:.1} s; sessions completed: {}\n",
        report.arms,
        report.seed,
        report.within_limits,
        report.arms,
        report.max_hyperextension.to_degrees(),
        report.max_shoulder_elevation.to_degrees(),
        report.validated,
        report.arms,
        mm(report.error_l1),
        mm(report.error_l2),
        report.over_1mm,
        report.within_uncertainty[0],
        report.within_uncertainty[1],
        report.within_uncertainty[2],
        report.validated,
        report.estimate_duration.median,
        report.estimate_duration.max,
        report.completed,
    );
    for (reason, count) in &report.refused {
        text.push_str(&format!("refused {count}: {reason}\n"));
    }
    emit(&text)
}
