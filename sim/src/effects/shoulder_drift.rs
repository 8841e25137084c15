//! `shoulder_drift`: the shoulder (trunk) is held by a spring of stiffness
//! `k` [N/m] instead of being fixed. Quasi-static: while the elbow is off
//! the table (q1 > 0) the shoulder sits displaced by F / k from its rest
//! position, F being the force the robot applies to the arm (x, z) in the
//! previous integration step; while the elbow rests on the table, the
//! table holds the arm and the shoulder stays put. The whole arm moves
//! with the shoulder.

use super::Parameter;

/// Parameters: k [N/m].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "k",
    "N/m",
    100.0,
    1.0e6,
    "shoulder support stiffness",
)];

/// Yielding shoulder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShoulderDrift {
    /// Stiffness [N/m].
    pub k: f64,
}

impl ShoulderDrift {
    /// Shoulder displacement [m] under robot force `force` (x, z) [N].
    pub fn displacement(&self, force: [f64; 2]) -> [f64; 2] {
        [force[0] / self.k, force[1] / self.k]
    }
}
