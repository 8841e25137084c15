//! The serial link at 200 Hz (host side) and a simulated AREBO device
//! speaking the same protocol over a pseudo-terminal.
//!
//! # Theory of operation
//! [`Session`] opens a tty (a real `/dev/ttyACM*` or a pty's slave) with
//! the `serialport` crate (115200 8N1 raw, exclusive, 0.1 s read timeout),
//! sends a heartbeat every [`HEARTBEAT_PERIOD`], decodes stream frames with
//! [`crate::protocol::Decoder`] and checks their age with
//! [`crate::safety::check_fresh`]. A stale stream, a read or write error, a
//! vanished port or a control type the device does not confirm latches
//! [`SessionState::SafeStop`] and commands the device what the stop's
//! category says ([`StopCause::category`]): gravity compensation, the
//! device's own fallback (it carries its own ≈ 32 N; the host can no longer
//! add the held arm's weight), or motors off only where the device's state
//! is not the one the host knows (best effort: the device also stops
//! assisting on its own when heartbeats stop for 1 s). The device's status and error bits are checked by the caller
//! against what it expects ([`crate::safety::check_device`]): the
//! supervisor in torque mode, the calibration in gravity compensation.
//!
//! [`spawn_device`] runs the simulated robot ([`crate::sim`]) on the pty's
//! master in a thread: it executes commands, moves the SJM along a
//! trajectory and streams one frame per 5 ms of simulated time;
//! [`DeviceFault`] injects garbage, stalls, an unplug or a lost heartbeat.

use crate::control::GravityParameters;
use crate::encoder::{actuated_angles, Encoder};
use crate::held_arm::HeldArm;
use crate::human::ShoulderAngles;
use crate::kinematics::{self, ElbowBranch, ShoulderBranch};
use crate::protocol::{
    status_byte, status_control, Command, ControlType, Decoder, Telemetry, COMMAND_HEADER,
    ERROR_HEARTBEAT, TELEMETRY_HEADER,
};
use crate::safety::{self, AreboLimit, AreboViolation, SafetyLimits};
use crate::sim::{self, RobotSensor, Setup, ShoulderJointModel};
use limb_kernel::monitor::Violation;
use limb_kernel::{StopCategory, StopReason};
use limb_session::clock::AlignedClock;
use nalgebra::Vector3;
use serialport::{SerialPort, TTYPort};
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Link failures.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// Reading or writing the port failed.
    #[error("serial port I/O: {0}")]
    Io(#[from] std::io::Error),
    /// Opening or configuring the port failed.
    #[error("serial port: {0}")]
    Port(#[from] serialport::Error),
    /// The session is in a safe stop (the cause says why).
    #[error("safe stop: {0:?}")]
    Stopped(StopCause),
}

/// Baud rate of the link.
pub const BAUD_RATE: u32 = 115_200;
/// Longest a read waits for data.
pub const READ_TIMEOUT: Duration = Duration::from_millis(100);
/// Longest the device may take to confirm a new control type [s].
pub const CONTROL_CONFIRMATION: f64 = 0.5;

/// A pseudo-terminal pair: the device end and the path a host opens.
pub struct PseudoTerminal {
    /// Master side (the simulated device's end).
    pub device: TTYPort,
    /// Path of the slave side (what a host opens, like `/dev/ttyACM0`).
    pub path: PathBuf,
    /// The slave kept open so the master does not hang up before a host
    /// opens the path.
    _slave: TTYPort,
}

impl core::fmt::Debug for PseudoTerminal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "PseudoTerminal({})", self.path.display())
    }
}

/// Opens a raw pseudo-terminal pair.
///
/// # Errors
/// [`LinkError`] when the system has no free pty.
pub fn pseudo_terminal() -> Result<PseudoTerminal, LinkError> {
    let (device, slave) = TTYPort::pair()?;
    let path = slave
        .name()
        .map(PathBuf::from)
        .ok_or(serialport::Error::new(
            serialport::ErrorKind::NoDevice,
            "the pty has no slave path",
        ))?;
    Ok(PseudoTerminal {
        device,
        path,
        _slave: slave,
    })
}

