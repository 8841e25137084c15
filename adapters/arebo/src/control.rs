//! AREBO's controller (paper 2.3): gravity compensation, the torque PD,
//! unassisted and weight-support modes, adaptive de-weighting.
//!
//! # Theory of operation
//! ```text
//! θ ─▶ τ_g(θ) ──────────────────────────────────────────┐
//! τ_r (torque sensors) ─▶ τ_int = τ_r − τ_g ─┐           ▼
//! mode ─▶ τ_d ───────────────────────────────┴▶ Δτ ─▶ PD ─▶ + ─▶ motor torque
//! ```
//! τ_d is 0 in the unassisted mode and Jᵀ α R_H0 f_h(φ) in the weight
//! support mode. The torque PD is the paper's
//! τ_c[n] = k1 Δτ[n] + k2 Δτ[n−1] per actuated joint with
//! **Δτ = τ_d − τ_int**: the paper prints Δτ = τ_d − τ_r − τ_g with
//! τ_r = τ_int + τ_g, which subtracts the robot's weight twice; the
//! interaction torque is the sensor reading less the robot's own gravity
//! torque, and that is what must track τ_d. The motor is commanded τ_g + τ_c
//! (gravity compensation feeds forward, paper Figure 8).
//!
//! # Gravity model
//! θ1 turns about the vertical z_R0 and carries no gravity torque. With
//! link 2 (r1) and link 3 (r2) centres of mass anywhere in their links'
//! planes, the potential is
//! U = P1 sin θ2 + P2 cos θ2 + P3 sin(θ2+θ3) + P4 cos(θ2+θ3)
//! (P in N m), so τ_g = ∂U/∂θ is linear in P = (P1..P4):
//! τ_g2 = P1 c2 − P2 s2 + P3 c23 − P4 s23, τ_g3 = P3 c23 − P4 s23.
//! [`GravityIdentification`] fits P by least squares over static poses
//! (the paper's calibration, 2.3.2). [`GravityParameters::ASSUMED`] are the
//! masses this crate assumes until identified (and that the simulator
//! uses): link 2 1.5 kg at 0.17 m; joint-3 actuator and flange 1.2 kg at
//! r1; link 3 1.0 kg at 0.19 m; the cuff (spherical joint) 0.6 kg at r2;
//! all on the link axes (P2 = P4 = 0). These are assumptions, not
//! measurements; the paper does not publish them.

use crate::calibration::{FitError, ValidatedArmModel};
use crate::human::{self, ArmMass, ShoulderAngles, GRAVITY};
use crate::kinematics::{self, ActuatedAngles, LINK_1, LINK_2};
use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

/// Gravity model parameters P1..P4 [N m] (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GravityParameters(pub [f64; 4]);

impl GravityParameters {
    /// The assumed masses (module docs): P1 = g(1.5·0.17 + (1.2 + 1.0 +
    /// 0.6)·r1), P3 = g(1.0·0.19 + 0.6·r2).
    pub const ASSUMED: GravityParameters = GravityParameters([
        GRAVITY * (1.5 * 0.17 + (1.2 + 1.0 + 0.6) * LINK_1),
        0.0,
        GRAVITY * (1.0 * 0.19 + 0.6 * LINK_2),
        0.0,
    ]);

    /// Gravity torques τ_g(θ) [N m] at the actuated joints.
    pub fn torques(&self, q: ActuatedAngles) -> Vector3<f64> {
        regressor(q) * Vector4::from(self.0)
    }
}

/// τ_g = Y(θ) P: the 3×4 gravity regressor.
fn regressor(q: ActuatedAngles) -> nalgebra::Matrix3x4<f64> {
    let [_, t2, t3] = q.0;
    let (s2, c2) = (libm::sin(t2), libm::cos(t2));
    let (s23, c23) = (libm::sin(t2 + t3), libm::cos(t2 + t3));
    nalgebra::Matrix3x4::new(
        0.0, 0.0, 0.0, 0.0, //
        c2, -s2, c23, -s23, //
        0.0, 0.0, c23, -s23,
    )
}

/// Streaming least-squares identification of [`GravityParameters`] from
/// static poses (normal equations, constant memory).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GravityIdentification {
    normal: Matrix4<f64>,
    rhs: Vector4<f64>,
    poses: usize,
}

impl GravityIdentification {
    /// Adds a static pose θ and the torques held there [N m]; non-finite
    /// input is ignored and reported.
    ///
    /// # Errors
    /// [`FitError::NonFinite`].
    pub fn add(&mut self, q: ActuatedAngles, held: &Vector3<f64>) -> Result<(), FitError> {
        if !q.0.iter().chain(held.iter()).all(|v| v.is_finite()) {
            return Err(FitError::NonFinite);
        }
        let y = regressor(q);
        self.normal += y.transpose() * y;
        self.rhs += y.transpose() * held;
        self.poses += 1;
        Ok(())
    }

