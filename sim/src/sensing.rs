//! What the plant's robot measures and how finely (`plant.md`): the
//! integration step, the measurement noise of each channel and the
//! measurement itself, frame S. A leaf: the plant and the effects that
//! act on its measurements ([`crate::effects`]) both read it.

use limb_kernel::geometry::{Pose, Wrench};

/// Integration step [s] (0.5 ms).
pub const STEP: f64 = 0.0005;
/// Measurement noise σ of `plant.md`: position x, z, y [m] (iiwa
/// repeatability).
pub const POSITION_NOISE: f64 = 1e-4;
/// Measurement noise σ of psi [rad].
pub const ANGLE_NOISE: f64 = 1e-3;
/// Measurement noise σ of the forces fx, fz [N].
pub const FORCE_NOISE: f64 = 0.5;
/// Measurement noise σ of the torque ty [N m].
pub const TORQUE_NOISE: f64 = 0.025;
/// Resolution of the ground-truth potentiometers [rad] (10 bit).
pub const POTENTIOMETER_RESOLUTION: f64 = 0.0047;

/// What the robot measures, frame S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Time [s].
    pub time: f64,
    /// Grasp pose [m, m, rad].
    pub pose: Pose,
    /// Lateral position y [m] (zero plus noise in the plane of S).
    pub lateral: f64,
    /// External wrench estimate f_ext [N, N, N m].
    pub wrench: Wrench,
}
