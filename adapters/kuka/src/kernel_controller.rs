//! The kernel behind the FRI session: a [`Controller`] that calls the
//! kernel's pure `step` once per monitoring message.
//!
//! Theory of operation, per handled monitoring message:
//! 1. the first message with a measured joint position records frame S
//!    (the process is started with the grasp closed: that flange pose is
//!    Σ_S, see [`crate::grasp_frame`]);
//! 2. measured joints → iiwa forward kinematics → grasp pose (x, z, ψ) in
//!    S; `externalTorque` → flange wrench F = (J Jᵀ)⁻¹ J τ → (fx, fz, ty) in
//!    S ([`crate::kinematics`]);
//! 3. kernel time = the robot's time stamp since the first message (kept
//!    monotone: never behind the last kernel time; the client's clock when
//!    a message has no time stamp); the operator ([`limb_sim::operator`]) may make a request
//!    — only while the robot is COMMANDING_ACTIVE with quality ≥ GOOD;
//! 4. if the robot is not commanding (overlay aborted, quality dropped,
//!    IDLE) while the kernel is moving the arm (Estimate, Manipulate), the
//!    kernel is asked to stop: the robot no longer follows, so the path and
//!    the move are void (safe stop, latched until an operator reset);
//! 5. `Kernel::step` → command → intent, by the configured overlay:
//!    joint position (set-point pose → flange target → damped least-squares
//!    inverse from the last target) or wrench (the kernel's wrench in the
//!    base frame as `cartesianWrenchFeedForward`).
//!
//! When the link is silent, [`Controller::on_link_stale`] steps the kernel
//! with the last frame at (last message time + silence): past the kernel's
//! `max_sensor_age` (20 ms) its watchdog trips the safe stop. A gap between
//! two robot time stamps longer than `max_sensor_age` is silence too: the
//! kernel is first stepped with the old frame at the new time (so an
//! unpaced simulation, whose clock is the plant's, trips the same way).

use limb_kernel::geometry::Wrench;
use limb_kernel::{Command, Kernel, KernelConfig, PathSample, Request, StateKind};
use limb_sim::operator::{completes_session, describe, FittedModel, Operator, SessionPlan};

use crate::grasp_frame::GraspFrame;
use crate::kinematics::{forward, inverse, wrench_from_joint_torque};
use crate::messages::{ConnectionQuality, SessionState};
use crate::session::{CartesianWrench, CommandIntent, Controller, JointVector, MonitoringView};

/// Tolerance of the inverse kinematics (m, rad mixed).
const INVERSE_TOLERANCE: f64 = 1e-9;
/// Iterations of the inverse per step (the target moves ≤ 0.15 mm per
/// millisecond, so two or three suffice; eight is a bound).
const INVERSE_ITERATIONS: usize = 8;

/// How the kernel's impedance output reaches the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Overlay {
    /// Joint-position targets (robot in joint impedance or position
    /// control, `clientCommandMode` POSITION).
    JointPosition,
    /// `cartesianWrenchFeedForward` (robot in Cartesian impedance,
    /// `clientCommandMode` WRENCH); joint position = IPO position.
    Wrench,
}

/// The configuration of the loop around the kernel.
#[derive(Debug, Clone, Copy)]
pub struct LoopSettings {
    /// Overlay the kernel's output is sent as.
    pub overlay: Overlay,
    /// Heading of S's x axis (wrist → shoulder) about base z [rad].
    pub heading: f64,
    /// The operator's plan (settle, manipulation target, hold).
    pub plan: SessionPlan,
}

/// What happened in the loop.
#[derive(Debug, Clone, Default)]
pub struct LoopRecord {
    /// Kernel steps taken (monitoring messages and stale ticks).
    pub steps: u64,
    /// Steps taken because the link was stale (receive timeout, or a gap
    /// between time stamps longer than the kernel's sensor-age limit).
    pub stale_steps: u64,
    /// Monitoring messages without a usable measured joint position.
    pub missing_measurements: u64,
    /// Set-points whose inverse kinematics did not converge (held).
    pub inverse_failures: u64,
    /// Stops requested because the robot stopped commanding mid-motion.
    pub overlay_lost_stops: u64,
    /// Kernel events in words, with kernel time [s].
    pub events: Vec<(f64, String)>,
    /// The model, the first time the kernel was in Validated.
    pub model: Option<FittedModel>,
    /// Manipulate → Validated happened.
    pub completed: bool,
    /// The last command.
    pub last_command: Option<Command>,
}

/// The kernel as an FRI [`Controller`].
pub struct KernelController {
    kernel: Box<Kernel>,
    operator: Operator,
    settings: LoopSettings,
    frame: Option<GraspFrame>,
    last_sample: Option<PathSample>,
    last_message_time: f64,
    last_now: f64,
    time_origin: Option<f64>,
    last_target: Option<JointVector>,
    record: LoopRecord,
}