/// Why a session stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StopCause {
    /// A safety verdict (stale stream, limits, device status).
    Violation(AreboViolation),
    /// The port failed (unplugged, closed, a write that did not go out).
    PortLost,
}

impl StopCause {
    /// The stop category of the host's own stop (`limb_kernel::stop`): a
    /// limit the kernel also has, the kernel's category; a shoulder angle
    /// out of range a hold (as the kernel's joint limits); the device's
    /// heartbeat or torque-sensor fault and a lost port a ramp-down (the
    /// device has stopped applying the host's target, or the host cannot
    /// reach it: its gravity compensation remains); an unknown device error
    /// or a control type the host did not set motors off (the device is
    /// not in the state the host knows, so holding is itself the hazard).
    /// The link applies [`StopCategory::MotorsOff`] as control type 0 and
    /// both others as gravity compensation.
    pub fn category(&self) -> StopCategory {
        let StopCause::Violation(v) = self else {
            return StopCategory::RampDown;
        };
        match v.limit {
            AreboLimit::Kernel(limit) => {
                StopReason::Monitor(Violation::new(limit, v.value, v.bound)).category()
            }
            AreboLimit::Flexion | AreboLimit::Abduction => StopCategory::Hold,
            AreboLimit::DeviceHeartbeatMissing | AreboLimit::TorqueSensorFault => {
                StopCategory::RampDown
            }
            AreboLimit::UnknownDeviceError | AreboLimit::ControlType => StopCategory::MotorsOff,
        }
    }
}

/// The control type that applies `category` on AREBO: motors off only for
/// [`StopCategory::MotorsOff`], else the device's gravity compensation.
pub fn stop_control(category: StopCategory) -> ControlType {
    match category {
        StopCategory::MotorsOff => ControlType::Off,
        StopCategory::Hold | StopCategory::RampDown => ControlType::GravityCompensation,
    }
}

impl core::fmt::Display for StopCause {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StopCause::Violation(v) => write!(f, "violation: {v}"),
            StopCause::PortLost => f.write_str("port_lost"),
        }
    }
}

/// Host session state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SessionState {
    /// Frames arrive and are fresh.
    Running,
    /// Latched; the device given its stop category's control type.
    SafeStop(StopCause),
}

/// Heartbeat period [s] (the device gives up after about 1 s).
pub const HEARTBEAT_PERIOD: f64 = 0.1;

/// One decoded stream frame with its time on the session clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Received {
    /// The frame.
    pub telemetry: Telemetry,
    /// When the device measured it [s, session clock]: the read's host
    /// time less the frame's age on the device's own clock (its run time,
    /// aligned as `limb_session::clock::AlignedClock` aligns a robot's
    /// stamps). A frame read from a backlog, or one whose run time stopped,
    /// is as old as the device's clock says, not as fresh as the read.
    pub time: f64,
    /// When the host read it [s, session clock].
    pub read_at: f64,
}

/// The host end of the link.
pub struct Session {
    port: TTYPort,
    decoder: Decoder,
    start: Instant,
    last_frame: Option<f64>,
    last_heartbeat: Option<f64>,
    limits: SafetyLimits,
    state: SessionState,
    /// Frames with a valid checksum whose payload is not a stream frame.
    unparsed: u32,
    /// The device's run time against the session clock.
    clock: AlignedClock,
    /// Packet number of the last stream frame.
    last_packet: Option<u16>,
    /// Stream frames whose packet number did not follow the last one's.
    packet_gaps: u32,
}

