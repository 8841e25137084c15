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
//! estimate` reports); the lengths range over [`LENGTH_RANGES`], widened
//! to [`LENGTH_REACH`] around the estimate where that reaches beyond.
//! On a person's build the arm has a third parameter, the shoulder's
//! height above the elbow at rest (`shoulder_height`: a person's arm
//! rests bent), started at the kernel's estimate of the shoulder and the
//! elbow. Lengths that are given are held fixed (and the arm flat).

use crate::model::{Candidate, Parameter, Scale};
use limb_kernel::estimation::{estimate_arm, Method};
use limb_kernel::path::{is_due, PathSample, PATH_CAPACITY};
use limb_sim::effects::{
    active_torque, backlash, cuff_offset, descriptor, grasp_compliance, grasp_slip, joint_friction,
    latency, mass_mismatch, passive_stiffness, plane_tilt, quantization, shoulder_drift,
    shoulder_rhythm, spasticity,
};
use limb_sim::log::Record;

/// The candidates with their search ranges: each parameter is the
/// effect's entry of `limb_sim::effects::CATALOGUE` searched over a range
/// inside the allowed one, logarithmic for quantities spanning decades,
/// starting just above zero where zero means "no effect".
/// `grasp_slip.at` spans the log (`duration` seconds).
pub fn candidates(duration: f64) -> Vec<Candidate> {
    use Scale::{Linear, Logarithmic};
    let one = |name, allowed: &[Parameter], searched: &[(f64, f64, Scale)]| Candidate {
        name,
        parameters: allowed
            .iter()
            .zip(searched)
            .map(|(p, &(min, max, scale))| p.searched(min, max, scale))
            .collect(),
    };
    let log = |min, max| (min, max, Logarithmic);
    vec![
        one(
            "joint_friction",
            &joint_friction::PARAMETERS,
            &[log(0.002, 5.0), log(0.002, 5.0)],
        ),
        one("backlash", &backlash::PARAMETERS, &[log(0.0005, 0.2)]),
        one(
            "quantization",
            &quantization::PARAMETERS,
            &[log(1e-5, 0.05), log(1e-4, 0.2)],
        ),
        one("latency", &latency::PARAMETERS, &[log(0.0005, 0.5)]),
        one(
            "grasp_compliance",
            &grasp_compliance::PARAMETERS,
            &[log(50.0, 1e6)],
        ),
        one(
            "mass_mismatch",
            &mass_mismatch::PARAMETERS,
            &[log(0.2, 5.0)],
        ),
        one(
            "plane_tilt",
            &plane_tilt::PARAMETERS,
            &[(-1.0, 1.0, Linear)],
        ),
        one(
            "shoulder_drift",
            &shoulder_drift::PARAMETERS,
            &[log(100.0, 1e6)],
        ),
        one(
            "active_torque",
            &active_torque::PARAMETERS,
            &[log(0.005, 5.0), log(0.05, 10.0)],
        ),
        one(
            "grasp_slip",
            &grasp_slip::PARAMETERS,
            &[
                (-0.05, 0.05, Linear),
                (0.0, duration.clamp(1.0, 60.0), Linear),
            ],
        ),
        // A person's arm's own effects (`spec/human-arm.md`).
        one(
            "passive_stiffness",
            &passive_stiffness::PARAMETERS,
            &[log(0.002, 10.0), log(0.002, 10.0)],
        ),
        one(
            "spasticity",
            &spasticity::PARAMETERS,
            &[log(0.002, 50.0), (0.0, 0.5, Linear)],
        ),
        one(
            "shoulder_rhythm",
            &shoulder_rhythm::PARAMETERS,
            &[(-0.1, 0.1, Linear), (-0.1, 0.1, Linear)],
        ),
        one(
            "cuff_offset",
            &cuff_offset::PARAMETERS,
            &[(-0.08, 0.08, Linear), (-0.05, 0.15, Linear)],
        ),
    ]
}

/// How far around the kernel's estimate the fitted lengths reach at
/// least [m] (the estimate is within 12 mm on every withheld-effect
/// shared log; plain circle fits can be 91 mm off on a compliant grasp).
pub const LENGTH_REACH: f64 = 0.1;
/// Range of each length [m], l1 then l2, whatever the kernel estimates:
/// the estimate is no bound on the arm. Under a very soft shoulder drift
/// or a late grasp slip it put l1 11-19 cm long (blind self-check seed
/// 271828, cases 9, 53, 150, 193), and a range of the estimate ± 10 cm
/// held the fitted l1 at its lower end, 13-90 mm from the arm.
pub const LENGTH_RANGES: [[f64; 2]; 2] = [[0.15, 0.5], [0.08, 0.35]];
/// Shortest length searched [m].
const SHORTEST: f64 = 0.05;
/// Name of the base candidate: the arm's own lengths.
pub const ARM: &str = "arm";

