//! The one session loop: `limb run` runs it on the host, the firmware on a
//! Cortex-M7, `limb kuka run`, `limb arebo run` and `limb zenoh node` on
//! their robots (`no_std`, no allocation).
//!
//! # Theory of operation
//! The kernel, not a script, drives the session. Each turn of the loop:
//! 1. [`Robot::sense`] waits for the robot's next frame;
//! 2. kernel time comes from the frame's stamp and arrival
//!    ([`AlignedClock`]); the stamp reaches the kernel as the robot gave it;
//! 3. a gap between two robot stamps longer than the kernel's
//!    `max_sensor_age` is silence on the robot's clock: the kernel is first
//!    stepped without a frame at the new time, and it judges the silence;
//! 4. a robot that does not follow commands while the kernel moves the arm
//!    (Estimate, Manipulate) voids the motion: `Request::Stop`;
//! 5. the [`Supervisor`] makes its requests, then [`Kernel::step`];
//! 6. the kernel's events go to the observer and the supervisor, the
//!    command to [`Robot::actuate`];
//! 7. the session ends when the robot ends or the supervisor is finished.
//!
//! A [`Sensed::Silent`] robot steps the kernel without a frame at the
//! silent time (`Kernel::step(None, now)`): the kernel, not the loop,
//! judges its newest frame's age, and past `max_sensor_age` its watchdog
//! trips the safe stop. The loop replays nothing.
//!
//! An [`Observer`] sees each frame's step from just before
//! [`Kernel::step`] to just after it, every kernel step (frames and
//! silences, [`Step`]) and every trace event: the host times the step and
//! writes the session logs there, the firmware counts the step's
//! instructions. Nothing the observer does changes the session.

use crate::clock::AlignedClock;
use crate::command_hash::CommandHash;
use crate::operator::{completes_session, FittedModel};
use crate::robot::{Frame, Robot, Sensed};
use crate::supervisor::Supervisor;
use limb_kernel::trace::{Event, TraceEvent};
use limb_kernel::{Command, Kernel, PathSample, Request, StateKind};

/// What a session's runner watches. Every method has an empty default.
pub trait Observer<R: ?Sized> {
    /// Called immediately before `Kernel::step` on `frame`, with the
    /// kernel's state then.
    fn before_step(&mut self, _robot: &R, _frame: &Frame, _state: StateKind) {}
    /// Called immediately after the step returned `command`, before the
    /// robot carries it out; `state` is the state the step began in (the
    /// concluding Estimate step has `state` Estimate and `command.state`
    /// Validated).
    fn after_step(&mut self, _robot: &R, _frame: &Frame, _state: StateKind, _command: &Command) {}
    /// Each transition or refusal the kernel recorded, in order.
    fn event(&mut self, _event: &TraceEvent) {}
    /// Every kernel step, on a new frame or (`stale`) on none, the kernel
    /// judging its last frame again, after the step returned, before its
    /// events.
    fn stepped(&mut self, _step: &Step<'_>) {}
}

/// One kernel step as the observers see it.
#[derive(Clone, Copy, Debug)]
pub struct Step<'a> {
    /// Kernel time of the step [s].
    pub now: f64,
    /// The frame the kernel judged: the new one, or on a silent step the
    /// last one the robot gave.
    pub sample: &'a PathSample,
    /// True on a step without a new frame (`Kernel::step(None, now)`): the
    /// robot was silent, or its stamps jumped by more than the kernel's
    /// `max_sensor_age`.
    pub stale: bool,
    /// What the step returned.
    pub command: &'a Command,
}

/// An observer that watches nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unobserved;

impl<R: ?Sized> Observer<R> for Unobserved {}

/// Two observers, in order.
impl<R: ?Sized, A: Observer<R>, B: Observer<R>> Observer<R> for (A, B) {
    fn before_step(&mut self, robot: &R, frame: &Frame, state: StateKind) {
        self.0.before_step(robot, frame, state);
        self.1.before_step(robot, frame, state);
    }

