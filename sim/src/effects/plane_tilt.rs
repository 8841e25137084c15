//! `plane_tilt`: the arm moves in a plane tilted by `angle` [rad] about the
//! x axis. In that plane only g · cos(angle) acts; a point at in-plane
//! height h is seen by the robot at z = h cos(angle), y = h sin(angle), so
//! the lateral y shows the tilt (y / z = tan(angle)).

use super::Parameter;

/// Parameters: angle [rad].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "angle",
    "rad",
    -1.0,
    1.0,
    "tilt of the arm's plane about x",
)];

/// Tilted arm plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneTilt {
    /// Tilt [rad].
    pub angle: f64,
}
