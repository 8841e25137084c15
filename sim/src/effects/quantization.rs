//! `quantization`: coarse resolution of the measured pose. The measured
//! (noisy) x and z are rounded to multiples of `pos` [m], psi to multiples
//! of `ang` [rad]; a zero step leaves that channel unrounded. The wrench is
//! not affected.

use super::Parameter;

/// Parameters: pos [m], ang [rad].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new("pos", "m", 0.0, 0.05, "position resolution"),
    Parameter::new("ang", "rad", 0.0, 0.2, "angle resolution"),
];

/// Pose quantisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantization {
    /// Position step [m].
    pub pos: f64,
    /// Angle step [rad].
    pub ang: f64,
}

/// `value` rounded to a multiple of `step` (unchanged for a zero step).
fn round_to(value: f64, step: f64) -> f64 {
    if step > 0.0 {
        libm::round(value / step) * step
    } else {
        value
    }
}

impl Quantization {
    /// The measured pose (x, z, psi) after rounding.
    pub fn apply(&self, pose: [f64; 3]) -> [f64; 3] {
        [
            round_to(pose[0], self.pos),
            round_to(pose[1], self.pos),
            round_to(pose[2], self.ang),
        ]
    }
}
