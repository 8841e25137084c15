//! `quantization`: coarse resolution of the measured pose. The measured
//! (noisy) x and z are rounded to multiples of `pos` [m], psi to multiples
//! of `ang` [rad]; a zero step leaves that channel unrounded. The wrench is
//! not affected.

use super::Parameter;
#[cfg(feature = "std")]
use crate::sensing::{ANGLE_NOISE, POSITION_NOISE};

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

    /// E[round((v + n) / step) · step] for n ~ N(0, σ²), per pose channel
    /// (σ of `plant.md`): what [`Quantization::apply`] gives on average
    /// for a noise-free pose `pose` read with the plant's noise. For a
    /// step under 1.5 σ the expectation differs from v by less than 1e-4
    /// σ (the bias's Fourier series decays as exp(−2π²σ²/step²)), so such
    /// a step is not modelled. With the `std` feature only (see
    /// [`super::measurement`]).
    #[cfg(feature = "std")]
    pub fn expected(&self, pose: [f64; 3]) -> [f64; 3] {
        let one = |value: f64, step: f64, sigma: f64| -> f64 {
            if step <= 1.5 * sigma {
                return value;
            }
            let centre = (value / step).round();
            // Steps farther than 6σ from the value have no probability left:
            // at most 11 terms (step > 1.5 σ bounds the count).
            let reach = (6.0 * sigma / step).ceil() as i64 + 1;
            let cdf = |x: f64| 0.5 * (1.0 + libm::erf(x / (sigma * core::f64::consts::SQRT_2)));
            let mut mean = 0.0;
            for k in -reach..=reach {
                let level = centre + k as f64;
                let lo = (level - 0.5) * step - value;
                let hi = (level + 0.5) * step - value;
                mean += level * step * (cdf(hi) - cdf(lo));
            }
            mean
        };
        [
            one(pose[0], self.pos, POSITION_NOISE),
            one(pose[1], self.pos, POSITION_NOISE),
            one(pose[2], self.ang, ANGLE_NOISE),
        ]
    }
}
