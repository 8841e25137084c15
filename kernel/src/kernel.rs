//! The runtime wrapper: one pure `step(frame, now) -> Command` and explicit
//! operator requests, driving the typed states of [`crate::state`].
//!
//! # Theory of operation
//! Each [`Kernel::step`]:
//! 1. in SafeStop, returns the latched stop command and nothing else;
//! 2. runs the watchdog on the frame and the clock;
//! 3. updates the rate window (speed, force rate);
//! 4. runs the monitors that apply to the state ([`crate::monitor`]);
//! 5. computes the state's set-point (recording the path and, when the
//!    estimation motion ends, estimating and validating the arm);
//! 6. runs the impedance generator and checks the command is finite.
//!
//! Any violation or failure in 2-6 enters SafeStop in the same step and the
//! step returns the stop command. Requests ([`Kernel::request`]) change state
//! only along the diagram of [`crate::state`]; anything else is refused with
//! a reason. Transitions and refusals go to the [`crate::trace`].
//!
//! The kernel owns no clock and does no I/O: `now` is an input.
//!
//! # Timing
//! Steps are O(1) except the one that concludes the estimation motion,
//! which runs the estimator over the recorded path (bounded by
//! [`crate::path::PATH_CAPACITY`]; see the benchmarks for its figure).

use crate::arm::JointAngles;
use crate::command::{Command, CommandMode};
use crate::config::{ConfigError, KernelConfig, SafetyLimits};
use crate::geometry::{Pose, Wrench};
use crate::impedance::{ImpedanceLaw, Saturation};
use crate::monitor::force::ForceMonitor;
use crate::monitor::joint_limits::JointLimitMonitor;
use crate::monitor::rates::RateWindow;
use crate::monitor::speed::SpeedMonitor;
use crate::monitor::watchdog::Watchdog;
use crate::monitor::workspace::WorkspaceMonitor;
use crate::monitor::Verdict;
use crate::motion::SetPoint;
use crate::path::{GraspPath, PathSample, PATH_SAMPLE_PERIOD};
use crate::state::{Grasp, StateKind, StopReason, TargetError};
use crate::trace::{Cause, Event, Trace, TraceEvent};
use crate::validate::ValidatedArm;

/// The kernel's current state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum State {
    /// See [`crate::state::Grasp`].
    Grasp(Grasp),
    /// See [`crate::state::Estimate`].
    Estimate(crate::state::Estimate),
    /// See [`crate::state::Validated`].
    Validated(crate::state::Validated),
    /// See [`crate::state::Manipulate`].
    Manipulate(crate::state::Manipulate),
    /// See [`crate::state::SafeStop`].
    SafeStop(crate::state::SafeStop),
}

impl State {
    /// The state's name.
    pub fn kind(&self) -> StateKind {
        match self {
            State::Grasp(_) => StateKind::Grasp,
            State::Estimate(_) => StateKind::Estimate,
            State::Validated(_) => StateKind::Validated,
            State::Manipulate(_) => StateKind::Manipulate,
            State::SafeStop(_) => StateKind::SafeStop,
        }
    }

    /// The validated model, in the states that hold one.
    pub fn arm(&self) -> Option<&ValidatedArm> {
        match self {
            State::Validated(v) => Some(v.arm()),
            State::Manipulate(m) => Some(m.arm()),
            _ => None,
        }
    }
}

/// An operator's or supervisor's request.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Request {
    /// Grasp → Estimate: start the estimation motion from the current pose.
    StartEstimation,
    /// Validated → Manipulate: move the arm to these joint angles.
    ApproveManipulation(JointAngles),
    /// Manipulate → Validated: end the manipulation and hold.
    FinishManipulation,
    /// Any state → SafeStop.
    Stop,
    /// SafeStop → Grasp.
    Reset,
}

/// Why a request was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum RefusalReason {
    /// The current state has no transition for this request.
    NotAllowedInState,
    /// No fresh, finite measurement to start from.
    NoFreshMeasurement,
    /// `now` is not finite or went backwards.
    InvalidTime,
    /// The manipulation target was refused.
    Target(TargetError),
    /// The estimation motion could not be planned.
    Plan(crate::motion::PlanError),
}

