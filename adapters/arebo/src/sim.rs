//! Simulated AREBO attached to the shoulder joint model (SJM, paper 2.4.1).
//!
//! # Theory of operation
//! The SJM is a 2-DoF shoulder (φ1 flexion, φ2 abduction; frame H0 as in
//! [`crate::human`]) moving a rigid arm of mass m, centre of mass c and
//! inertia I about each axis. Its motors run a PD position controller with
//! gravity feed-forward, the sum scaled by (1 − ξ) (ξ = impairment, paper
//! 2.4.5). AREBO's cuff is rigidly attached at distance l, so the robot's
//! endpoint follows the arm; the robot is modelled as an ideal force source
//! at the cuff (the torque loop's 2.75 Hz bandwidth is well above the
//! 0.1-0.35 Hz movements) and as a sensor: θ1..θ3 from the arm endpoint by
//! inverse kinematics, through ~1° of gearbox backlash (the motor-side
//! encoder lags the link by up to half the play, a dead-band) and the
//! motor encoders' quantisation. Integration: semi-implicit Euler at 1 kHz,
//! robot sampling and control at 200 Hz.
//!
//! The distal joints θ4, θ5 are not simulated (reported as 0 counts); the
//! human-angle estimate does not use them.

use crate::calibration::{
    self, CalibrationLimits, FitError, PathBuffer, Rejection, ValidatedArmModel, CALIBRATION_PHASE,
};
use crate::control::{self, AdaptiveDeweighting};
use crate::encoder::{BacklashCompensator, Encoder};
use crate::human::{self, ArmMass, ShoulderAngles};
use crate::kinematics::{self, ElbowBranch, ShoulderBranch};
use nalgebra::Vector3;

/// Simulation step of the SJM dynamics [s] (1 kHz).
pub const PHYSICS_STEP: f64 = 0.001;
/// Robot sampling period [s] (200 Hz firmware loop).
pub const SAMPLE_PERIOD: f64 = 0.005;
const SUBSTEPS: usize = 5;

/// A small deterministic generator (SplitMix64), so runs replay exactly.
#[derive(Clone, Copy, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [low, high).
    pub fn range(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * self.uniform()
    }
}

/// Physical set-up of one experiment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    /// Arm mass properties (paper: weights on the SJM link).
    pub arm: ArmMass,
    /// Inertia about each shoulder axis [kg m²].
    pub inertia: f64,
    /// SJM PD stiffness [N m/rad].
    pub stiffness: f64,
    /// SJM PD damping [N m s/rad].
    pub damping: f64,
    /// Strength of each SJM motor as a multiple of the torque that holds
    /// the arm at the target or the current pose, whichever is larger; its
    /// output saturates there (plus
    /// [`Setup::strength_floor`]) before the (1 − ξ) scaling, so the
    /// impaired arm lifts (1 − ξ) of that.
    pub strength: f64,
    /// Strength added to every pose [N m] (lets the PD work near φ = 0).
    pub strength_floor: f64,
    /// True ψx [rad].
    pub psi_x: f64,
    /// True shoulder centre, frame R0 [m].
    pub origin: Vector3<f64>,
    /// True cuff distance l [m].
    pub length: f64,
    /// Gearbox backlash on θ1..θ3 [rad] (paper 2.2.2: about 1°), modelled
    /// as a dead-band between link and motor-side encoder.
    pub backlash: [f64; 3],
    /// The play the adapter's [`BacklashCompensator`] removes [rad]
    /// (zero: raw motor-side angles).
    pub compensated_backlash: [f64; 3],
}