impl KernelController {
    /// A controller running a kernel built from `config`.
    ///
    /// # Errors
    /// The kernel's configuration error, in words.
    pub fn new(config: KernelConfig, settings: LoopSettings) -> Result<Self, String> {
        let kernel =
            Kernel::new(config).map_err(|error| format!("kernel configuration: {error:?}"))?;
        Ok(Self {
            kernel: Box::new(kernel),
            operator: Operator::new(settings.plan),
            settings,
            frame: None,
            last_sample: None,
            last_message_time: 0.0,
            last_now: f64::NEG_INFINITY,
            time_origin: None,
            last_target: None,
            record: LoopRecord::default(),
        })
    }

    /// The kernel.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// The loop's record so far.
    pub fn record(&self) -> &LoopRecord {
        &self.record
    }

    /// Frame S, once recorded.
    pub fn grasp_frame(&self) -> Option<&GraspFrame> {
        self.frame.as_ref()
    }

    /// The frame-S sample of a measured joint position (recording frame S
    /// at the first one), `None` without a measurement.
    fn sample(&mut self, view: &MonitoringView, time: f64) -> Option<PathSample> {
        let joints = view.measured_joint_position?;
        let flange = forward(&joints);
        let heading = self.settings.heading;
        let frame = *self
            .frame
            .get_or_insert_with(|| GraspFrame::record(flange, heading));
        let (pose, _lateral) = frame.pose_in_s(&flange);
        let wrench = view
            .external_torque
            .and_then(|torque| wrench_from_joint_torque(&joints, &torque))
            .map_or(Wrench::ZERO, |base| frame.wrench_in_s(&base));
        if self.last_target.is_none() {
            self.last_target = Some(joints);
        }
        Some(PathSample { time, pose, wrench })
    }

    /// Steps the kernel and records what happened.
    fn step(&mut self, sample: &PathSample, now: f64) -> Command {
        self.last_now = now;
        let command = self.kernel.step(sample, now);
        self.record.steps += 1;
        self.operator.observe(command);
        self.drain_events();
        if self.record.model.is_none() {
            self.record.model = self.kernel.state().arm().map(FittedModel::of);
        }
        self.record.last_command = Some(command);
        command
    }

    fn drain_events(&mut self) {
        while let Some(event) = self.kernel.pop_event() {
            self.record.completed |= completes_session(&event);
            self.record.events.push((event.time, describe(&event)));
        }
    }

    fn request(&mut self, request: Request, now: f64) {
        // A refusal is recorded as a kernel event; nothing else to do.
        let _ = self.kernel.request(request, now);
        self.drain_events();
    }

    /// The intent for `command` under the configured overlay.
    fn intent(&mut self, command: &Command) -> CommandIntent {
        let Some(frame) = self.frame else {
            return CommandIntent::Hold;
        };
        match self.settings.overlay {
            Overlay::Wrench => {
                let base = frame.wrench_to_base(command.wrench);
                // KUKA order: Fx, Fy, Fz, then A (about z), B (y), C (x).
                let wrench: CartesianWrench =
                    [base[0], base[1], base[2], base[5], base[4], base[3]];
                CommandIntent::Wrench(wrench)
            }
            Overlay::JointPosition => {
                let (Some(set_point), Some(seed)) = (command.set_point, self.last_target) else {
                    return CommandIntent::Hold;
                };
                let target = frame.flange_target(set_point.pose);
                match inverse(&target, &seed, INVERSE_TOLERANCE, INVERSE_ITERATIONS) {
                    Ok(joints) => {
                        self.last_target = Some(joints);
                        CommandIntent::JointPosition(joints)
                    }
                    Err(_) => {
                        self.record.inverse_failures += 1;
                        CommandIntent::Hold
                    }
                }
            }
        }
    }
}

impl Controller for KernelController {
    fn on_monitoring(&mut self, view: &MonitoringView, now: f64) -> CommandIntent {
        let stamp = view.timestamp.unwrap_or(now);
        let origin = *self.time_origin.get_or_insert(stamp);
        let time = (stamp - origin).max(self.last_now);
        let Some(sample) = self.sample(view, time) else {
            self.record.missing_measurements += 1;
            return CommandIntent::Hold;
        };
        if let Some(last) = self.last_sample {
            // Silence seen on the robot's clock: before this frame, the
            // kernel's data was as old as the gap; the watchdog judges that.
            if time - last.time > self.kernel.config().limits.max_sensor_age {
                self.record.stale_steps += 1;
                self.step(&last, time);
            }
        }
        self.last_message_time = time;
        self.last_sample = Some(sample);
        let commanding = view.session_state == SessionState::CommandingActive
            && view.quality >= ConnectionQuality::Good;
        let moving = matches!(
            self.kernel.state().kind(),
            StateKind::Estimate | StateKind::Manipulate
        );
        if !commanding {
            // The robot holds its own position; rebase the inverse on it.
            self.last_target = view.measured_joint_position;
            if moving {
                self.record.overlay_lost_stops += 1;
                self.request(Request::Stop, time);
            }
        } else if let Some(request) = self.operator.request(self.kernel.state().kind(), time) {
            self.request(request, time);
        }
        let command = self.step(&sample, time);
        self.intent(&command)
    }

    fn on_link_stale(&mut self, silent_for: f64, _now: f64) {
        let Some(sample) = self.last_sample else {
            return;
        };
        let time = (self.last_message_time + silent_for).max(self.last_now);
        self.record.stale_steps += 1;
        self.step(&sample, time);
    }
}