impl Session {
    /// Opens `path` and starts the stream.
    ///
    /// # Errors
    /// [`LinkError`] when the port cannot be opened or configured.
    pub fn open(path: &Path, limits: SafetyLimits) -> Result<Self, LinkError> {
        let port = serialport::new(path.to_string_lossy(), BAUD_RATE)
            .timeout(READ_TIMEOUT)
            .open_native()?;
        let mut session = Self {
            port,
            decoder: Decoder::new(TELEMETRY_HEADER),
            start: Instant::now(),
            last_frame: None,
            last_heartbeat: None,
            limits,
            state: SessionState::Running,
            unparsed: 0,
            clock: AlignedClock::default(),
            last_packet: None,
            packet_gaps: 0,
        };
        session.send(Command::StartStream)?;
        Ok(session)
    }

    /// Seconds since the session opened (the session's clock).
    pub fn now(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// The session state.
    pub fn state(&self) -> SessionState {
        self.state
    }

    /// Decoder counters (frames, checksum errors, discarded bytes).
    pub fn stats(&self) -> crate::protocol::DecoderStats {
        self.decoder.stats
    }

    /// Frames with a valid checksum that were not a 53-byte stream frame
    /// (dropped, counted here).
    pub fn unparsed_frames(&self) -> u32 {
        self.unparsed
    }

    /// Stream frames whose packet number did not follow the last one's
    /// (lost, repeated or reordered frames; a reset packet number once).
    pub fn packet_gaps(&self) -> u32 {
        self.packet_gaps
    }

    /// The frame's time on the session clock (see [`Received::time`]),
    /// counting a gap in its packet number.
    fn received(&mut self, telemetry: Telemetry, read_at: f64) -> Received {
        if self
            .last_packet
            .is_some_and(|last| telemetry.packet != last.wrapping_add(1))
        {
            self.packet_gaps = self.packet_gaps.saturating_add(1);
        }
        self.last_packet = Some(telemetry.packet);
        let stamp = f64::from(telemetry.run_time_ms) * 1e-3;
        let device_now = self.clock.frame(stamp, read_at);
        Received {
            telemetry,
            time: read_at - (device_now - stamp),
            read_at,
        }
    }

    /// Sends a command. A write that fails latches the safe stop (and tries
    /// to command the motors off).
    ///
    /// # Errors
    /// [`LinkError::Io`] when the write failed.
    pub fn send(&mut self, command: Command) -> Result<(), LinkError> {
        let written = self.port.write_all(&command.encode());
        if written.is_err() {
            self.stop(StopCause::PortLost);
        }
        Ok(written?)
    }

    /// Latches the safe stop with `cause` (the first cause is kept) and
    /// commands the device its category's control type ([`stop_control`]),
    /// best effort: the port may be gone.
    pub fn stop(&mut self, cause: StopCause) {
        if self.state == SessionState::Running {
            self.state = SessionState::SafeStop(cause);
            let control = stop_control(cause.category());
            let _ = self
                .port
                .write_all(&Command::SetControlType(control).encode());
        }
    }

    /// The end of a session: a stopped session gives the device its stop
    /// category's control type again, a running one gravity compensation,
    /// the device's own fallback (it carries its own weight; the arm rests
    /// on its support). Best effort: the port may be gone.
    pub fn finish(&mut self) {
        let control = match self.state {
            SessionState::SafeStop(cause) => stop_control(cause.category()),
            SessionState::Running => ControlType::GravityCompensation,
        };
        let _ = self
            .port
            .write_all(&Command::SetControlType(control).encode());
    }

    /// Sets the device's control type and waits until a frame reports it
    /// (at most [`CONTROL_CONFIRMATION`]); returns the frames from the
    /// confirming one on (those before it are dropped).
    ///
    /// # Errors
    /// [`LinkError::Stopped`] when the device did not confirm (the session
    /// is then in a safe stop with an [`AreboLimit::ControlType`] verdict)
    /// or the session stopped meanwhile.
    pub fn set_control(&mut self, control: ControlType) -> Result<Vec<Received>, LinkError> {
        self.send(Command::SetControlType(control))?;
        let deadline = self.now() + CONTROL_CONFIRMATION;
        let mut reported = None;
        while self.now() < deadline {
            let mut frames = self.poll();
            for (i, frame) in frames.iter().enumerate() {
                reported = status_control(frame.telemetry.status);
                if reported == Some(control) {
                    return Ok(frames.split_off(i));
                }
            }
            if let SessionState::SafeStop(cause) = self.state {
                return Err(LinkError::Stopped(cause));
            }
        }
        let cause = StopCause::Violation(AreboViolation {
            limit: AreboLimit::ControlType,
            value: f64::from(reported.map_or(3, |c| c as u8)),
            bound: f64::from(control as u8),
        });
        self.stop(cause);
        Err(LinkError::Stopped(cause))
    }

    /// One poll: heartbeat when due, read what arrived (waits at most
    /// [`READ_TIMEOUT`]), decode, check freshness: every frame's age on the
    /// device's clock (a backlog read after a host stall, or a device clock
    /// that stopped, is stale), and the time since the newest. Returns the
    /// frames decoded, stamped with their time on the session clock.
    pub fn poll(&mut self) -> Vec<Received> {
        let now = self.now();
        if self
            .last_heartbeat
            .is_none_or(|t| now - t >= HEARTBEAT_PERIOD)
        {
            // A failed write latches the stop inside `send`.
            let _ = self.send(Command::Heartbeat);
            self.last_heartbeat = Some(now);
        }
        // Large enough to drain a backlog quickly (a frame is 57 bytes).
        let mut bytes = [0u8; 4096];
        let mut frames = Vec::new();
        let read = match self.port.read(&mut bytes) {
            Err(e) if e.kind() == ErrorKind::TimedOut => Ok(0),
            other => other,
        };
        let now = self.now();
        match read {
            Ok(n) => {
                for byte in bytes.iter().take(n) {
                    let Some(payload) = self.decoder.push(*byte) else {
                        continue;
                    };
                    match Telemetry::parse(&payload) {
                        Some(telemetry) => {
                            let frame = self.received(telemetry, now);
                            frames.push(frame);
                        }
                        None => self.unparsed = self.unparsed.saturating_add(1),
                    }
                }
            }
            Err(_) => self.stop(StopCause::PortLost),
        }
        for frame in &frames {
            if let Err(violation) = safety::check_fresh(Some(frame.time), now, &self.limits) {
                self.stop(StopCause::Violation(violation));
            }
            self.last_frame = Some(self.last_frame.map_or(frame.time, |t| t.max(frame.time)));
        }
        if let Err(violation) = safety::check_fresh(self.last_frame, now, &self.limits) {
            // Before the first frame, allow one stale period for start-up.
            if self.last_frame.is_some() || now > self.limits.stale_after + 0.5 {
                self.stop(StopCause::Violation(violation));
            }
        }
        frames
    }
}

/// Faults the simulated device can be told to show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum DeviceFault {
    /// Normal streaming.
    None = 0,
    /// Garbage, a truncated frame and a frame with a wrong checksum before
    /// every valid frame.
    Garbage = 1,
    /// Stops sending (the firmware hangs).
    Stall = 2,
    /// Closes the port (USB unplugged).
    Unplug = 3,
    /// Behaves as if the host's heartbeats stopped arriving: reports
    /// [`ERROR_HEARTBEAT`] and stops applying the torque target.
    HeartbeatLost = 4,
    /// Keeps streaming, its run time stopped (a hung firmware clock).
    FrozenClock = 5,
}