impl RefusalReason {
    /// Stable numeric code of the reason.
    pub const fn code(&self) -> u16 {
        match self {
            RefusalReason::NotAllowedInState => 1,
            RefusalReason::NoFreshMeasurement => 2,
            RefusalReason::InvalidTime => 3,
            RefusalReason::Target(_) => 4,
            RefusalReason::Plan(_) => 5,
        }
    }
}

/// Why new safety limits were refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LimitUpdateRefusal {
    /// Limits change only while the arm is held still: in Grasp, Validated
    /// or SafeStop, never during the estimation motion or a manipulation.
    NotAllowedInState(StateKind),
    /// The configuration with the new limits fails [`KernelConfig::check`].
    Invalid(ConfigError),
}

/// A refused request: what was asked, in which state, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Refusal {
    /// The request.
    pub request: Request,
    /// The state it was refused in.
    pub state: StateKind,
    /// Why.
    pub reason: RefusalReason,
}

/// The kernel: configuration, state, recorded path and monitors.
///
/// # Invariants
/// The configuration passed [`KernelConfig::check`]. `path` holds samples
/// only from the current or last estimation motion.
#[derive(Clone, Debug)]
pub struct Kernel {
    config: KernelConfig,
    law: ImpedanceLaw,
    state: State,
    path: GraspPath,
    rates: RateWindow,
    last_frame: Option<PathSample>,
    last_now: Option<f64>,
    trace: Trace,
}