/// Range of a person's shoulder height above the elbow at rest [m] (the
/// arm's third parameter on a person's build; `shoulder_height`'s allowed
/// range, less its top).
pub const HEIGHT_RANGE: [f64; 2] = [0.0, 0.2];
/// Most of l1 the shoulder's height may be (the sine of the upper arm's
/// slope at rest, 30°): the plant refuses a height of l1 or more, and the
/// linearised fit must not step where the plant cannot follow. MyoArm's
/// subjects rest at 0.15 (q1 −0.15 rad).
pub const HEIGHT_SHARE: f64 = 0.5;

/// Where the arm's fit starts: the kernel's estimate of the lengths and,
/// on a person's build, of the shoulder's height above the elbow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Start {
    /// l1, l2 [m].
    pub lengths: (f64, f64),
    /// The estimated shoulder centre's height above the elbow's at the
    /// start of the motion [m] (frame S's z), inside [`HEIGHT_RANGE`].
    pub height: f64,
}

/// The arm's candidate (the engine's base): l1 and l2 over
/// [`LENGTH_RANGES`], each widened to reach [`LENGTH_REACH`] around
/// `start` (the kernel's estimate), never below [`SHORTEST`]; on a
/// person's build (`raised`) also the shoulder's height above the elbow
/// at rest over [`HEIGHT_RANGE`] (`shoulder_height`): a person's arm
/// rests bent, and that is the arm's geometry, as its lengths are.
pub fn arm_candidate(start: Option<(f64, f64)>, raised: bool) -> Candidate {
    let range = |i: usize, centre: Option<f64>| {
        let [low, high] = LENGTH_RANGES[i];
        match centre {
            Some(c) => [
                low.min((c - LENGTH_REACH).max(SHORTEST)),
                high.max(c + LENGTH_REACH),
            ],
            None => [low, high],
        }
    };
    let [a, b] = range(0, start.map(|s| s.0));
    let [c, d] = range(1, start.map(|s| s.1));
    let mut parameters = vec![
        Parameter::new("l1", "m", a, b, "upper-arm length"),
        Parameter::new("l2", "m", c, d, "forearm length"),
    ];
    if raised {
        parameters.push(Parameter::new(
            "height",
            "m",
            HEIGHT_RANGE[0],
            HEIGHT_RANGE[1],
            "shoulder centre's height above the elbow's at rest",
        ));
    }
    Candidate {
        name: ARM,
        parameters,
    }
}

/// The kernel's own estimate of the arm from the log's measured path
/// (what `limb estimate` reports with `auto`), when it has one: the
/// samples the kernel would record, at most its path capacity.
pub fn kernel_estimate(records: &[Record]) -> Option<Start> {
    let mut path: Vec<PathSample> = Vec::new();
    for sample in records.iter().map(Record::path_sample) {
        if path.len() < PATH_CAPACITY && is_due(path.last(), sample.time) {
            path.push(sample);
        }
    }
    let estimate = estimate_arm(&path, Method::Auto).ok()?;
    let (l1, l2) = (estimate.upper_arm_length, estimate.forearm_length);
    let height = estimate.shoulder.z - estimate.elbow.z;
    let height = if height.is_finite() {
        height.clamp(HEIGHT_RANGE[0], HEIGHT_RANGE[1])
    } else {
        0.0
    };
    (l1.is_finite() && l2.is_finite() && l1 > 0.0 && l2 > 0.0).then_some(Start {
        lengths: (l1, l2),
        height,
    })
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

#[cfg(test)]
mod tests {
    use super::{arm_candidate, candidates, candidates_match_catalogue};

    #[test]
    fn candidates_are_searched_inside_the_catalogue() {
        for duration in [0.0, 29.16, 90.0] {
            assert_eq!(candidates_match_catalogue(&candidates(duration)), Ok(()));
        }
        for start in [None, Some((0.3, 0.2)), Some((0.06, 0.05))] {
            for raised in [false, true] {
                let arm = arm_candidate(start, raised);
                assert!(arm.parameters.iter().all(|p| p.is_valid()), "{arm:?}");
                assert_eq!(arm.parameters.len(), 2 + usize::from(raised));
            }
        }
    }
}