/// Shared switch for [`DeviceFault`].
#[derive(Clone, Debug, Default)]
pub struct FaultSwitch(Arc<AtomicU8>);

impl FaultSwitch {
    /// Sets the fault.
    pub fn set(&self, fault: DeviceFault) {
        self.0.store(fault as u8, Ordering::SeqCst);
    }

    fn get(&self) -> DeviceFault {
        match self.0.load(Ordering::SeqCst) {
            1 => DeviceFault::Garbage,
            2 => DeviceFault::Stall,
            3 => DeviceFault::Unplug,
            4 => DeviceFault::HeartbeatLost,
            5 => DeviceFault::FrozenClock,
            _ => DeviceFault::None,
        }
    }
}

/// What the simulated device reports when it ends.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceRecord {
    /// True shoulder angles per streamed frame (the SJM's encoders).
    pub truth: Vec<ShoulderAngles>,
    /// The control type the device ran per streamed frame.
    pub control: Vec<ControlType>,
    /// Every control type the host set, in order (those after the last
    /// streamed frame too: a session's end).
    pub set_controls: Vec<ControlType>,
    /// Frames streamed.
    pub frames: usize,
}

/// A trajectory the device's SJM follows (simulated time [s]).
pub type DeviceTrajectory = Box<dyn Fn(f64) -> (ShoulderAngles, [f64; 2]) + Send>;