impl Kernel {
    /// A kernel in Grasp with configuration `config`.
    ///
    /// # Errors
    /// The configuration's first unusable value.
    pub fn new(config: KernelConfig) -> Result<Self, ConfigError> {
        config.check()?;
        let l = &config.limits;
        Ok(Self {
            law: ImpedanceLaw::new(&config.impedance, l.max_force, l.max_torque, l.max_speed),
            rates: RateWindow::new(l.rate_window),
            config,
            state: State::Grasp(Grasp::new()),
            path: GraspPath::new(),
            last_frame: None,
            last_now: None,
            trace: Trace::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &KernelConfig {
        &self.config
    }

    /// The current state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The grasp path recorded by the current or last estimation motion.
    pub fn path(&self) -> &[PathSample] {
        &self.path
    }

    /// Removes and returns the oldest trace event.
    pub fn pop_event(&mut self) -> Option<TraceEvent> {
        self.trace.pop()
    }

    /// Trace events lost because nobody drained the trace.
    pub fn dropped_events(&self) -> u32 {
        self.trace.dropped()
    }

    /// One control step: sensor `frame` (frame S) at kernel time `now` [s].
    /// Never panics; any fault becomes a safe stop in this same step.
    pub fn step(&mut self, frame: &PathSample, now: f64) -> Command {
        if let State::SafeStop(stop) = &self.state {
            return stop_command(stop.hold());
        }
        let watchdog = Watchdog::new(self.config.limits.max_sensor_age);
        let previous = self.last_frame.map(|f| f.time);
        if let Err(violation) = watchdog.check(frame, now, previous, self.last_now) {
            return self.stop(StopReason::Monitor(violation), now, None);
        }
        self.last_now = Some(now);
        if previous.is_none_or(|t| frame.time > t) {
            self.rates.push(*frame);
            self.last_frame = Some(*frame);
        }
        let rates = self.rates.rates();
        if let Err(violation) = self.check_monitors(frame, rates.speed(), rates.force_rate) {
            return self.stop(StopReason::Monitor(violation), now, Some(frame.pose));
        }
        let (set_point, mode) = match self.state_set_point(frame, now) {
            Ok(v) => v,
            Err(reason) => return self.stop(reason, now, Some(frame.pose)),
        };
        let out = self.law.command(frame.pose, rates.velocity, set_point);
        let command = Command {
            state: self.state.kind(),
            mode,
            set_point: Some(out.set_point),
            wrench: out.wrench,
            saturation: out.saturation,
        };
        if !command.is_finite() || out.saturation.non_finite {
            return self.stop(StopReason::NonFiniteCommand, now, Some(frame.pose));
        }
        command
    }

    /// Handles an operator or supervisor request at kernel time `now` [s].
    ///
    /// # Errors
    /// A [`Refusal`] naming the request, the state and the reason; the state
    /// is then unchanged.
    pub fn request(&mut self, request: Request, now: f64) -> Result<StateKind, Refusal> {
        let from = self.state.kind();
        let refuse = |reason| Refusal {
            request,
            state: from,
            reason,
        };
        let time_ok = now.is_finite() && self.last_now.is_none_or(|t| now >= t);
        let state = core::mem::replace(&mut self.state, State::Grasp(Grasp::new()));
        let result = match (request, state) {
            (Request::Stop, State::SafeStop(stop)) => Ok(State::SafeStop(stop)),
            (Request::Stop, other) => {
                let at = self.last_frame.map(|f| f.pose);
                Ok(State::SafeStop(stop_state(other, StopReason::Operator, at)))
            }
            (Request::Reset, State::SafeStop(stop)) => {
                self.rates.clear();
                self.last_frame = None;
                Ok(State::Grasp(stop.reset()))
            }
            (_, other) if !time_ok => Err((other, refuse(RefusalReason::InvalidTime))),
            (Request::StartEstimation, State::Grasp(grasp)) => match self.fresh_pose(now) {
                None => Err((
                    State::Grasp(grasp),
                    refuse(RefusalReason::NoFreshMeasurement),
                )),
                Some(pose) => {
                    match grasp.start_estimation(pose, now, &self.config.estimation_motion) {
                        Ok(estimate) => {
                            self.path.clear();
                            Ok(State::Estimate(estimate))
                        }
                        Err((grasp, error)) => {
                            Err((State::Grasp(grasp), refuse(RefusalReason::Plan(error))))
                        }
                    }
                }
            },
            (Request::ApproveManipulation(target), State::Validated(validated)) => {
                let (joints, workspace) = self.geometry_monitors();
                match validated.plan_manipulation(
                    target,
                    self.config.manipulation_peak_speed,
                    &joints,
                    &workspace,
                ) {
                    Ok(plan) => Ok(State::Manipulate(validated.begin_manipulation(plan, now))),
                    Err(error) => Err((
                        State::Validated(validated),
                        refuse(RefusalReason::Target(error)),
                    )),
                }
            }
            (Request::FinishManipulation, State::Manipulate(manipulate)) => {
                Ok(State::Validated(manipulate.finish(now)))
            }
            (_, other) => Err((other, refuse(RefusalReason::NotAllowedInState))),
        };
        let time = if now.is_finite() { now } else { f64::NAN };
        match result {
            Ok(state) => {
                self.state = state;
                let to = self.state.kind();
                if to != from {
                    self.record(time, from, to, Cause::Request(request));
                }
                Ok(to)
            }
            Err((state, refusal)) => {
                self.state = state;
                self.trace.record(TraceEvent {
                    time,
                    event: Event::Refused(refusal),
                });
                Err(refusal)
            }
        }
    }

    /// Replaces the safety limits (REQ-SM-007). Allowed only while the arm
    /// is held still (Grasp, Validated, SafeStop) and only for limits that
    /// pass [`KernelConfig::check`] with the rest of the configuration. The
    /// impedance saturation follows the new limits at once and the rate
    /// window starts afresh; a pose already outside tighter limits stops
    /// the kernel at the next step, as any violation does.
    ///
    /// # Errors
    /// Why the limits were refused; the configuration is then unchanged.
    pub fn update_limits(&mut self, limits: SafetyLimits) -> Result<(), LimitUpdateRefusal> {
        let state = self.state.kind();
        if matches!(state, StateKind::Estimate | StateKind::Manipulate) {
            return Err(LimitUpdateRefusal::NotAllowedInState(state));
        }
        let config = KernelConfig {
            limits,
            ..self.config
        };
        config.check().map_err(LimitUpdateRefusal::Invalid)?;
        self.config = config;
        self.law = ImpedanceLaw::new(
            &config.impedance,
            limits.max_force,
            limits.max_torque,
            limits.max_speed,
        );
        self.rates = RateWindow::new(limits.rate_window);
        Ok(())
    }

    /// The latest measured pose, if fresh and finite at `now`.
    fn fresh_pose(&self, now: f64) -> Option<Pose> {
        let frame = self.last_frame?;
        let age = now - frame.time;
        (frame.pose.is_finite() && (0.0..=self.config.limits.max_sensor_age).contains(&age))
            .then_some(frame.pose)
    }

    fn geometry_monitors(&self) -> (JointLimitMonitor, WorkspaceMonitor) {
        let l = &self.config.limits;
        (
            JointLimitMonitor {
                shoulder_elevation: l.shoulder_elevation,
                elbow_flexion: l.elbow_flexion,
                max_model_mismatch: l.max_model_mismatch,
            },
            WorkspaceMonitor {
                x: l.workspace_x,
                z: l.workspace_z,
                table_tolerance: l.table_tolerance,
            },
        )
    }

    /// The monitors that apply to the current state (watchdog excluded).
    fn check_monitors(&self, frame: &PathSample, speed: f64, force_rate: f64) -> Verdict {
        let l = &self.config.limits;
        ForceMonitor {
            max_force: l.max_force,
            max_torque: l.max_torque,
            max_force_rate: l.max_force_rate,
        }
        .check(frame.wrench, force_rate)?;
        if matches!(self.state, State::Estimate(_) | State::Manipulate(_)) {
            SpeedMonitor {
                max_speed: l.max_speed,
            }
            .check(speed)?;
        }
        let (joints, workspace) = self.geometry_monitors();
        let arm = self.state.arm().map(ValidatedArm::geometry);
        workspace.check(frame.pose, arm.map(|a| a.elbow_from_pose(frame.pose)))?;
        match arm {
            Some(arm) => joints.check(arm, frame.pose),
            None => Ok(()),
        }
    }

    /// The state's set-point for this step, with its mode. Concludes the
    /// estimation motion when it is over.
    fn state_set_point(
        &mut self,
        frame: &PathSample,
        now: f64,
    ) -> Result<(SetPoint, CommandMode), StopReason> {
        match &mut self.state {
            State::Grasp(grasp) => Ok((grasp.hold(frame.pose), CommandMode::Hold)),
            State::Validated(validated) => Ok((validated.hold(), CommandMode::Hold)),
            State::Manipulate(manipulate) => Ok((manipulate.set_point(now), CommandMode::Track)),
            State::SafeStop(_) => Err(StopReason::Operator),
            State::Estimate(estimate) => {
                let due = self
                    .path
                    .last()
                    .is_none_or(|last| frame.time - last.time >= PATH_SAMPLE_PERIOD * (1.0 - 1e-6));
                if due && self.path.push(*frame).is_err() {
                    return Err(StopReason::PathBufferFull);
                }
                if !estimate.is_finished(now) {
                    return Ok((estimate.set_point(now), CommandMode::Track));
                }
                let estimate = *estimate;
                let validated = estimate.conclude(
                    &self.path,
                    self.config.estimation_method,
                    &self.config.validation,
                )?;
                let hold = validated.hold();
                self.state = State::Validated(validated);
                self.record(
                    now,
                    StateKind::Estimate,
                    StateKind::Validated,
                    Cause::ModelValidated,
                );
                Ok((hold, CommandMode::Hold))
            }
        }
    }

    /// Enters SafeStop for `reason` and returns the stop command.
    fn stop(&mut self, reason: StopReason, now: f64, at: Option<Pose>) -> Command {
        let from = self.state.kind();
        let state = core::mem::replace(&mut self.state, State::Grasp(Grasp::new()));
        let stop = stop_state(state, reason, at);
        let hold = stop.hold();
        self.state = State::SafeStop(stop);
        self.record(
            if now.is_finite() { now } else { f64::NAN },
            from,
            StateKind::SafeStop,
            Cause::Stop(reason),
        );
        stop_command(hold)
    }

    fn record(&mut self, time: f64, from: StateKind, to: StateKind, cause: Cause) {
        self.trace.record(TraceEvent {
            time,
            event: Event::Transition { from, to, cause },
        });
    }
}

/// Moves any state into SafeStop.
fn stop_state(state: State, reason: StopReason, at: Option<Pose>) -> crate::state::SafeStop {
    match state {
        State::Grasp(s) => s.stop(reason, at),
        State::Estimate(s) => s.stop(reason, at),
        State::Validated(s) => s.stop(reason, at),
        State::Manipulate(s) => s.stop(reason, at),
        State::SafeStop(s) => s,
    }
}

/// The latched stop command: zero motion, zero wrench.
fn stop_command(hold: Option<SetPoint>) -> Command {
    Command {
        state: StateKind::SafeStop,
        mode: CommandMode::Stop,
        set_point: hold,
        wrench: Wrench::ZERO,
        saturation: Saturation::default(),
    }
}
