//! The serial link at 200 Hz, host side.
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
//! [`pseudo_terminal`] opens a pty pair: its slave is a path a session
//! opens like a device's, its master the end a simulated device (the
//! `sim` feature's `device` module) or a test speaks on.

use crate::protocol::{status_control, Command, ControlType, Decoder, Telemetry, TELEMETRY_HEADER};
use crate::safety::{self, AreboLimit, AreboViolation, SafetyLimits};
use limb_kernel::monitor::Violation;
use limb_kernel::{StopCategory, StopReason};
use limb_session::clock::AlignedClock;
use serialport::{SerialPort, TTYPort};
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
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
