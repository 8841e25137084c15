//! The serial link at 200 Hz (host side) and a simulated AREBO device
//! speaking the same protocol over a pseudo-terminal.
//!
//! # Theory of operation
//! [`Session`] opens a tty (a real `/dev/ttyACM*` or a pty's slave),
//! puts it in raw 115200 8N1 mode with a 0.1 s read timeout, sends a
//! heartbeat every 0.1 s, decodes stream frames with
//! [`crate::protocol::Decoder`] and checks their age with
//! [`crate::safety::check_fresh`]. A stale stream, a read error or a
//! vanished port latches [`SessionState::SafeStop`] and commands the
//! device's motors off (best effort: the device also stops assisting on
//! its own when heartbeats stop for 1 s).
//!
//! [`spawn_device`] runs the simulated robot ([`crate::sim`]) on the pty's
//! master in a thread: it executes commands, moves the SJM along a
//! trajectory and streams one frame per 5 ms of simulated time;
//! [`DeviceFault`] injects garbage, stalls or an unplug.

use crate::control::GravityParameters;
use crate::human::ShoulderAngles;
use crate::kinematics;
use crate::protocol::{
    Command, ControlType, Decoder, Telemetry, COMMAND_HEADER, ERROR_HEARTBEAT, TELEMETRY_HEADER,
};
use crate::safety::{self, AreboViolation, SafetyLimits};
use crate::sim::{self, RobotSensor, Setup, ShoulderJointModel};
use nix::sys::termios::{self, BaudRate, SetArg, SpecialCharacterIndices};
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::os::fd::AsFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Link failures.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// Opening, reading or writing the port failed.
    #[error("serial port I/O: {0}")]
    Io(#[from] std::io::Error),
    /// Configuring the terminal failed.
    #[error("terminal settings: {0}")]
    Terminal(#[from] nix::Error),
}

/// Raw 115200 8N1; reads return after `timeout_tenths` × 0.1 s without
/// data (0: immediately).
fn make_raw(fd: impl AsFd, timeout_tenths: u8) -> Result<(), LinkError> {
    let mut settings = termios::tcgetattr(&fd)?;
    termios::cfmakeraw(&mut settings);
    termios::cfsetspeed(&mut settings, BaudRate::B115200)?;
    settings.control_chars[SpecialCharacterIndices::VMIN as usize] = 0;
    settings.control_chars[SpecialCharacterIndices::VTIME as usize] = timeout_tenths;
    termios::tcsetattr(&fd, SetArg::TCSANOW, &settings)?;
    Ok(())
}

/// A pseudo-terminal pair: the device end and the path a host opens.
#[derive(Debug)]
pub struct PseudoTerminal {
    /// Master side (the simulated device's end).
    pub device: File,
    /// Path of the slave side (what a host opens, like `/dev/ttyACM0`).
    pub path: PathBuf,
    /// The slave kept open so the master does not hang up before a host
    /// opens the path.
    _slave: File,
}

/// Opens a raw pseudo-terminal pair.
///
/// # Errors
/// [`LinkError`] when the system has no free pty.
pub fn pseudo_terminal() -> Result<PseudoTerminal, LinkError> {
    let pair = nix::pty::openpty(None, None)?;
    make_raw(&pair.slave, 1)?;
    let path = nix::unistd::ttyname(&pair.slave)?;
    Ok(PseudoTerminal {
        device: File::from(pair.master),
        path,
        _slave: File::from(pair.slave),
    })
}

/// Why a session stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StopCause {
    /// A safety verdict (stale stream, limits).
    Violation(AreboViolation),
    /// The port failed (unplugged, closed).
    PortLost,
}

/// Host session state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SessionState {
    /// Frames arrive and are fresh.
    Running,
    /// Latched; commands the device off.
    SafeStop(StopCause),
}

/// Heartbeat period [s] (the device gives up after about 1 s).
pub const HEARTBEAT_PERIOD: f64 = 0.1;

/// The host end of the link.
#[derive(Debug)]
pub struct Session {
    port: File,
    decoder: Decoder,
    start: Instant,
    last_frame: Option<f64>,
    last_heartbeat: Option<f64>,
    limits: SafetyLimits,
    state: SessionState,
}

