//! Interaction force monitor: magnitude, torque and rate of change.

use super::{at_most, Limit, Verdict};
use crate::geometry::Wrench;

/// Force, torque and force-rate limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceMonitor {
    /// Largest |(fx, fz)| [N].
    pub max_force: f64,
    /// Largest |ty| [N m].
    pub max_torque: f64,
    /// Largest force rate [N/s].
    pub max_force_rate: f64,
}

impl ForceMonitor {
    /// Verdict on the measured wrench and force rate [N/s].
    pub fn check(&self, wrench: Wrench, force_rate: f64) -> Verdict {
        at_most(
            Limit::ForceMagnitude,
            wrench.force_magnitude(),
            self.max_force,
        )?;
        at_most(Limit::Torque, libm::fabs(wrench.ty), self.max_torque)?;
        at_most(Limit::ForceRate, force_rate, self.max_force_rate)
    }
}
