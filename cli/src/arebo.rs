//! `limb arebo …`: the AREBO adapter from the command line.
//!
//! * `limb arebo sim [--seed N]`: the paper's experiments on the simulator
//!   (calibration, joint-angle accuracy, adaptive weight support); JSON.
//! * `limb arebo serve [--seconds S]`: a simulated AREBO on a pseudo-terminal;
//!   prints the device path, then serves for S seconds.
//! * `limb arebo calibrate --device PATH [--backlash-deg B]`: with the robot
//!   gravity compensated, records 15 s of flexion/extension and 15 s of
//!   small random movements, fits and validates the arm model; JSON.
//! * `limb arebo run --device PATH [--seconds S] [--alpha A] [--backlash-deg B]`:
//!   calibrates, then runs the control step (unassisted, or weight support
//!   with α = A) in torque mode, sending the torque target each frame;
//!   JSON summary.
//! * `limb arebo run --kernel --device PATH [--seconds S] [--heading H]
//!   [--clock host|robot] [--until-stopped] [--log FILE] [--zenoh ...]`:
//!   the limb kernel's session (Grasp → Estimate → Validated → Manipulate)
//!   on AREBO, the cuff on the wrist of the arm lying on its table
//!   (`limb_arebo::robot`), under the scripted operator or a Zenoh
//!   supervisor; a thin shell over `limb-session` like `limb kuka run`.
//! * `limb arebo serve --held-arm [--lock-step]`: the simulated device
//!   holding the kernel's reference arm at the wrist (for `run --kernel`).
//!
//! A safe stop (stale data, a limit, a device error or status bit, a port
//! failure) commands the motors off, prints the JSON with a `stop` object
//! (cause, stable code, value, bound) and exits 3, in both `calibrate` and
//! `run`.