/// What the simulated device's cuff holds.
pub trait Person: Send {
    /// Advances one stream period with the robot pushing the cuff with
    /// `force` [N, R0]; `moved`: periods since the person started.
    fn advance(&mut self, moved: usize, force: &Vector3<f64>);
    /// The cuff centre [m, R0].
    fn cuff(&self) -> Vector3<f64>;
    /// The cuff's roll axis z_R5 [R0], when the person turns it (θ4, θ5
    /// then follow it; otherwise they read 0).
    fn cuff_axis(&self) -> Option<Vector3<f64>> {
        None
    }
    /// The person's own angles for the record (the SJM's φ; the held
    /// arm's shoulder elevation q1 as `flexion`, elbow flexion q2 as
    /// `abduction`).
    fn angles(&self) -> ShoulderAngles;
}

/// The shoulder joint model following a trajectory from the person's
/// start (the paper's experiments).
struct Shoulder {
    sjm: ShoulderJointModel,
    trajectory: DeviceTrajectory,
}

impl Person for Shoulder {
    fn advance(&mut self, moved: usize, force: &Vector3<f64>) {
        for k in 0..5 {
            let t = (moved * 5 + k) as f64 * sim::PHYSICS_STEP;
            self.sjm.step((self.trajectory)(t), force);
        }
    }

    fn cuff(&self) -> Vector3<f64> {
        self.sjm.endpoint()
    }

    fn angles(&self) -> ShoulderAngles {
        self.sjm.angles()
    }
}

/// The kernel's reference arm held at the wrist ([`HeldArm`]).
impl Person for HeldArm {
    fn advance(&mut self, _: usize, force: &Vector3<f64>) {
        HeldArm::advance(self, force, sim::SAMPLE_PERIOD);
    }

    fn cuff(&self) -> Vector3<f64> {
        HeldArm::cuff(self)
    }

    fn cuff_axis(&self) -> Option<Vector3<f64>> {
        Some(self.forearm())
    }

    fn angles(&self) -> ShoulderAngles {
        let [q1, q2] = self.joints();
        ShoulderAngles {
            flexion: q1,
            abduction: q2,
        }
    }
}

/// How the simulated device paces its stream periods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DevicePacing {
    /// A sleep of this much real time after each period.
    Wall(Duration),
    /// In torque mode, each period waits for the host's target answering
    /// the last frame (at most [`LOCK_STEP_TIMEOUT`]): a simulation whose
    /// loop closes however loaded the machine is, as fast as the host
    /// answers. Other control types (and a device not streaming) take one
    /// sample period of real time per period.
    LockStep,
}

/// Longest a lock-stepped device waits for the host's target.
pub const LOCK_STEP_TIMEOUT: Duration = Duration::from_secs(1);

/// What the host's commands set on the simulated device.
struct Inputs {
    streaming: bool,
    control: ControlType,
    target: [f32; 3],
    packet: u16,
    last_heartbeat: Instant,
    set_controls: Vec<ControlType>,
}