    /// The least-squares parameters.
    ///
    /// # Errors
    /// [`FitError::TooFewPoints`] under 4 poses; [`FitError::Degenerate`]
    /// when the poses do not excite all four parameters.
    pub fn solve(&self) -> Result<GravityParameters, FitError> {
        if self.poses < 4 {
            return Err(FitError::TooFewPoints);
        }
        let p = self
            .normal
            .cholesky()
            .ok_or(FitError::Degenerate)?
            .solve(&self.rhs);
        Ok(GravityParameters([p.x, p.y, p.z, p.w]))
    }
}

/// Interaction force [N, frame R0] from interaction torques [N m]:
/// solves J_aᵀ f = τ_int with J_a the actuated 3×3 block.
///
/// # Errors
/// `None` near a kinematic singularity (J_a not invertible).
pub fn interaction_force(q: ActuatedAngles, interaction: &Vector3<f64>) -> Option<Vector3<f64>> {
    let j = kinematics::jacobian(q);
    let actuated: Matrix3<f64> = j.fixed_view::<3, 3>(0, 0).into_owned();
    if libm::fabs(actuated.determinant()) < 1e-6 {
        return None;
    }
    actuated
        .transpose()
        .try_inverse()
        .map(|inverse| inverse * interaction)
}

/// Gains of the discrete torque PD, per actuated joint [1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorqueGains {
    /// k1 (on Δτ[n]).
    pub k1: [f64; 3],
    /// k2 (on Δτ[n−1]).
    pub k2: [f64; 3],
}

/// The torque PD τ_c[n] = k1 Δτ[n] + k2 Δτ[n−1], Δτ = τ_d − τ_int.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorqueController {
    gains: TorqueGains,
    previous_error: Vector3<f64>,
}

impl TorqueController {
    /// A controller with zero error history.
    pub fn new(gains: TorqueGains) -> Self {
        Self {
            gains,
            previous_error: Vector3::zeros(),
        }
    }

    /// One 200 Hz step: desired interaction torques τ_d, torque sensor
    /// readings τ_r and gravity torques τ_g [N m] in; motor torques
    /// τ_g + τ_c [N m] out. A non-finite input resets the history and
    /// commands gravity compensation only (τ_c = 0).
    pub fn step(
        &mut self,
        desired: &Vector3<f64>,
        measured: &Vector3<f64>,
        gravity: &Vector3<f64>,
    ) -> Vector3<f64> {
        let error = desired - (measured - gravity);
        if !error.iter().all(|v| v.is_finite()) {
            self.previous_error = Vector3::zeros();
            return *gravity;
        }
        let k1 = Vector3::from(self.gains.k1);
        let k2 = Vector3::from(self.gains.k2);
        let output = k1.component_mul(&error) + k2.component_mul(&self.previous_error);
        self.previous_error = error;
        gravity + output
    }
}

/// Largest |φ2| the weight support computes with [rad] (paper 2.3.4: 45°).
pub const SUPPORT_ABDUCTION_LIMIT: f64 = core::f64::consts::FRAC_PI_4;

/// Operating mode (paper 2.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Unassisted (zero interaction force): τ_d = 0.
    Unassisted,
    /// Weight support with de-weighting α ∈ [0, 1].
    WeightSupport {
        /// Fraction of the arm's holding torque supported.
        alpha: f64,
    },
}

/// The endpoint force [N, frame R0] the weight support applies to the arm:
/// f_int = α R_H0 J_h^{-T}(φ) τ_h(φ), with φ2 clamped to ±45°.
///
/// # Errors
/// [`human::ArmError`] for non-finite φ.
pub fn support_force(
    alpha: f64,
    phi: ShoulderAngles,
    model: &ValidatedArmModel,
    arm: ArmMass,
) -> Result<Vector3<f64>, human::ArmError> {
    let clamped = ShoulderAngles {
        flexion: phi.flexion,
        abduction: phi
            .abduction
            .clamp(-SUPPORT_ABDUCTION_LIMIT, SUPPORT_ABDUCTION_LIMIT),
    };
    let holding = human::gravity_torques(clamped, model.psi_x(), arm);
    let force_h0 = human::support_force(clamped, model.length(), holding)?;
    Ok(human::base_rotation(model.psi_x()) * force_h0 * alpha.clamp(0.0, 1.0))
}

/// Desired interaction torques τ_d [N m] of a mode at θ and φ.
///
/// # Errors
/// [`human::ArmError`] for non-finite φ in the weight-support mode.
pub fn desired_torques(
    mode: Mode,
    q: ActuatedAngles,
    phi: ShoulderAngles,
    model: &ValidatedArmModel,
    arm: ArmMass,
) -> Result<Vector3<f64>, human::ArmError> {
    match mode {
        Mode::Unassisted => Ok(Vector3::zeros()),
        Mode::WeightSupport { alpha } => Ok(kinematics::joint_torques(
            q,
            &support_force(alpha, phi, model, arm)?,
        )),
    }
}

/// A trial succeeds when both shoulder angles end within this of the
/// target [rad] (paper 2.4.5: ±5°).
pub const SUCCESS_TOLERANCE: f64 = 5.0 * core::f64::consts::PI / 180.0;

