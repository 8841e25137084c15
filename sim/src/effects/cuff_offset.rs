//! `cuff_offset`: the robot's cuff does not hold the forearm on its
//! joint line. A cuff strapped on the distal forearm sits on its surface,
//! `across` from the line elbow → wrist (perpendicular to it, in the
//! arm's plane; positive on the side away from the table when the arm
//! lies on it, the dorsal side), and short of the wrist by `along`: the
//! forearm and hand, the rod of `plant.md`, extend `along` beyond the
//! cuff.
//!
//! # Model
//! l2 stays the length the robot sees: from the elbow to the cuff's foot
//! on the forearm's line. With u = (−cos psi, sin psi) along the forearm
//! and n = (sin psi, cos psi) across it,
//!
//! ```text
//! G = E + l2 u + across (n − n₀)        n₀ = (0, 1)
//! ```
//!
//! (less n₀ so that frame S keeps its origin at the grasp at t = 0; the
//! shoulder then sits at (L, −across)); the Jacobian gains across ·
//! (cos psi, −sin psi) in both columns, J̇ q̇ gains −across · n · psi̇².
//! psi is the cuff's orientation, rigid with the forearm: unchanged. The
//! forearm's rod is l2 + along long (centre of mass (l2 + along)/2,
//! inertia m2 (l2 + along)²/12), so `along` changes how the forearm's
//! weight loads the robot.
//!
//! # Magnitudes
//! The distal radius is 1.5-3 cm thick: a cuff on it holds the forearm
//! 2-3 cm off its line (the line elbow → wrist runs close to the radius
//! and ulna's axis). A cuff is strapped 2-8 cm proximal of the wrist
//! joint, and the hand (0.6 % of body mass) makes the rod longer still.
//! Allowed: across ±0.08 m, along −0.05-0.15 m.

use super::Parameter;

/// Parameters: across [m], along [m].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new(
        "across",
        "m",
        -0.08,
        0.08,
        "grasp's distance from the forearm's line, dorsal positive",
    ),
    Parameter::new(
        "along",
        "m",
        -0.05,
        0.15,
        "how far the forearm's rod extends beyond the grasp",
    ),
];

/// Grasp off the forearm's line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CuffOffset {
    /// Perpendicular offset [m].
    pub across: f64,
    /// Rod beyond the grasp [m].
    pub along: f64,
}

impl CuffOffset {
    /// The grasp's displacement (x, z) [m] from the forearm's line at
    /// forearm elevation `psi` [rad], zero at psi = 0.
    pub fn displacement(&self, psi: f64) -> [f64; 2] {
        let (s, c) = (libm::sin(psi), libm::cos(psi));
        [self.across * s, self.across * (c - 1.0)]
    }
}
