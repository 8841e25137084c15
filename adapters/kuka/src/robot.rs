//! The KUKA arm behind FRI as the robot of a `limb-session` session: FRI
//! monitoring messages in as kernel frames, kernel commands out as FRI
//! replies. Translation only; the loop, the clock, the watchdog and the
//! supervisor are the session's.
//!
//! Theory of operation, per handled monitoring message:
//! 1. the first message with a measured joint position records frame S
//!    (the process is started with the grasp closed: that flange pose is
//!    Σ_S, see [`crate::grasp_frame`]);
//! 2. measured joints → iiwa forward kinematics → grasp pose (x, z, ψ) and
//!    lateral y in S; `externalTorque` → flange wrench F = (J Jᵀ)⁻¹ J τ →
//!    (fx, fz, ty) in S ([`crate::kinematics`]);
//! 3. the frame's stamp is the robot's time stamp since its first message,
//!    exactly as the robot gave it (a clock that jumps back, stalls or
//!    repeats reaches the kernel's watchdog as it is); a message without a
//!    stamp is stamped with the client's receive time. Its arrival is the
//!    client's receive time;
//! 4. the robot follows commands only while COMMANDING_ACTIVE with quality
//!    GOOD or better ([`limb_session::Frame::following`]); while it does
//!    not, the joint target is rebased on the measured position;
//! 5. the kernel's command → intent, by the configured overlay: joint
//!    position (set-point pose → flange target → damped least-squares
//!    inverse from the last target) or wrench (the kernel's wrench in the
//!    base frame as `cartesianWrenchFeedForward`) → the FRI reply.
//!
//! A receive timeout with no handled message is [`Sensed::Silent`]: the
//! session steps the kernel with the last frame, and past its
//! `max_sensor_age` the watchdog trips the safe stop.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use limb_kernel::geometry::Wrench;
use limb_kernel::{Command, PathSample};
pub use limb_session::ArrivalClock;
use limb_session::{Frame, Robot, Sensed};

use crate::grasp_frame::GraspFrame;
use crate::kinematics::{forward, inverse, wrench_from_joint_torque};
use crate::messages::{ConnectionQuality, SessionState};
use crate::session::{CartesianWrench, CommandIntent, JointVector, MonitoringView};
use crate::udp::{ClientCounts, ClientError, FriClient, Receipt};

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

impl Overlay {
    /// Stable name, as `limb kuka run --overlay` spells it.
    pub const fn name(self) -> &'static str {
        match self {
            Overlay::JointPosition => "joint-position",
            Overlay::Wrench => "wrench",
        }
    }
}

/// What the translation counted.
#[derive(Debug, Clone, Copy, Default)]
pub struct FriRecord {
    /// Monitoring messages without a usable measured joint position
    /// (answered with hold, not shown to the kernel).
    pub missing_measurements: u64,
    /// Set-points whose inverse kinematics did not converge (held).
    pub inverse_failures: u64,
    /// The client's cycle counts.
    pub client: ClientCounts,
}

/// A KUKA arm behind an FRI client.
pub struct FriRobot {
    client: FriClient,
    overlay: Overlay,
    heading: f64,
    clock: ArrivalClock,
    frame: Option<GraspFrame>,
    time_origin: Option<f64>,
    last_arrival: f64,
    last_target: Option<JointVector>,
    end: Option<Instant>,
    stop: Option<Arc<AtomicBool>>,
    record: FriRecord,
}

impl FriRobot {
    /// The arm behind `client`, its kernel output sent as `overlay`, frame
    /// S's x axis (wrist → shoulder) at `heading` [rad] about base z; the
    /// session ends after `duration` (never when `None`).
    pub fn new(
        client: FriClient,
        overlay: Overlay,
        heading: f64,
        duration: Option<Duration>,
    ) -> Self {
        Self {
            client,
            overlay,
            heading,
            clock: ArrivalClock::Host,
            frame: None,
            time_origin: None,
            last_arrival: 0.0,
            last_target: None,
            end: duration.and_then(|d| Instant::now().checked_add(d)),
            stop: None,
            record: FriRecord::default(),
        }
    }

