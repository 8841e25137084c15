//! End-effector speed monitor (the paper's 2.5 % of maximum, with margin).

use super::{at_most, Limit, Verdict};

/// Grasp-point speed limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedMonitor {
    /// Largest speed [m/s].
    pub max_speed: f64,
}

impl SpeedMonitor {
    /// Verdict on the windowed grasp-point speed [m/s].
    pub fn check(&self, speed: f64) -> Verdict {
        at_most(Limit::Speed, speed, self.max_speed)
    }
}
