//! The simulated device's firmware loop: the host's commands in, one
//! stream frame out per period, each period 5 ms of simulated time.
//!
//! # Theory of operation
//! Per period: apply the host's commands (a lock-stepped device in torque
//! mode first waits for the target answering its last frame), the robot's
//! force on the cuff by its control type, the person moved one period
//! under it (while streaming), the encoders read off the cuff, the frame
//! formed (the torque sensors: the robot's weight unless the motors are
//! off, plus the interaction) and, while streaming, written to the pty,
//! then the period paced ([`DevicePacing`]). [`DeviceFault`] corrupts,
//! withholds or ends the stream, or freezes the run time.

use super::fault::{DeviceFault, FaultSwitch};
use super::person::Person;
use crate::control::{interaction_force, GravityParameters};
use crate::encoder::{actuated_angles, Encoder};
use crate::human::ShoulderAngles;
use crate::kinematics::{self, ElbowBranch, ShoulderBranch};
use crate::protocol::{
    status_byte, Command, ControlType, Decoder, Telemetry, COMMAND_HEADER, ERROR_HEARTBEAT,
};
use crate::sim::{self, RobotSensor, SplitMix64};
use nalgebra::Vector3;
use serialport::TTYPort;
use std::io::{ErrorKind, Read, Write};
use std::sync::mpsc::{Receiver, Sender};
use std::time::{Duration, Instant};

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

