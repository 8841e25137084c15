//! `passive_stiffness`: the passive elastic torque of a person's shoulder
//! and elbow (ligaments, capsule, stretched muscle), nearly zero in
//! mid-range and rising steeply towards each end of the joint's range.
//!
//! # Model
//! The double-exponential form of Riener & Edrich (1999, "Identification
//! of passive elastic joint moments in the lower extremities", J.
//! Biomech. 32:539-544) and Amankwah, Triolo & Kirsch (2004, "Effects of
//! spinal cord injury on lower-limb passive joint moments revealed
//! through a nonlinear viscoelastic model", J. Rehabil. Res. Dev.
//! 41:15-32), per joint i with its range [lo_i, hi_i] in the plant's
//! coordinates:
//!
//! ```text
//! τ_i(q_i) = k_i · ( exp(−s (q_i − lo_i)) − exp(−s (hi_i − q_i)) )   [N m]
//! ```
//!
//! k_i is the elastic torque at the end of the range (the parameters
//! `shoulder` and `elbow`); s = [`STEEPNESS`] how steeply it rises there.
//! The torque pushes away from the nearer end: towards flexion near full
//! extension, towards extension near full flexion.
//!
//! # Ranges (the plant's coordinates)
//! * elbow q2: [`ELBOW_RANGE`] = 0 (full extension, the arm lying on the
//!   table) to 2.5 rad (about 145° of flexion, the normal active range).
//! * shoulder q1 (upper-arm elevation above the table): [`SHOULDER_RANGE`]
//!   = 0 (lying on the table) to 2.0 rad.
//!
//! # Magnitudes
//! A few tenths of a N m at mid-range to about 1-3 N m near the end of
//! range in a relaxed healthy arm, several times that in a contracted or
//! spastic one (an order of magnitude, not a fit to data). Riener &
//! Edrich's exponents are of the order of a few per radian; the
//! [`STEEPNESS`] of 3 per rad is of that order. Allowed: 0-10 N m per
//! joint.

use super::Parameter;

/// Parameters: shoulder [N m], elbow [N m].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new(
        "shoulder",
        "N m",
        0.0,
        10.0,
        "passive shoulder torque at the end of its range",
    ),
    Parameter::new(
        "elbow",
        "N m",
        0.0,
        10.0,
        "passive elbow torque at the end of its range",
    ),
];

/// How steeply the passive torque rises towards an end of range [1/rad].
pub const STEEPNESS: f64 = 3.0;
/// The shoulder's range in q1 [rad]: lying on the table to 2 rad.
pub const SHOULDER_RANGE: [f64; 2] = [0.0, 2.0];
/// The elbow's range in q2 [rad]: full extension to 145° of flexion.
pub const ELBOW_RANGE: [f64; 2] = [0.0, 2.5];

/// Passive joint stiffness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassiveStiffness {
    /// Shoulder's end-of-range torque [N m].
    pub shoulder: f64,
    /// Elbow's end-of-range torque [N m].
    pub elbow: f64,
}

/// The double exponential of one joint at angle `q` in `range`, for
/// end-of-range torque `k`.
fn elastic(k: f64, q: f64, range: [f64; 2]) -> f64 {
    k * (libm::exp(-STEEPNESS * (q - range[0])) - libm::exp(-STEEPNESS * (range[1] - q)))
}

impl PassiveStiffness {
    /// Passive torques at the shoulder and the elbow for joint angles q
    /// [N m].
    pub fn torques(&self, q: [f64; 2]) -> [f64; 2] {
        [
            elastic(self.shoulder, q[0], SHOULDER_RANGE),
            elastic(self.elbow, q[1], ELBOW_RANGE),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::PassiveStiffness;

    #[test]
    fn pushes_away_from_the_nearer_end_of_range() {
        let p = PassiveStiffness {
            shoulder: 1.0,
            elbow: 2.0,
        };
        let at_rest = p.torques([0.0, 0.0]);
        assert!((at_rest[1] - 2.0).abs() < 0.01 && at_rest[0] > 0.99);
        let flexed = p.torques([1.0, 2.5]);
        assert!((flexed[1] + 2.0).abs() < 0.01);
        let mid = p.torques([1.0, 1.25]);
        assert!(mid[1].abs() < 1e-12 && mid[0].abs() < 1e-12);
    }
}
