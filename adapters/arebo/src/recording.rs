//! Calibration over a device session (paper 2.3.3, 2.4.3): the person
//! moves the cuff through two movements while the robot carries its own
//! weight, and the fits of [`crate::calibration`] turn the recorded
//! endpoints into a [`ValidatedArmModel`].
//!
//! # Theory of operation
//! ```text
//! set control type: gravity compensation (confirmed by the device's status)
//!   frames ─▶ check_device (gravity compensation, no error bit) ─▶ phase by
//!   device run time: [0, T) flexion/extension, [T, 2T) small random moves
//!   ─▶ counts ─▶ backlash compensation (settable play; 0 = none) ─▶ FK
//!   ─▶ fit_plane, fit_sphere ─▶ validate
//! ```
//! The robot is gravity compensated, never off: with the motors off the
//! person would carry its weight (25-35 N at the cuff). Phases are timed by
//! the device's run time (ms since its start), so a late or lost frame does
//! not shift the boundary. A device error bit, another control type, a stale
//! stream or a port failure stops the session (motors off) and the
//! calibration with it.

use crate::calibration::{
    self, CalibrationLimits, FitError, PlaneFit, Rejection, SphereFit, ValidatedArmModel,
    CALIBRATION_PHASE,
};
use crate::encoder::{BacklashCompensator, NOMINAL_BACKLASH};
use crate::link::{LinkError, Session, SessionState, StopCause};
use crate::protocol::ControlType;
use crate::safety;
use nalgebra::Vector3;
use std::time::{Duration, Instant};

/// How to calibrate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationSettings {
    /// Length of each movement [s, device run time].
    pub phase: f64,
    /// Gearbox play the compensation removes on θ1..θ3 [rad]: about 1° on
    /// AREBO ([`NOMINAL_BACKLASH`]), 0 for a robot without play.
    pub backlash: [f64; 3],
    /// What the validator accepts.
    pub limits: CalibrationLimits,
}

impl Default for CalibrationSettings {
    fn default() -> Self {
        Self {
            phase: CALIBRATION_PHASE,
            backlash: NOMINAL_BACKLASH,
            limits: CalibrationLimits::default(),
        }
    }
}

/// A calibration that passed the validator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// The model.
    pub model: ValidatedArmModel,
    /// The flexion-plane fit.
    pub plane: PlaneFit,
    /// The sphere fit.
    pub sphere: SphereFit,
    /// Samples used by each fit.
    pub samples: [usize; 2],
    /// Samples left out because a joint may have been inside its play.
    pub left_out: usize,
}

/// Which movement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Movement {
    /// Flexion/extension (for ψx).
    Flexion,
    /// Small random movements (for the shoulder origin and l).
    Sphere,
}

/// Why a calibration gave no model.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// The session stopped (device error bit, control type, stale stream,
    /// port failure); the motors were commanded off.
    #[error("safe stop: {0:?}")]
    Stopped(StopCause),
    /// A movement's fit failed.
    #[error("{movement:?} fit: {error:?}")]
    Fit {
        /// Which movement.
        movement: Movement,
        /// Why.
        error: FitError,
    },
    /// The validator rejected the fits.
    #[error("rejected: {0:?}")]
    Rejected(Rejection),
    /// The device's run time did not cover both movements in time.
    #[error("the device's run time did not advance through both movements")]
    DeviceClock,
    /// A setting is unusable.
    #[error("setting: {0}")]
    Setting(&'static str),
    /// The link failed outside a safe stop.
    #[error(transparent)]
    Link(LinkError),
}

impl From<LinkError> for CalibrationError {
    fn from(error: LinkError) -> Self {
        match error {
            LinkError::Stopped(cause) => Self::Stopped(cause),
            other => Self::Link(other),
        }
    }
}

/// Records both movements on `session` and validates the fits. Leaves the
/// device gravity compensated.
///
/// # Errors
/// [`CalibrationError`]; after [`CalibrationError::Stopped`] the session
/// is latched in its safe stop.
pub fn calibrate(
    session: &mut Session,
    settings: &CalibrationSettings,
) -> Result<Calibration, CalibrationError> {
    if !(settings.phase.is_finite() && settings.phase > 0.0) {
        return Err(CalibrationError::Setting("the phase must be positive"));
    }
    if !settings.backlash.iter().all(|b| b.is_finite() && *b >= 0.0) {
        return Err(CalibrationError::Setting(
            "the backlash must be finite and not negative",
        ));
    }
    let mut pending = session.set_control(ControlType::GravityCompensation)?;
    let mut compensator = BacklashCompensator::new(settings.backlash);
    let mut paths: [Vec<Vector3<f64>>; 2] = [Vec::new(), Vec::new()];
    let mut left_out = 0;
    let mut start = None;
    // The device clock must get through both movements; a generous host
    // bound catches one that stands still while streaming.
    let deadline = Instant::now() + Duration::from_secs_f64(4.0 * settings.phase + 5.0);
    'record: loop {
        if let SessionState::SafeStop(cause) = session.state() {
            return Err(CalibrationError::Stopped(cause));
        }
        if Instant::now() > deadline {
            return Err(CalibrationError::DeviceClock);
        }
        let frames = if pending.is_empty() {
            session.poll()
        } else {
            std::mem::take(&mut pending)
        };
        for received in frames {
            let frame = received.telemetry;
            let device =
                safety::check_device(frame.status, frame.error, ControlType::GravityCompensation);
            if let Err(violation) = device {
                let cause = StopCause::Violation(violation);
                session.stop(cause);
                return Err(CalibrationError::Stopped(cause));
            }
            let origin = *start.get_or_insert(frame.run_time_ms);
            let elapsed = f64::from(frame.run_time_ms.wrapping_sub(origin)) * 1e-3;
            let Some(path) = paths.get_mut((elapsed / settings.phase) as usize) else {
                break 'record;
            };
            let endpoint = compensator.endpoint(&frame.counts);
            if compensator.settled() {
                path.push(endpoint);
            } else {
                left_out += 1;
            }
        }
    }
    let fit_error = |movement| move |error| CalibrationError::Fit { movement, error };
    let plane = calibration::fit_plane(&paths[0]).map_err(fit_error(Movement::Flexion))?;
    let sphere = calibration::fit_sphere(&paths[1]).map_err(fit_error(Movement::Sphere))?;
    let model = calibration::validate(&plane, &sphere, &settings.limits)
        .map_err(CalibrationError::Rejected)?;
    Ok(Calibration {
        model,
        plane,
        sphere,
        samples: [paths[0].len(), paths[1].len()],
        left_out,
    })
}