/// Decodes the host's commands from `port` into `commands` until the port
/// closes or fails, or the device has ended (`commands` disconnected).
pub(super) fn forward_commands(mut port: TTYPort, commands: Sender<Command>) {
    let mut decoder = Decoder::new(COMMAND_HEADER);
    let mut bytes = [0u8; 256];
    loop {
        let n = match port.read(&mut bytes) {
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
}

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

/// The simulated device between periods.
pub(super) struct Device {
    person: Box<dyn Person>,
    sensor: RobotSensor,
    inputs: Inputs,
    /// The last encoder counts θ1..θ5.
    counts: [i32; 5],
    /// The bytes of [`DeviceFault::Garbage`].
    garbage: SplitMix64,
    /// Streamed periods simulated.
    simulated: usize,
    /// The device's run time [ms]: the simulated time, unless frozen.
    run_time: f64,
    /// The period the person started in.
    started: Option<usize>,
    record: DeviceRecord,
}

impl Device {
    /// A device, not streaming, motors off, its cuff on `person`, reading
    /// θ1..θ3 through `backlash` [rad] of play; the host's heartbeat
    /// counts from now.
    pub(super) fn new(person: Box<dyn Person>, backlash: [f64; 3]) -> Self {
        Self {
            person,
            sensor: RobotSensor::new(backlash),
            inputs: Inputs {
                streaming: false,
                control: ControlType::Off,
                target: [0f32; 3],
                packet: 0,
                last_heartbeat: Instant::now(),
                set_controls: Vec::new(),
            },
            counts: [0i32; 5],
            garbage: SplitMix64::new(7),
            // The device's clock runs while it streams; the person follows
            // the trajectory from when the robot first carries its own
            // weight (told to start once it is gravity compensated).
            simulated: 0,
            run_time: 0.0,
            started: None,
            record: DeviceRecord {
                truth: Vec::new(),
                control: Vec::new(),
                set_controls: Vec::new(),
                frames: 0,
            },
        }
    }

    /// Runs periods on `writer` until `frames` frames are streamed (or
    /// 2 × `frames` periods have passed), taking the host's `commands`,
    /// showing what `fault` says and paced by `pacing`; then takes what
    /// the host still sends (its session's end) for at most 0.5 s.
    pub(super) fn run(
        mut self,
        mut writer: TTYPort,
        commands: &Receiver<Command>,
        frames: usize,
        pacing: DevicePacing,
        fault: &FaultSwitch,
    ) -> DeviceRecord {
        let mut awaiting_target = false;
        // Idle (not streaming) periods count too, so a device nobody
        // starts still ends.
        for _ in 0..frames.saturating_mul(2) {
            if self.record.frames >= frames {
                break;
            }
            if awaiting_target {
                self.receive(commands, LOCK_STEP_TIMEOUT, true);
            }
            while let Ok(command) = commands.try_recv() {
                self.inputs.apply(command);
            }
            if !self.period(&mut writer, fault.get()) {
                break;
            }
            awaiting_target = self.pace(pacing);
        }
        self.receive(commands, Duration::from_millis(500), false);
        self.record.set_controls = self.inputs.set_controls;
        self.record
    }

    /// Applies the host's commands as they arrive, for at most `timeout`
    /// or until the host's end is gone, or (when `until_target`) a
    /// control target has arrived.
    fn receive(&mut self, commands: &Receiver<Command>, timeout: Duration, until_target: bool) {
        let deadline = Instant::now() + timeout;
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match commands.recv_timeout(left) {
                Ok(command) => {
                    if self.inputs.apply(command) && until_target {
                        break;
                    }
                }
                Err(_) => break,
            }
        }
    }

    /// One period showing `fault`; false when the device is gone
    /// (unplugged, or its frame could not be written).
    fn period(&mut self, writer: &mut TTYPort, fault: DeviceFault) -> bool {
        let Inputs {
            streaming, control, ..
        } = self.inputs;
        let heartbeat_missing = self.inputs.last_heartbeat.elapsed() > Duration::from_secs(1)
            || fault == DeviceFault::HeartbeatLost;
        let force = self.force_on_cuff(heartbeat_missing);
        if streaming {
            self.move_person(&force);
        }
        self.read_encoders();
        let frame = self.telemetry(&force, heartbeat_missing, fault);
        if fault == DeviceFault::Unplug {
            return false;
        }
        if streaming && fault != DeviceFault::Stall {
            if !self.write(writer, &frame, fault) {
                return false;
            }
            self.record.truth.push(self.person.angles());
            self.record.control.push(control);
            self.record.frames += 1;
        }
        true
    }

    /// The force the robot puts on the cuff [N, R0] at the last counts, by
    /// its control type: motors off, its weight rests on the person's arm
    /// (f = −J_a^{-T} τ_g, about 25-35 N); gravity compensation holds its
    /// own weight (no force); torque mode applies the target τ_d as an
    /// ideal force J_a^{-T} τ_d, unless the host's heartbeat is missing
    /// (then as gravity compensation). No force at a singularity.
    fn force_on_cuff(&self, heartbeat_missing: bool) -> Vector3<f64> {
        let q = actuated_angles(&self.counts);
        let applied = match self.inputs.control {
            ControlType::Off => -GravityParameters::ASSUMED.torques(q),
            ControlType::Torque if !heartbeat_missing => {
                Vector3::from(self.inputs.target.map(f64::from))
            }
            ControlType::Torque | ControlType::GravityCompensation => Vector3::zeros(),
        };
        interaction_force(q, &applied).unwrap_or_default()
    }

    /// Moves the person one period under `force`: its time starts at the
    /// first streamed period in which the motors are on.
    fn move_person(&mut self, force: &Vector3<f64>) {
        if self.inputs.control != ControlType::Off {
            self.started.get_or_insert(self.simulated);
        }
        let moved = self.started.map_or(0, |started| self.simulated - started);
        self.person.advance(moved, force);
        self.simulated += 1;
    }

    /// The counts of the person's cuff: θ1..θ3 through the robot's sensor
    /// (kept where the cuff is out of reach); θ4, θ5 (joint-side
    /// encoders) follow the cuff's roll axis from the true link angles,
    /// when the person turns it.
    fn read_encoders(&mut self) {
        let cuff = self.person.cuff();
        if let Some(c) = self.sensor.read(&cuff) {
            self.counts = c;
        }
        let distal = self.person.cuff_axis().and_then(|axis| {
            let link = kinematics::inverse(&cuff, ShoulderBranch::Front, ElbowBranch::Negative);
            link.ok().and_then(|q| kinematics::distal_angles(q, &axis))
        });
        if let Some([t4, t5]) = distal {
            self.counts[3] = Encoder::Distal.counts(t4);
            self.counts[4] = Encoder::Distal.counts(t5);
        }
    }

    /// The period's stream frame (the packet number then advances): the
    /// sensors read the robot's weight unless the motors are off (then the
    /// cuff carries it), plus the interaction with the cuff `force`; the
    /// run time is the simulated time [ms] unless
    /// [`DeviceFault::FrozenClock`] holds it.
    fn telemetry(
        &mut self,
        force: &Vector3<f64>,
        heartbeat_missing: bool,
        fault: DeviceFault,
    ) -> Telemetry {
        let control = self.inputs.control;
        let q = actuated_angles(&self.counts);
        let gravity = GravityParameters::ASSUMED.torques(q);
        let interaction = kinematics::joint_torques(q, force);
        let held = if control == ControlType::Off {
            Vector3::zeros()
        } else {
            gravity
        };
        let sensed = held + interaction;
        if fault != DeviceFault::FrozenClock {
            self.run_time = self.simulated as f64 * sim::SAMPLE_PERIOD * 1000.0;
        }
        let frame = Telemetry {
            status: status_byte(self.inputs.streaming, control),
            error: if heartbeat_missing {
                ERROR_HEARTBEAT
            } else {
                0
            },
            packet: self.inputs.packet,
            run_time_ms: self.run_time as u32,
            counts: self.counts,
            torques: [sensed.x as f32, sensed.y as f32, sensed.z as f32],
            commanded: [held.x as f32, held.y as f32, held.z as f32],
        };
        self.inputs.packet = self.inputs.packet.wrapping_add(1);
        frame
    }

    /// Writes `frame` to `writer`, under [`DeviceFault::Garbage`] after 17
    /// random bytes, a truncated copy and a copy with a wrong checksum;
    /// false when the write failed.
    fn write(&mut self, writer: &mut TTYPort, frame: &Telemetry, fault: DeviceFault) -> bool {
        let mut bytes = Vec::new();
        if fault == DeviceFault::Garbage {
            bytes.extend((0..17).map(|_| (self.garbage.uniform() * 256.0) as u8));
            let valid = frame.encode();
            bytes.extend_from_slice(&valid[..20]);
            let mut corrupt = valid.clone();
            corrupt[30] ^= 0xA5;
            bytes.extend_from_slice(&corrupt);
        }
        bytes.extend_from_slice(&frame.encode());
        writer.write_all(&bytes).is_ok()
    }

    /// Ends a period as `pacing` says; true when the next period waits for
    /// the host's target (lock-stepped, streaming in torque mode).
    fn pace(&self, pacing: DevicePacing) -> bool {
        match pacing {
            DevicePacing::Wall(period) => {
                std::thread::sleep(period);
                false
            }
            DevicePacing::LockStep => {
                let awaiting_target =
                    self.inputs.streaming && self.inputs.control == ControlType::Torque;
                if !awaiting_target {
                    std::thread::sleep(Duration::from_secs_f64(sim::SAMPLE_PERIOD));
                }
                awaiting_target
            }
        }
    }
}