use crate::error::{print_json, CliError};
use crate::robot_session::{run_robot, SessionArgs};
use clap::Subcommand;
use limb_arebo::calibration::{ValidatedArmModel, CALIBRATION_PHASE};
use limb_arebo::control::{GravityParameters, Mode};
use limb_arebo::device::{self, DevicePacing, FaultSwitch};
use limb_arebo::human::ArmMass;
use limb_arebo::link::{self, LinkError, Session, SessionState, StopCause};
use limb_arebo::protocol::{Command, ControlType};
use limb_arebo::recording::{self, Calibration, CalibrationError, CalibrationSettings};
use limb_arebo::robot::{AreboRobot, AreboStop};
use limb_arebo::safety::SafetyLimits;
use limb_arebo::sim;
use limb_arebo::supervisor::{ControlStep, Output, Sample};
use limb_session::{ArrivalClock, SessionPlan};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// `limb arebo` subcommands.
#[derive(Subcommand)]
pub enum AreboCommand {
    /// Run the paper's experiments on the simulated AREBO + shoulder model.
    Sim {
        /// Seed of the random movements and targets.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Serve a simulated AREBO on a pseudo-terminal.
    Serve {
        /// How long to serve [s].
        #[arg(long, default_value_t = 60.0)]
        seconds: f64,
        /// The cuff holds the wrist of the kernel's reference arm (l1
        /// 0.30 m, l2 0.20 m, on its table; `limb_arebo::held_arm`), not the
        /// shoulder joint model.
        #[arg(long)]
        held_arm: bool,
        /// In torque mode, wait for the host's target after each frame
        /// (the device's clock is then the simulation's: use `run --clock
        /// robot`).
        #[arg(long)]
        lock_step: bool,
    },
    /// Calibrate the arm model against a device.
    Calibrate {
        /// Serial device path (e.g. /dev/ttyACM0 or a pty from `serve`).
        #[arg(long)]
        device: PathBuf,
        /// Gearbox play compensated on θ1..θ3 [deg] (0: a robot without play).
        #[arg(long, default_value_t = 1.0)]
        backlash_deg: f64,
    },
    /// Calibrate, then run the control step (unassisted or weight support).
    Run {
        /// Serial device path.
        #[arg(long)]
        device: PathBuf,
        /// How long to run after calibration [s].
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        /// De-weighting α (0: unassisted mode).
        #[arg(long, default_value_t = 0.0)]
        alpha: f64,
        /// Gearbox play compensated on θ1..θ3 [deg] (0: a robot without play).
        #[arg(long, default_value_t = 1.0)]
        backlash_deg: f64,
        /// Run the limb kernel's session instead of the weight support
        /// (no calibration: the kernel estimates the arm by lifting it).
        #[arg(long)]
        kernel: bool,
        /// With --kernel: heading of frame S's x axis (wrist → shoulder)
        /// about AREBO's base z axis [rad].
        #[arg(long, default_value_t = limb_arebo::held_arm::REFERENCE_HEADING)]
        heading: f64,
        #[command(flatten)]
        session: Box<SessionArgs>,
    },
}

/// Runs one `limb arebo` subcommand.
pub fn run(command: AreboCommand) -> Result<(), CliError> {
    match command {
        AreboCommand::Sim { seed } => simulate(seed),
        AreboCommand::Serve {
            seconds,
            held_arm,
            lock_step,
        } => serve(seconds, held_arm, lock_step),
        AreboCommand::Calibrate {
            device,
            backlash_deg,
        } => calibrate(&device, backlash_deg),
        AreboCommand::Run {
            device,
            seconds,
            kernel: true,
            heading,
            session,
            ..
        } => kernel_session(&device, seconds, heading, &session),
        AreboCommand::Run {
            device,
            seconds,
            alpha,
            backlash_deg,
            session,
            ..
        } => {
            if session.any() {
                return Err(CliError::BadInput(
                    "--zenoh, --until-stopped and --log need --kernel".into(),
                ));
            }
            stream(&device, seconds, alpha, backlash_deg)
        }
    }
}

fn simulate(seed: u64) -> Result<(), CliError> {
    let setup = sim::Setup::default();
    let model = sim::calibrate(setup, seed)
        .map_err(|e| CliError::Internal(format!("simulated calibration: {e:?}")))?;
    let errors = sim::polysine_experiment(setup, &model, 120.0, seed + 1);
    let trials = sim::weight_support_experiment(setup, &model, 300, seed + 2);
    let success = |a: usize, b: usize| {
        trials[a - 1..b].iter().filter(|t| t.succeeded).count() as f64 / (b + 1 - a) as f64
    };
    print_json(&json!({
        "calibration": {
            "psi_x_error_deg": (model.psi_x() - setup.psi_x).to_degrees(),
            "origin_error_mm": (model.origin() - setup.origin).norm() * 1e3,
            "length_error_mm": (model.length() - setup.length) * 1e3,
        },
        "median_abs_error_deg": { "flexion": errors.flexion.to_degrees(), "abduction": errors.abduction.to_degrees() },
        "paper_median_abs_error_deg": { "flexion": 2.10, "abduction": 1.30 },
        "weight_support": {
            "alpha": trials.iter().map(|t| t.alpha).collect::<Vec<_>>(),
            "success_rate": [success(1, 100), success(101, 200), success(201, 300)],
        },
    }))
}

fn serve(seconds: f64, held_arm: bool, lock_step: bool) -> Result<(), CliError> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(CliError::BadInput(format!(
            "--seconds must be positive, got {seconds}"
        )));
    }
    let pty = link::pseudo_terminal().map_err(|e| CliError::Internal(e.to_string()))?;
    let device = pty
        .device
        .try_clone_native()
        .map_err(|e| CliError::Internal(e.to_string()))?;
    let small = sim::sphere_calibration(1);
    let motion = sim::accuracy_motion(2);
    let phase = CALIBRATION_PHASE;
    let trajectory = Box::new(move |t: f64| {
        if t < phase {
            sim::flexion_calibration(t)
        } else if t < 2.0 * phase {
            small.at(t - phase)
        } else {
            motion.at(t - 2.0 * phase)
        }
    });
    let frames = (seconds / sim::SAMPLE_PERIOD) as usize;
    let period = Duration::from_secs_f64(sim::SAMPLE_PERIOD);
    println!("{}", pty.path.display());
    let handle = match (held_arm, lock_step) {
        (false, true) => return Err(CliError::BadInput("--lock-step needs --held-arm".into())),
        (false, false) => device::spawn_device(
            device,
            sim::Setup::default(),
            trajectory,
            frames,
            period,
            FaultSwitch::default(),
        ),
        (true, lock_step) => device::spawn_held_arm(
            device,
            frames,
            if lock_step {
                DevicePacing::LockStep
            } else {
                DevicePacing::Wall(period)
            },
        ),
    }
    .map_err(|e| CliError::Internal(e.to_string()))?;
    handle
        .join()
        .map_err(|_| CliError::Internal("device thread panicked".into()))?;
    Ok(())
}

