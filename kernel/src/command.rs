//! What the kernel asks of the robot for one step.

use crate::geometry::Wrench;
use crate::impedance::Saturation;
use crate::motion::SetPoint;
use crate::state::StateKind;

/// How the robot should treat the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CommandMode {
    /// Follow the set-point (Estimate, Manipulate).
    Track,
    /// Zero motion: the set-point is a constant pose with zero velocity and
    /// acceleration (Grasp, Validated), or there is no set-point and the
    /// robot holds its own current position.
    Hold,
    /// Latched stop: zero motion and zero wrench until an operator reset.
    Stop,
}

/// The command of one step, frame S.
///
/// # Invariants
/// Every number is finite. In [`CommandMode::Hold`] and
/// [`CommandMode::Stop`] the set-point velocity and acceleration are zero.
/// `|(fx, fz)|` never exceeds the configured force limit nor `|ty|` the
/// torque limit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Command {
    /// State the kernel is in after this step.
    pub state: StateKind,
    /// How to treat the command.
    pub mode: CommandMode,
    /// Virtual equilibrium for a robot-side impedance controller; `None`
    /// means: hold your current position.
    pub set_point: Option<SetPoint>,
    /// Wrench at the grasp for a wrench-overlay robot [N, N, N m].
    pub wrench: Wrench,
    /// Saturations that acted on this command.
    pub saturation: Saturation,
}

impl Command {
    /// True when every number of the command is finite.
    pub fn is_finite(&self) -> bool {
        self.wrench.is_finite()
            && self.set_point.is_none_or(|s| {
                s.pose.is_finite() && s.velocity.is_finite() && s.acceleration.is_finite()
            })
    }
}
