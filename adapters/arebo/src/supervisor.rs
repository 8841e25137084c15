//! The host-side AREBO control step: one stream frame in, a torque target
//! or a latched safe stop out.
//!
//! # Theory of operation
//! ```text
//! frame (status, error, counts, τ_r, time) ─▶ freshness ─▶ device status and
//!        error bits (torque mode, no error) ─▶ backlash-compensated θ ─▶ FK ─▶ φ̂
//!        τ_int = τ_r − τ_g(θ) ─▶ f_int = J_a^{-T} τ_int
//!        check_frame(φ̂, f_int, τ_r) ─▶ mode ─▶ τ_d  (sent as the control target;
//!                                                  the firmware runs the torque PD)
//! ```
//! Any verdict latches [`Output::SafeStop`]; the caller then commands the
//! motors off. Pure: time is an input.

use crate::calibration::ValidatedArmModel;
use crate::control::{self, GravityParameters, Mode};
use crate::encoder::{BacklashCompensator, Encoder};
use crate::human::{ArmMass, ShoulderAngles};
use crate::kinematics::{self, ActuatedAngles};
use crate::protocol::ControlType;
use crate::safety::{self, AreboLimit, AreboViolation, SafetyLimits};
use limb_kernel::monitor::Limit;
use nalgebra::Vector3;

/// One decoded stream frame, as the control step needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The device's status byte (streaming, control type).
    pub status: u8,
    /// The device's error bits.
    pub error: u16,
    /// Encoder counts θ1..θ5.
    pub counts: [i32; 5],
    /// Torque sensor readings τ_r [N m].
    pub torques: Vector3<f64>,
    /// Host receive time [s].
    pub time: f64,
}

/// What one step decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Output {
    /// Send τ_d [N m] as the control target; φ̂ for display and logging.
    Target {
        /// Desired interaction torques τ_d [N m].
        desired: Vector3<f64>,
        /// Estimated shoulder angles.
        angles: ShoulderAngles,
    },
    /// Latched stop with the verdict that caused it.
    SafeStop(AreboViolation),
}

/// The host-side control step of `limb arebo run`: the paper's control
/// modes behind the safety verdicts, latching the first verdict. (Not a
/// `limb_session::Supervisor`, which requests the kernel's transitions.)
#[derive(Clone, Copy, Debug)]
pub struct ControlStep {
    model: ValidatedArmModel,
    arm: ArmMass,
    gravity: GravityParameters,
    limits: SafetyLimits,
    compensator: BacklashCompensator,
    stopped: Option<AreboViolation>,
}

fn violation(limit: Limit, value: f64, bound: f64) -> AreboViolation {
    AreboViolation {
        limit: AreboLimit::Kernel(limit),
        value,
        bound,
    }
}

impl ControlStep {
    /// A control step for a validated arm model (the only way to have one).
    pub fn new(
        model: ValidatedArmModel,
        arm: ArmMass,
        gravity: GravityParameters,
        limits: SafetyLimits,
        backlash: [f64; 3],
    ) -> Self {
        Self {
            model,
            arm,
            gravity,
            limits,
            compensator: BacklashCompensator::new(backlash),
            stopped: None,
        }
    }

    /// One step at `now` [s] with the newest sample (None: nothing yet).
    pub fn step(&mut self, sample: Option<&Sample>, now: f64, mode: Mode) -> Output {
        if let Some(v) = self.stopped {
            return Output::SafeStop(v);
        }
        match self.evaluate(sample, now, mode) {
            Ok(output) => output,
            Err(v) => {
                self.stopped = Some(v);
                Output::SafeStop(v)
            }
        }
    }

