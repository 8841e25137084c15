//! A simulated AREBO device speaking the link's protocol on a
//! pseudo-terminal's master ([`crate::link::pseudo_terminal`]), for tests,
//! `limb arebo serve` and kernel sessions without the robot.
//!
//! # Theory of operation
//! [`spawn_device`] runs the simulated robot ([`crate::sim`]) on the pty's
//! master in a thread: it executes commands, moves the SJM along a
//! trajectory and streams one frame per 5 ms of simulated time;
//! [`spawn_held_arm`] moves the kernel's reference arm held at the wrist
//! ([`crate::held_arm`]) instead, and [`on_simulated_held_arm`] puts
//! [`AreboRobot`] on it. [`DeviceFault`] injects garbage, stalls, an
//! unplug, a lost heartbeat or a frozen run time.
//!
//! The device's parts: [`Person`], what the cuff holds; the firmware loop
//! (one period per stream frame, paced by [`DevicePacing`]); the faults.

mod fault;
mod firmware;
mod person;

pub use fault::{DeviceFault, FaultSwitch};
pub use firmware::{DevicePacing, DeviceRecord, LOCK_STEP_TIMEOUT};
pub use person::{DeviceTrajectory, Person};

use crate::control::GravityParameters;
use crate::held_arm::{HeldArm, REFERENCE_HEADING};
use crate::link::{self, LinkError, Session};
use crate::robot::AreboRobot;
use crate::safety::SafetyLimits;
use crate::sim::Setup;
use firmware::Device;
use limb_session::ArrivalClock;
use person::Shoulder;
use serialport::{SerialPort, TTYPort};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::Duration;

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
/// [`crate::protocol::ERROR_HEARTBEAT`].
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
    let person = Shoulder::new(setup, trajectory);
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
    person: Box<dyn Person>,
    frames: usize,
    pacing: DevicePacing,
    fault: FaultSwitch,
) -> Result<JoinHandle<DeviceRecord>, LinkError> {
    let mut writer = device.try_clone_native()?;
    // A simulated device waits for a slow host rather than ending (a test
    // machine under load must not turn into a device fault).
    writer.set_timeout(DEVICE_WRITE_TIMEOUT)?;
    let (sender, commands) = mpsc::channel();
    // A helper thread forwards commands; it ends when the port closes or
    // the device thread has ended.
    std::thread::spawn(move || firmware::forward_commands(device, sender));
    Ok(std::thread::spawn(move || {
        Device::new(person, setup.backlash).run(writer, &commands, frames, pacing, &fault)
    }))
}

/// AREBO on a fresh pseudo-terminal whose simulated device holds the
/// kernel's reference arm at the wrist ([`HeldArm::reference`], no
/// backlash), lock-stepped with the host for at most `frames` frames: the
/// device's thread and the robot, in torque mode, on the device's clock
/// (no freshness check of the link's on the host's clock: the kernel
/// judges). What the tests and `limb arebo serve --held-arm --lock-step`
/// + `run --kernel --clock robot` run.
///
/// # Errors
/// [`LinkError`] when no pty can be opened or the device does not confirm
/// torque mode.
pub fn on_simulated_held_arm(
    frames: usize,
) -> Result<(JoinHandle<DeviceRecord>, AreboRobot), LinkError> {
    let pty = link::pseudo_terminal()?;
    let device = spawn_held_arm(
        pty.device.try_clone_native()?,
        frames,
        DevicePacing::LockStep,
    )?;
    let session = Session::open(&pty.path, SafetyLimits::judged_by_kernel())?;
    let mut robot =
        AreboRobot::start(session, REFERENCE_HEADING, GravityParameters::ASSUMED, None)?;
    robot.arrival_clock(ArrivalClock::Robot);
    Ok((device, robot))
}
