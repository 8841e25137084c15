//! `shoulder_rhythm`: the shoulder's centre of rotation is not fixed: it
//! translates as the upper arm elevates (scapulohumeral rhythm: the
//! scapula rotates and slides on the thorax, about 1° for every 2° of
//! humeral elevation, Inman, Saunders & Abbott 1944, "Observations on
//! the function of the shoulder joint", J. Bone Joint Surg. 26:1-30).
//! The glenohumeral centre moves with the elevation: de Groot & Brand
//! 2001 ("A three-dimensional regression model of the shoulder rhythm",
//! Clin. Biomech. 16:735-743) regress the shoulder girdle's position on
//! humeral elevation; Dvir & Berme 1978 ("The shoulder complex in
//! elevation of the arm: a mechanism approach", J. Biomech. 11:219-225)
//! report the centre rising and moving medially by several centimetres
//! over the range.
//!
//! # Model
//! The shoulder sits at (L + x·q1, z·q1) in the plant's frame (L = l1 +
//! l2, its place at rest), q1 the upper arm's elevation above the table:
//! linear in the elevation, coefficients `x` and `z` in m/rad. The whole
//! arm rides on it: the grasp is displaced by the same amount, the
//! Jacobian's shoulder column gains (x, z), and the arm's weight acts
//! through the centre's rise (a gravity torque (m1 + m2) g z on q1). The
//! inertia of the translation is neglected (at the lift's 5 cm/s its
//! kinetic energy is below 0.1 mJ).
//!
//! # Unlike `shoulder_drift`
//! `shoulder_drift` is a spring: the shoulder yields to the robot's force
//! and comes back when it is released. Here the displacement is set by
//! the posture alone, whatever the force: it does not yield, it follows
//! the elevation.
//!
//! # Magnitudes
//! 1-3 cm of centre displacement over the first radian of elevation
//! (0.01-0.03 m/rad), upwards (z > 0) and, in the plant's frame, either
//! way along x. Allowed: ±0.1 m/rad each.

use super::Parameter;

/// Parameters: x [m/rad], z [m/rad].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new(
        "x",
        "m/rad",
        -0.1,
        0.1,
        "shoulder centre's horizontal shift per radian of upper-arm elevation",
    ),
    Parameter::new(
        "z",
        "m/rad",
        -0.1,
        0.1,
        "shoulder centre's rise per radian of upper-arm elevation",
    ),
];

/// Shoulder centre moving with the elevation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShoulderRhythm {
    /// Horizontal shift [m/rad].
    pub x: f64,
    /// Rise [m/rad].
    pub z: f64,
}

impl ShoulderRhythm {
    /// The shoulder centre's displacement (x, z) [m] at elevation `q1`
    /// [rad].
    pub fn displacement(&self, q1: f64) -> [f64; 2] {
        [self.x * q1, self.z * q1]
    }
}
