//! One whole closed-loop kernel session: the loop that `limb run` runs on
//! the host and the firmware runs on a Cortex-M7, so that both execute the
//! same code (`no_std`, no allocation).
//!
//! # Theory of operation
//! The kernel, not a script, drives the session: each control period the
//! plant's measurement goes into [`Kernel::step`] and the kernel's
//! set-point drives the plant's Cartesian impedance for the next period.
//! The [`Operator`] makes the person's requests (start the estimation once
//! the grasp is settled, approve the target in Validated, finish once the
//! move is held). The session ends when it completes (Manipulate →
//! Validated), when the kernel stops, or at the plan's timeout.
//!
//! An [`Observer`] sees each step from just before [`Kernel::step`] to
//! just after it, and every trace event: the host times the step and logs
//! the plant's state there, the firmware counts the step's instructions.
//! Nothing the observer does changes the session.
//!
//! # Determinism
//! [`Outcome::command_hash`] is FNV-1a (64 bit) over every command the
//! kernel issued, each number taken as its IEEE-754 bit pattern
//! ([`CommandHash`]): two sessions with the same hash issued the same
//! commands bit for bit (up to a 2⁻⁶⁴ collision). [`EventLine`] and
//! [`Digest`] print a session in one canonical text (times and lengths with
//! Rust's shortest round-trip `f64` form, i.e. exact), which the host
//! (`limb run --digest`) and the firmware both print for comparison.

use crate::operator::{completes_session, Described, FittedModel, Operator, SessionPlan};
use crate::plant::Measurement;
use core::fmt;
use limb_kernel::motion::SetPoint;
use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, Kernel, PathSample, Request, StateKind};

/// A plant the kernel can close the loop on.
pub trait ClosedLoopPlant {
    /// Plant time [s].
    fn time(&self) -> f64;
    /// What a robot measures now: time stamp, grasp pose, lateral y and
    /// wrench (frame S); the kernel gets all but y.
    fn measure(&mut self) -> Measurement;
    /// Advances the plant by `duration` seconds with the robot's impedance
    /// following `set_point` (held when the kernel gives none).
    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64);
}

impl ClosedLoopPlant for crate::Plant {
    fn time(&self) -> f64 {
        crate::Plant::time(self)
    }

    fn measure(&mut self) -> Measurement {
        crate::Plant::measure(self)
    }

    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64) {
        crate::closed_loop::advance(self, set_point, duration);
    }
}

/// What a session's runner watches. Every method has an empty default.
pub trait Observer<P: ?Sized> {
    /// Called immediately before `Kernel::step` on the frame of
    /// `measurement` (at its time), with the kernel's state then.
    fn before_step(&mut self, _plant: &P, _measurement: &Measurement, _state: StateKind) {}
    /// Called immediately after the step returned `command`, before the
    /// plant advances; `state` is the state the step began in (the
    /// concluding Estimate step has `state` Estimate and `command.state`
    /// Validated).
    fn after_step(
        &mut self,
        _plant: &P,
        _measurement: &Measurement,
        _state: StateKind,
        _command: &Command,
    ) {
    }
    /// Each transition or refusal the kernel recorded, in order.
    fn event(&mut self, _event: &TraceEvent) {}
}

/// An observer that watches nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unobserved;

impl<P: ?Sized> Observer<P> for Unobserved {}

/// FNV-1a (64 bit) over commands, field by field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandHash(u64);

