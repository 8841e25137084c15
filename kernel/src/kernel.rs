//! The runtime wrapper: one pure `step(frame, now) -> Command` and explicit
//! operator requests, driving the typed states of [`crate::state`].
//!
//! # Theory of operation
//! Each [`Kernel::step`]:
//! 1. in SafeStop, returns the stop's command at `now` ([`crate::stop`]:
//!    the set-point on its way to rest, the wrench of its category) and
//!    keeps watching the arm for the reset (a reset needs it still);
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
use crate::geometry::{Pose, Wrench};
use crate::impedance::{ImpedanceLaw, Saturation};
use crate::lift::{holding_pose, LiftPhase};
use crate::monitor::joint_limits::JointEnvelope;
use crate::monitor::rates::RateWindow;
use crate::monitor::set::MonitorSet;
use crate::monitor::{Limit, Verdict, Violation};
use crate::motion::SetPoint;
use crate::path::{PathSample, PATH_CAPACITY};
use crate::state::{
    EstimateStage, EstimateStep, Grasp, LimitUpdateRefusal, Refusal, RefusalReason, Request,
    SafeStop, State, StateKind, StopStart, Validated,
};
use crate::stop::StopCategory;
use crate::stop::StopReason;
use crate::trace::{Cause, Event, Trace, TraceEvent};
use crate::validate::ValidatedArm;

/// The kernel: configuration, state, recorded path and monitors.
///
/// # Invariants
/// The configuration passed [`KernelConfig::check`]. `path` holds samples
/// only from the current or last estimation motion.
///
/// `N` is the capacity of the path buffer [samples]. A product uses the
/// default, [`PATH_CAPACITY`] (`Kernel` is `Kernel<PATH_CAPACITY>`); the
/// Kani proofs of a lift's first step use a kernel of a few samples (a
/// first step records at most one), the same code: at 4 096 samples the
/// buffer alone kept CBMC from converting their formula in 10 min.
#[derive(Clone, Debug)]
pub struct Kernel<const N: usize = PATH_CAPACITY> {
    config: KernelConfig,
    law: ImpedanceLaw,
    /// The monitors of `config.limits`.
    monitors: MonitorSet,
    state: State,
    path: heapless::Vec<PathSample, N>,
    rates: RateWindow,
    last_frame: Option<PathSample>,
    /// The newest frame the adapter gave, trusted or not: a step without
    /// a frame (silence) judges it again at its own time.
    latest: Option<PathSample>,
    /// The lateral position y of `latest` [m, frame S] (0 before any).
    latest_lateral: f64,
    last_now: Option<f64>,
    /// The set-point and wrench of the last command before any stop.
    commanded: Option<(SetPoint, Wrench, CommandMode)>,
    /// The latest finite time a stop has been stepped at (its move and
    /// ramp never go back with a clock that does) [s].
    stop_clock: f64,
    /// The force magnitude of the last ramp-down command [N]: a ramp-down
    /// never commands more (limits raised during it do not raise it).
    ramp_force: f64,
    /// Running mean (time constant [`HOLDING_TIME_CONSTANT`]) of the
    /// holding pose x − f_ext/K of the trusted frames less the set-point
    /// commanded before each: where a stop's set-point holds the arm,
    /// without the force noise of one frame (0.5 N / 200 N/m = 2.5 mm).
    holding_offset: Option<Pose>,
    trace: Trace,
}

/// Time constant of the holding pose's running mean [s]: 50 ms at 1 kHz
/// averages 50 frames (2.5 mm of force noise → 0.25 mm).
pub(crate) const HOLDING_TIME_CONSTANT: f64 = 0.05;

/// REQ-SM-004's decision, taken before any other: a request at kernel
/// time `now` [s], the kernel's last clock `last`, is refused for an
/// invalid time when `now` is not finite or is before `last`, unless it is
/// a stop or the reset of a stop (`kind` SafeStop), which are honoured at
/// any clock. `None`: the clock does not refuse it.
fn clock_refusal(
    request: Request,
    kind: StateKind,
    now: f64,
    last: Option<f64>,
) -> Option<RefusalReason> {
    let exempt =
        request == Request::Stop || (request == Request::Reset && kind == StateKind::SafeStop);
    let sane = now.is_finite() && last.is_none_or(|t| now >= t);
    (!sane && !exempt).then_some(RefusalReason::InvalidTime)
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
}

