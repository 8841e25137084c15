//! `latency`: the measured pose and wrench are `delay` [s] old while the
//! time stamp and the commands are current. The plant keeps a ring buffer
//! of the exact pose and wrench of each integration step; a measurement
//! takes the entry `delay / STEP` steps back (rounded to whole steps), or
//! the initial one before that much time has passed. Noise is drawn at the
//! time of measurement.

use super::Parameter;
use crate::sensing::STEP;

/// Parameters: delay [s].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "delay",
    "s",
    0.0,
    0.5,
    "age of the measured pose and wrench",
)];

/// Measurement delay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Latency {
    /// Delay [s].
    pub delay: f64,
}

impl Latency {
    /// The delay in whole integration steps.
    pub fn steps(&self) -> usize {
        libm::round(self.delay / STEP) as usize
    }
}