impl Inputs {
    /// Applies `command`; true when it was a control target.
    fn apply(&mut self, command: Command) -> bool {
        match command {
            Command::StartStream => self.streaming = true,
            Command::StopStream => self.streaming = false,
            Command::Heartbeat => self.last_heartbeat = Instant::now(),
            Command::SetControlType(kind) => {
                self.control = kind;
                self.set_controls.push(kind);
            }
            Command::SetControlTarget(torques) => {
                self.target = torques;
                return true;
            }
            Command::ResetPacketNumber => self.packet = 0,
            Command::GetVersion | Command::Calibrate | Command::SetDiagnostics(_) => {}
        }
        false
    }
}

/// Longest the simulated device waits to write a frame into a full pty.
const DEVICE_WRITE_TIMEOUT: Duration = Duration::from_secs(30);

/// Runs the simulated AREBO on `device` until it has streamed `frames`
/// frames (or spent 2 × `frames` periods), one period of `wall_period`
/// real time per frame; each streamed frame advances the simulation by
/// 5 ms, and the frame's run time is that simulated time. The simulated
/// person starts `trajectory` (its time 0) at the first streamed frame in
/// which the motors are on.
///
/// The robot acts on the cuff by its control type: motors off, its weight
/// rests on the person's arm (f = −J_a^{-T} τ_g, about 25-35 N); gravity
/// compensation holds its own weight (no force); torque mode applies the
/// target τ_d as an ideal force J_a^{-T} τ_d, until the host's heartbeat is
/// missing for 1 s, when it falls back to gravity compensation and reports
/// [`ERROR_HEARTBEAT`].
///
/// # Errors
/// [`LinkError`] when the port cannot be cloned.
pub fn spawn_device(
    device: TTYPort,
    setup: Setup,
    trajectory: DeviceTrajectory,
    frames: usize,
    wall_period: Duration,
    fault: FaultSwitch,
) -> Result<JoinHandle<DeviceRecord>, LinkError> {
    let person = Shoulder {
        sjm: ShoulderJointModel::new(setup, trajectory(0.0).0),
        trajectory,
    };
    let pacing = DevicePacing::Wall(wall_period);
    spawn_device_holding(device, setup, Box::new(person), frames, pacing, fault)
}

/// [`spawn_device_holding`] the kernel's reference arm
/// ([`HeldArm::reference`]) with no backlash.
///
/// # Errors
/// [`LinkError`] when the port cannot be cloned.
pub fn spawn_held_arm(
    device: TTYPort,
    frames: usize,
    pacing: DevicePacing,
) -> Result<JoinHandle<DeviceRecord>, LinkError> {
    let setup = Setup {
        backlash: [0.0; 3],
        ..Setup::default()
    };
    let arm = Box::new(HeldArm::reference());
    spawn_device_holding(device, setup, arm, frames, pacing, FaultSwitch::default())
}

