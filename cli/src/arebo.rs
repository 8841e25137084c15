//! `limb arebo …`: the AREBO adapter from the command line.
//!
//! * `limb arebo sim [--seed N]`: the paper's experiments on the simulator
//!   (calibration, joint-angle accuracy, adaptive weight support); JSON.
//! * `limb arebo serve [--seconds S]`: a simulated AREBO on a pseudo-terminal;
//!   prints the device path, then serves for S seconds.
//! * `limb arebo calibrate --device PATH`: records 15 s of flexion/extension
//!   and 15 s of small random movements, fits and validates the arm model;
//!   JSON.
//! * `limb arebo run --device PATH [--seconds S] [--alpha A]`: calibrates,
//!   then runs the supervisor (unassisted, or weight support with α = A),
//!   sending the torque target each frame; stale data or a limit stops it;
//!   JSON summary.

use crate::error::{print_json, CliError};
use clap::Subcommand;
use limb_arebo::calibration::{self, CalibrationLimits, PlaneFit, SphereFit, ValidatedArmModel};
use limb_arebo::control::{GravityParameters, Mode};
use limb_arebo::encoder::{BacklashCompensator, NOMINAL_BACKLASH};
use limb_arebo::human::ArmMass;
use limb_arebo::link::{self, FaultSwitch, Session, SessionState};
use limb_arebo::protocol::{Command, ControlType, Telemetry};
use limb_arebo::safety::SafetyLimits;
use limb_arebo::sim;
use limb_arebo::supervisor::{Output, Sample, Supervisor};
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
    },
    /// Calibrate the arm model against a device.
    Calibrate {
        /// Serial device path (e.g. /dev/ttyACM0 or a pty from `serve`).
        #[arg(long)]
        device: PathBuf,
    },
    /// Calibrate, then run the supervisor (unassisted or weight support).
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
    },
}

/// Runs one `limb arebo` subcommand.
pub fn run(command: AreboCommand) -> Result<(), CliError> {
    match command {
        AreboCommand::Sim { seed } => simulate(seed),
        AreboCommand::Serve { seconds } => serve(seconds),
        AreboCommand::Calibrate { device } => calibrate(&device),
        AreboCommand::Run {
            device,
            seconds,
            alpha,
        } => stream(&device, seconds, alpha),
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

fn serve(seconds: f64) -> Result<(), CliError> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(CliError::BadInput(format!(
            "--seconds must be positive, got {seconds}"
        )));
    }
    let pty = link::pseudo_terminal().map_err(|e| CliError::Internal(e.to_string()))?;
    let device = pty
        .device
        .try_clone()
        .map_err(|e| CliError::Internal(e.to_string()))?;
    let small = sim::sphere_calibration(1);
    let motion = sim::accuracy_motion(2);
    let phase = sim::CALIBRATION_PHASE;
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
    println!("{}", pty.path.display());
    let handle = link::spawn_device(
        device,
        sim::Setup::default(),
        trajectory,
        frames,
        Duration::from_secs_f64(sim::SAMPLE_PERIOD),
        FaultSwitch::default(),
    )
    .map_err(|e| CliError::Internal(e.to_string()))?;
    handle
        .join()
        .map_err(|_| CliError::Internal("device thread panicked".into()))?;
    Ok(())
}

fn open(device: &Path) -> Result<Session, CliError> {
    Session::open(device, SafetyLimits::default())
        .map_err(|e| CliError::BadInput(format!("{}: {e}", device.display())))
}

/// Polls until `count` frames or a safe stop.
fn collect(session: &mut Session, count: usize) -> Result<Vec<Telemetry>, CliError> {
    let mut frames = Vec::with_capacity(count);
    while frames.len() < count {
        frames.extend(session.poll());
        if let SessionState::SafeStop(cause) = session.state() {
            return Err(CliError::Internal(format!("safe stop: {cause:?}")));
        }
    }
    Ok(frames)
}