impl<const N: usize> Kernel<N> {
    /// A kernel in Grasp with the checked `config`. Always inlined, so that
    /// [`Kernel::new_in`] writes it straight into its slot.
    #[inline(always)]
    fn fresh(config: KernelConfig) -> Self {
        let l = &config.limits;
        Self {
            law: ImpedanceLaw::new(&config.impedance, l.max_force, l.max_torque, l.max_speed),
            rates: RateWindow::new(l.rate_window),
            monitors: MonitorSet::from_limits(l),
            config,
            state: State::Grasp(Grasp::new()),
            path: heapless::Vec::new(),
            last_frame: None,
            latest: None,
            latest_lateral: 0.0,
            last_now: None,
            commanded: None,
            stop_clock: f64::NAN,
            ramp_force: f64::INFINITY,
            holding_offset: None,
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

    /// One control step at kernel time `now` [s] on the robot's new sensor
    /// `frame` (frame S), or on none (`None`: the robot was silent since
    /// the last step). The kernel alone judges silence: a silent step
    /// judges the newest frame it was given again at `now`, so past
    /// `max_sensor_age` the watchdog stops it ([`Limit::StaleSensor`]); a
    /// kernel that was never given a frame cannot command and stops at
    /// once (the age infinite). Never panics; any fault becomes a safe
    /// stop in this same step.
    ///
    /// A frame's lateral position is taken as 0 (a robot that moves only
    /// in S's sagittal plane, or does not measure it):
    /// [`Self::step_with_lateral`].
    ///
    /// [`Limit::StaleSensor`]: crate::monitor::Limit::StaleSensor
    pub fn step(&mut self, frame: Option<&PathSample>, now: f64) -> Command {
        self.step_with_lateral(frame, 0.0, now)
    }

    /// [`Self::step`] on a `frame` whose grasp the robot measured at
    /// lateral position `lateral` (y of frame S [m]; ignored without a
    /// frame). The lateral position is read only by Estimate, for the
    /// tilt of the arm's plane (REQ-EST-011); a non-finite one is a
    /// non-finite sensor value and stops a running kernel
    /// ([`Limit::NonFiniteSensor`]).
    ///
    /// [`Limit::NonFiniteSensor`]: crate::monitor::Limit::NonFiniteSensor
    pub fn step_with_lateral(
        &mut self,
        frame: Option<&PathSample>,
        lateral: f64,
        now: f64,
    ) -> Command {
        if let Some(frame) = frame {
            self.latest = Some(*frame);
            self.latest_lateral = lateral;
        }
        let latest = self.latest;
        if let State::SafeStop(stop) = self.state {
            return self.stopped_step(&stop, latest.as_ref(), now);
        }
        let Some(frame) = &latest else {
            let age = self.config.limits.max_sensor_age;
            let stale = Violation::new(Limit::StaleSensor, f64::INFINITY, age);
            return self.stop(StopReason::Monitor(stale), now);
        };
        // One place where a step stops (the stop's planning is then one
        // piece of code, for readers and for the proofs alike).
        match self.running_step(frame, now) {
            Ok(command) => command,
            Err(reason) => self.stop(reason, now),
        }
    }

    /// A step outside SafeStop: the command, or why the kernel stops (the
    /// stop then starts from what was trusted before: a frame the monitors
    /// refuse is never a pose to hold, not even the session's first).
    fn running_step(&mut self, frame: &PathSample, now: f64) -> Result<Command, StopReason> {
        let previous = self.last_frame.map(|f| f.time);
        self.monitors
            .watchdog
            .check(frame, now, previous, self.last_now)
            .map_err(StopReason::Monitor)?;
        if !self.latest_lateral.is_finite() {
            let faulty = Violation::new(Limit::NonFiniteSensor, f64::NAN, f64::NAN);
            return Err(StopReason::Monitor(faulty));
        }
        self.last_now = Some(now);
        let newer = previous.is_none_or(|t| frame.time > t);
        if newer {
            self.rates.push(*frame);
        }
        let rates = self.rates.rates();
        let envelope = match self.check_monitors(frame, rates.speed(), rates.force_rate) {
            Ok(envelope) => envelope,
            // A frame the monitors refuse is not trusted: it leaves the
            // rate window, and neither the last frame nor the holding
            // pose's mean takes it, so the stop holds where the last
            // trusted frame put the arm (one frame 5 m off moved the
            // stop's target 0.1 m towards it).
            Err(violation) => {
                if newer {
                    self.rates.retract_newest();
                }
                return Err(StopReason::Monitor(violation));
            }
        };
        if newer {
            self.last_frame = Some(*frame);
            self.update_holding_offset(frame, previous);
        }
        let (set_point, mode) = match self.state_set_point(frame, now, envelope) {
            Ok(Plan::Follow(set_point, mode)) => (set_point, mode),
            Ok(Plan::Enter(validated)) => {
                let hold = validated.hold();
                self.state = State::Validated(validated);
                self.record(
                    now,
                    StateKind::Estimate,
                    StateKind::Validated,
                    Cause::ModelValidated,
                );
                (hold, CommandMode::Hold)
            }
            Ok(Plan::Stopped(stop)) => return Ok(self.stopped_step(&stop, Some(frame), now)),
            Err(reason) => return Err(reason),
        };
        let out = self.law.command(frame.pose, rates.velocity, set_point);
        self.check_set_point(&out.set_point)
            .map_err(StopReason::Monitor)?;
        let command = Command {
            state: self.state.kind(),
            mode,
            set_point: Some(out.set_point),
            wrench: out.wrench,
            saturation: out.saturation,
            stop: None,
        };
        if !command.is_finite() || out.saturation.non_finite {
            return Err(StopReason::NonFiniteCommand);
        }
        self.commanded = Some((out.set_point, out.wrench, mode));
        Ok(command)
    }

    /// The stop that holds the kernel, while it holds it.
    pub fn stopped(&self) -> Option<&SafeStop> {
        match &self.state {
            State::SafeStop(stop) => Some(stop),
            _ => None,
        }
    }

    /// A step in SafeStop: the stop's set-point at `now`, its category's
    /// wrench (a hold: the impedance law about the set-point on the
    /// trusted frame, else the wrench of the stop), and the frame, when
    /// trusted and newer, into the rate window that judges the reset.
    ///
    /// A frame is trusted as a running step trusts one: finite, within
    /// the force and torque limits and inside the workspace box (the
    /// monitors that judge a frame alone). Any other (a glitch) is passed
    /// over: the law holds about the last trusted frame, and neither the
    /// rate window nor the reset sees it (trusted, one frame 5 m off
    /// commanded the 45 N force limit and let the arm's weight go).
    fn stopped_step(&mut self, stop: &SafeStop, frame: Option<&PathSample>, now: f64) -> Command {
        let m = &self.monitors;
        let trusted = frame.filter(|f| {
            f.time.is_finite()
                && f.pose.is_finite()
                && f.wrench.is_finite()
                && m.force.check(f.wrench, 0.0).is_ok()
                && m.workspace.check(f.pose, None).is_ok()
        });
        if let Some(frame) = trusted {
            let newer = self.last_frame.is_none_or(|f| frame.time > f.time);
            if newer && now.is_finite() && frame.time <= now {
                self.rates.push(*frame);
                self.last_frame = Some(*frame);
            }
        }
        // stop_clock is NaN until the first finite stop step.
        if now.is_finite() && (self.stop_clock.is_nan() || now > self.stop_clock) {
            self.stop_clock = now;
        }
        let now = self.stop_clock;
        let set_point = stop.set_point(now);
        let mut saturation = Saturation::default();
        // The stop's own wrench was commanded under the limits of its
        // time; limits updated since (allowed in SafeStop) bound it too.
        let measured = trusted.copied().or(self.last_frame);
        let wrench = match (stop.category(), set_point, measured) {
            (StopCategory::Hold, Some(set_point), Some(frame)) => {
                let out = self
                    .law
                    .command(frame.pose, self.rates.rates().velocity, set_point);
                if out.saturation.non_finite {
                    self.law.limit(stop.ramped_wrench(now), &mut saturation)
                } else {
                    saturation = out.saturation;
                    out.wrench
                }
            }
            _ => self.law.limit(stop.ramped_wrench(now), &mut saturation),
        };
        let wrench = self.ramp_bounded(stop.category(), wrench);
        Command {
            state: StateKind::SafeStop,
            mode: CommandMode::Stop,
            set_point,
            wrench,
            saturation,
            stop: Some(stop.category()),
        }
    }

    /// A ramp-down's `wrench` no larger in force than the ramp-down's
    /// previous command (REQ-STOP-001: its force only falls, also when the
    /// limits are raised during it); other categories unchanged.
    fn ramp_bounded(&mut self, category: StopCategory, wrench: Wrench) -> Wrench {
        if category != StopCategory::RampDown {
            return wrench;
        }
        let force = wrench.force_magnitude();
        let wrench = if force > self.ramp_force {
            let scale = self.ramp_force / force;
            Wrench::new(wrench.fx * scale, wrench.fz * scale, wrench.ty)
        } else {
            wrench
        };
        self.ramp_force = self.ramp_force.min(wrench.force_magnitude());
        wrench
    }

    /// Updates the running mean of the holding pose's offset from the
    /// set-point commanded before `frame` (trusted: the watchdog passed
    /// it), weighted by the frame's interval since `previous`.
    fn update_holding_offset(&mut self, frame: &PathSample, previous: Option<f64>) {
        let Some((set_point, _, _)) = self.commanded else {
            return;
        };
        let holding = holding_pose(frame, &self.config.impedance.stiffness);
        let sample = Pose::new(
            holding.x - set_point.pose.x,
            holding.z - set_point.pose.z,
            holding.psi - set_point.pose.psi,
        );
        if !sample.is_finite() {
            return;
        }
        let weight = previous.map_or(1.0, |t| {
            ((frame.time - t) / HOLDING_TIME_CONSTANT).clamp(0.0, 1.0)
        });
        let mean = self.holding_offset.unwrap_or(sample);
        self.holding_offset = Some(Pose::new(
            mean.x + (sample.x - mean.x) * weight,
            mean.z + (sample.z - mean.z) * weight,
            mean.psi + (sample.psi - mean.psi) * weight,
        ));
    }

    /// What the kernel knows when it stops at `now`, from trusted frames
    /// only (before the first one, no pose: the stop then commands its own
    /// wrench and holds no pose): the set-point and wrench commanded last, where the arm is
    /// held (that set-point moved by the running mean of the holding
    /// pose's offset from it, or the last frame's holding pose), the last
    /// trusted measured pose, and how a hold moves from the state it
    /// leaves:
    /// * the lift (its set-point leads the arm by up to 0.15 m and carries
    ///   it): the set-point slows down along its line (coasting), in at
    ///   least [`crate::stop::LIFT_HOLD_MIN_TIME`], at the lift's settling
    ///   speeds;
    /// * the lift's settling move: on to the lift's own holding pose;
    /// * elsewhere (the manipulation tracks its set-point closely, and may
    ///   be lowering the arm): straight to the holding pose, in at least
    ///   [`crate::stop::HOLD_MIN_TIME`] at up to the speed limit.
    fn stop_start(&self, now: f64) -> StopStart {
        let trusted = self
            .last_frame
            .filter(|f| f.pose.is_finite() && f.wrench.is_finite());
        let stiffness = &self.config.impedance.stiffness;
        let mut holding = match (self.commanded, self.holding_offset) {
            (Some((s, _, _)), Some(offset)) => Some(Pose::new(
                s.pose.x + offset.x,
                s.pose.z + offset.z,
                s.pose.psi + offset.psi,
            )),
            _ => trusted.map(|f| holding_pose(&f, stiffness)),
        };
        let shaping = &self.config.lift_shaping;
        let (mut peak_speed, mut min_time, mut coast) = (
            self.config.limits.max_speed,
            crate::stop::HOLD_MIN_TIME,
            false,
        );
        if let State::Estimate(estimate) = &self.state {
            match estimate.stage() {
                EstimateStage::Lifting(lift) => match lift.phase() {
                    LiftPhase::Lifting | LiftPhase::AwaitingForearm { .. } => {
                        (peak_speed, min_time, coast) =
                            (shaping.hold_speed, crate::stop::LIFT_HOLD_MIN_TIME, true);
                    }
                    LiftPhase::Settling { hold, .. } => {
                        holding = Some(*hold);
                        peak_speed = shaping.hold_speed;
                    }
                },
                EstimateStage::Concluding(_) => {}
            }
        }
        StopStart {
            now: if now.is_finite() { now } else { f64::NAN },
            set_point: self.commanded.map(|(s, _, _)| s),
            wrench: self.commanded.map_or(Wrench::ZERO, |(_, w, _)| w),
            holding,
            measured: trusted.map(|f| f.pose),
            peak_speed,
            peak_rate: shaping.hold_rate,
            min_time,
            coast,
        }
    }

    /// True when a reset at `now` finds the stop's set-point at rest and
    /// the arm still: a fresh, finite frame, the rate window spanned and
    /// the grasp slower than [`crate::stop::RESET_MAX_SPEED`].
    fn still_for_reset(&self, stop: &SafeStop, now: f64) -> bool {
        stop.is_settled(now)
            && self.fresh_pose(now).is_some()
            && self.rates.spans()
            && self.rates.rates().speed() <= crate::stop::RESET_MAX_SPEED
    }

    /// Handles an operator or supervisor request at kernel time `now` [s].
    ///
    /// # Errors
    /// A [`Refusal`] naming the request, the state and the reason; the state
    /// is then unchanged.
    pub fn request(&mut self, request: Request, now: f64) -> Result<StateKind, Refusal> {
        let from = self.state.kind();
        if let Some(reason) = clock_refusal(request, from, now, self.last_now) {
            let refusal = Refusal {
                request,
                state: from,
                reason,
            };
            let time = if now.is_finite() { now } else { f64::NAN };
            return Err(self.refused(refusal, time));
        }
        self.answer(request, now)
    }

    /// [`Kernel::request`] once the clock has let `request` through
    /// (REQ-SM-004): what the state makes of it.
    fn answer(&mut self, request: Request, now: f64) -> Result<StateKind, Refusal> {
        let from = self.state.kind();
        let time = if now.is_finite() { now } else { f64::NAN };
        let next = match self.next_state(request, now) {
            Ok(Some(next)) => next,
            // A stop requested while stopped: the stop stays as it is.
            Ok(None) => return Ok(from),
            Err(reason) => {
                let refusal = Refusal {
                    request,
                    state: from,
                    reason,
                };
                return Err(self.refused(refusal, time));
            }
        };
        match request {
            // A reset starts the session afresh: nothing measured before
            // the stop judges what follows.
            Request::Reset => {
                self.rates.clear();
                self.last_frame = None;
                self.commanded = None;
                self.holding_offset = None;
            }
            Request::StartEstimation => self.path.clear(),
            _ => {}
        }
        self.state = next;
        let to = self.state.kind();
        if to != from {
            self.record(time, from, to, Cause::Request(request));
        }
        Ok(to)
    }

    /// The state `request` at `now` leads to from the kernel's (`None`:
    /// it stays as it is), or why that state refuses it. It only reads the
    /// kernel, so a refused request changes nothing (REQ-SM-002), and the
    /// 2 kB state is written only when it changes: moved through the
    /// answer on every request, it kept real Kani's symbolic execution of
    /// the gating harnesses from ending in 10 min (a refusal from Grasp
    /// alone took over 6 min; borrowed, 121 s).
    fn next_state(&self, request: Request, now: f64) -> Result<Option<State>, RefusalReason> {
        let next = match (request, &self.state) {
            (Request::Stop, State::SafeStop(_)) => return Ok(None),
            (Request::Stop, other) => Ok(State::SafeStop(stop_state(
                other,
                StopReason::Operator,
                self.stop_start(now),
            ))),
            (Request::Reset, State::SafeStop(stop)) if self.still_for_reset(stop, now) => {
                Ok(State::Grasp(stop.reset()))
            }
            (Request::Reset, State::SafeStop(_)) => Err(RefusalReason::ArmNotStill),
            (Request::StartEstimation, State::Grasp(grasp)) => {
                let pose = self
                    .fresh_pose(now)
                    .ok_or(RefusalReason::NoFreshMeasurement)?;
                // The motion starts where the arm is held (the hold
                // set-point), not at the latest measurement: the set-point
                // must not step by the measurement's noise (a joint-position
                // robot turns a 0.2 mm step in one period into a force
                // spike). The fresh measurement gates the request.
                let start = grasp.held().unwrap_or(pose);
                grasp
                    .start_estimation(start, now, &self.config.estimation_motion)
                    .map(State::Estimate)
                    .map_err(|(_, error)| RefusalReason::Plan(error))
            }
            (Request::ApproveManipulation(target), State::Validated(validated)) => validated
                .plan_manipulation(
                    target,
                    self.config.manipulation_peak_speed,
                    &self.monitors.joint_limits,
                    &self.monitors.workspace,
                )
                .map(|plan| State::Manipulate(validated.begin_manipulation(plan, now)))
                .map_err(RefusalReason::Target),
            (Request::FinishManipulation, State::Manipulate(manipulate)) => {
                Ok(State::Validated(manipulate.finish(now)))
            }
            _ => Err(RefusalReason::NotAllowedInState),
        };
        next.map(Some)
    }

    /// Traces `refusal` at kernel time `time` [s] (NaN for a clock that was
    /// not finite) and returns it.
    fn refused(&mut self, refusal: Refusal, time: f64) -> Refusal {
        self.trace.record(TraceEvent {
            time,
            event: Event::Refused(refusal),
        });
        refusal
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
        self.monitors = MonitorSet::from_limits(&limits);
        Ok(())
    }

    /// The latest measured pose, if fresh and finite at `now`.
    fn fresh_pose(&self, now: f64) -> Option<Pose> {
        let frame = self.last_frame?;
        let age = now - frame.time;
        (frame.pose.is_finite() && (0.0..=self.config.limits.max_sensor_age).contains(&age))
            .then_some(frame.pose)
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
        let pose = set_point.pose;
        let arm = self.state.arm().map(ValidatedArm::geometry);
        self.monitors
            .workspace
            .check(pose, arm.map(|a| a.elbow_from_pose(pose)))
    }

    /// The monitors that apply to the current state (watchdog excluded);
    /// in Estimate without a model, the provisional model's joint envelope
    /// they judged at the frame's pose.
    fn check_monitors(
        &self,
        frame: &PathSample,
        speed: f64,
        force_rate: f64,
    ) -> Result<Option<JointEnvelope>, Violation> {
        let m = &self.monitors;
        m.force.check(frame.wrench, force_rate)?;
        if matches!(self.state, State::Estimate(_) | State::Manipulate(_)) {
            m.speed.check(speed)?;
        }
        let joints = &m.joint_limits;
        let arm = self.state.arm().map(ValidatedArm::geometry);
        m.workspace
            .check(frame.pose, arm.map(|a| a.elbow_from_pose(frame.pose)))?;
        match (&self.state, arm) {
            (_, Some(arm)) => joints.check(arm, frame.pose).map(|()| None),
            (State::Estimate(estimate), None) => {
                let envelope = estimate.joint_envelope(frame, &self.config.validation);
                joints.check_envelope(envelope).map(|()| envelope)
            }
            _ => Ok(None),
        }
    }

    /// The state's set-point for this step, with its mode, or, on the step
    /// the estimation concludes, the validated state to enter.
    fn state_set_point(
        &mut self,
        frame: &PathSample,
        now: f64,
        envelope: Option<JointEnvelope>,
    ) -> Result<Plan, StopReason> {
        Ok(match &mut self.state {
            State::Grasp(grasp) => Plan::Follow(grasp.hold(frame.pose), CommandMode::Hold),
            State::Validated(validated) => Plan::Follow(validated.hold(), CommandMode::Hold),
            State::Manipulate(manipulate) => {
                Plan::Follow(manipulate.set_point(now), CommandMode::Track)
            }
            // Kernel::step gives a stopped kernel the stop's own step
            // before any monitor; were a running step to find one, it
            // would give the same.
            State::SafeStop(stop) => Plan::Stopped(*stop),
            State::Estimate(estimate) => {
                let lifting = estimate.lift_ended().is_none();
                let step = estimate.advance(
                    &mut self.path,
                    frame,
                    self.latest_lateral,
                    now,
                    envelope,
                    &self.config,
                )?;
                if let Some(reason) = estimate.lift_ended().filter(|_| lifting) {
                    self.trace.record(TraceEvent {
                        time: now,
                        event: Event::LiftEnded(reason),
                    });
                }
                match step {
                    EstimateStep::Move(set_point) => Plan::Follow(set_point, CommandMode::Track),
                    EstimateStep::Hold(set_point) => Plan::Follow(set_point, CommandMode::Hold),
                    EstimateStep::Validated(validated) => Plan::Enter(validated),
                }
            }
        })
    }

    /// Enters SafeStop for `reason` and returns the stop's first command
    /// (the stop's own wrench: the frame of this step does not command).
    fn stop(&mut self, reason: StopReason, now: f64) -> Command {
        let from = self.state.kind();
        let start = self.stop_start(now);
        let stop = stop_state(&self.state, reason, start);
        self.state = State::SafeStop(stop);
        self.stop_clock = start.now;
        self.record(
            if now.is_finite() { now } else { f64::NAN },
            from,
            StateKind::SafeStop,
            Cause::Stop(reason),
        );
        // The stopping step's own wrench: the stop's (the frame that
        // tripped is not used to command), within the current limits (they
        // may have been lowered since it was commanded: found by the
        // kernel_sequence fuzz target).
        let mut saturation = Saturation::default();
        self.ramp_force = f64::INFINITY;
        let wrench = self.law.limit(stop.ramped_wrench(now), &mut saturation);
        let wrench = self.ramp_bounded(stop.category(), wrench);
        Command {
            state: StateKind::SafeStop,
            mode: CommandMode::Stop,
            set_point: stop.set_point(now),
            wrench,
            saturation,
            stop: Some(stop.category()),
        }
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
    /// The estimation concluded and the validator accepted its model:
    /// enter this state.
    Enter(Validated),
    /// The kernel is stopped: the stop's own step.
    Stopped(SafeStop),
}

/// Moves any state into SafeStop.
///
/// The state is borrowed, not copied: only its variant is read (what
/// moving the whole 2 kB state cost real Kani: [`Kernel::next_state`]).
fn stop_state(state: &State, reason: StopReason, start: StopStart) -> SafeStop {
    match state {
        State::Grasp(s) => s.stop(reason, start),
        State::Estimate(s) => s.stop(reason, start),
        State::Validated(s) => s.stop(reason, start),
        State::Manipulate(s) => s.stop(reason, start),
        State::SafeStop(s) => *s,
    }
}

#[cfg(any(test, kani))]
impl<const N: usize> Kernel<N> {
    /// A kernel with the default configuration in `state`, as if a session
    /// had reached it: proofs start there without running one.
    pub(crate) fn in_state(state: State) -> Self {
        let config = KernelConfig::default();
        config.check().expect("the default configuration is valid");
        let mut kernel = Self::fresh(config);
        kernel.state = state;
        kernel
    }
}

/// Proofs of the runtime wrapper: one step from each state, requests,
/// the latch and limit updates.
///
/// Unwind bounds: a kernel is built by [`Kernel::new`], whose configuration
/// check runs over at most 11 values per group (the validation limits'
/// positive values, `all_positive`: 12), and the fixed validated arm by the
/// validator, which checks 22 values for finiteness (24); one step pushes
/// one frame into an empty rate window (its trimming loop runs at most
/// once) and loops over 3 axes in the impedance law. The Estimate harness
/// starts from a fresh lift, where a step records at most one sample; the
/// refinement's bounded slices over a long path are REQ-TIME-002's tests.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::arm::JointAngles;
    use crate::kani_inputs::{
        any_frame_or_at, any_known_target, any_request, any_request_of_known_targets,
        validated_arm, HOLD,
    };
    use crate::kani_stubs::libm_stubbed;
    use crate::lift::verification::{any_first_step_frame, first_lift, FIRST_STEP_AT};
    use crate::motion::EstimationMotion;
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
    pub(super) fn check_step(
        before: StateKind,
        frame: &PathSample,
        now: f64,
        command: &Command,
        limits: &SafetyLimits,
    ) -> Result<(), &'static str> {
        command.check_components(limits)?;
        let (p, w) = (frame.pose, frame.wrench);
        let floor = -limits.table_tolerance;
        // The age only of finite times (∞ − ∞ is NaN: real Kani's check).
        let fault = !(now.is_finite()
            && frame.time.is_finite()
            && p.is_finite()
            && w.is_finite()
            && (0.0..=limits.max_sensor_age).contains(&(now - frame.time))
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

    /// One step with any frame (or a plausible one at `at`) at the clock
    /// `now`, checked by [`check_step`]. The frame's own time is any
    /// number, so its age at `now` is any too (fresh, stale, from the
    /// future). Each state's harnesses take one finite clock `t` and any
    /// clock that is not finite ([`any_bad_clock`]) apart: with the clock
    /// a symbolic choice of the two, no one-step harness was decided in
    /// 10 min (the Grasp step: 645-654 s); at `t` alone the Grasp step is
    /// decided in 296 s (real Kani, 2026-12-07). A finite clock other
    /// than `t` would make the state's time-dependent set-point (the
    /// lift's, the manipulation's) a symbolic polynomial, whose workspace
    /// bound no solver decides in the 10 min this proof has: that range is
    /// sampled by the proptests
    /// `req_mon_007_one_step_from_each_state_meets_the_check` and
    /// `arbitrary_sessions_keep_every_safety_property`, with this check.
    ///
    /// The kernel is borrowed, never moved into the helper: moved (a
    /// 230 kB value), a Grasp step whose running part was stubbed by an
    /// operator's stop was undecided in 10 min (its solver's first round
    /// never ended); borrowed, decided in 94 s (real Kani, 2026-12-06).
    fn one_step<const N: usize>(kernel: &mut Kernel<N>, at: Pose, now: f64) -> Command {
        let before = kernel.state().kind();
        let frame = any_frame_or_at(at, now);
        let command = kernel.step(Some(&frame), now);
        assert_eq!(command.state, kernel.state().kind());
        assert_eq!(
            check_step(before, &frame, now, &command, &kernel.config().limits),
            Ok(())
        );
        command
    }

    /// Any clock that is not finite: NaN (any payload) or ±∞ (drawn into
    /// the domain, not assumed there: the sampling stand-in would reject
    /// most draws).
    fn any_bad_clock() -> f64 {
        let drawn: f64 = kani::any();
        if drawn.is_finite() {
            f64::NAN
        } else {
            drawn
        }
    }

    /// REQ-CMD-001, REQ-STOP-001: what [`Kernel::stop`] must give for
    /// `reason`: the stop command (SafeStop, stop mode, the reason's
    /// category) within its check ([`Command::check_components`] under
    /// `limits`), the kernel (now of kind `after`) in SafeStop. The
    /// contract the Manipulate step's proof assumes of the stop
    /// ([`stub::stop`]) and [`verify_req_cmd_001_a_stop_meets_its_contract`]
    /// proves.
    pub(super) fn stop_contract(
        reason: StopReason,
        command: &Command,
        after: StateKind,
        limits: &SafetyLimits,
    ) -> Result<(), &'static str> {
        command.check_components(limits)?;
        if command.state != StateKind::SafeStop || after != StateKind::SafeStop {
            return Err("a stop did not enter SafeStop");
        }
        if command.stop != Some(reason.category()) {
            return Err("a stop commanded another category than its reason's");
        }
        Ok(())
    }

    /// Any reason to stop: each monitor's limit (payload any), each cause
    /// without a payload, and one of each cause with one (the stop reads
    /// a reason only through its category, [`StopReason::category`], and
    /// copies it into the state and the trace).
    fn any_stop_reason() -> StopReason {
        use crate::monitor::Limit::*;
        let limits = [
            NonFiniteSensor,
            ClockFault,
            SensorTimeReversed,
            StaleSensor,
            ForceMagnitude,
            Torque,
            GraspBelowTable,
            ElbowBelowTable,
            ForceRate,
            Speed,
            WorkspaceX,
            WorkspaceZ,
            ShoulderElevation,
            ElbowFlexion,
            ModelMismatch,
        ];
        match kani::any::<u8>() {
            0 => StopReason::Operator,
            1 => StopReason::NonFiniteCommand,
            2 => StopReason::PathBufferFull,
            3 => StopReason::PlanFailed(crate::motion::PlanError::NonFinite),
            4 => StopReason::EstimationFailed(
                crate::estimation::EstimateError::UpperArmPhaseTooShort,
            ),
            5 => StopReason::ModelRejected(crate::validate::Rejection::NonFinite),
            n => {
                let limit = limits[usize::from(n) % limits.len()];
                StopReason::Monitor(Violation::new(limit, kani::any(), kani::any()))
            }
        }
    }

    /// REQ-CMD-001, REQ-STOP-001: a stop from Manipulate, as the
    /// Manipulate step's harness calls it (the move approved at t = 0,
    /// nothing commanded yet), with the step's frame trusted or none, for
    /// any reason at the step's clock, meets [`stop_contract`].
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(24))]
    pub(super) fn verify_req_cmd_001_a_stop_meets_its_contract() {
        let (mut kernel, at) = kernel_in(StateKind::Manipulate);
        if kani::any() {
            kernel.last_frame = Some(any_frame_or_at(at, 0.001));
        }
        let reason = any_stop_reason();
        let command = kernel.stop(reason, 0.001);
        let after = kernel.state().kind();
        assert_eq!(
            stop_contract(reason, &command, after, &kernel.config().limits),
            Ok(())
        );
        kani::cover!(command.stop == Some(StopCategory::Hold), "stop: hold");
        kani::cover!(
            command.stop == Some(StopCategory::RampDown),
            "stop: ramp-down"
        );
        kani::cover!(
            command.stop == Some(StopCategory::MotorsOff),
            "stop: motors off"
        );
        kani::cover!(command.set_point.is_some(), "stop: holds a pose");
    }

