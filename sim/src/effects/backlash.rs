//! `backlash`: play between the true forearm angle psi and the measured one.
//!
//! The measured angle is a follower inside a dead band of total `width`
//! [rad]: it stays put while |psi_true − psi_follower| ≤ width / 2 and is
//! dragged along at distance width / 2 once the gap exceeds it. It starts
//! at the true angle. The follower is updated at each measurement (100 Hz
//! in a scripted run; psi moves far less than the width in 10 ms).

use super::Parameter;

/// Parameters: width [rad].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "width",
    "rad",
    0.0,
    0.2,
    "total play of the measured psi",
)];

/// Backlash on psi.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Backlash {
    /// Total play [rad].
    pub width: f64,
}

impl Backlash {
    /// The follower's next position for true angle `psi` [rad].
    pub fn follow(&self, follower: f64, psi: f64) -> f64 {
        let half = self.width / 2.0;
        if psi - follower > half {
            psi - half
        } else if follower - psi > half {
            psi + half
        } else {
            follower
        }
    }
}
