//! `plane_tilt`: the arm and the robot's grasp move in a plane tilted by
//! `angle` [rad] about the x axis, while the robot reports its pose in S.
//! A point at in-plane height h is seen at z = h cos(angle) and lateral
//! y = h sin(angle), so y / z = tan(angle) shows the tilt. x, psi and the
//! wrench are as measured in the plane.
//!
//! # Choice
//! Scaling gravity by cos(angle) in the dynamics was tried and rejected:
//! the shared reference log (`shared/data/effects/plane_tilt.csv`) has x
//! and psi at the nominal values within noise (0.10 mm, 1.0 mrad RMS), which
//! a g · cos(angle) arm misses by 0.9 mm and 3.7 mrad. The effect is
//! therefore measurement-side only; see `sim/README.md`.

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
