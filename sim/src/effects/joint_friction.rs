//! `joint_friction`: Coulomb plus viscous friction in the shoulder (q1) and
//! elbow (q2) joints of the arm.
//!
//! τ_i = −coulomb · tanh(q̇_i / [`SMOOTHING`]) − viscous · q̇_i [N m], added
//! to the generalised forces of both joints. The tanh replaces sign(q̇) so
//! the semi-implicit Euler step stays stable at rest (no chattering).

use super::Parameter;

/// Joint speed below which the Coulomb term fades in linearly [rad/s].
pub const SMOOTHING: f64 = 0.01;

/// Parameters: coulomb [N m], viscous [N m s/rad].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new("coulomb", "N m", 0.0, 5.0, "Coulomb friction torque"),
    Parameter::new(
        "viscous",
        "N m s/rad",
        0.0,
        5.0,
        "viscous friction coefficient",
    ),
];

/// Joint friction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointFriction {
    /// Coulomb friction torque [N m].
    pub coulomb: f64,
    /// Viscous coefficient [N m s/rad].
    pub viscous: f64,
}

impl JointFriction {
    /// Friction torques at the two joints for joint speeds q̇ [N m].
    pub fn torques(&self, qd: [f64; 2]) -> [f64; 2] {
        qd.map(|v| -self.coulomb * libm::tanh(v / SMOOTHING) - self.viscous * v)
    }
}