impl Session {
    /// Opens `path` and starts the stream.
    ///
    /// # Errors
    /// [`LinkError`] when the port cannot be opened or configured.
    pub fn open(path: &Path, limits: SafetyLimits) -> Result<Self, LinkError> {
        let port = OpenOptions::new().read(true).write(true).open(path)?;
        make_raw(&port, 1)?;
        let mut session = Self {
            port,
            decoder: Decoder::new(TELEMETRY_HEADER),
            start: Instant::now(),
            last_frame: None,
            last_heartbeat: None,
            limits,
            state: SessionState::Running,
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

    /// Sends a command.
    ///
    /// # Errors
    /// [`LinkError::Io`].
    pub fn send(&mut self, command: Command) -> Result<(), LinkError> {
        self.port.write_all(&command.encode())?;
        Ok(())
    }

    fn stop(&mut self, cause: StopCause) {
        if self.state == SessionState::Running {
            self.state = SessionState::SafeStop(cause);
            // Best effort: the port may be gone.
            let _ = self.send(Command::SetControlType(ControlType::Off));
        }
    }

    /// One poll: heartbeat when due, read what arrived (waits at most
    /// 0.1 s), decode, check freshness. Returns the frames decoded.
    pub fn poll(&mut self) -> Vec<Telemetry> {
        let now = self.now();
        if self
            .last_heartbeat
            .is_none_or(|t| now - t >= HEARTBEAT_PERIOD)
        {
            if self.send(Command::Heartbeat).is_err() {
                self.stop(StopCause::PortLost);
            }
            self.last_heartbeat = Some(now);
        }
        let mut bytes = [0u8; 512];
        let mut frames = Vec::new();
        match self.port.read(&mut bytes) {
            Ok(n) => {
                for byte in bytes.iter().take(n) {
                    if let Some(t) = self.decoder.push(*byte).and_then(|p| Telemetry::parse(&p)) {
                        frames.push(t);
                    }
                }
            }
            Err(_) => self.stop(StopCause::PortLost),
        }
        let now = self.now();
        if !frames.is_empty() {
            self.last_frame = Some(now);
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
            _ => DeviceFault::None,
        }
    }
}

/// What the simulated device reports when it ends.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceRecord {
    /// True shoulder angles per streamed frame (the SJM's encoders).
    pub truth: Vec<ShoulderAngles>,
    /// Frames streamed.
    pub frames: usize,
}

/// A trajectory the device's SJM follows (simulated time [s]).
pub type DeviceTrajectory = Box<dyn Fn(f64) -> (ShoulderAngles, [f64; 2]) + Send>;

/// Runs the simulated AREBO on `device` until it has streamed `frames`
/// frames (or spent 2 × `frames` periods), one period of `wall_period`
/// real time per frame; each streamed frame advances the simulation by
/// 5 ms.
pub fn spawn_device(
    device: File,
    setup: Setup,
    trajectory: DeviceTrajectory,
    frames: usize,
    wall_period: Duration,
    fault: FaultSwitch,
) -> Result<JoinHandle<DeviceRecord>, LinkError> {
    let mut writer = device.try_clone()?;
    let (commands, received) = mpsc::channel();
    let mut reader = device;
    // Reads block on a pty master; a helper thread forwards commands and
    // ends when the port closes.
    std::thread::spawn(move || {
        let mut decoder = Decoder::new(COMMAND_HEADER);
        let mut bytes = [0u8; 256];
        while let Ok(n) = reader.read(&mut bytes) {
            if n == 0 {
                break;
            }
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
        let mut sjm = ShoulderJointModel::new(setup, trajectory(0.0).0);
        let mut sensor = RobotSensor::new(setup.backlash);
        let mut record = DeviceRecord {
            truth: Vec::new(),
            frames: 0,
        };
        let (mut streaming, mut control, mut target) = (false, ControlType::Off, [0f32; 3]);
        let mut packet = 0u16;
        let start = Instant::now();
        let mut last_heartbeat = start;
        let mut counts = [0i32; 5];
        let mut garbage = sim::SplitMix64::new(7);
        // Simulated time runs while the device streams, so the motion
        // starts when a host starts the stream.
        let mut simulated = 0usize;
        // Idle (not streaming) periods count too, so a device nobody
        // starts still ends.
        for _ in 0..frames.saturating_mul(2) {
            if record.frames >= frames {
                break;
            }
            while let Ok(command) = received.try_recv() {
                match command {
                    Command::StartStream => streaming = true,
                    Command::StopStream => streaming = false,
                    Command::Heartbeat => last_heartbeat = Instant::now(),
                    Command::SetControlType(kind) => control = kind,
                    Command::SetControlTarget(torques) => target = torques,
                    Command::ResetPacketNumber => packet = 0,
                    Command::GetVersion | Command::Calibrate | Command::SetDiagnostics(_) => {}
                }
            }
            let heartbeat_missing = last_heartbeat.elapsed() > Duration::from_secs(1);
            let q = sim::actuated_angles(&counts);
            // Torque mode: the robot pushes the cuff with J_a^{-T} τ_d
            // (ideal torque tracking); off without a heartbeat.
            let torque_on = control == ControlType::Torque && !heartbeat_missing;
            let desired = nalgebra::Vector3::new(
                f64::from(target[0]),
                f64::from(target[1]),
                f64::from(target[2]),
            );
            let force = if torque_on {
                crate::control::interaction_force(q, &desired).unwrap_or_default()
            } else {
                nalgebra::Vector3::zeros()
            };
            if streaming {
                for k in 0..5 {
                    let t = (simulated * 5 + k) as f64 * sim::PHYSICS_STEP;
                    sjm.step(trajectory(t), &force);
                }
                simulated += 1;
            }
            if let Some(c) = sensor.read(&sjm.endpoint()) {
                counts = c;
            }
            let gravity = GravityParameters::ASSUMED.torques(sim::actuated_angles(&counts));
            let interaction = kinematics::joint_torques(sim::actuated_angles(&counts), &force);
            let sensed = gravity + interaction;
            let frame = Telemetry {
                status: u8::from(streaming) | ((control as u8) << 4),
                error: if heartbeat_missing {
                    ERROR_HEARTBEAT
                } else {
                    0
                },
                packet,
                run_time_ms: u32::try_from(start.elapsed().as_millis()).unwrap_or(u32::MAX),
                counts,
                torques: [sensed.x as f32, sensed.y as f32, sensed.z as f32],
                commanded: [gravity.x as f32, gravity.y as f32, gravity.z as f32],
            };
            packet = packet.wrapping_add(1);
            let fault = fault.get();
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
                record.truth.push(sjm.angles());
                record.frames += 1;
            }
            std::thread::sleep(wall_period);
        }
        record
    }))
}