/// Records the two calibration phases on `session` and validates the fits.
fn calibrate_session(
    session: &mut Session,
    device: &Path,
) -> Result<(ValidatedArmModel, PlaneFit, SphereFit), CliError> {
    let per_phase = (sim::CALIBRATION_PHASE / sim::SAMPLE_PERIOD) as usize;
    let frames = collect(session, 2 * per_phase)?;
    let mut compensator = BacklashCompensator::new(NOMINAL_BACKLASH);
    // Keep the samples outside the joints' play (see BacklashCompensator).
    let mut phases = [Vec::new(), Vec::new()];
    for (n, frame) in frames.iter().enumerate() {
        let endpoint = sim::endpoint_estimate(&mut compensator, &frame.counts);
        if compensator.settled() {
            phases[usize::from(n >= per_phase)].push(endpoint);
        }
    }
    let rejected = |what: &str, e: &dyn std::fmt::Debug| {
        CliError::BadInput(format!("{}: {what}: {e:?}", device.display()))
    };
    let plane = calibration::fit_plane(&phases[0]).map_err(|e| rejected("flexion plane", &e))?;
    let sphere = calibration::fit_sphere(&phases[1]).map_err(|e| rejected("sphere", &e))?;
    let model = calibration::validate(&plane, &sphere, &CalibrationLimits::default())
        .map_err(|e| rejected("validation", &e))?;
    Ok((model, plane, sphere))
}

fn model_json(model: &ValidatedArmModel) -> serde_json::Value {
    json!({
        "psi_x_deg": model.psi_x().to_degrees(),
        "origin_m": [model.origin().x, model.origin().y, model.origin().z],
        "length_m": model.length(),
    })
}

fn calibrate(device: &Path) -> Result<(), CliError> {
    let mut session = open(device)?;
    let (model, plane, sphere) = calibrate_session(&mut session, device)?;
    print_json(&json!({
        "model": model_json(&model),
        "plane_residual_m": plane.residual,
        "sphere_residual_m": sphere.residual,
    }))
}

fn stream(device: &Path, seconds: f64, alpha: f64) -> Result<(), CliError> {
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
    let mut session = open(device)?;
    let (model, _, _) = calibrate_session(&mut session, device)?;
    let arm = ArmMass {
        mass: 2.0,
        centre_of_mass: 0.15,
    };
    let mut supervisor = Supervisor::new(
        model,
        arm,
        GravityParameters::ASSUMED,
        SafetyLimits::default(),
        NOMINAL_BACKLASH,
    );
    let mode = if alpha > 0.0 {
        Mode::WeightSupport { alpha }
    } else {
        Mode::Unassisted
    };
    let internal = |e: link::LinkError| CliError::Internal(e.to_string());
    session
        .send(Command::SetControlType(ControlType::Torque))
        .map_err(internal)?;
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    let (mut frames, mut last_angles, mut stop) = (0usize, None, None);
    while Instant::now() < end && session.state() == SessionState::Running && stop.is_none() {
        for frame in session.poll() {
            frames += 1;
            let sample = Sample {
                counts: frame.counts,
                torques: nalgebra::Vector3::from(frame.torques.map(f64::from)),
                time: session.now(),
            };
            match supervisor.step(Some(&sample), session.now(), mode) {
                Output::Target { desired, angles } => {
                    last_angles = Some(angles);
                    let target = [desired.x as f32, desired.y as f32, desired.z as f32];
                    session
                        .send(Command::SetControlTarget(target))
                        .map_err(internal)?;
                }
                Output::SafeStop(violation) => {
                    stop = Some(violation);
                    break;
                }
            }
        }
    }
    let _ = session.send(Command::SetControlType(ControlType::Off));
    let stats = session.stats();
    print_json(&json!({
        "model": model_json(&model),
        "frames": frames,
        "checksum_errors": stats.checksum_errors,
        "discarded_bytes": stats.discarded,
        "link_state": format!("{:?}", session.state()),
        "supervisor_stop": stop.map(|v| format!("{v:?}")),
        "last_angles_deg": last_angles.map(|a| [a.flexion.to_degrees(), a.abduction.to_degrees()]),
    }))
}