    /// Kani stubs of the kernel's own parts, each any result its proved
    /// contract allows.
    #[cfg(kani)]
    mod stub {
        use super::*;

        /// Stub of [`Kernel::stopped_step`] for a lift's first step,
        /// which starts in Estimate and leaves it only through
        /// [`Kernel::stop`]: fails the proof if it is reached.
        pub(super) fn stopped_step<const N: usize>(
            _: &mut Kernel<N>,
            stop: &SafeStop,
            _: Option<&PathSample>,
            _: f64,
        ) -> Command {
            kani::assert(false, "a lift's first step took a stopped step");
            Command {
                state: StateKind::SafeStop,
                mode: CommandMode::Stop,
                set_point: None,
                wrench: Wrench::ZERO,
                saturation: Saturation::default(),
                stop: Some(stop.category()),
            }
        }

        /// Stub of [`Kernel::stop`] by [`stop_contract`]: the kernel in
        /// SafeStop for `reason` (latched from no pose: the state's pose is
        /// not the contract's), any command the contract allows.
        pub(super) fn stop<const N: usize>(
            kernel: &mut Kernel<N>,
            reason: StopReason,
            now: f64,
        ) -> Command {
            let at = if now.is_finite() { now } else { f64::NAN };
            let start = StopStart::at_pose(at, None);
            kernel.state = State::SafeStop(stop_state(&kernel.state, reason, start));
            let command = Command {
                state: StateKind::SafeStop,
                mode: CommandMode::Stop,
                set_point: if kani::any() { Some(kani::any()) } else { None },
                wrench: kani::any(),
                saturation: Saturation {
                    force: kani::any(),
                    torque: kani::any(),
                    speed: kani::any(),
                    non_finite: kani::any(),
                },
                stop: Some(reason.category()),
            };
            let after = kernel.state.kind();
            kani::assume(stop_contract(reason, &command, after, &kernel.config.limits).is_ok());
            command
        }
    }