    /// Reads arrivals on `clock` (the default is [`ArrivalClock::Host`]).
    pub fn arrival_clock(&mut self, clock: ArrivalClock) {
        self.clock = clock;
    }

    /// Ends the session once `stop` is set (checked at each datagram and
    /// receive timeout).
    pub fn stop_when(&mut self, stop: Arc<AtomicBool>) {
        self.stop = Some(stop);
    }

    fn ended(&self) -> bool {
        self.end.is_some_and(|end| Instant::now() >= end)
            || self
                .stop
                .as_ref()
                .is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// What the translation counted.
    pub fn record(&self) -> &FriRecord {
        &self.record
    }

    /// Frame S, once recorded.
    pub fn grasp_frame(&self) -> Option<&GraspFrame> {
        self.frame.as_ref()
    }

    /// The kernel frame of a monitoring message received at `arrival`
    /// (recording frame S at the first one), `None` without a measurement.
    fn frame(&mut self, view: &MonitoringView, arrival: f64) -> Option<Frame> {
        let joints = view.measured_joint_position?;
        let stamp = view.timestamp.unwrap_or(arrival);
        let origin = *self.time_origin.get_or_insert(stamp);
        let arrival = match self.clock {
            ArrivalClock::Host => arrival,
            ArrivalClock::Robot => stamp - origin,
        };
        self.last_arrival = arrival;
        let flange = forward(&joints);
        let heading = self.heading;
        let frame = *self
            .frame
            .get_or_insert_with(|| GraspFrame::record(flange, heading));
        let (pose, lateral) = frame.pose_in_s(&flange);
        let wrench = view
            .external_torque
            .and_then(|torque| wrench_from_joint_torque(&joints, &torque))
            .map_or(Wrench::ZERO, |base| frame.wrench_in_s(&base));
        let following = view.session_state == SessionState::CommandingActive
            && view.quality >= ConnectionQuality::Good;
        if !following || self.last_target.is_none() {
            // The robot holds its own position; rebase the inverse on it.
            self.last_target = Some(joints);
        }
        Some(Frame {
            sample: PathSample {
                time: stamp - origin,
                pose,
                wrench,
            },
            lateral: Some(lateral),
            arrival,
            following,
        })
    }

    /// The intent for `command` under the configured overlay.
    fn intent(&mut self, command: &Command) -> CommandIntent {
        let Some(frame) = self.frame else {
            return CommandIntent::Hold;
        };
        match self.overlay {
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

impl Robot for FriRobot {
    type Error = ClientError;

    fn sense(&mut self) -> Result<Sensed, ClientError> {
        loop {
            let receipt = self.client.receive()?;
            if self.ended() {
                return Ok(Sensed::Ended);
            }
            match receipt {
                Receipt::Monitoring(view) => {
                    let arrival = self.client.received_at();
                    if let Some(frame) = self.frame(&view, arrival) {
                        return Ok(Sensed::Frame(frame));
                    }
                    self.record.missing_measurements += 1;
                    let outcome = self.client.answer(CommandIntent::Hold)?;
                    self.record.client.tally(&outcome);
                }
                Receipt::Done(outcome) => {
                    self.record.client.tally(&outcome);
                    if let Some(silence) = self.client.silence() {
                        return Ok(Sensed::Silent(match self.clock {
                            ArrivalClock::Host => self.client.clock(),
                            ArrivalClock::Robot => self.last_arrival + silence,
                        }));
                    }
                }
            }
        }
    }

    fn actuate(&mut self, command: &Command) -> Result<(), ClientError> {
        let intent = self.intent(command);
        let outcome = self.client.answer(intent)?;
        self.record.client.tally(&outcome);
        Ok(())
    }
}

impl limb_session::log::Logged for FriRobot {}
