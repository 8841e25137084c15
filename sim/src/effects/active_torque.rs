//! `active_torque`: the person is not passive. A torque
//! τ = amp · sin(2π · freq · t) [N m] acts at the elbow (on q2).

use super::Parameter;

/// Parameters: amp [N m], freq [Hz].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new("amp", "N m", 0.0, 5.0, "torque amplitude"),
    Parameter::new("freq", "Hz", 0.0, 10.0, "torque frequency"),
];

/// Periodic elbow torque.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveTorque {
    /// Amplitude [N m].
    pub amp: f64,
    /// Frequency [Hz].
    pub freq: f64,
}

impl ActiveTorque {
    /// Elbow torque at time `t` [s] (N m).
    pub fn torque(&self, t: f64) -> f64 {
        self.amp * libm::sin(2.0 * core::f64::consts::PI * self.freq * t)
    }
}