impl Default for Setup {
    /// 2 kg arm, centre of mass 0.15 m, l = 0.175 m (paper Table 1),
    /// shoulder at (0.10, −0.10, 0.30) m, ψx = 10°; SJM PD 20 N m/rad,
    /// 2.19 N m s/rad (critically damped) with gravity feed-forward; each
    /// motor saturates at the torque that holds the arm at the target (or
    /// the current pose, if larger; strength 1.0) + 0.05 N m, then is
    /// scaled by (1 − ξ): the impaired
    /// arm lifts (1 − ξ) of its weight at any pose, so it needs support
    /// α ≳ ξ. (A fixed saturation makes the needed α depend on the target's
    /// gravity torque; an unsaturated scaled PD never fails when
    /// under-supported.) The PD is stiff enough that over-support after ξ
    /// drops stays within 5°. Backlash 1° on every actuated joint (a
    /// dead-band, also on the gravity-loaded θ2, θ3).
    fn default() -> Self {
        Self {
            arm: ArmMass {
                mass: 2.0,
                centre_of_mass: 0.15,
            },
            inertia: 0.06,
            stiffness: 20.0,
            damping: 2.19,
            strength: 1.0,
            strength_floor: 0.05,
            psi_x: 10f64.to_radians(),
            origin: Vector3::new(0.10, -0.10, 0.30),
            length: 0.175,
            backlash: [1f64.to_radians(); 3],
            compensated_backlash: [1f64.to_radians(); 3],
        }
    }
}

/// The 2-DoF shoulder joint model with its arm.
#[derive(Clone, Copy, Debug)]
pub struct ShoulderJointModel {
    setup: Setup,
    phi: [f64; 2],
    rate: [f64; 2],
    /// Impairment ξ ∈ [0, 1].
    pub impairment: f64,
}

impl ShoulderJointModel {
    /// At rest at `phi`, healthy (ξ = 0).
    pub fn new(setup: Setup, phi: ShoulderAngles) -> Self {
        Self {
            setup,
            phi: [phi.flexion, phi.abduction],
            rate: [0.0; 2],
            impairment: 0.0,
        }
    }

    /// Current shoulder angles (the SJM's encoders: ground truth).
    pub fn angles(&self) -> ShoulderAngles {
        ShoulderAngles {
            flexion: self.phi[0],
            abduction: self.phi[1],
        }
    }

    /// The cuff position p_h = p_r, frame R0 [m].
    pub fn endpoint(&self) -> Vector3<f64> {
        self.setup.origin
            + human::base_rotation(self.setup.psi_x)
                * human::direction(self.angles())
                * self.setup.length
    }

    /// Advances one [`PHYSICS_STEP`] toward `target` (angles and rates)
    /// with the robot pushing the cuff with `cuff_force` [N, frame R0].
    pub fn step(&mut self, target: (ShoulderAngles, [f64; 2]), cuff_force: &Vector3<f64>) {
        let s = self.setup;
        let phi = self.angles();
        let holding = human::gravity_torques(phi, s.psi_x, s.arm);
        let target_holding = human::gravity_torques(target.0, s.psi_x, s.arm);
        let force_h0 = human::base_rotation(s.psi_x).inverse() * cuff_force;
        let external = human::jacobian(phi, s.length).transpose() * force_h0;
        let desired = [target.0.flexion, target.0.abduction];
        for j in 0..2 {
            let command = s.stiffness * (desired[j] - self.phi[j])
                + s.damping * (target.1[j] - self.rate[j])
                + holding[j];
            let limit =
                s.strength * target_holding[j].abs().max(holding[j].abs()) + s.strength_floor;
            let motor = (1.0 - self.impairment) * command.clamp(-limit, limit);
            let acceleration = (motor - holding[j] + external[j]) / s.inertia;
            self.rate[j] += acceleration * PHYSICS_STEP;
        }
        for j in 0..2 {
            self.phi[j] += self.rate[j] * PHYSICS_STEP;
        }
    }
}

/// AREBO's sensing of the attached arm: IK of the cuff position, backlash,
/// encoder quantisation.
#[derive(Clone, Copy, Debug)]
pub struct RobotSensor {
    backlash: [f64; 3],
    motor_side: Option<[f64; 3]>,
}

impl RobotSensor {
    /// A sensor with `backlash` [rad] of play on θ1..θ3.
    pub fn new(backlash: [f64; 3]) -> Self {
        Self {
            backlash,
            motor_side: None,
        }
    }