/// True when `reached` is within ±5° of `target` on φ1 and φ2.
pub fn trial_succeeded(reached: ShoulderAngles, target: ShoulderAngles) -> bool {
    libm::fabs(reached.flexion - target.flexion) <= SUCCESS_TOLERANCE
        && libm::fabs(reached.abduction - target.abduction) <= SUCCESS_TOLERANCE
}

/// Adaptive de-weighting (paper 2.3.4): α[k+1] = F(S[k], α[k]) α[k] + Δ(S[k]),
/// F = 1 on failure, 0.95 on success with α ≤ 0.5, 0.98 on success with
/// α > 0.5; Δ = 0.02 on failure, 0 on success. α stays in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveDeweighting {
    alpha: f64,
}

impl AdaptiveDeweighting {
    /// Starts at α[1] (the paper uses 0.3); clamped to [0, 1], NaN → 0.
    pub fn new(initial: f64) -> Self {
        Self {
            alpha: if initial.is_nan() {
                0.0
            } else {
                initial.clamp(0.0, 1.0)
            },
        }
    }

    /// The current α.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Applies trial k's outcome; returns α[k+1].
    pub fn update(&mut self, succeeded: bool) -> f64 {
        let (forgetting, learning) = match (succeeded, self.alpha <= 0.5) {
            (false, _) => (1.0, 0.02),
            (true, true) => (0.95, 0.0),
            (true, false) => (0.98, 0.0),
        };
        self.alpha = (forgetting * self.alpha + learning).clamp(0.0, 1.0);
        self.alpha
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn angle() -> impl Strategy<Value = f64> {
        -3.1f64..3.1
    }

    proptest! {
        /// Identification from noise-free static poses recovers P.
        #[test]
        fn gravity_identification_recovers_parameters(p in proptest::array::uniform4(-5.0f64..5.0), poses in proptest::collection::vec(proptest::array::uniform3(angle()), 8..20)) {
            let truth = GravityParameters(p);
            let mut identification = GravityIdentification::default();
            for q in &poses {
                let q = ActuatedAngles(*q);
                identification.add(q, &truth.torques(q)).unwrap();
            }
            if let Ok(fit) = identification.solve() {
                for (a, b) in fit.0.iter().zip(p.iter()) {
                    prop_assert!(libm::fabs(a - b) < 1e-6);
                }
            }
        }

        /// τ_g is the gradient of the potential U (finite differences).
        #[test]
        fn gravity_is_potential_gradient(q in proptest::array::uniform3(angle())) {
            let p = GravityParameters::ASSUMED.0;
            let potential = |q: [f64; 3]| p[0] * libm::sin(q[1]) + p[1] * libm::cos(q[1]) + p[2] * libm::sin(q[1] + q[2]) + p[3] * libm::cos(q[1] + q[2]);
            let tau = GravityParameters::ASSUMED.torques(ActuatedAngles(q));
            for i in 0..3 {
                let (mut a, mut b) = (q, q);
                a[i] += 1e-6;
                b[i] -= 1e-6;
                prop_assert!(libm::fabs((potential(a) - potential(b)) / 2e-6 - tau[i]) < 1e-6);
            }
        }

        /// α stays in [0, 1] under any outcome sequence.
        #[test]
        fn alpha_stays_in_range(outcomes in proptest::collection::vec(any::<bool>(), 0..400), initial in -1.0f64..2.0) {
            let mut adaptive = AdaptiveDeweighting::new(initial);
            for s in outcomes {
                let a = adaptive.update(s);
                prop_assert!((0.0..=1.0).contains(&a));
            }
        }
    }

    #[test]
    fn deweighting_follows_the_paper() {
        let mut adaptive = AdaptiveDeweighting::new(0.3);
        assert!((adaptive.update(false) - 0.32).abs() < 1e-12);
        assert!((adaptive.update(true) - 0.32 * 0.95).abs() < 1e-12);
        let mut high = AdaptiveDeweighting::new(0.6);
        assert!((high.update(true) - 0.588).abs() < 1e-12);
    }

    #[test]
    fn torque_pd_uses_interaction_torque() {
        let gains = TorqueGains {
            k1: [2.0; 3],
            k2: [-1.0; 3],
        };
        let mut pd = TorqueController::new(gains);
        let gravity = Vector3::new(0.0, 5.0, 2.0);
        // Sensor reads exactly the robot's weight: no interaction, no
        // correction in the unassisted mode.
        let out = pd.step(&Vector3::zeros(), &gravity, &gravity);
        assert_eq!(out, gravity);
        // 1 N m of interaction on joint 2: Δτ = −1, output k1·(−1).
        let out = pd.step(
            &Vector3::zeros(),
            &(gravity + Vector3::new(0.0, 1.0, 0.0)),
            &gravity,
        );
        assert!((out - gravity - Vector3::new(0.0, -2.0, 0.0)).norm() < 1e-12);
        let out = pd.step(
            &Vector3::zeros(),
            &(gravity + Vector3::new(0.0, 1.0, 0.0)),
            &gravity,
        );
        assert!((out - gravity - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    }
}