    fn evaluate(
        &mut self,
        sample: Option<&Sample>,
        now: f64,
        mode: Mode,
    ) -> Result<Output, AreboViolation> {
        safety::check_fresh(sample.map(|s| s.time), now, &self.limits)?;
        let sample = sample.ok_or(violation(
            Limit::StaleSensor,
            f64::INFINITY,
            self.limits.stale_after,
        ))?;
        // The targets mean something only while the device applies them.
        safety::check_device(sample.status, sample.error, ControlType::Torque)?;
        let motor = [0, 1, 2].map(|i| Encoder::Actuated(i).angle(sample.counts[i]));
        let q = ActuatedAngles(self.compensator.link_angles(motor));
        let endpoint = kinematics::endpoint(q);
        let non_finite = violation(Limit::NonFiniteSensor, f64::NAN, 0.0);
        let angles = self.model.angles(&endpoint).map_err(|_| non_finite)?;
        let interaction = sample.torques - self.gravity.torques(q);
        // Near a kinematic singularity the force is unobservable: stop.
        let force = control::interaction_force(q, &interaction).ok_or(violation(
            Limit::ForceMagnitude,
            f64::INFINITY,
            self.limits.max_force,
        ))?;
        safety::check_frame(angles, &force, &sample.torques, &self.limits)?;
        let desired = control::desired_torques(mode, q, angles, &self.model, self.arm)
            .map_err(|_| non_finite)?;
        Ok(Output::Target { desired, angles })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::{fit_plane, fit_sphere, validate, CalibrationLimits, PathBuffer};
    use crate::human;

    fn model() -> ValidatedArmModel {
        let origin = Vector3::new(0.10, -0.10, 0.30);
        let at =
            |phi: ShoulderAngles| origin + human::base_rotation(0.1) * human::direction(phi) * 0.2;
        let mut plane = PathBuffer::new();
        let mut sphere = PathBuffer::new();
        for i in 0..200 {
            let s = i as f64 / 199.0;
            let _ = plane.push(at(ShoulderAngles {
                flexion: 1.5 * s,
                abduction: 0.0,
            }));
            let _ = sphere.push(at(ShoulderAngles {
                flexion: 0.8 + 0.3 * libm::sin(9.0 * s),
                abduction: 0.3 * libm::cos(7.0 * s),
            }));
        }
        validate(
            &fit_plane(&plane).unwrap(),
            &fit_sphere(&sphere).unwrap(),
            &CalibrationLimits::default(),
        )
        .unwrap()
    }

    fn sample_at(
        model: &ValidatedArmModel,
        phi: ShoulderAngles,
        force: Vector3<f64>,
        time: f64,
    ) -> Sample {
        let q = kinematics::inverse(
            &model.endpoint(phi),
            kinematics::ShoulderBranch::Front,
            kinematics::ElbowBranch::Negative,
        )
        .unwrap();
        let counts = [q.0[0], q.0[1], q.0[2], 0.0, 0.0];
        let counts = [0, 1, 2, 3, 4].map(|i| {
            if i < 3 {
                Encoder::Actuated(i).counts(counts[i])
            } else {
                0
            }
        });
        let torques = GravityParameters::ASSUMED.torques(q) + kinematics::joint_torques(q, &force);
        Sample {
            status: crate::protocol::status_byte(true, ControlType::Torque),
            error: 0,
            counts,
            torques,
            time,
        }
    }

    fn control_step(model: ValidatedArmModel) -> ControlStep {
        let arm = ArmMass {
            mass: 2.0,
            centre_of_mass: 0.15,
        };
        ControlStep::new(
            model,
            arm,
            GravityParameters::ASSUMED,
            SafetyLimits::default(),
            [0.0; 3],
        )
    }

    #[test]
    fn nominal_frames_give_targets_and_verdicts_latch() {
        let model = model();
        let mut s = control_step(model);
        let phi = ShoulderAngles {
            flexion: 0.7,
            abduction: 0.2,
        };
        let frame = sample_at(&model, phi, Vector3::new(1.0, 0.0, 2.0), 1.0);
        match s.step(Some(&frame), 1.01, Mode::WeightSupport { alpha: 0.5 }) {
            Output::Target { desired, angles } => {
                assert!(
                    (angles.flexion - 0.7).abs() < 1e-3 && (angles.abduction - 0.2).abs() < 1e-3
                );
                assert!(desired.norm() > 0.0);
            }
            Output::SafeStop(v) => panic!("{v:?}"),
        }
        // Stale: 0.2 s old.
        let stop = s.step(Some(&frame), 1.2, Mode::Unassisted);
        assert!(
            matches!(stop, Output::SafeStop(v) if v.limit == AreboLimit::Kernel(Limit::StaleSensor))
        );
        // Latched even with a fresh frame.
        let fresh = sample_at(&model, phi, Vector3::zeros(), 1.3);
        assert!(matches!(
            s.step(Some(&fresh), 1.3, Mode::Unassisted),
            Output::SafeStop(_)
        ));
    }

    /// Finding 7 of issue 18: the device's heartbeat-missing bit (it has
    /// stopped assisting) stops the host, as does a device that left
    /// torque mode.
    #[test]
    fn device_error_bits_stop_the_supervisor() {
        let model = model();
        let phi = ShoulderAngles {
            flexion: 0.7,
            abduction: 0.2,
        };
        let mode = Mode::WeightSupport { alpha: 0.5 };
        let mut s = control_step(model);
        let mut frame = sample_at(&model, phi, Vector3::zeros(), 1.0);
        assert!(matches!(
            s.step(Some(&frame), 1.0, mode),
            Output::Target { .. }
        ));
        frame.error = crate::protocol::ERROR_HEARTBEAT;
        assert!(matches!(
            s.step(Some(&frame), 1.0, mode),
            Output::SafeStop(v) if v.limit == AreboLimit::DeviceHeartbeatMissing
        ));
        let mut s = control_step(model);
        let mut off = sample_at(&model, phi, Vector3::zeros(), 1.0);
        off.status = crate::protocol::status_byte(true, ControlType::Off);
        assert!(matches!(
            s.step(Some(&off), 1.0, mode),
            Output::SafeStop(v) if v.limit == AreboLimit::ControlType
        ));
    }

    #[test]
    fn arm_limits_and_force_limits_stop() {
        let model = model();
        let mut s = control_step(model);
        let wide = sample_at(
            &model,
            ShoulderAngles {
                flexion: 0.7,
                abduction: 1.0,
            },
            Vector3::zeros(),
            0.0,
        );
        assert!(
            matches!(s.step(Some(&wide), 0.0, Mode::Unassisted), Output::SafeStop(v) if v.limit == AreboLimit::Abduction)
        );
        let mut s = control_step(model);
        let shove = sample_at(
            &model,
            ShoulderAngles {
                flexion: 0.7,
                abduction: 0.0,
            },
            Vector3::new(0.0, 80.0, 0.0),
            0.0,
        );
        assert!(matches!(
            s.step(Some(&shove), 0.0, Mode::Unassisted),
            Output::SafeStop(v) if v.limit == AreboLimit::Kernel(Limit::ForceMagnitude)
        ));
        let mut s = control_step(model);
        assert!(matches!(
            s.step(None, 0.0, Mode::Unassisted),
            Output::SafeStop(_)
        ));
    }
}