impl Default for CommandHash {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl CommandHash {
    fn byte(&mut self, byte: u8) {
        self.0 = (self.0 ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
    }

    fn number(&mut self, value: f64) {
        for byte in value.to_bits().to_le_bytes() {
            self.byte(byte);
        }
    }

    /// Adds `command`: state, mode, whether a set-point is present, the
    /// set-point's pose, velocity and acceleration (x, z, psi), the wrench
    /// (fx, fz, ty) and the four saturation flags.
    pub fn push(&mut self, command: &Command) {
        self.byte(command.state as u8);
        self.byte(command.mode as u8);
        match &command.set_point {
            Some(s) => {
                self.byte(1);
                let (p, v, a) = (s.pose, s.velocity, s.acceleration);
                for value in [p.x, p.z, p.psi, v.x, v.z, v.psi, a.x, a.z, a.psi] {
                    self.number(value);
                }
            }
            None => self.byte(0),
        }
        let w = command.wrench;
        for value in [w.fx, w.fz, w.ty] {
            self.number(value);
        }
        let s = command.saturation;
        for flag in [s.force, s.torque, s.speed, s.non_finite] {
            self.byte(u8::from(flag));
        }
    }

    /// The hash so far.
    pub fn value(&self) -> u64 {
        self.0
    }
}

/// How a session ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The validated model as it was when the manipulation was approved.
    pub model: Option<FittedModel>,
    /// State at the end.
    pub final_state: StateKind,
    /// True when the session went Grasp → … → Manipulate → Validated.
    pub completed: bool,
    /// Commands whose wrench or set-point was limited.
    pub saturated_commands: u64,
    /// Kernel steps taken.
    pub steps: u64,
    /// [`CommandHash`] of every command issued, in order.
    pub command_hash: u64,
}

/// Runs one session of `kernel` on `plant` following `plan`, showing each
/// step and event to `observer`.
pub fn run<P, O>(
    kernel: &mut Kernel,
    plant: &mut P,
    plan: &SessionPlan,
    observer: &mut O,
) -> Outcome
where
    P: ClosedLoopPlant + ?Sized,
    O: Observer<P> + ?Sized,
{
    let period = 1.0 / plan.rate;
    let mut outcome = Outcome {
        model: None,
        final_state: kernel.state().kind(),
        completed: false,
        saturated_commands: 0,
        steps: 0,
        command_hash: 0,
    };
    let mut hash = CommandHash::default();
    let mut operator = Operator::new(*plan);
    while plant.time() < plan.timeout {
        let measurement = plant.measure();
        let frame = PathSample {
            time: measurement.time,
            pose: measurement.pose,
            wrench: measurement.wrench,
        };
        let now = frame.time;
        if let Some(request) = operator.request(kernel.state().kind(), now) {
            if matches!(request, Request::ApproveManipulation(_)) {
                outcome.model = kernel.state().arm().map(FittedModel::of);
            }
            // A refusal is recorded in the trace and shown as an event.
            let _ = kernel.request(request, now);
        }
        let state = kernel.state().kind();
        observer.before_step(plant, &measurement, state);
        let command = kernel.step(&frame, now);
        observer.after_step(plant, &measurement, state, &command);
        hash.push(&command);
        outcome.steps += 1;
        outcome.saturated_commands += u64::from(command.saturation.any());
        while let Some(event) = kernel.pop_event() {
            outcome.completed |= completes_session(&event);
            observer.event(&event);
        }
        operator.observe(command);
        if outcome.completed || command.state == StateKind::SafeStop {
            break;
        }
        plant.advance(command.set_point.as_ref(), period);
    }
    outcome.final_state = kernel.state().kind();
    outcome.command_hash = hash.value();
    outcome
}

/// One event in the canonical text: `event TIME WHAT`.
#[derive(Clone, Copy, Debug)]
pub struct EventLine<'a>(pub &'a TraceEvent);

impl fmt::Display for EventLine<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "event {:?} {}", self.0.time, Described(self.0))
    }
}

/// The outcome in the canonical text (after the [`EventLine`]s): the model
/// exactly, the step counts, the final state and the command hash, one
/// item a line.
#[derive(Clone, Copy, Debug)]
pub struct Digest<'a>(pub &'a Outcome);

impl fmt::Display for Digest<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let o = self.0;
        match &o.model {
            Some(m) => writeln!(
                f,
                "model l1 {:?} l2 {:?} shoulder {:?} {:?} elbow {:?} {:?}",
                m.upper_arm_length,
                m.forearm_length,
                m.shoulder.x,
                m.shoulder.z,
                m.elbow.x,
                m.elbow.z
            )?,
            None => writeln!(f, "model none")?,
        }
        writeln!(
            f,
            "steps {} saturated {} final {:?} completed {}",
            o.steps, o.saturated_commands, o.final_state, o.completed
        )?;
        write!(f, "command-hash {:016x}", o.command_hash)
    }
}

#[cfg(test)]
mod tests {
    use super::CommandHash;
    use limb_kernel::geometry::{Pose, Wrench};
    use limb_kernel::impedance::Saturation;
    use limb_kernel::motion::SetPoint;
    use limb_kernel::{Command, CommandMode, StateKind};

    fn command(x: f64) -> Command {
        Command {
            state: StateKind::Grasp,
            mode: CommandMode::Hold,
            set_point: Some(SetPoint::hold(Pose::new(x, 0.0, 0.0))),
            wrench: Wrench::ZERO,
            saturation: Saturation::default(),
        }
    }

    fn hash(commands: &[Command]) -> u64 {
        let mut h = CommandHash::default();
        commands.iter().for_each(|c| h.push(c));
        h.value()
    }

    /// REQ-DET-001: the command hash that compares host and target sessions
    /// changes with any bit of any command and with their order.
    #[test]
    fn the_hash_sees_every_bit_and_the_order() {
        let (a, b) = (command(0.1), command(0.2));
        assert_ne!(hash(&[a, b]), hash(&[b, a]));
        // One ulp apart.
        assert_ne!(
            hash(&[a]),
            hash(&[command(f64::from_bits(0.1f64.to_bits() + 1))])
        );
        assert_ne!(
            hash(&[a]),
            hash(&[Command {
                set_point: None,
                ..a
            }])
        );
        let mut saturated = a;
        saturated.saturation.speed = true;
        assert_ne!(hash(&[a]), hash(&[saturated]));
        assert_eq!(hash(&[a, b]), hash(&[a, b]));
    }
}
