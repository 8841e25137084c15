//! What the kernel asks of the robot for one step.

use crate::config::SafetyLimits;
use crate::geometry::Wrench;
use crate::impedance::Saturation;
use crate::motion::SetPoint;
use crate::state::StateKind;
use crate::stop::StopCategory;

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
    /// Latched stop until an operator reset: the set-point comes to rest
    /// as the stop's category says ([`Command::stop`], [`crate::stop`]).
    Stop,
}

/// The command of one step, frame S.
///
/// # Invariants
/// Every number is finite. In [`CommandMode::Hold`] the set-point
/// velocity and acceleration are zero. [`CommandMode::Stop`] comes with
/// its category in `stop` (and only it); a motors-off stop has no
/// set-point and zero wrench. `|(fx, fz)|` never exceeds the configured
/// force limit nor `|ty|` the torque limit.
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
    /// In SafeStop, what the stop does to the arm; `None` otherwise.
    pub stop: Option<StopCategory>,
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

/// Relative slack for comparisons against saturation limits (rounding of
/// the scaling by limit / magnitude).
const ROUNDING: f64 = 1e-12;

impl Command {
    /// The invariants above as an executable check against `limits`
    /// (REQ-CMD-001, REQ-CMD-003): [`Command::check_components`] and the
    /// force magnitude within `max_force`. The proptest properties
    /// (`limb-verification`) assert this function.
    ///
    /// # Errors
    /// The first invariant that does not hold, in words.
    pub fn check(&self, limits: &SafetyLimits) -> Result<(), &'static str> {
        self.check_components(limits)?;
        if self.wrench.force_magnitude() <= limits.max_force * (1.0 + ROUNDING) {
            Ok(())
        } else {
            Err("commanded force exceeds the force limit")
        }
    }

    /// The invariants that need no square root, which the Kani harnesses of
    /// [`crate::kernel`] prove (the proofs replace `hypot` by a stub, so
    /// the force magnitude is the proptest's to check): every number
    /// finite; each force component and the torque within their limits;
    /// zero set-point velocity and acceleration when holding; the stop
    /// mode exactly in SafeStop, exactly with a stop category; a motors-off
    /// stop with neither set-point nor wrench.
    ///
    /// # Errors
    /// The first invariant that does not hold, in words.
    pub fn check_components(&self, limits: &SafetyLimits) -> Result<(), &'static str> {
        let ensure = |condition: bool, failure| if condition { Ok(()) } else { Err(failure) };
        ensure(self.is_finite(), "command is not finite")?;
        let w = self.wrench;
        let force_bound = limits.max_force * (1.0 + ROUNDING);
        ensure(
            libm::fabs(w.fx) <= force_bound && libm::fabs(w.fz) <= force_bound,
            "a commanded force component exceeds the force limit",
        )?;
        ensure(
            libm::fabs(w.ty) <= limits.max_torque * (1.0 + ROUNDING),
            "commanded torque exceeds the torque limit",
        )?;
        let still = |s: &SetPoint| {
            s.velocity.x == 0.0
                && s.velocity.z == 0.0
                && s.velocity.psi == 0.0
                && s.acceleration.x == 0.0
                && s.acceleration.z == 0.0
                && s.acceleration.psi == 0.0
        };
        if self.mode == CommandMode::Hold {
            ensure(
                self.set_point.as_ref().is_none_or(still),
                "a hold command moves the set-point",
            )?;
        }
        ensure(
            (self.mode == CommandMode::Stop) == (self.state == StateKind::SafeStop),
            "stop mode and SafeStop disagree",
        )?;
        ensure(
            (self.mode == CommandMode::Stop) == self.stop.is_some(),
            "stop mode and stop category disagree",
        )?;
        if self.stop == Some(StopCategory::MotorsOff) {
            ensure(
                w.fx == 0.0 && w.fz == 0.0 && w.ty == 0.0 && self.set_point.is_none(),
                "a motors-off stop commands a set-point or a wrench",
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Pose, PoseRate};

    fn hold() -> Command {
        Command {
            state: StateKind::Grasp,
            mode: CommandMode::Hold,
            set_point: Some(SetPoint::hold(Pose::default())),
            wrench: Wrench::new(1.0, 2.0, 0.5),
            saturation: Saturation::default(),
            stop: None,
        }
    }

    /// Each invariant, broken alone, is reported; a valid command passes.
    #[test]
    fn each_broken_invariant_is_named() {
        let limits = SafetyLimits::default();
        assert_eq!(hold().check(&limits), Ok(()));
        let mut moving = hold();
        if let Some(s) = moving.set_point.as_mut() {
            s.velocity = PoseRate::new(0.0, 0.0, 0.1);
        }
        let stop = Command {
            state: StateKind::SafeStop,
            mode: CommandMode::Stop,
            stop: Some(StopCategory::MotorsOff),
            set_point: None,
            wrench: Wrench::ZERO,
            ..hold()
        };
        assert_eq!(stop.check(&limits), Ok(()));
        let held_stop = Command {
            stop: Some(StopCategory::Hold),
            ..moving
        };
        let held_stop = Command {
            state: StateKind::SafeStop,
            mode: CommandMode::Stop,
            ..held_stop
        };
        assert_eq!(
            held_stop.check(&limits),
            Ok(()),
            "a stop's set-point may move"
        );
        let cases = [
            (
                Command {
                    wrench: Wrench::new(f64::NAN, 0.0, 0.0),
                    ..hold()
                },
                "command is not finite",
            ),
            (
                Command {
                    set_point: Some(SetPoint {
                        velocity: PoseRate::new(0.0, f64::NAN, 0.0),
                        ..SetPoint::hold(Pose::default())
                    }),
                    ..hold()
                },
                "command is not finite",
            ),
            (
                Command {
                    set_point: Some(SetPoint {
                        acceleration: PoseRate::new(0.0, 0.0, f64::INFINITY),
                        ..SetPoint::hold(Pose::default())
                    }),
                    ..hold()
                },
                "command is not finite",
            ),
            (
                Command {
                    wrench: Wrench::new(0.0, 46.0, 0.0),
                    ..hold()
                },
                "a commanded force component exceeds the force limit",
            ),
            (
                Command {
                    wrench: Wrench::new(40.0, 40.0, 0.0),
                    ..hold()
                },
                "commanded force exceeds the force limit",
            ),
            // 45.25 N: each component within 45 N, the magnitude 0.25 N over.
            (
                Command {
                    wrench: Wrench::new(32.0, 32.0, 0.0),
                    ..hold()
                },
                "commanded force exceeds the force limit",
            ),
            (
                Command {
                    wrench: Wrench::new(0.0, 0.0, -8.5),
                    ..hold()
                },
                "commanded torque exceeds the torque limit",
            ),
            (moving, "a hold command moves the set-point"),
            (
                Command {
                    mode: CommandMode::Stop,
                    ..hold()
                },
                "stop mode and SafeStop disagree",
            ),
            (
                Command { stop: None, ..stop },
                "stop mode and stop category disagree",
            ),
            (
                Command {
                    stop: Some(StopCategory::Hold),
                    ..hold()
                },
                "stop mode and stop category disagree",
            ),
            (
                Command {
                    wrench: Wrench::new(0.0, 0.0, 0.5),
                    ..stop
                },
                "a motors-off stop commands a set-point or a wrench",
            ),
            (
                Command {
                    set_point: Some(SetPoint::hold(Pose::default())),
                    ..stop
                },
                "a motors-off stop commands a set-point or a wrench",
            ),
        ];
        for (command, failure) in cases {
            assert_eq!(command.check(&limits), Err(failure), "{command:?}");
        }
    }
}