    /// Encoder counts θ1..θ5 for the cuff at `endpoint` [m, frame R0];
    /// `None` where the robot cannot be there (IK error).
    pub fn read(&mut self, endpoint: &Vector3<f64>) -> Option<[i32; 5]> {
        let link = kinematics::inverse(endpoint, ShoulderBranch::Front, ElbowBranch::Negative)
            .ok()?
            .0;
        let mut motor = self.motor_side.unwrap_or(link);
        for ((m, l), play) in motor.iter_mut().zip(link.iter()).zip(self.backlash.iter()) {
            *m = m.clamp(l - 0.5 * play, l + 0.5 * play);
        }
        self.motor_side = Some(motor);
        let mut counts = [0i32; 5];
        for (i, angle) in motor.iter().enumerate() {
            counts[i] = Encoder::Actuated(i).counts(*angle);
        }
        Some(counts)
    }
}

/// A trajectory generator: angles and rates at time t [s].
pub type Trajectory<'a> = &'a dyn Fn(f64) -> (ShoulderAngles, [f64; 2]);

/// Runs the SJM along `trajectory` for `duration` [s] with no robot force
/// (unassisted, ideal transparency), calling `sample` at 200 Hz with the
/// true angles and the robot's encoder counts.
pub fn run_unassisted(
    setup: Setup,
    trajectory: Trajectory,
    duration: f64,
    mut sample: impl FnMut(ShoulderAngles, Option<[i32; 5]>),
) {
    let mut sjm = ShoulderJointModel::new(setup, trajectory(0.0).0);
    let mut sensor = RobotSensor::new(setup.backlash);
    let samples = (duration / SAMPLE_PERIOD) as usize;
    for n in 0..samples {
        for k in 0..SUBSTEPS {
            let t = (n * SUBSTEPS + k) as f64 * PHYSICS_STEP;
            sjm.step(trajectory(t), &Vector3::zeros());
        }
        sample(sjm.angles(), sensor.read(&sjm.endpoint()));
    }
}

/// Sum of four sines (paper 2.4.3): Σ A_i sin(2π f_i t + v_i) + A_0 per
/// joint, with its rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polysine {
    /// Offsets A_10, A_20 [rad].
    pub offset: [f64; 2],
    /// Amplitude of each component per joint [rad].
    pub amplitude: [f64; 2],
    /// Phases v_ji [rad].
    pub phase: [[f64; 4]; 2],
}

/// The paper's frequencies f_i [Hz].
pub const POLYSINE_FREQUENCIES: [f64; 4] = [0.1, 0.2, 0.35, 0.3];

impl Polysine {
    /// Random phases; flexion in [centre ± 4A], abduction likewise.
    pub fn new(offset: [f64; 2], amplitude: [f64; 2], rng: &mut SplitMix64) -> Self {
        let mut phase = [[0.0; 4]; 2];
        for row in phase.iter_mut() {
            for v in row.iter_mut() {
                *v = rng.range(0.0, 2.0 * core::f64::consts::PI);
            }
        }
        Self {
            offset,
            amplitude,
            phase,
        }
    }

    /// Angles and rates at t [s].
    pub fn at(&self, t: f64) -> (ShoulderAngles, [f64; 2]) {
        let mut value = self.offset;
        let mut rate = [0.0; 2];
        for j in 0..2 {
            for (i, f) in POLYSINE_FREQUENCIES.iter().enumerate() {
                let w = 2.0 * core::f64::consts::PI * f;
                value[j] += self.amplitude[j] * libm::sin(w * t + self.phase[j][i]);
                rate[j] += self.amplitude[j] * w * libm::cos(w * t + self.phase[j][i]);
            }
        }
        (
            ShoulderAngles {
                flexion: value[0],
                abduction: value[1],
            },
            rate,
        )
    }
}

/// Why a simulated calibration failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CalibrationFailure {
    /// A fit failed.
    Fit(FitError),
    /// The validator rejected the fits.
    Rejected(Rejection),
}

