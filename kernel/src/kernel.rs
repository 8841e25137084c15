//! The runtime wrapper: one pure `step(frame, now) -> Command` and explicit
//! operator requests, driving the typed states of [`crate::state`].
//!
//! # Theory of operation
//! Each [`Kernel::step`]:
//! 1. in SafeStop, returns the latched stop command and nothing else;
//! 2. runs the watchdog on the frame and the clock;
//! 3. updates the rate window (speed, force rate);
//! 4. runs the monitors that apply to the state ([`crate::monitor`]);
//! 5. computes the state's set-point (in Estimate: recording the path into
//!    the online estimate, shaping the lift, refining the estimate while
//!    held); on the step the refinement finishes, the validator turns the
//!    estimate into a Validated state or refuses it;
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
//! Every step is O(1): a recording step adds one sample to the online
//! estimate ([`crate::estimation::online`]); while concluding, a step runs
//! at most [`crate::estimation::refine::SAMPLES_PER_STEP`] samples of the
//! refinement; the step that finishes it runs the validator once. Figures:
//! `cargo bench -p limb-kernel --bench estimators` and the `step_time` of
//! `limb run --json`.

use crate::command::{Command, CommandMode};
use crate::config::{ConfigError, KernelConfig, SafetyLimits};
use crate::estimation::ArmEstimate;
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
use crate::path::{GraspPath, PathSample};
use crate::state::{
    EstimateStep, Grasp, LimitUpdateRefusal, Refusal, RefusalReason, Request, State, StateKind,
    StopReason,
};
use crate::trace::{Cause, Event, Trace, TraceEvent};
use crate::validate::ValidatedArm;

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
            Ok(Plan::Follow(set_point, mode)) => (set_point, mode),
            Ok(Plan::Validate(estimate)) => match self.conclude_estimation(&estimate, now) {
                Ok(hold) => (hold, CommandMode::Hold),
                Err(reason) => return self.stop(reason, now, Some(frame.pose)),
            },
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
        match (&self.state, arm) {
            (_, Some(arm)) => joints.check(arm, frame.pose),
            (State::Estimate(estimate), None) => {
                joints.check_envelope(estimate.joint_envelope(frame.pose, &self.config.validation))
            }
            _ => Ok(()),
        }
    }

    /// The state's set-point for this step, with its mode, or, on the step
    /// the estimation's refinement finishes, the estimate to validate.
    fn state_set_point(&mut self, frame: &PathSample, now: f64) -> Result<Plan, StopReason> {
        Ok(match &mut self.state {
            State::Grasp(grasp) => Plan::Follow(grasp.hold(frame.pose), CommandMode::Hold),
            State::Validated(validated) => Plan::Follow(validated.hold(), CommandMode::Hold),
            State::Manipulate(manipulate) => {
                Plan::Follow(manipulate.set_point(now), CommandMode::Track)
            }
            State::SafeStop(_) => return Err(StopReason::Operator),
            State::Estimate(estimate) => {
                let lifting = estimate.lift().ended().is_none();
                let step = estimate.advance(&mut self.path, frame, now, &self.config)?;
                if let Some(reason) = estimate.lift().ended().filter(|_| lifting) {
                    self.trace.record(TraceEvent {
                        time: now,
                        event: Event::LiftEnded(reason),
                    });
                }
                match step {
                    EstimateStep::Move(set_point) => Plan::Follow(set_point, CommandMode::Track),
                    EstimateStep::Hold(set_point) => Plan::Follow(set_point, CommandMode::Hold),
                    EstimateStep::Concluded(estimate) => Plan::Validate(estimate),
                }
            }
        })
    }

    /// Estimate → Validated through the validator (the only way to a
    /// validated model); returns the hold set-point.
    fn conclude_estimation(
        &mut self,
        estimate: &ArmEstimate,
        now: f64,
    ) -> Result<SetPoint, StopReason> {
        let State::Estimate(estimating) = self.state else {
            return Err(StopReason::Operator);
        };
        let start = self
            .path
            .first()
            .map_or(estimating.grasp_pose().point(), |s| s.pose.point());
        let validated = estimating.conclude(estimate, start, &self.config.validation)?;
        let hold = validated.hold();
        self.state = State::Validated(validated);
        self.record(
            now,
            StateKind::Estimate,
            StateKind::Validated,
            Cause::ModelValidated,
        );
        Ok(hold)
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

/// What the state asks of this step.
enum Plan {
    /// Command this set-point in this mode.
    Follow(SetPoint, CommandMode),
    /// The estimation concluded: validate this estimate.
    Validate(ArmEstimate),
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
