//! The arm's candidate unmodelled effects with their search ranges, the
//! arm lengths' own candidate, and the helpers its start points use.
//!
//! # The arm is fitted, not given
//! The arm lengths l1, l2 are the model's own fitted parameters (the
//! engine's [`crate::model::Model::base`], as mass and offset are for a
//! drive): fitted first, on the nominal sim, and refitted with every
//! effect, so the arm the diagnosis reports is the arm corrected for the
//! effects it found. The search starts at the kernel's own estimate on
//! the same log ([`kernel_estimate`]: `Method::Auto`, what `limb
//! estimate` reports) and spans [`LENGTH_REACH`] around it. Lengths that
//! are given are held fixed.

use crate::model::{Candidate, Parameter, Scale};
use limb_kernel::estimation::{estimate_arm, Method};
use limb_kernel::path::{is_due, PathSample, PATH_CAPACITY};
use limb_sim::effects::descriptor;
use limb_sim::log::Record;

fn parameter(
    name: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    scale: Scale,
) -> Parameter {
    Parameter {
        name,
        unit,
        min,
        max,
        scale,
    }
}

/// The candidates with their search ranges: inside the effect's range of
/// `limb_sim::effects::CATALOGUE`, logarithmic for quantities spanning
/// decades, starting just above zero where zero means "no effect".
/// `grasp_slip.at` spans the log (`duration` seconds).
pub fn candidates(duration: f64) -> Vec<Candidate> {
    use Scale::{Linear, Logarithmic};
    let one = |name, parameters| Candidate { name, parameters };
    vec![
        one(
            "joint_friction",
            vec![
                parameter("coulomb", "N m", 0.002, 5.0, Logarithmic),
                parameter("viscous", "N m s/rad", 0.002, 5.0, Logarithmic),
            ],
        ),
        one(
            "backlash",
            vec![parameter("width", "rad", 0.0005, 0.2, Logarithmic)],
        ),
        one(
            "quantization",
            vec![
                parameter("pos", "m", 1e-5, 0.05, Logarithmic),
                parameter("ang", "rad", 1e-4, 0.2, Logarithmic),
            ],
        ),
        one(
            "latency",
            vec![parameter("delay", "s", 0.0005, 0.5, Logarithmic)],
        ),
        one(
            "grasp_compliance",
            vec![parameter("k", "N/m", 50.0, 1e6, Logarithmic)],
        ),
        one(
            "mass_mismatch",
            vec![parameter("factor", "1", 0.2, 5.0, Logarithmic)],
        ),
        one(
            "plane_tilt",
            vec![parameter("angle", "rad", -1.0, 1.0, Linear)],
        ),
        one(
            "shoulder_drift",
            vec![parameter("k", "N/m", 100.0, 1e6, Logarithmic)],
        ),
        one(
            "active_torque",
            vec![
                parameter("amp", "N m", 0.005, 5.0, Logarithmic),
                parameter("freq", "Hz", 0.05, 10.0, Logarithmic),
            ],
        ),
        one(
            "grasp_slip",
            vec![
                parameter("shift", "m", -0.05, 0.05, Linear),
                parameter("at", "s", 0.0, duration.clamp(1.0, 60.0), Linear),
            ],
        ),
    ]
}

/// How far around the kernel's estimate the fitted lengths are searched
/// [m] (the estimate is within 12 mm on every withheld-effect log; plain
/// circle fits can be 91 mm off on a compliant grasp).
pub const LENGTH_REACH: f64 = 0.1;
/// Range searched for each length when the kernel cannot estimate the
/// arm from the log [m]: l1, then l2.
const LENGTH_RANGES: [[f64; 2]; 2] = [[0.15, 0.5], [0.08, 0.35]];
/// Shortest length searched [m].
const SHORTEST: f64 = 0.05;
/// Name of the base candidate: the arm's own lengths.
pub const ARM: &str = "arm";

/// The arm lengths' candidate (the engine's base): l1 and l2 searched
/// around `start` (the kernel's estimate), or over [`LENGTH_RANGES`].
pub fn arm_candidate(start: Option<(f64, f64)>) -> Candidate {
    let range = |i: usize, centre: Option<f64>| match centre {
        Some(c) => [(c - LENGTH_REACH).max(SHORTEST), c + LENGTH_REACH],
        None => LENGTH_RANGES[i],
    };
    let [a, b] = range(0, start.map(|s| s.0));
    let [c, d] = range(1, start.map(|s| s.1));
    Candidate {
        name: ARM,
        parameters: vec![
            parameter("l1", "m", a, b, Scale::Linear),
            parameter("l2", "m", c, d, Scale::Linear),
        ],
    }
}

/// The kernel's own estimate of the arm from the log's measured path
/// (what `limb estimate` reports with `auto`), when it has one: the
/// samples the kernel would record, at most its path capacity.
pub fn kernel_estimate(records: &[Record]) -> Option<(f64, f64)> {
    let mut path: Vec<PathSample> = Vec::new();
    for sample in records.iter().map(Record::path_sample) {
        if path.len() < PATH_CAPACITY && is_due(path.last(), sample.time) {
            path.push(sample);
        }
    }
    let estimate = estimate_arm(&path, Method::Auto).ok()?;
    let (l1, l2) = (estimate.upper_arm_length, estimate.forearm_length);
    (l1.is_finite() && l2.is_finite() && l1 > 0.0 && l2 > 0.0).then_some((l1, l2))
}

/// The spacing of the lattice `values` sit on: the median gap between
/// neighbouring distinct values (tiny for unrounded data).
pub(super) fn resolution(values: &[f64]) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let mut gaps: Vec<f64> = sorted.windows(2).map(|w| w[1] - w[0]).collect();
    if gaps.is_empty() {
        return 0.0;
    }
    gaps.sort_by(f64::total_cmp);
    gaps[gaps.len() / 2]
}

/// Every candidate names an effect of the sim's catalogue, with the same
/// parameter names and units, searched inside the catalogue's range.
pub fn candidates_match_catalogue(candidates: &[Candidate]) -> Result<(), String> {
    for c in candidates.iter().filter(|c| c.name != ARM) {
        let d = descriptor(c.name).ok_or_else(|| format!("{} is not a sim effect", c.name))?;
        if d.parameters.len() != c.parameters.len() {
            return Err(format!("{}: parameter count differs", c.name));
        }
        for (p, q) in c.parameters.iter().zip(d.parameters) {
            if p.name != q.name
                || p.unit != q.unit
                || p.min < q.min
                || p.max > q.max
                || !p.is_valid()
            {
                return Err(format!(
                    "{}.{}: name, unit or range differs from the sim's",
                    c.name, p.name
                ));
            }
        }
    }
    Ok(())
}