fn record(setup: Setup, trajectory: Trajectory, duration: f64) -> PathBuffer {
    let mut path = PathBuffer::new();
    let mut compensator = BacklashCompensator::new(setup.compensated_backlash);
    run_unassisted(setup, trajectory, duration, |_, counts| {
        if let Some(counts) = counts {
            // Capacity 3000 = 15 s at 200 Hz; longer runs keep the first
            // 15 s. Samples inside a joint's play are left out.
            let endpoint = compensator.endpoint(&counts);
            if compensator.settled() {
                let _ = path.push(endpoint);
            }
        }
    });
    path
}

/// The paper's calibration (2.4.3) on the simulator: three sinusoidal
/// flexion movements 0-90° in 15 s for ψx, then 15 s of small random
/// (polysine, ±20° about φ = (45°, 0)) movements for origin and l.
///
/// # Errors
/// [`CalibrationFailure`] when a fit fails or the validator rejects it.
pub fn calibrate(setup: Setup, seed: u64) -> Result<ValidatedArmModel, CalibrationFailure> {
    let plane = calibration::fit_plane(&record(setup, &flexion_calibration, CALIBRATION_PHASE))
        .map_err(CalibrationFailure::Fit)?;
    let small = sphere_calibration(seed);
    let sphere = calibration::fit_sphere(&record(setup, &|t| small.at(t), CALIBRATION_PHASE))
        .map_err(CalibrationFailure::Fit)?;
    calibration::validate(&plane, &sphere, &CalibrationLimits::default())
        .map_err(CalibrationFailure::Rejected)
}

/// Calibration phase 1: three flexion movements 0-90° in 15 s, φ2 = 0.
pub fn flexion_calibration(t: f64) -> (ShoulderAngles, [f64; 2]) {
    let quarter = core::f64::consts::FRAC_PI_4;
    let w = 2.0 * core::f64::consts::PI * 0.2;
    (
        ShoulderAngles {
            flexion: quarter * (1.0 - libm::cos(w * t)),
            abduction: 0.0,
        },
        [quarter * w * libm::sin(w * t), 0.0],
    )
}

/// Calibration phase 2: small random movements, a polysine of ±20° about
/// φ = (45°, 0).
pub fn sphere_calibration(seed: u64) -> Polysine {
    let mut rng = SplitMix64::new(seed);
    Polysine::new(
        [core::f64::consts::FRAC_PI_4, 0.0],
        [5f64.to_radians(); 2],
        &mut rng,
    )
}

/// The joint-angle accuracy motion (paper 2.4.3): flexion 0-90°,
/// abduction ±30°.
pub fn accuracy_motion(seed: u64) -> Polysine {
    let mut rng = SplitMix64::new(seed);
    Polysine::new(
        [45f64.to_radians(), 0.0],
        [11.25f64.to_radians(), 7.5f64.to_radians()],
        &mut rng,
    )
}

/// Median absolute errors of the estimated shoulder angles [rad].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleErrors {
    /// Flexion φ1.
    pub flexion: f64,
    /// Abduction φ2.
    pub abduction: f64,
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_unstable_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The paper's joint-angle accuracy experiment (2.4.3): polysine movements
/// (flexion 0-90°, abduction ±30°) for `duration` [s]; the robot's counts
/// go through FK and `model` to φ̂, compared with the SJM's φ.
pub fn polysine_experiment(
    setup: Setup,
    model: &ValidatedArmModel,
    duration: f64,
    seed: u64,
) -> AngleErrors {
    let mut rng = SplitMix64::new(seed);
    let motion = Polysine::new(
        [45f64.to_radians(), 0.0],
        [11.25f64.to_radians(), 7.5f64.to_radians()],
        &mut rng,
    );
    let (mut flexion, mut abduction) = (Vec::new(), Vec::new());
    let mut compensator = BacklashCompensator::new(setup.compensated_backlash);
    run_unassisted(setup, &|t| motion.at(t), duration, |truth, counts| {
        let estimate = counts.and_then(|c| model.angles(&compensator.endpoint(&c)).ok());
        if let Some(estimate) = estimate {
            flexion.push((estimate.flexion - truth.flexion).abs());
            abduction.push((estimate.abduction - truth.abduction).abs());
        }
    });
    AngleErrors {
        flexion: median(&mut flexion),
        abduction: median(&mut abduction),
    }
}