    fn after_step(&mut self, robot: &R, frame: &Frame, state: StateKind, command: &Command) {
        self.0.after_step(robot, frame, state, command);
        self.1.after_step(robot, frame, state, command);
    }

    fn event(&mut self, event: &TraceEvent) {
        self.0.event(event);
        self.1.event(event);
    }

    fn stepped(&mut self, step: &Step<'_>) {
        self.0.stepped(step);
        self.1.stepped(step);
    }
}

/// An observer lent to the session.
impl<R: ?Sized, A: Observer<R> + ?Sized> Observer<R> for &mut A {
    fn before_step(&mut self, robot: &R, frame: &Frame, state: StateKind) {
        (**self).before_step(robot, frame, state);
    }

    fn after_step(&mut self, robot: &R, frame: &Frame, state: StateKind, command: &Command) {
        (**self).after_step(robot, frame, state, command);
    }

    fn event(&mut self, event: &TraceEvent) {
        (**self).event(event);
    }

    fn stepped(&mut self, step: &Step<'_>) {
        (**self).stepped(step);
    }
}

/// An observer that may be absent.
impl<R: ?Sized, A: Observer<R>> Observer<R> for Option<A> {
    fn before_step(&mut self, robot: &R, frame: &Frame, state: StateKind) {
        if let Some(a) = self {
            a.before_step(robot, frame, state);
        }
    }

    fn after_step(&mut self, robot: &R, frame: &Frame, state: StateKind, command: &Command) {
        if let Some(a) = self {
            a.after_step(robot, frame, state, command);
        }
    }

    fn event(&mut self, event: &TraceEvent) {
        if let Some(a) = self {
            a.event(event);
        }
    }

    fn stepped(&mut self, step: &Step<'_>) {
        if let Some(a) = self {
            a.stepped(step);
        }
    }
}

/// How a session ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The model the kernel validated last (taken at each transition into
    /// Validated).
    pub model: Option<FittedModel>,
    /// State at the end.
    pub final_state: StateKind,
    /// True when the session went Grasp → … → Manipulate → Validated.
    pub completed: bool,
    /// Commands whose wrench or set-point was limited.
    pub saturated_commands: u64,
    /// Kernel steps taken (frames and silences).
    pub steps: u64,
    /// Steps without a new frame: the robot was silent, or its stamps
    /// jumped by more than the kernel's sensor-age limit.
    pub stale_steps: u64,
    /// Stops requested because the robot stopped following mid-motion.
    pub unfollowed_stops: u64,
    /// [`CommandHash`] of every command issued, in order.
    pub command_hash: u64,
}

/// The loop's memory across turns.
struct Loop {
    outcome: Outcome,
    hash: CommandHash,
    clock: AlignedClock,
    last: Option<PathSample>,
}

impl Loop {
    /// One kernel step on `sample` at `now`, counted, hashed and shown to
    /// `observer` (`stale`: a step without a frame, the robot silent;
    /// `sample` is then the last frame, which the kernel judges again).
    /// `lateral` is the frame's lateral position [m] (0 when the robot
    /// does not measure it).
    fn step<R, O>(
        &mut self,
        kernel: &mut Kernel,
        observer: &mut O,
        (sample, lateral): (&PathSample, f64),
        now: f64,
        stale: bool,
    ) -> Command
    where
        R: ?Sized,
        O: Observer<R> + ?Sized,
    {
        let command = kernel.step_with_lateral((!stale).then_some(sample), lateral, now);
        self.hash.push(&command);
        self.outcome.steps += 1;
        self.outcome.stale_steps += u64::from(stale);
        self.outcome.saturated_commands += u64::from(command.saturation.any());
        observer.stepped(&Step {
            now,
            sample,
            stale,
            command: &command,
        });
        command
    }

