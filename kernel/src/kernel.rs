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
        Ok(Self::fresh(config))
    }

    /// [`Kernel::new`] built in place in `slot` (a `static` on a target, a
    /// heap allocation on a host), for callers that must not hold a
    /// `size_of::<Kernel>()` value (about 230 kB, the path buffer) on their
    /// stack. The path buffer is left uninitialised (it is empty), so the
    /// kernel is written field by field into `slot` and never moved.
    ///
    /// # Errors
    /// The configuration's first unusable value; `slot` is then untouched.
    pub fn new_in(
        slot: &mut core::mem::MaybeUninit<Self>,
        config: KernelConfig,
    ) -> Result<&mut Self, ConfigError> {
        config.check()?;
        Ok(slot.write(Self::fresh(config)))
    }

    /// A kernel in Grasp with the checked `config`. Always inlined, so that
    /// [`Kernel::new_in`] writes it straight into its slot.
    #[inline(always)]
    fn fresh(config: KernelConfig) -> Self {
        let l = &config.limits;
        Self {
            law: ImpedanceLaw::new(&config.impedance, l.max_force, l.max_torque, l.max_speed),
            rates: RateWindow::new(l.rate_window),
            config,
            state: State::Grasp(Grasp::new()),
            path: GraspPath::new(),
            last_frame: None,
            last_now: None,
            trace: Trace::default(),
        }
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
        if let Err(violation) = self.check_set_point(&out.set_point) {
            return self.stop(StopReason::Monitor(violation), now, Some(frame.pose));
        }
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
                    // The motion starts where the arm is held (the hold
                    // set-point), not at the latest measurement: the
                    // set-point must not step by the measurement's noise
                    // (a joint-position robot turns a 0.2 mm step in one
                    // period into a force spike). The fresh measurement
                    // gates the request.
                    let start = grasp.held().unwrap_or(pose);
                    match grasp.start_estimation(start, now, &self.config.estimation_motion) {
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
            JointLimitMonitor::from_limits(l),
            WorkspaceMonitor {
                x: l.workspace_x,
                z: l.workspace_z,
                table_tolerance: l.table_tolerance,
            },
        )
    }

    /// REQ-MON-012: in a state that moves the arm (Estimate, Manipulate)
    /// the set-point about to be commanded is checked against the same
    /// workspace box and table as the measured pose (and, with a model,
    /// the elbow it implies): a set-point outside is a violation before it
    /// reaches the robot.
    fn check_set_point(&self, set_point: &SetPoint) -> Verdict {
        if !matches!(self.state, State::Estimate(_) | State::Manipulate(_)) {
            return Ok(());
        }
        let (_, workspace) = self.geometry_monitors();
        let pose = set_point.pose;
        let arm = self.state.arm().map(ValidatedArm::geometry);
        workspace.check(pose, arm.map(|a| a.elbow_from_pose(pose)))
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

#[cfg(any(test, kani))]
impl Kernel {
    /// A kernel with the default configuration in `state`, as if a session
    /// had reached it: proofs start there without running one.
    pub(crate) fn in_state(state: State) -> Self {
        let mut kernel =
            Self::new(KernelConfig::default()).expect("the default configuration is valid");
        kernel.state = state;
        kernel
    }
}

/// Proofs of the runtime wrapper: one step from each state, requests,
/// the latch and limit updates.
///
/// Unwind bounds: a kernel is built by [`Kernel::new`], whose configuration
/// check runs over at most 8 values per group (9), and the fixed validated
/// arm by the validator, which checks 16 values (17); one step pushes one
/// frame into an empty rate window (its trimming loop runs at most once)
/// and loops over 3 axes in the impedance law. The Estimate harness starts
/// from a fresh lift, where a step records at most one sample; the
/// refinement's bounded slices over a long path are REQ-TIME-002's tests.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::kani_inputs::{
        any_frame, any_frame_or_at, any_request, validated_arm, HOLD, MANIPULATION_TARGET,
    };
    use crate::state::Validated;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// Where the arm rests at the start of a session (frame S origin).
    const REST: Pose = Pose::new(0.0, 0.0, 0.0);

    /// REQ-MON-006, REQ-MON-007, REQ-MON-012, REQ-CMD-001: what one step
    /// must give for `frame` at `now` from a state of kind `before`, decided
    /// without a square root: the command's invariants
    /// ([`Command::check_components`]), the stop command from SafeStop, a
    /// stop in the same step for any fault visible without a model (bad
    /// clock or frame, stale or future frame, a force component, the torque
    /// or the grasp point beyond its limit), and, in a state that moves the
    /// arm, a set-point inside the workspace box and above the table.
    pub fn check_step(
        before: StateKind,
        frame: &PathSample,
        now: f64,
        command: &Command,
        limits: &SafetyLimits,
    ) -> Result<(), &'static str> {
        command.check_components(limits)?;
        let (p, w) = (frame.pose, frame.wrench);
        let age = now - frame.time;
        let floor = -limits.table_tolerance;
        let fault = !(now.is_finite()
            && frame.time.is_finite()
            && p.is_finite()
            && w.is_finite()
            && (0.0..=limits.max_sensor_age).contains(&age)
            && libm::fabs(w.fx) <= limits.max_force
            && libm::fabs(w.fz) <= limits.max_force
            && libm::fabs(w.ty) <= limits.max_torque
            && p.z >= floor
            && limits.workspace_x.contains(p.x)
            && limits.workspace_z.contains(p.z));
        if (fault || before == StateKind::SafeStop) && command.state != StateKind::SafeStop {
            return Err("a fault or SafeStop did not give the stop command");
        }
        let moving = matches!(command.state, StateKind::Estimate | StateKind::Manipulate);
        if let (true, Some(s)) = (moving, command.set_point) {
            let q = s.pose;
            if !(q.z >= floor
                && limits.workspace_x.contains(q.x)
                && limits.workspace_z.contains(q.z))
            {
                return Err("a set-point outside the workspace was commanded");
            }
        }
        Ok(())
    }

    /// One step with any frame (or a plausible one at `at`) at any clock
    /// (or at `t`), checked by [`check_step`].
    fn one_step(mut kernel: Kernel, at: Pose, t: f64) -> Command {
        let before = kernel.state().kind();
        let now = if kani::any() { t } else { kani::any() };
        let frame = any_frame_or_at(at, now);
        let command = kernel.step(&frame, now);
        assert_eq!(command.state, kernel.state().kind());
        assert_eq!(
            check_step(before, &frame, now, &command, &kernel.config().limits),
            Ok(())
        );
        command
    }

    fn validated_kernel() -> Kernel {
        Kernel::in_state(State::Validated(Validated::holding(validated_arm(), HOLD)))
    }

    /// Grasp, Estimate (from the rest pose at t = 0), Validated (the fixed
    /// arm at [`HOLD`]) or Manipulate (towards the fixed target), with
    /// where the arm is; Manipulate only where the target is accepted.
    fn kernel_in(kind: StateKind) -> (Kernel, Pose) {
        match kind {
            StateKind::Grasp => (Kernel::in_state(State::Grasp(Grasp::new())), REST),
            StateKind::Estimate => {
                let estimate = Grasp::new().start_estimation(
                    REST,
                    0.0,
                    &KernelConfig::default().estimation_motion,
                );
                kani::assume(estimate.is_ok());
                let estimate = estimate.expect("assumed");
                (Kernel::in_state(State::Estimate(estimate)), REST)
            }
            StateKind::Validated => (validated_kernel(), HOLD),
            StateKind::Manipulate => {
                let mut kernel = validated_kernel();
                let approved =
                    kernel.request(Request::ApproveManipulation(MANIPULATION_TARGET), 0.0);
                kani::assume(approved == Ok(StateKind::Manipulate));
                (kernel, HOLD)
            }
            StateKind::SafeStop => {
                let mut kernel = validated_kernel();
                assert_eq!(kernel.request(Request::Stop, 0.0), Ok(StateKind::SafeStop));
                (kernel, HOLD)
            }
        }
    }

    /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step from
    /// Grasp with any frame and clock never panics, commands within the
    /// limits and stops on any fault in the same step.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(9))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    pub fn verify_req_panic_001_step_from_grasp() {
        let (kernel, at) = kernel_in(StateKind::Grasp);
        let command = one_step(kernel, at, 0.0);
        kani::cover!(command.state == StateKind::Grasp, "grasp step: holds");
        kani::cover!(command.state == StateKind::SafeStop, "grasp step: stops");
    }

    /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007, REQ-MON-012:
    /// one step during the estimation (the first of a fresh lift: one sample
    /// recorded into the online estimate, the lift shaped; the online
    /// estimator's catch-up loop runs only after 50 judged samples) with
    /// any frame and clock never panics, commands within the limits and
    /// stops on any fault in the same step.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(9))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_panic_001_step_during_estimation() {
        let (kernel, at) = kernel_in(StateKind::Estimate);
        let command = one_step(kernel, at, 0.5);
        kani::cover!(
            command.state == StateKind::Estimate,
            "estimate step: tracks"
        );
        kani::cover!(command.state == StateKind::SafeStop, "estimate step: stops");
    }

    /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step in
    /// Validated with any frame and clock never panics, commands within the
    /// limits and stops on any fault in the same step.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(17))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_panic_001_step_in_validated() {
        let (kernel, at) = kernel_in(StateKind::Validated);
        let command = one_step(kernel, at, 0.0);
        kani::cover!(
            command.state == StateKind::Validated,
            "validated step: holds"
        );
        kani::cover!(
            command.state == StateKind::SafeStop,
            "validated step: stops"
        );
    }

    /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007, REQ-MON-012:
    /// one step while manipulating with any frame and clock never panics, commands within
    /// the limits and stops on any fault in the same step.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(17))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_panic_001_step_while_manipulating() {
        let (kernel, at) = kernel_in(StateKind::Manipulate);
        let command = one_step(kernel, at, 0.001);
        kani::cover!(
            command.state == StateKind::Manipulate,
            "manipulate step: tracks"
        );
        kani::cover!(
            command.state == StateKind::SafeStop,
            "manipulate step: stops"
        );
    }

    /// REQ-SM-006, REQ-CMD-003: once stopped, steps with any frames and
    /// clocks and any requests but Reset give the same zero-wrench,
    /// zero-motion stop command.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(17))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    pub fn verify_req_sm_006_safe_stop_is_latched() {
        let (mut kernel, _) = kernel_in(StateKind::SafeStop);
        let limits = kernel.config().limits;
        let first = kernel.step(&any_frame(), kani::any());
        assert_eq!(first.check_components(&limits), Ok(()));
        assert_eq!(first.mode, CommandMode::Stop);
        // Two rounds: a request, then a step (no loop: nothing to unwind).
        let request = any_request();
        kani::assume(request != Request::Reset);
        let _ = kernel.request(request, kani::any());
        assert_eq!(kernel.step(&any_frame(), kani::any()), first);
        let request = any_request();
        kani::assume(request != Request::Reset);
        let answer = kernel.request(request, kani::any());
        assert_eq!(kernel.step(&any_frame(), kani::any()), first);
        assert_eq!(kernel.state().kind(), StateKind::SafeStop);
        kani::cover!(answer.is_err(), "latch: a request refused");
        kani::cover!(
            first.set_point == Some(SetPoint::hold(HOLD)),
            "latch: holds the pose"
        );
    }

    fn any_state_kind() -> StateKind {
        StateKind::ALL[usize::from(kani::any::<u8>() % 5)]
    }

    /// REQ-SM-005, REQ-SM-002: from any state, any request at any clock
    /// reaches Validated or Manipulate only from a state that already holds
    /// the same validated model (Manipulate only from Validated by an
    /// approved target), and a refusal names the request and the state and
    /// changes nothing.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(17))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_sm_005_no_manipulation_without_a_validated_model() {
        let (mut kernel, _) = kernel_in(any_state_kind());
        let before = *kernel.state();
        let request = any_request();
        let result = kernel.request(request, if kani::any() { 0.01 } else { kani::any() });
        let after = kernel.state();
        match after.kind() {
            StateKind::Validated | StateKind::Manipulate => {
                assert!(after.arm().is_some());
                assert_eq!(
                    after.arm(),
                    before.arm(),
                    "a model appeared without validation"
                );
            }
            _ => {}
        }
        if after.kind() == StateKind::Manipulate && before.kind() != StateKind::Manipulate {
            assert_eq!(before.kind(), StateKind::Validated);
            assert!(matches!(request, Request::ApproveManipulation(_)));
        }
        if let Err(refusal) = result {
            assert_eq!(*after, before, "a refused request changed the state");
            // The request by its kind (a refused target may hold NaN).
            assert_eq!(
                core::mem::discriminant(&refusal.request),
                core::mem::discriminant(&request)
            );
            assert_eq!(refusal.state, before.kind());
        }
        kani::cover!(
            before.kind() == StateKind::Validated && after.kind() == StateKind::Manipulate,
            "gating: Manipulate approved"
        );
        kani::cover!(result.is_err(), "gating: refused");
    }

    /// REQ-SM-004: a request at a non-finite or backwards clock is refused
    /// for an invalid time, except a stop and the reset of a stop.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(17))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_sm_004_requests_need_a_sane_clock() {
        let (mut kernel, _) = kernel_in(any_state_kind());
        let kind = kernel.state().kind();
        let last = 1.0;
        kernel.last_now = Some(last);
        let now: f64 = kani::any();
        let request = any_request();
        let result = kernel.request(request, now);
        let exempt =
            request == Request::Stop || (request == Request::Reset && kind == StateKind::SafeStop);
        let sane = now.is_finite() && now >= last;
        if !(sane || exempt) {
            assert_eq!(
                result.map_err(|r| r.reason),
                Err(RefusalReason::InvalidTime)
            );
            kani::cover!(true, "clock: refused");
        }
        kani::cover!(
            exempt && !now.is_finite() && result.is_ok(),
            "clock: stop honoured"
        );
    }

    /// REQ-SM-007: new limits are taken only in Grasp, Validated or
    /// SafeStop and only when the whole configuration passes its check;
    /// otherwise the configuration is unchanged.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(17))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_sm_007_limits_change_only_while_held() {
        let (mut kernel, _) = kernel_in(any_state_kind());
        let before = *kernel.config();
        let mut limits = before.limits;
        // Any force limit, speed limit and elbow range (the others follow
        // the same check); or the defaults, which are valid.
        if kani::any() {
            limits.max_force = kani::any();
            limits.max_speed = kani::any();
            limits.elbow_flexion = crate::config::Interval::new(kani::any(), kani::any());
        }
        let kind = kernel.state().kind();
        let result = kernel.update_limits(limits);
        let held = matches!(
            kind,
            StateKind::Grasp | StateKind::Validated | StateKind::SafeStop
        );
        let valid = KernelConfig { limits, ..before }.check().is_ok();
        assert_eq!(result.is_ok(), held && valid);
        if result.is_ok() {
            assert_eq!(kernel.config().limits, limits);
        } else {
            assert_eq!(*kernel.config(), before);
        }
        kani::cover!(result.is_ok(), "limits: taken");
        kani::cover!(
            result == Err(LimitUpdateRefusal::NotAllowedInState(StateKind::Manipulate)),
            "limits: refused while moving"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "step from grasp",
                5_000,
                verify_req_panic_001_step_from_grasp,
            );
            kani::check(
                "step during estimation",
                5_000,
                verify_req_panic_001_step_during_estimation,
            );
            kani::check(
                "step in validated",
                5_000,
                verify_req_panic_001_step_in_validated,
            );
            kani::check(
                "step while manipulating",
                5_000,
                verify_req_panic_001_step_while_manipulating,
            );
            kani::check("latch", 2_000, verify_req_sm_006_safe_stop_is_latched);
            kani::check(
                "gating",
                5_000,
                verify_req_sm_005_no_manipulation_without_a_validated_model,
            );
            kani::check("clock", 5_000, verify_req_sm_004_requests_need_a_sane_clock);
            kani::check(
                "limits",
                5_000,
                verify_req_sm_007_limits_change_only_while_held,
            );
        }

        /// A manipulation approved at a later time starts there: its first
        /// set-point is the hold pose, its last the target's.
        #[test]
        fn manipulation_timing_starts_at_the_approval() {
            let (mut kernel, _) = kernel_in(StateKind::Validated);
            let approved_at = 5.0;
            let request = Request::ApproveManipulation(MANIPULATION_TARGET);
            assert_eq!(
                kernel.request(request, approved_at),
                Ok(StateKind::Manipulate)
            );
            let State::Manipulate(manipulate) = *kernel.state() else {
                panic!("not manipulating")
            };
            assert_eq!(manipulate.set_point(approved_at).pose, HOLD);
            let goal = manipulate.arm().geometry().forward(MANIPULATION_TARGET);
            assert_eq!(manipulate.set_point(approved_at + 1e3).pose, goal);
            assert_ne!(manipulate.set_point(approved_at + 0.5).pose, HOLD);
        }

        proptest! {
            /// REQ-MON-007, REQ-CMD-001: with the real libm a step from each
            /// state meets the proofs' check and the command its full check
            /// (the force magnitude included).
            #[test]
            fn req_mon_007_one_step_from_each_state_meets_the_check(
                kind in 0..4usize, dx in -0.1..0.1f64, dz in -0.1..0.1f64, dpsi in -0.2..0.2f64,
                fx in -60.0..60.0f64, fz in -60.0..60.0f64, ty in -10.0..10.0f64,
                age in -0.01..0.03f64, now in 0.0..2.0f64,
            ) {
                let (mut kernel, at) = kernel_in(StateKind::ALL[kind]);
                let before = kernel.state().kind();
                let frame = PathSample {
                    time: now - age,
                    pose: Pose::new(at.x + dx, at.z + dz, at.psi + dpsi),
                    wrench: Wrench::new(fx, fz, ty),
                };
                let command = kernel.step(&frame, now);
                let limits = kernel.config().limits;
                prop_assert_eq!(check_step(before, &frame, now, &command, &limits), Ok(()));
                prop_assert_eq!(command.check(&limits), Ok(()));
            }
        }
    }
}