/// `limb arebo run --kernel`: the kernel's session on AREBO, a thin shell
/// over `limb-session` (as `limb kuka run`). A device stop (status or
/// error bits, the link's own stop) prints the summary with the stop and
/// exits 3.
fn kernel_session(
    device: &Path,
    seconds: f64,
    heading: f64,
    options: &SessionArgs,
) -> Result<(), CliError> {
    let duration = Duration::try_from_secs_f64(seconds)
        .map_err(|error| CliError::BadInput(format!("--seconds {seconds}: {error}")))?;
    if !heading.is_finite() {
        return Err(CliError::BadInput(format!(
            "--heading {heading}: not finite"
        )));
    }
    let clock = options.clock()?;
    let limits = match clock {
        ArrivalClock::Host => SafetyLimits::default(),
        ArrivalClock::Robot => SafetyLimits::judged_by_kernel(),
    };
    let session = Session::open(device, limits)
        .map_err(|e| CliError::BadInput(format!("{}: {e}", device.display())))?;
    let mut robot =
        match AreboRobot::start(session, heading, GravityParameters::ASSUMED, Some(duration)) {
            Ok(robot) => robot,
            Err(LinkError::Stopped(cause)) => return stopped(json!({ "model": null }), cause),
            Err(e) => return Err(CliError::Internal(e.to_string())),
        };
    robot.arrival_clock(clock);
    let plan = SessionPlan {
        rate: 1.0 / sim::SAMPLE_PERIOD,
        ..SessionPlan::default()
    };
    let ended = run_robot(&mut robot, options, plan)?;
    robot.finish();
    let record = robot.record();
    let outcome = ended.outcome.as_ref().ok();
    let summary = json!({
        "kernel_state": ended.kernel.state().kind().title(),
        "stop_category": ended.kernel.stopped().map(|s| s.category().name()),
        "kernel_steps": outcome.map(|o| o.steps),
        "stale_steps": outcome.map(|o| o.stale_steps),
        "frames": record.frames,
        "silent_polls": record.silent_polls,
        "packet_gaps": robot.session().packet_gaps(),
        "events": ended.events.json(),
        "model": outcome.and_then(|o| o.model).map(|m| json!({
            "l1": m.upper_arm_length, "l2": m.forearm_length,
            "shoulder": [m.shoulder.x, m.shoulder.z], "elbow": [m.elbow.x, m.elbow.z],
        })),
    });
    match ended.outcome {
        Ok(_) => print_json(&summary),
        Err(AreboStop::Device(violation)) => stopped(summary, StopCause::Violation(violation)),
        Err(AreboStop::Link(cause) | AreboStop::Io(LinkError::Stopped(cause))) => {
            stopped(summary, cause)
        }
        Err(AreboStop::Io(e)) => Err(CliError::Internal(e.to_string())),
    }
}

fn open(device: &Path) -> Result<Session, CliError> {
    Session::open(device, SafetyLimits::default())
        .map_err(|e| CliError::BadInput(format!("{}: {e}", device.display())))
}

/// The calibration settings of `--backlash-deg`.
fn settings(backlash_deg: f64) -> Result<CalibrationSettings, CliError> {
    if !(backlash_deg.is_finite() && backlash_deg >= 0.0) {
        return Err(CliError::BadInput(format!(
            "--backlash-deg must be finite and not negative, got {backlash_deg}"
        )));
    }
    Ok(CalibrationSettings {
        backlash: [backlash_deg.to_radians(); 3],
        ..CalibrationSettings::default()
    })
}

/// A safe stop as JSON: the cause, and for a verdict its stable code,
/// value and bound.
fn stop_json(cause: StopCause) -> serde_json::Value {
    match cause {
        StopCause::PortLost => json!({
            "cause": "port_lost",
            "category": cause.category().name(),
        }),
        StopCause::Violation(v) => json!({
            "cause": "violation",
            "category": cause.category().name(),
            "limit": v.limit.name(),
            "code": v.limit.code(),
            "value": v.value,
            "bound": v.bound,
        }),
    }
}

/// Prints `summary` with the stop and fails with [`CliError::SafetyStop`]
/// (exit 3), the same way in `calibrate` and `run`.
fn stopped(mut summary: serde_json::Value, cause: StopCause) -> Result<(), CliError> {
    summary["stop"] = stop_json(cause);
    print_json(&summary)?;
    Err(CliError::SafetyStop(cause.to_string()))
}