/// [`spawn_device`] with the cuff on `person` (e.g. the kernel's reference
/// arm held at the wrist, [`HeldArm`]), which starts moving at the first
/// streamed frame in which the motors are on, paced by `pacing`.
///
/// # Errors
/// [`LinkError`] when the port cannot be cloned.
pub fn spawn_device_holding(
    device: TTYPort,
    setup: Setup,
    mut person: Box<dyn Person>,
    frames: usize,
    pacing: DevicePacing,
    fault: FaultSwitch,
) -> Result<JoinHandle<DeviceRecord>, LinkError> {
    let mut writer = device.try_clone_native()?;
    // A simulated device waits for a slow host rather than ending (a test
    // machine under load must not turn into a device fault).
    writer.set_timeout(DEVICE_WRITE_TIMEOUT)?;
    let (commands, received) = mpsc::channel();
    let mut reader = device;
    // A helper thread forwards commands; it ends when the port closes or
    // the device thread has ended.
    std::thread::spawn(move || {
        let mut decoder = Decoder::new(COMMAND_HEADER);
        let mut bytes = [0u8; 256];
        loop {
            let n = match reader.read(&mut bytes) {
                Ok(0) => return,
                Ok(n) => n,
                Err(e) if e.kind() == ErrorKind::TimedOut => 0,
                Err(_) => return,
            };
            for byte in bytes.iter().take(n) {
                if let Some(command) = decoder.push(*byte).and_then(|p| Command::parse(&p)) {
                    if commands.send(command).is_err() {
                        return;
                    }
                }
            }
        }
    });
    Ok(std::thread::spawn(move || {
        let mut sensor = RobotSensor::new(setup.backlash);
        let mut record = DeviceRecord {
            truth: Vec::new(),
            control: Vec::new(),
            set_controls: Vec::new(),
            frames: 0,
        };
        let mut inputs = Inputs {
            streaming: false,
            control: ControlType::Off,
            target: [0f32; 3],
            packet: 0,
            last_heartbeat: Instant::now(),
            set_controls: Vec::new(),
        };
        let mut awaiting_target = false;
        let mut counts = [0i32; 5];
        let mut garbage = sim::SplitMix64::new(7);
        // The device's clock runs while it streams; the person follows the
        // trajectory from when the robot first carries its own weight
        // (told to start once it is gravity compensated).
        let mut simulated = 0usize;
        let mut run_time = 0.0;
        let mut started: Option<usize> = None;
        // Idle (not streaming) periods count too, so a device nobody
        // starts still ends.
        for _ in 0..frames.saturating_mul(2) {
            if record.frames >= frames {
                break;
            }
            if awaiting_target {
                let deadline = Instant::now() + LOCK_STEP_TIMEOUT;
                while let Some(left) = deadline.checked_duration_since(Instant::now()) {
                    match received.recv_timeout(left) {
                        Ok(command) if inputs.apply(command) => break,
                        Ok(_) => {}
                        Err(_) => break,
                    }
                }
            }
            while let Ok(command) = received.try_recv() {
                inputs.apply(command);
            }
            let Inputs {
                streaming,
                control,
                target,
                last_heartbeat,
                ..
            } = inputs;
            let fault = fault.get();
            let heartbeat_missing = last_heartbeat.elapsed() > Duration::from_secs(1)
                || fault == DeviceFault::HeartbeatLost;
            let q = actuated_angles(&counts);
            let gravity = GravityParameters::ASSUMED.torques(q);
            let applied = match control {
                ControlType::Off => -gravity,
                ControlType::Torque if !heartbeat_missing => nalgebra::Vector3::new(
                    f64::from(target[0]),
                    f64::from(target[1]),
                    f64::from(target[2]),
                ),
                ControlType::Torque | ControlType::GravityCompensation => {
                    nalgebra::Vector3::zeros()
                }
            };
            let force = crate::control::interaction_force(q, &applied).unwrap_or_default();
            if streaming {
                if control != ControlType::Off {
                    started.get_or_insert(simulated);
                }
                let moved = started.map_or(0, |started| simulated - started);
                person.advance(moved, &force);
                simulated += 1;
            }
            let cuff = person.cuff();
            if let Some(c) = sensor.read(&cuff) {
                counts = c;
            }
            // θ4, θ5 (joint-side encoders) follow the cuff's roll axis
            // from the true link angles.
            let distal = person.cuff_axis().and_then(|axis| {
                let link = kinematics::inverse(&cuff, ShoulderBranch::Front, ElbowBranch::Negative);
                link.ok().and_then(|q| kinematics::distal_angles(q, &axis))
            });
            if let Some([t4, t5]) = distal {
                counts[3] = Encoder::Distal.counts(t4);
                counts[4] = Encoder::Distal.counts(t5);
            }
            let q = actuated_angles(&counts);
            let gravity = GravityParameters::ASSUMED.torques(q);
            let interaction = kinematics::joint_torques(q, &force);
            // The sensors read the robot's weight unless the motors are off
            // (then the cuff carries it), plus the interaction.
            let held = if control == ControlType::Off {
                nalgebra::Vector3::zeros()
            } else {
                gravity
            };
            let sensed = held + interaction;
            if fault != DeviceFault::FrozenClock {
                run_time = simulated as f64 * sim::SAMPLE_PERIOD * 1000.0;
            }
            let frame = Telemetry {
                status: status_byte(streaming, control),
                error: if heartbeat_missing {
                    ERROR_HEARTBEAT
                } else {
                    0
                },
                packet: inputs.packet,
                run_time_ms: run_time as u32,
                counts,
                torques: [sensed.x as f32, sensed.y as f32, sensed.z as f32],
                commanded: [held.x as f32, held.y as f32, held.z as f32],
            };
            inputs.packet = inputs.packet.wrapping_add(1);
            if fault == DeviceFault::Unplug {
                break;
            }
            if streaming && fault != DeviceFault::Stall {
                let mut bytes = Vec::new();
                if fault == DeviceFault::Garbage {
                    bytes.extend((0..17).map(|_| (garbage.uniform() * 256.0) as u8));
                    let valid = frame.encode();
                    bytes.extend_from_slice(&valid[..20]);
                    let mut corrupt = valid.clone();
                    corrupt[30] ^= 0xA5;
                    bytes.extend_from_slice(&corrupt);
                }
                bytes.extend_from_slice(&frame.encode());
                if writer.write_all(&bytes).is_err() {
                    break;
                }
                record.truth.push(person.angles());
                record.control.push(control);
                record.frames += 1;
            }
            match pacing {
                DevicePacing::Wall(period) => std::thread::sleep(period),
                DevicePacing::LockStep => {
                    awaiting_target = streaming && control == ControlType::Torque;
                    if !awaiting_target {
                        std::thread::sleep(Duration::from_secs_f64(sim::SAMPLE_PERIOD));
                    }
                }
            }
        }
        // What the host still sent (its session's end) until it closed,
        // for at most 0.5 s.
        let deadline = Instant::now() + Duration::from_millis(500);
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match received.recv_timeout(left) {
                Ok(command) => {
                    inputs.apply(command);
                }
                Err(_) => break,
            }
        }
        record.set_controls = inputs.set_controls;
        record
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use limb_kernel::monitor::Limit;

    /// REQ-STOP-001: the host's own stops on AREBO, each cause its
    /// category and control type: gravity compensation (the device's own
    /// fallback) for every cause but a device whose state the host does
    /// not know, which is switched off; changing one fails here.
    #[test]
    fn req_stop_001_each_host_stop_has_its_category_and_control_type() {
        use ControlType::{GravityCompensation, Off};
        use StopCategory::{Hold, MotorsOff, RampDown};
        let verdict = |limit| {
            StopCause::Violation(AreboViolation {
                limit,
                value: 1.0,
                bound: 0.0,
            })
        };
        let table = [
            (StopCause::PortLost, RampDown, GravityCompensation),
            (
                verdict(AreboLimit::Kernel(Limit::StaleSensor)),
                RampDown,
                GravityCompensation,
            ),
            (
                verdict(AreboLimit::Kernel(Limit::ForceMagnitude)),
                RampDown,
                GravityCompensation,
            ),
            (
                verdict(AreboLimit::Kernel(Limit::Speed)),
                Hold,
                GravityCompensation,
            ),
            (verdict(AreboLimit::Flexion), Hold, GravityCompensation),
            (verdict(AreboLimit::Abduction), Hold, GravityCompensation),
            (
                verdict(AreboLimit::DeviceHeartbeatMissing),
                RampDown,
                GravityCompensation,
            ),
            (
                verdict(AreboLimit::TorqueSensorFault),
                RampDown,
                GravityCompensation,
            ),
            (verdict(AreboLimit::UnknownDeviceError), MotorsOff, Off),
            (verdict(AreboLimit::ControlType), MotorsOff, Off),
        ];
        for (cause, category, control) in table {
            assert_eq!(cause.category(), category, "{cause}");
            assert_eq!(stop_control(cause.category()), control, "{cause}");
        }
    }
}