/// One weight-support trial's record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trial {
    /// Trial number k (from 1).
    pub number: usize,
    /// Impairment ξ during the trial.
    pub impairment: f64,
    /// α used during the trial (α[k]).
    pub alpha: f64,
    /// Whether the arm ended within ±5° of the target.
    pub succeeded: bool,
}

/// Normalised minimum-jerk profile u(s), s ∈ [0, 1], and du/ds.
fn minimum_jerk(s: f64) -> (f64, f64) {
    let s = s.clamp(0.0, 1.0);
    (
        10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5),
        30.0 * s.powi(2) - 60.0 * s.powi(3) + 30.0 * s.powi(4),
    )
}

/// Impairment schedule of paper 2.4.5: 0.6 / 0.2 / 0 for trials 1-100 /
/// 101-200 / 201-300.
pub fn impairment_schedule(trial: usize) -> f64 {
    match trial {
        0..=100 => 0.6,
        101..=200 => 0.2,
        _ => 0.0,
    }
}

/// The adaptive weight-support experiment (paper 2.4.5): `trials`
/// point-to-point moves (3 s minimum jerk, 2 s rest; targets flexion
/// 0-60°, abduction 0-30°), the SJM impaired per
/// [`impairment_schedule`], AREBO in the weight-support mode with α
/// adapted after each trial from α[1] = 0.3. φ̂ for the support comes from
/// the robot's counts through `model`; the arm's mass properties are
/// taken as identified (the setup's).
pub fn weight_support_experiment(
    setup: Setup,
    model: &ValidatedArmModel,
    trials: usize,
    seed: u64,
) -> Vec<Trial> {
    let mut rng = SplitMix64::new(seed);
    let mut start = ShoulderAngles {
        flexion: 0.3,
        abduction: 0.1,
    };
    let mut sjm = ShoulderJointModel::new(setup, start);
    let mut sensor = RobotSensor::new(setup.backlash);
    let mut compensator = BacklashCompensator::new(setup.compensated_backlash);
    let mut adaptive = AdaptiveDeweighting::new(0.3);
    let mut force = Vector3::zeros();
    let mut records = Vec::with_capacity(trials);
    for number in 1..=trials {
        let target = ShoulderAngles {
            flexion: rng.range(0.0, 60f64.to_radians()),
            abduction: rng.range(0.0, 30f64.to_radians()),
        };
        sjm.impairment = impairment_schedule(number);
        let alpha = adaptive.alpha();
        let samples = (5.0 / SAMPLE_PERIOD) as usize;
        for n in 0..samples {
            let estimate = sensor
                .read(&sjm.endpoint())
                .and_then(|c| model.angles(&compensator.endpoint(&c)).ok());
            // The robot holds its last force if a sample cannot be read.
            if let Some(phi) = estimate {
                force = control::support_force(alpha, phi, model, setup.arm).unwrap_or(force);
            }
            for k in 0..SUBSTEPS {
                let t = (n * SUBSTEPS + k) as f64 * PHYSICS_STEP;
                let (u, du) = minimum_jerk(t / 3.0);
                let blend = |a: f64, b: f64| a + (b - a) * u;
                let rate = |a: f64, b: f64| (b - a) * du / 3.0;
                let desired = ShoulderAngles {
                    flexion: blend(start.flexion, target.flexion),
                    abduction: blend(start.abduction, target.abduction),
                };
                let rates = [
                    rate(start.flexion, target.flexion),
                    rate(start.abduction, target.abduction),
                ];
                sjm.step((desired, rates), &force);
            }
        }
        let succeeded = control::trial_succeeded(sjm.angles(), target);
        records.push(Trial {
            number,
            impairment: sjm.impairment,
            alpha,
            succeeded,
        });
        adaptive.update(succeeded);
        start = target;
    }
    records
}