    /// The step's trace events to `observer` and `supervisor`, then its
    /// command to `supervisor`.
    #[allow(clippy::too_many_arguments)]
    fn tell<R, S, O>(
        &mut self,
        kernel: &mut Kernel,
        supervisor: &mut S,
        observer: &mut O,
        sample: &PathSample,
        command: &Command,
        now: f64,
    ) where
        R: ?Sized,
        S: Supervisor + ?Sized,
        O: Observer<R> + ?Sized,
    {
        while let Some(event) = kernel.pop_event() {
            self.outcome.completed |= completes_session(&event);
            if let Event::Transition {
                to: StateKind::Validated,
                ..
            } = event.event
            {
                if let Some(arm) = kernel.state().arm() {
                    self.outcome.model = Some(FittedModel::of(arm));
                }
            }
            observer.event(&event);
            supervisor.event(kernel, &event);
        }
        supervisor.after_step(kernel, sample, command, now);
    }

    /// A step without a frame at `now` (silence, or a gap in the robot's
    /// stamps), if there was a frame before.
    fn stale_step<R, S, O>(
        &mut self,
        kernel: &mut Kernel,
        supervisor: &mut S,
        observer: &mut O,
        now: f64,
    ) where
        R: ?Sized,
        S: Supervisor + ?Sized,
        O: Observer<R> + ?Sized,
    {
        if let Some(last) = self.last {
            let command = self.step::<R, O>(kernel, observer, (&last, 0.0), now, true);
            self.tell::<R, S, O>(kernel, supervisor, observer, &last, &command, now);
        }
    }
}

/// Runs one session of `kernel` on `robot` under `supervisor`, showing each
/// frame's step and every event to `observer`.
///
/// # Errors
/// The robot's I/O failure (the outcome so far is lost with it).
pub fn run<R, S, O>(
    kernel: &mut Kernel,
    robot: &mut R,
    supervisor: &mut S,
    observer: &mut O,
) -> Result<Outcome, R::Error>
where
    R: Robot + ?Sized,
    S: Supervisor + ?Sized,
    O: Observer<R> + ?Sized,
{
    let mut session = Loop {
        outcome: Outcome {
            model: None,
            final_state: kernel.state().kind(),
            completed: false,
            saturated_commands: 0,
            steps: 0,
            stale_steps: 0,
            unfollowed_stops: 0,
            command_hash: 0,
        },
        hash: CommandHash::default(),
        clock: AlignedClock::default(),
        last: None,
    };
    let max_age = kernel.config().limits.max_sensor_age;
    loop {
        let frame = match robot.sense()? {
            Sensed::Ended => break,
            Sensed::Silent(at) => {
                let now = session.clock.at(at);
                session.stale_step::<R, S, O>(kernel, supervisor, observer, now);
                if supervisor.finished(kernel.state().kind(), session.outcome.completed) {
                    break;
                }
                continue;
            }
            Sensed::Frame(frame) => frame,
        };
        let now = session.clock.frame(frame.sample.time, frame.arrival);
        if session
            .last
            .is_some_and(|last| frame.sample.time - last.time > max_age)
        {
            session.stale_step::<R, S, O>(kernel, supervisor, observer, now);
        }
        session.last = Some(frame.sample);
        let moving = matches!(
            kernel.state().kind(),
            StateKind::Estimate | StateKind::Manipulate
        );
        if !frame.following && moving {
            session.outcome.unfollowed_stops += 1;
            // A refusal is recorded in the trace and shown as an event.
            let _ = kernel.request(Request::Stop, now);
        }
        supervisor.before_step(kernel, now, frame.following);
        let state = kernel.state().kind();
        observer.before_step(robot, &frame, state);
        let lateral = frame.lateral.unwrap_or(0.0);
        let command = session.step::<R, O>(kernel, observer, (&frame.sample, lateral), now, false);
        observer.after_step(robot, &frame, state, &command);
        session.tell::<R, S, O>(kernel, supervisor, observer, &frame.sample, &command, now);
        robot.actuate(&command)?;
        if supervisor.finished(kernel.state().kind(), session.outcome.completed) {
            break;
        }
    }
    session.outcome.final_state = kernel.state().kind();
    session.outcome.command_hash = session.hash.value();
    Ok(session.outcome)
}