/// Calibrates on `session`; a safe stop is printed and exits 3.
fn calibrate_session(
    session: &mut Session,
    device: &Path,
    settings: &CalibrationSettings,
) -> Result<Result<Calibration, StopCause>, CliError> {
    match recording::calibrate(session, settings) {
        Ok(calibration) => Ok(Ok(calibration)),
        Err(CalibrationError::Stopped(cause)) => Ok(Err(cause)),
        Err(CalibrationError::Link(e)) => Err(CliError::Internal(e.to_string())),
        Err(e) => Err(CliError::BadInput(format!("{}: {e}", device.display()))),
    }
}

fn model_json(model: &ValidatedArmModel) -> serde_json::Value {
    json!({
        "psi_x_deg": model.psi_x().to_degrees(),
        "origin_m": [model.origin().x, model.origin().y, model.origin().z],
        "length_m": model.length(),
    })
}

fn calibrate(device: &Path, backlash_deg: f64) -> Result<(), CliError> {
    let settings = settings(backlash_deg)?;
    let mut session = open(device)?;
    let calibrated = calibrate_session(&mut session, device, &settings)?;
    // The person lets go of a gravity-compensated robot; then motors off.
    let _ = session.send(Command::SetControlType(ControlType::Off));
    match calibrated {
        Ok(c) => print_json(&json!({
            "model": model_json(&c.model),
            "plane_residual_m": c.plane.residual,
            "sphere_residual_m": c.sphere.residual,
            "samples": c.samples,
            "left_out": c.left_out,
        })),
        Err(cause) => stopped(json!({ "model": null }), cause),
    }
}

fn stream(device: &Path, seconds: f64, alpha: f64, backlash_deg: f64) -> Result<(), CliError> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(CliError::BadInput(format!(
            "--seconds must be positive, got {seconds}"
        )));
    }
    if !(0.0..=1.0).contains(&alpha) {
        return Err(CliError::BadInput(format!(
            "--alpha must be in [0, 1], got {alpha}"
        )));
    }
    let settings = settings(backlash_deg)?;
    let mut session = open(device)?;
    let calibration = match calibrate_session(&mut session, device, &settings)? {
        Ok(calibration) => calibration,
        Err(cause) => return stopped(json!({ "model": null, "frames": 0 }), cause),
    };
    let model = calibration.model;
    let arm = ArmMass {
        mass: 2.0,
        centre_of_mass: 0.15,
    };
    let mut control_step = ControlStep::new(
        model,
        arm,
        GravityParameters::ASSUMED,
        SafetyLimits::default(),
        settings.backlash,
    );
    let mode = if alpha > 0.0 {
        Mode::WeightSupport { alpha }
    } else {
        Mode::Unassisted
    };
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    let (mut frames, mut last_angles, mut verdict) = (0usize, None, None);
    // A control type the device does not confirm latches the stop.
    let mut pending = session.set_control(ControlType::Torque).unwrap_or_default();
    while Instant::now() < end && session.state() == SessionState::Running && verdict.is_none() {
        let received = if pending.is_empty() {
            session.poll()
        } else {
            std::mem::take(&mut pending)
        };
        for frame in received {
            frames += 1;
            let sample = Sample {
                status: frame.telemetry.status,
                error: frame.telemetry.error,
                counts: frame.telemetry.counts,
                torques: nalgebra::Vector3::from(frame.telemetry.torques.map(f64::from)),
                time: frame.time,
            };
            match control_step.step(Some(&sample), session.now(), mode) {
                Output::Target { desired, angles } => {
                    last_angles = Some(angles);
                    let target = [desired.x as f32, desired.y as f32, desired.z as f32];
                    // A failed write latches the session's stop.
                    if session.send(Command::SetControlTarget(target)).is_err() {
                        break;
                    }
                }
                Output::SafeStop(violation) => {
                    session.stop(StopCause::Violation(violation));
                    verdict = Some(violation);
                    break;
                }
            }
        }
    }
    session.finish();
    let stats = session.stats();
    let summary = json!({
        "model": model_json(&model),
        "frames": frames,
        "checksum_errors": stats.checksum_errors,
        "discarded_bytes": stats.discarded,
        "unparsed_frames": session.unparsed_frames(),
        "last_angles_deg": last_angles.map(|a| [a.flexion.to_degrees(), a.abduction.to_degrees()]),
    });
    match session.state() {
        SessionState::Running => print_json(&summary),
        SessionState::SafeStop(cause) => stopped(summary, cause),
    }
}