    /// The path buffer [samples] of the kernels whose proofs take a lift's
    /// first step, which records at most one sample: with the product's
    /// 4 096 ([`PATH_CAPACITY`]) CBMC's conversion of their formula did
    /// not end in 10 min; with 64, 20 s (real Kani, 2026-12-07).
    const FIRST_LIFT_STEP_PATH: usize = 4;

    /// A kernel in Estimate at the start of [`first_lift`] (at kernel
    /// time 0, nothing recorded), with a path buffer of
    /// [`FIRST_LIFT_STEP_PATH`], and where the arm is: the lift's grasp.
    fn lifting_kernel() -> (Kernel<FIRST_LIFT_STEP_PATH>, Pose) {
        let lift = first_lift();
        let grasp = lift.motion().lift().start();
        let estimate = crate::state::verification::lifting(grasp, lift);
        (Kernel::in_state(State::Estimate(estimate)), grasp)
    }

    #[cfg_attr(
        kani,
        kani::stub(
            crate::estimation::online::OnlineEstimator::joint_envelope,
            crate::estimation::online::stub::joint_envelope
        )
    )]
    /// REQ-CMD-001, REQ-STOP-001: a stop during [`first_lift`]'s first
    /// step, as the Estimate step's harness can call it at
    /// [`FIRST_STEP_AT`]: from the lift as planned or as its first step
    /// left it (the real step, on a frame the monitors passed: lifting on,
    /// or settling after the force margin), with that frame trusted or
    /// none, for any reason, meets [`stop_contract`].
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(12))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::sqrt, crate::kani_stubs::stub::sqrt))]
    pub(super) fn verify_req_cmd_001_a_stop_during_a_lift_meets_its_contract() {
        let config = KernelConfig::default();
        let mut lift = first_lift();
        let grasp = lift.motion().lift().start();
        let frame = any_first_step_frame(&config.limits);
        if kani::any() {
            let online = crate::estimation::online::OnlineEstimator::new();
            let settings = crate::lift::LiftSettings::of(&config);
            let _ = lift.advance(FIRST_STEP_AT, &frame, &online, Some(None), &settings);
        }
        let settling = lift.ended().is_some();
        let estimate = crate::state::verification::lifting(grasp, lift);
        let mut kernel = Kernel::<FIRST_LIFT_STEP_PATH>::in_state(State::Estimate(estimate));
        if kani::any() {
            kernel.last_frame = Some(frame);
        }
        let reason = any_stop_reason();
        let command = kernel.stop(reason, FIRST_STEP_AT);
        let after = kernel.state().kind();
        assert_eq!(
            stop_contract(reason, &command, after, &kernel.config().limits),
            Ok(())
        );
        kani::cover!(settling, "stop during a lift: settling");
        kani::cover!(
            command.set_point.is_some(),
            "stop during a lift: holds a pose"
        );
    }

    /// REQ-CMD-001, REQ-STOP-001: a stop at the start of [`first_lift`]
    /// at any clock that is not finite, as the Estimate step's harness at
    /// a bad clock calls it (the watchdog refuses the step: no frame is
    /// trusted), for any reason, meets [`stop_contract`].
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(12))]
    pub(super) fn verify_req_cmd_001_a_stop_during_a_lift_at_a_bad_clock_meets_its_contract() {
        let (mut kernel, _) = lifting_kernel();
        let reason = any_stop_reason();
        let command = kernel.stop(reason, any_bad_clock());
        let after = kernel.state().kind();
        assert_eq!(
            stop_contract(reason, &command, after, &kernel.config().limits),
            Ok(())
        );
        kani::cover!(
            command.stop == Some(StopCategory::MotorsOff),
            "stop during a lift at a bad clock: motors off"
        );
    }

    /// Where Manipulate's move starts: held 0.1 m straight above
    /// [`TABLE_TARGET`]'s grasp (frame S) [m, rad].
    const LOWERING_FROM: Pose = Pose::new(0.0, 0.1, 0.0);
    /// Manipulate's target: the fixed arm extended on the table (q = 0, the
    /// grasp at [`REST`]) [rad]. Its kinematics and checks (sines and
    /// cosines of 0, distances along an axis, the angle of +0) and its
    /// move's length from [`LOWERING_FROM`] are exact under the libm stubs
    /// (`crate::kani_stubs::stub`), so the plan, its `Ok` and the move are
    /// numbers to symbolic execution. Towards `MANIPULATION_TARGET` from
    /// [`HOLD`] the plan's checks are symbolic, and the Manipulate state
    /// taken out of its `Result` is merged with the error's bytes. With
    /// this target the gating from Manipulate is verified in 194 s (540 s
    /// before) and the Manipulate step's first solver round takes 80 s
    /// (258-428 s); the step is decided once its stop is stubbed by its
    /// contract, [`stub::stop`] (real Kani, 2026-12-07). [`LOWERING_FROM`]
    /// stands for any hold: the fixed arm (l1 + l2 = 0.5 m) cannot hold its
    /// grasp there with psi = 0; the step judges frames, not where the move
    /// started.
    const TABLE_TARGET: JointAngles = JointAngles {
        shoulder_elevation: 0.0,
        elbow_flexion: 0.0,
    };

    /// Grasp, Estimate (from the rest pose at t = 0), Validated (the fixed
    /// arm at [`HOLD`]), Manipulate (lowering the fixed arm from
    /// [`LOWERING_FROM`] to [`TABLE_TARGET`], approved at t = 0) or
    /// SafeStop (an operator's stop in Validated before any frame, latched
    /// at [`HOLD`]), with where the arm is. One default kernel is built,
    /// and the fixed arm validated at one call site, so that a harness over
    /// any state pays for each once; Manipulate is entered by the
    /// approval's plan and start, SafeStop by its request from Validated.
    fn kernel_in(kind: StateKind) -> (Kernel, Pose) {
        let mut kernel = Kernel::in_state(State::Grasp(Grasp::new()));
        let at = match kind {
            StateKind::Grasp => REST,
            StateKind::Estimate => {
                // The motion planned as `Grasp::start_estimation` plans it,
                // the estimate made of it as that makes it, not taken out
                // of that function's `Result` (why and what it measured:
                // `state::verification::lifting`).
                let motion =
                    EstimationMotion::new(REST, &KernelConfig::default().estimation_motion);
                kani::assume(motion.is_ok());
                kernel.state = State::Estimate(crate::state::verification::lifting(
                    REST,
                    crate::lift::ShapedLift::new(motion.expect("assumed"), 0.0),
                ));
                REST
            }
            StateKind::Validated | StateKind::Manipulate | StateKind::SafeStop => {
                // One call site of the validator for the three kinds.
                let hold = if kind == StateKind::Manipulate {
                    LOWERING_FROM
                } else {
                    HOLD
                };
                let validated = Validated::holding(validated_arm(), hold);
                kernel.state = State::Validated(validated);
                if kind == StateKind::Manipulate {
                    // The approval's own steps (the plan REQ-SM-003's proof
                    // checks, then its start), without the request's
                    // wrapper, whose every branch the solver would unroll
                    // (not decided in 10 min).
                    let plan = validated.plan_manipulation(
                        TABLE_TARGET,
                        kernel.config.manipulation_peak_speed,
                        &kernel.monitors.joint_limits,
                        &kernel.monitors.workspace,
                    );
                    kani::assume(plan.is_ok());
                    kernel.state = State::Manipulate(
                        validated.begin_manipulation(plan.expect("assumed"), 0.0),
                    );
                } else if kind == StateKind::SafeStop {
                    // An operator's stop before any frame, as the state's
                    // answer to the request makes it (not the request
                    // itself: REQ-SM-004's proof stubs that answer).
                    let start = kernel.stop_start(0.0);
                    kernel.state =
                        State::SafeStop(stop_state(&kernel.state, StopReason::Operator, start));
                }
                hold
            }
        };
        (kernel, at)
    }

    /// A whole-kernel harness with the libm functions named in brackets
    /// stubbed (as [`libm_stubbed!`]) and three parts of the step stubbed
    /// by the contracts their own harnesses prove, each assumed through
    /// the very function the proof asserts: the law's wrench
    /// ([`law_contract`], proved by
    /// `verify_req_cmd_001_law_is_finite_only_on_finite_inputs`), its
    /// wrench limit ([`limit_contract`],
    /// `verify_req_cmd_001_wrench_limit_is_saturated_and_flagged`) and the
    /// rate window's rates ([`rates_contract`],
    /// `verify_req_mon_002_rates_are_zero_until_the_window_spans`, over
    /// finite frames in time order: the only ones the kernel pushes). They
    /// take those parts' products and quotients of symbolic numbers out of
    /// the whole-step proofs; what the step composes of them (which state,
    /// which stop, which check) stays real. With them, and the clock split
    /// from the frame's choice ([`one_step`]), five of the eight one-step
    /// harnesses are decided in 10 min; the Manipulate step at its time
    /// also with the stop stubbed by its contract ([`stub::stop`]), both
    /// Estimate steps with the stubs of [`first_lift_step_stubbed!`] (the
    /// records in `spec/requirements.toml`).
    ///
    /// [`law_contract`]: crate::impedance::verification::law_contract
    /// [`limit_contract`]: crate::impedance::verification::limit_contract
    /// [`rates_contract`]: crate::monitor::rates::verification::rates_contract
    macro_rules! kernel_stubbed {
        ([$($f:ident),+] $(#[$attr:meta])* $vis:vis fn $name:ident() $body:block) => {
            libm_stubbed! { [$($f),+]
                $(#[$attr])*
                #[cfg_attr(kani, kani::stub(
                    crate::impedance::ImpedanceLaw::wrench_about,
                    crate::impedance::verification::stub::wrench_about
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::impedance::ImpedanceLaw::limit,
                    crate::impedance::verification::stub::limit
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::monitor::rates::rates_between,
                    crate::monitor::rates::verification::stub::rates_between
                ))]
                $vis fn $name() $body
            }
        };
    }

    /// [`kernel_stubbed!`] for a lift's first step ([`lifting_kernel`]),
    /// with the estimation's later parts stubbed by stubs that fail the
    /// proof when reached (an assertion `false`): the online estimate's
    /// forearm and upper-arm updates (a fresh estimate is Resting), the
    /// lift's conclusion and the refinement with the validator (the lift
    /// settles on a later step); the provisional model's joint envelope by
    /// the answer a fresh estimate gives, none (asserted: no provisional
    /// forearm); what only other states read by stubs that fail the
    /// proof when reached where they must not be (the stopped step, the
    /// manipulation's set-point, the validated model: symbolic execution
    /// does not fold the state's variant either, and those branches took
    /// half of the formula's 20.9 M clauses); and two parts by the
    /// contracts their own harnesses prove:
    /// the lift's step ([`first_step_contract`], by
    /// `lift::verification::stub::advance`, which asserts it is called
    /// where that contract was proved) and the stop ([`stop_contract`],
    /// [`stub::stop`], proved from the lift as planned and as its first
    /// step leaves it, and at a bad clock:
    /// [`verify_req_cmd_001_a_stop_during_a_lift_meets_its_contract`],
    /// [`verify_req_cmd_001_a_stop_during_a_lift_at_a_bad_clock_meets_its_contract`]).
    ///
    /// What each took out (real Kani, 2026-12-07): symbolic execution
    /// cannot fold the fresh estimate's phase, stage and model out of the
    /// kernel's state (an enum, read through a union of its variants), so
    /// without the estimation's stubs it unrolled all of those bodies and
    /// did not end in 10 min (12.8 GiB); with them, 84 s. The product's
    /// 4 096-sample path buffer kept CBMC's conversion from ending in
    /// 10 min (a buffer of [`FIRST_LIFT_STEP_PATH`]: 11-25 s). The default
    /// lift's duration is a formula under the libm stubs (its goal is
    /// planned through the sine and cosine of its angle), so [`first_lift`]
    /// goes straight up; the lift's step on a symbolic frame and the stop's
    /// pose built from that frame were each too much for the solver beside
    /// the rest of the step, hence their contracts.
    ///
    /// [`first_step_contract`]: crate::lift::verification::first_step_contract
    macro_rules! first_lift_step_stubbed {
        ([$($f:ident),+] $(#[$attr:meta])* $vis:vis fn $name:ident() $body:block) => {
            kernel_stubbed! { [$($f),+]
                $(#[$attr])*
                #[cfg_attr(kani, kani::stub(
                    crate::estimation::online::OnlineEstimator::record_forearm,
                    crate::estimation::online::stub::record_forearm
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::estimation::online::OnlineEstimator::catch_up,
                    crate::estimation::online::stub::catch_up
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::estimation::online::OnlineEstimator::joint_envelope,
                    crate::estimation::online::stub::joint_envelope
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::state::Estimate::conclude,
                    crate::state::verification::stub::conclude
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::state::Conclusion::advance,
                    crate::state::verification::stub::conclusion_advance
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::lift::ShapedLift::advance,
                    crate::lift::verification::stub::advance
                ))]
                #[cfg_attr(kani, kani::stub(Kernel::stop, stub::stop))]
                #[cfg_attr(kani, kani::stub(Kernel::stopped_step, stub::stopped_step))]
                #[cfg_attr(kani, kani::stub(
                    crate::state::Manipulate::set_point,
                    crate::state::verification::stub::manipulate_set_point
                ))]
                #[cfg_attr(kani, kani::stub(
                    crate::state::State::arm,
                    crate::state::verification::stub::arm
                ))]
                $vis fn $name() $body
            }
        };
    }

    kernel_stubbed! { [hypot, sqrt]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step from
        /// Grasp with any frame at the step's clock never panics, commands
        /// within the limits and stops on any fault in the same step (a
        /// clock that is not finite:
        /// [`verify_req_panic_001_step_from_grasp_at_a_bad_clock`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(12))]
        pub(super) fn verify_req_panic_001_step_from_grasp() {
            let (mut kernel, at) = kernel_in(StateKind::Grasp);
            let command = one_step(&mut kernel, at, 0.0);
            kani::cover!(command.state == StateKind::Grasp, "grasp step: holds");
            kani::cover!(command.state == StateKind::SafeStop, "grasp step: stops");
        }
    }

    kernel_stubbed! { [hypot, sqrt]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step from
        /// Grasp with any frame at any clock that is not finite never
        /// panics, commands within the limits and stops.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(12))]
        pub(super) fn verify_req_panic_001_step_from_grasp_at_a_bad_clock() {
            let (mut kernel, at) = kernel_in(StateKind::Grasp);
            let command = one_step(&mut kernel, at, any_bad_clock());
            kani::cover!(command.state == StateKind::SafeStop, "grasp step: stops");
        }
    }

    first_lift_step_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007, REQ-MON-012:
        /// one step during the estimation (the first of [`first_lift`] at
        /// [`FIRST_STEP_AT`]: one sample recorded into the path and the
        /// online estimate, the lift shaped) with any frame never panics,
        /// commands within the limits and stops on any fault in the same
        /// step.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(12))]
        pub(super) fn verify_req_panic_001_step_during_estimation() {
            let (mut kernel, at) = lifting_kernel();
            let command = one_step(&mut kernel, at, FIRST_STEP_AT);
            kani::cover!(
                command.state == StateKind::Estimate,
                "estimate step: tracks"
            );
            kani::cover!(command.state == StateKind::SafeStop, "estimate step: stops");
        }
    }

    first_lift_step_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007, REQ-MON-012:
        /// [`verify_req_panic_001_step_during_estimation`] at any clock that
        /// is not finite: the step stops.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(12))]
        pub(super) fn verify_req_panic_001_step_during_estimation_at_a_bad_clock() {
            let (mut kernel, at) = lifting_kernel();
            let command = one_step(&mut kernel, at, any_bad_clock());
            kani::cover!(command.state == StateKind::SafeStop, "estimate step: stops");
        }
    }

    kernel_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step in
        /// Validated with any frame at the step's clock never panics,
        /// commands within the limits and stops on any fault in the same
        /// step.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_panic_001_step_in_validated() {
            let (mut kernel, at) = kernel_in(StateKind::Validated);
            let command = one_step(&mut kernel, at, 0.0);
            kani::cover!(
                command.state == StateKind::Validated,
                "validated step: holds"
            );
            kani::cover!(
                command.state == StateKind::SafeStop,
                "validated step: stops"
            );
        }
    }

    kernel_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007: one step in
        /// Validated with any frame at any clock that is not finite never
        /// panics, commands within the limits and stops.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_panic_001_step_in_validated_at_a_bad_clock() {
            let (mut kernel, at) = kernel_in(StateKind::Validated);
            let command = one_step(&mut kernel, at, any_bad_clock());
            kani::cover!(
                command.state == StateKind::SafeStop,
                "validated step: stops"
            );
        }
    }

    kernel_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007, REQ-MON-012:
        /// one step while manipulating with any frame at the step's clock
        /// never panics, commands within the limits and stops on any fault
        /// in the same step. The stop is its contract's ([`stub::stop`],
        /// proved by [`verify_req_cmd_001_a_stop_meets_its_contract`]):
        /// with the real stop in the formula (the stop's pose built from
        /// the frame every monitor judged: 4.5 M variables, 10.4 M
        /// clauses) the solver's rounds did not end in 10 min; with the
        /// contract, 2.6 M variables and 1.3 M clauses, verified in 125 s,
        /// and the stop alone in 111 s (real Kani, 2026-12-07).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        #[cfg_attr(kani, kani::stub(Kernel::stop, stub::stop))]
        pub(super) fn verify_req_panic_001_step_while_manipulating() {
            let (mut kernel, at) = kernel_in(StateKind::Manipulate);
            let command = one_step(&mut kernel, at, 0.001);
            kani::cover!(
                command.state == StateKind::Manipulate,
                "manipulate step: tracks"
            );
            kani::cover!(
                command.state == StateKind::SafeStop,
                "manipulate step: stops"
            );
        }
    }

    kernel_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-006, REQ-MON-007, REQ-MON-012:
        /// one step while manipulating with any frame at any clock that is
        /// not finite never panics, commands within the limits and stops.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_panic_001_step_while_manipulating_at_a_bad_clock() {
            let (mut kernel, at) = kernel_in(StateKind::Manipulate);
            let command = one_step(&mut kernel, at, any_bad_clock());
            kani::cover!(
                command.state == StateKind::SafeStop,
                "manipulate step: stops"
            );
        }
    }

    /// REQ-SM-006, REQ-CMD-003, REQ-STOP-001 for one step of a `kernel`
    /// stopped for `reason` by a hold: a step with any frame or none
    /// (silence: the kernel judges its newest frame) at any clock stays in
    /// SafeStop with the same reason and category and commands the same
    /// set-point at rest, the held pose [`HOLD`], with a wrench within the
    /// `limits` (the impedance law's about it).
    fn latched_step(
        kernel: &mut Kernel,
        limits: &SafetyLimits,
        reason: Option<StopReason>,
    ) -> Command {
        let frame = kani::any::<PathSample>();
        let sensed: bool = kani::any();
        let command = kernel.step(sensed.then_some(&frame), kani::any());
        assert_eq!(command.check_components(limits), Ok(()));
        assert_eq!(command.mode, CommandMode::Stop);
        assert_eq!(command.stop, Some(StopCategory::Hold));
        assert_eq!(command.set_point, Some(SetPoint::hold(HOLD)));
        assert_eq!(kernel.state().kind(), StateKind::SafeStop);
        assert_eq!(kernel.stopped().map(|s| s.reason()), reason);
        command
    }

    kernel_stubbed! { [sqrt, hypot]
        /// REQ-SM-006, REQ-CMD-003, REQ-STOP-001: once stopped (a stop
        /// request in Validated: a hold), one step keeps the stop (see
        /// [`latched_step`]). With [`verify_req_sm_006_a_request_keeps_the_stop`]
        /// the latch's two moves, each proved from the latched stop; the
        /// harness that chained three steps and two requests was undecided
        /// in 10 min, and longer sequences from every state are the
        /// proptest `arbitrary_sessions_keep_every_safety_property`'s.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_006_a_step_keeps_the_stop() {
            let (mut kernel, _) = kernel_in(StateKind::SafeStop);
            let limits = kernel.config().limits;
            let stopped = kernel.stopped().copied();
            let command = latched_step(&mut kernel, &limits, stopped.map(|s| s.reason()));
            kani::cover!(
                stopped.map(|s| s.ramped_wrench(0.0)) != Some(command.wrench),
                "latch: the hold's wrench follows the arm"
            );
        }
    }

    libm_stubbed! { [sqrt, hypot]
        /// REQ-SM-006, REQ-STOP-001: once stopped (as
        /// [`verify_req_sm_006_a_step_keeps_the_stop`]), any request but
        /// Reset at any clock leaves the latched stop as it is: the state
        /// is unchanged, and [`Kernel::request`] writes nothing else a step
        /// reads (only the trace: a refusal, or nothing for a repeated
        /// stop), so the next step keeps the stop by that harness. A
        /// request and a step in one harness were undecided in 10 min.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_006_a_request_keeps_the_stop() {
            let (mut kernel, _) = kernel_in(StateKind::SafeStop);
            let before = *kernel.state();
            let request = any_request();
            kani::assume(request != Request::Reset);
            let answer = kernel.request(request, kani::any());
            assert_eq!(*kernel.state(), before, "a request moved the latched stop");
            kani::cover!(answer.is_err(), "latch: a request refused");
            kani::cover!(answer.is_ok(), "latch: a stop taken");
        }
    }

    /// Checks `property` from a state of any kind, with one call site per
    /// kind, so that the proof specialises the property to each state (a
    /// symbolic kind merges the five states into one kernel, whose
    /// symbolic execution did not finish in 10 min).
    fn from_any_state(property: fn(StateKind)) {
        match kani::any::<u8>() % 5 {
            0 => property(StateKind::Grasp),
            1 => property(StateKind::Estimate),
            2 => property(StateKind::Validated),
            3 => property(StateKind::Manipulate),
            _ => property(StateKind::SafeStop),
        }
    }

    /// REQ-SM-005, REQ-SM-002 from a kernel in `kind`: any request (its
    /// target accepted, beyond the joint limits or not finite: what any
    /// other target does is REQ-SM-003's proof) at a sane clock reaches
    /// Validated or Manipulate only from a state that already holds the
    /// same validated model (Manipulate only from Validated by an approved
    /// target), and a refusal names the request and the state and changes
    /// nothing. One harness per kind (all five in one, at any clock, did
    /// not finish in 10 min, nor did Validated's alone at any clock: its
    /// symbolic execution never ended; both measured while the answer
    /// still moved the state, not retried since). The clock is one sane
    /// value: which requests an insane clock lets through (a stop, a
    /// stop's reset: neither reaches Validated or Manipulate) is REQ-SM-004's
    /// proofs'. Returns the state's kind after the request and the answer.
    fn gating_from(kind: StateKind) -> (StateKind, Result<StateKind, Refusal>) {
        gating_of(kind, any_request_of_known_targets())
    }

    /// [`gating_from`] for the one `request` given.
    fn gating_of(kind: StateKind, request: Request) -> (StateKind, Result<StateKind, Refusal>) {
        let (mut kernel, _) = kernel_in(kind);
        let before = *kernel.state();
        let result = kernel.request(request, 0.01);
        let after = kernel.state();
        if matches!(after.kind(), StateKind::Validated | StateKind::Manipulate) {
            assert!(after.arm().is_some());
            assert_eq!(
                after.arm(),
                before.arm(),
                "a model appeared without validation"
            );
        }
        if after.kind() == StateKind::Manipulate && before.kind() != StateKind::Manipulate {
            assert_eq!(before.kind(), StateKind::Validated);
            assert!(matches!(request, Request::ApproveManipulation(_)));
        }
        if let Err(refusal) = &result {
            assert_eq!(*after, before, "a refused request changed the state");
            // The request by its kind (a refused target may hold NaN).
            assert_eq!(
                core::mem::discriminant(&refusal.request),
                core::mem::discriminant(&request)
            );
            assert_eq!(refusal.state, before.kind());
        }
        (after.kind(), result)
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002 in Grasp (see [`gating_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_grasp() {
            let (_, result) = gating_from(StateKind::Grasp);
            kani::cover!(result.is_ok(), "gating grasp: taken");
            kani::cover!(result.is_err(), "gating grasp: refused");
        }
    }

    /// REQ-SM-005, REQ-SM-002 in Estimate (see [`gating_from`]) for one
    /// `request` that is not a stop: Estimate refuses it and changes
    /// nothing. One harness per request, each on concrete values: over a
    /// symbolic choice of the six requests Estimate refuses the proof was
    /// not decided in 10 min (617 s: 6.0 M variables, 14 M clauses; 509 s
    /// with only the state's kind compared), one request alone is decided
    /// in about 3 min (real Kani, 2026-12-07). The stop is
    /// [`verify_req_sm_005_gating_in_estimate_a_stop`]'s.
    fn refused_in_estimate(request: Request) {
        let (after, result) = gating_of(StateKind::Estimate, request);
        assert_eq!(after, StateKind::Estimate);
        kani::cover!(result.is_err(), "gating estimate: refused");
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002: Estimate refuses a start of the
        /// estimation ([`refused_in_estimate`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_estimate_refuses_a_start() {
            refused_in_estimate(Request::StartEstimation);
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002: Estimate refuses an approval of any of
        /// the known targets ([`refused_in_estimate`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_estimate_refuses_an_approval() {
            refused_in_estimate(Request::ApproveManipulation(any_known_target()));
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002: Estimate refuses a finish of the
        /// manipulation ([`refused_in_estimate`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_estimate_refuses_a_finish() {
            refused_in_estimate(Request::FinishManipulation);
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002: Estimate refuses a reset
        /// ([`refused_in_estimate`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_estimate_refuses_a_reset() {
            refused_in_estimate(Request::Reset);
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002 in Estimate (see [`gating_from`]) for a
        /// stop; its cover shows the stop taken, to SafeStop.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_estimate_a_stop() {
            let (after, result) = gating_of(StateKind::Estimate, Request::Stop);
            kani::cover!(
                result.is_ok() && after == StateKind::SafeStop,
                "gating estimate: stopped"
            );
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002 in Validated (see [`gating_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_validated() {
            let (after, result) = gating_from(StateKind::Validated);
            kani::cover!(after == StateKind::Manipulate, "gating validated: manipulation approved");
            kani::cover!(result.is_err(), "gating validated: refused");
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002 in Manipulate (see [`gating_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_manipulate() {
            let (_, result) = gating_from(StateKind::Manipulate);
            kani::cover!(result.is_ok(), "gating manipulate: taken");
            kani::cover!(result.is_err(), "gating manipulate: refused");
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-005, REQ-SM-002 in SafeStop (see [`gating_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_005_gating_in_safe_stop() {
            let (_, result) = gating_from(StateKind::SafeStop);
            kani::cover!(result.is_ok(), "gating safe stop: taken");
            kani::cover!(result.is_err(), "gating safe stop: refused");
        }
    }

    /// REQ-SM-004, the decision [`Kernel::request`] takes first: for any
    /// request, state kind and clock, and any finite last clock or none,
    /// the clock refuses (for an invalid time) exactly the requests that
    /// are neither a stop nor a stop's reset, at a clock that is not a
    /// number, infinite or before the last one. That the kernel's requests
    /// go through it is the whole-kernel harness below and
    /// the transition tests.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_sm_004_the_clock_refuses_first() {
        let request = any_request();
        let kind = StateKind::ALL[usize::from(kani::any::<u8>() % 5)];
        let now: f64 = kani::any();
        let last = if kani::any() {
            None
        } else {
            Some(kani::any::<f64>())
        };
        kani::assume(last.is_none_or(f64::is_finite));
        let refusal = clock_refusal(request, kind, now, last);
        let bad = now.is_nan() || now.is_infinite() || matches!(last, Some(t) if now < t);
        let exempt = matches!(request, Request::Stop)
            || (matches!(request, Request::Reset) && kind == StateKind::SafeStop);
        assert_eq!(
            refusal,
            (bad && !exempt).then_some(RefusalReason::InvalidTime)
        );
        kani::cover!(refusal.is_some(), "clock: refused");
        kani::cover!(bad && exempt, "clock: a stop honoured at a bad clock");
        kani::cover!(!bad && refusal.is_none(), "clock: a sane clock passes");
    }

    /// The state's answer to a request, as far as REQ-SM-004 is concerned:
    /// reached, so the clock let the request through; accepted, so that a
    /// request the clock should have refused fails the proof.
    #[cfg(kani)]
    fn answer_reached(kernel: &mut Kernel, _: Request, _: f64) -> Result<StateKind, Refusal> {
        Ok(kernel.state.kind())
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-004: a request at a non-finite or backwards clock is refused
        /// for an invalid time, except a stop and the reset of a stop, which
        /// the clock lets through to the state's answer. Under Kani the
        /// answer is [`answer_reached`]: whether the clock lets a request
        /// through is decided before it (the state's answer to a stop
        /// plans the stop's motion, whose loops over a symbolic clock
        /// the solver did not unroll in 10 min); the answers themselves are
        /// REQ-SM-005's proof and the transition tests'.
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        #[cfg_attr(kani, kani::stub(Kernel::answer, answer_reached))]
        pub(super) fn verify_req_sm_004_requests_need_a_sane_clock() {
            from_any_state(|kind| {
                let (mut kernel, _) = kernel_in(kind);
                let kind = kernel.state().kind();
                let last = 1.0;
                kernel.last_now = Some(last);
                // Only clocks the requirement is about, non-finite or before the
                // last (every one of them can be drawn): a sane clock's request is
                // judged by the gating proof (REQ-SM-005) and the targets'
                // (REQ-SM-003).
                let drawn: f64 = kani::any();
                let now = if drawn.is_finite() && drawn >= last {
                    last - drawn
                } else {
                    drawn
                };
                let request = any_request();
                let result = kernel.request(request, now);
                let exempt = request == Request::Stop
                    || (request == Request::Reset && kind == StateKind::SafeStop);
                let reason = result.map_err(|r| r.reason);
                if exempt {
                    assert_ne!(reason, Err(RefusalReason::InvalidTime));
                } else {
                    assert_eq!(reason, Err(RefusalReason::InvalidTime));
                }
                kani::cover!(!exempt, "clock: refused");
                kani::cover!(
                    exempt && !now.is_finite() && result.is_ok(),
                    "clock: stop honoured"
                );
            });
        }
    }

    /// REQ-SM-007 from a kernel in `kind`: new limits (any force limit,
    /// speed limit and elbow range, the others following the same check;
    /// or the defaults, which are valid) are taken only in Grasp, Validated
    /// or SafeStop and only when the whole configuration passes its check;
    /// otherwise the configuration is unchanged. One harness per kind (all
    /// five in one did not finish in 10 min: each kind's kernel is built
    /// and updated on its own path), each with the covers its kind can
    /// reach.
    fn limits_update_from(kind: StateKind) -> Result<(), LimitUpdateRefusal> {
        let (mut kernel, _) = kernel_in(kind);
        let before = *kernel.config();
        let mut limits = before.limits;
        if kani::any() {
            limits.max_force = kani::any();
            limits.max_speed = kani::any();
            limits.elbow_flexion = crate::config::Interval::new(kani::any(), kani::any());
        }
        let result = kernel.update_limits(limits);
        let held = matches!(
            kind,
            StateKind::Grasp | StateKind::Validated | StateKind::SafeStop
        );
        let valid = KernelConfig { limits, ..before }.check().is_ok();
        assert_eq!(kernel.state().kind(), kind);
        assert_eq!(result.is_ok(), held && valid);
        if result.is_ok() {
            assert_eq!(kernel.config().limits, limits);
        } else {
            assert_eq!(*kernel.config(), before);
        }
        result
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-007 in Grasp (see [`limits_update_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_007_limits_change_in_grasp() {
            let result = limits_update_from(StateKind::Grasp);
            kani::cover!(result.is_ok(), "grasp: limits taken");
            kani::cover!(result.is_err(), "grasp: invalid limits refused");
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-007 in Estimate (see [`limits_update_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_007_limits_refused_while_estimating() {
            let result = limits_update_from(StateKind::Estimate);
            kani::cover!(
                result == Err(LimitUpdateRefusal::NotAllowedInState(StateKind::Estimate)),
                "estimate: limits refused"
            );
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-007 in Validated (see [`limits_update_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_007_limits_change_in_validated() {
            let result = limits_update_from(StateKind::Validated);
            kani::cover!(result.is_ok(), "validated: limits taken");
            kani::cover!(result.is_err(), "validated: invalid limits refused");
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-007 in Manipulate (see [`limits_update_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_007_limits_refused_while_manipulating() {
            let result = limits_update_from(StateKind::Manipulate);
            kani::cover!(
                result == Err(LimitUpdateRefusal::NotAllowedInState(StateKind::Manipulate)),
                "manipulate: limits refused"
            );
        }
    }

    libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
        /// REQ-SM-007 in SafeStop (see [`limits_update_from`]).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_sm_007_limits_change_in_safe_stop() {
            let result = limits_update_from(StateKind::SafeStop);
            kani::cover!(result.is_ok(), "safe stop: limits taken");
            kani::cover!(result.is_err(), "safe stop: invalid limits refused");
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::kani_inputs::MANIPULATION_TARGET;
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
            for (name, harness) in [
                (
                    "step from grasp at a bad clock",
                    verify_req_panic_001_step_from_grasp_at_a_bad_clock as fn(),
                ),
                (
                    "step during estimation at a bad clock",
                    verify_req_panic_001_step_during_estimation_at_a_bad_clock,
                ),
                (
                    "step in validated at a bad clock",
                    verify_req_panic_001_step_in_validated_at_a_bad_clock,
                ),
                (
                    "step while manipulating at a bad clock",
                    verify_req_panic_001_step_while_manipulating_at_a_bad_clock,
                ),
            ] {
                kani::check(name, 1_000, harness);
            }
            kani::check(
                "a stop meets its contract",
                2_000,
                verify_req_cmd_001_a_stop_meets_its_contract,
            );
            kani::check(
                "a stop during a lift meets its contract",
                2_000,
                verify_req_cmd_001_a_stop_during_a_lift_meets_its_contract,
            );
            kani::check(
                "a stop during a lift at a bad clock meets its contract",
                2_000,
                verify_req_cmd_001_a_stop_during_a_lift_at_a_bad_clock_meets_its_contract,
            );
            kani::check(
                "latch: a step",
                2_000,
                verify_req_sm_006_a_step_keeps_the_stop,
            );
            kani::check(
                "latch: a request",
                2_000,
                verify_req_sm_006_a_request_keeps_the_stop,
            );
            kani::check("gating grasp", 1_000, verify_req_sm_005_gating_in_grasp);
            for (name, harness) in [
                (
                    "gating estimate: a start",
                    verify_req_sm_005_gating_in_estimate_refuses_a_start as fn(),
                ),
                (
                    "gating estimate: an approval",
                    verify_req_sm_005_gating_in_estimate_refuses_an_approval,
                ),
                (
                    "gating estimate: a finish",
                    verify_req_sm_005_gating_in_estimate_refuses_a_finish,
                ),
                (
                    "gating estimate: a reset",
                    verify_req_sm_005_gating_in_estimate_refuses_a_reset,
                ),
            ] {
                kani::check(name, 100, harness);
            }
            kani::check(
                "gating estimate: a stop",
                100,
                verify_req_sm_005_gating_in_estimate_a_stop,
            );
            kani::check(
                "gating validated",
                1_000,
                verify_req_sm_005_gating_in_validated,
            );
            kani::check(
                "gating manipulate",
                1_000,
                verify_req_sm_005_gating_in_manipulate,
            );
            kani::check(
                "gating safe stop",
                1_000,
                verify_req_sm_005_gating_in_safe_stop,
            );
            kani::check("clock", 5_000, verify_req_sm_004_requests_need_a_sane_clock);
            kani::check(
                "the clock first",
                5_000,
                verify_req_sm_004_the_clock_refuses_first,
            );
            kani::check(
                "limits in grasp",
                1_000,
                verify_req_sm_007_limits_change_in_grasp,
            );
            kani::check(
                "limits while estimating",
                1_000,
                verify_req_sm_007_limits_refused_while_estimating,
            );
            kani::check(
                "limits in validated",
                1_000,
                verify_req_sm_007_limits_change_in_validated,
            );
            kani::check(
                "limits while manipulating",
                1_000,
                verify_req_sm_007_limits_refused_while_manipulating,
            );
            kani::check(
                "limits in safe stop",
                1_000,
                verify_req_sm_007_limits_change_in_safe_stop,
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
                let command = kernel.step(Some(&frame), now);
                let limits = kernel.config().limits;
                prop_assert_eq!(check_step(before, &frame, now, &command, &limits), Ok(()));
                prop_assert_eq!(command.check(&limits), Ok(()));
            }
        }
    }
}
