//! The human arm model (paper 2.1.2, 2.3.3, 2.3.4).
//!
//! # Theory of operation
//! The shoulder is a spherical joint at the origin of H0; H0 is R0 rotated
//! about x_R0 by ψx (R = Rx(ψx)). The robot's endpoint sits on the upper
//! arm at distance l from the joint centre. Of Φ = (φ1, φ2, φ3) only
//! flexion/extension φ1 and abduction/adduction φ2 move the endpoint; in
//! H0 (x forward, z up, y toward the side the arm abducts to) the unit
//! arm direction is
//!
//! u(φ) = (sin φ1 cos φ2, sin φ2, −cos φ1 cos φ2),
//!
//! so φ = 0 hangs the arm down, pure flexion moves it in the x-z plane of
//! H0 (whose normal in R0 is Rx(ψx)·y = (0, cos ψx, sin ψx)), and the
//! inverse φ2 = asin u_y, φ1 = atan2(u_x, −u_z) is singular at φ2 = ±90°.
//!
//! # Arm Jacobian and weight support
//! φ3 does not move the endpoint, so its Jacobian column is zero and the
//! paper's J_h ∈ R^{3×3} would be singular. We use as third coordinate the
//! distance along the arm (∂p/∂l = u): J_h = [l ∂u/∂φ1, l ∂u/∂φ2, u].
//! f_h = J_h^{-T} τ_h with τ_h = (τ_h1, τ_h2, 0) then is the force at the
//! cuff that makes τ_h about the shoulder and neither pushes nor pulls
//! along the arm. det J_h = l² cos φ2, invertible for |φ2| < 90°; the
//! weight-support controller keeps |φ2| ≤ 45° (paper 2.3.4).

use nalgebra::{Matrix3, Rotation3, Vector2, Vector3};

/// Standard gravity [m/s²].
pub const GRAVITY: f64 = 9.81;

/// Shoulder angles [rad]: flexion/extension φ1 and abduction/adduction φ2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShoulderAngles {
    /// φ1, flexion positive [rad].
    pub flexion: f64,
    /// φ2, abduction positive [rad].
    pub abduction: f64,
}

/// Why the arm model has no answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArmError {
    /// An input is NaN or infinite.
    NonFinite,
    /// The endpoint coincides with the shoulder centre (no direction).
    AtShoulder,
    /// |φ2| is at 90° (gimbal lock of the φ1/φ2 chart; J_h singular).
    Singular,
}

/// Rotation of H0 in R0: Rx(ψx).
pub fn base_rotation(psi_x: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), psi_x)
}

/// Unit arm direction u(φ), frame H0.
pub fn direction(phi: ShoulderAngles) -> Vector3<f64> {
    let (s1, c1) = (libm::sin(phi.flexion), libm::cos(phi.flexion));
    let (s2, c2) = (libm::sin(phi.abduction), libm::cos(phi.abduction));
    Vector3::new(s1 * c2, s2, -c1 * c2)
}

/// ∂u/∂φ1 and ∂u/∂φ2, frame H0 [1/rad].
fn direction_derivatives(phi: ShoulderAngles) -> (Vector3<f64>, Vector3<f64>) {
    let (s1, c1) = (libm::sin(phi.flexion), libm::cos(phi.flexion));
    let (s2, c2) = (libm::sin(phi.abduction), libm::cos(phi.abduction));
    (
        Vector3::new(c1 * c2, 0.0, s1 * c2),
        Vector3::new(-s1 * s2, c2, c1 * s2),
    )
}

/// Shoulder angles of an arm direction `relative` (any length > 0, frame H0).
///
/// # Errors
/// [`ArmError::NonFinite`], [`ArmError::AtShoulder`] for a zero vector.
pub fn angles(relative: &Vector3<f64>) -> Result<ShoulderAngles, ArmError> {
    if !relative.iter().all(|v| v.is_finite()) {
        return Err(ArmError::NonFinite);
    }
    let length = relative.norm();
    if length < 1e-9 {
        return Err(ArmError::AtShoulder);
    }
    let u = relative / length;
    Ok(ShoulderAngles {
        flexion: libm::atan2(u.x, -u.z),
        abduction: libm::asin(u.y.clamp(-1.0, 1.0)),
    })
}

/// Arm Jacobian J_h = [l ∂u/∂φ1, l ∂u/∂φ2, u] (frame H0; m/rad, m/rad, 1).
pub fn jacobian(phi: ShoulderAngles, length: f64) -> Matrix3<f64> {
    let (d1, d2) = direction_derivatives(phi);
    Matrix3::from_columns(&[d1 * length, d2 * length, direction(phi)])
}

/// Mass properties of the upper arm for the weight-support model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmMass {
    /// Arm (plus cuff share) mass [kg].
    pub mass: f64,
    /// Distance of its centre of mass from the shoulder centre along u [m].
    pub centre_of_mass: f64,
}

/// Torques τ_h = (τ_h1, τ_h2) [N m] the shoulder must make to hold the arm
/// still at φ against gravity (gravity is −z_R0; `psi_x` orients H0).
pub fn gravity_torques(phi: ShoulderAngles, psi_x: f64, arm: ArmMass) -> Vector2<f64> {
    let gravity_h0 = base_rotation(psi_x).inverse() * Vector3::new(0.0, 0.0, -GRAVITY);
    let (d1, d2) = direction_derivatives(phi);
    let weight = gravity_h0 * arm.mass;
    // Holding torque = −(generalised gravity force) = −(c ∂u/∂φ)ᵀ m g.
    Vector2::new(
        -arm.centre_of_mass * d1.dot(&weight),
        -arm.centre_of_mass * d2.dot(&weight),
    )
}

/// f_h = J_h^{-T}(φ) (τ_h1, τ_h2, 0) [N], frame H0: the cuff force that
/// makes the holding torques `torques` and nothing along the arm.
///
/// # Errors
/// [`ArmError::NonFinite`]; [`ArmError::Singular`] when J_h cannot be
/// inverted (|φ2| ≈ 90° or l ≈ 0).
pub fn support_force(
    phi: ShoulderAngles,
    length: f64,
    torques: Vector2<f64>,
) -> Result<Vector3<f64>, ArmError> {
    let j = jacobian(phi, length);
    if !j.iter().chain(torques.iter()).all(|v| v.is_finite()) {
        return Err(ArmError::NonFinite);
    }
    if libm::fabs(length * length * libm::cos(phi.abduction)) < 1e-9 {
        return Err(ArmError::Singular);
    }
    let inverse = j.transpose().try_inverse().ok_or(ArmError::Singular)?;
    Ok(inverse * Vector3::new(torques.x, torques.y, 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// angles ∘ direction is the identity for |φ2| < 90°, |φ1| < 180°.
        #[test]
        fn angles_invert_direction(f in -3.1f64..3.1, a in -1.5f64..1.5, scale in 0.05f64..2.0) {
            let phi = ShoulderAngles { flexion: f, abduction: a };
            let back = angles(&(direction(phi) * scale)).unwrap();
            prop_assert!(libm::fabs(back.flexion - f) < 1e-9 && libm::fabs(back.abduction - a) < 1e-9);
        }

        /// The support force makes exactly the holding torques, has no
        /// component along the arm, and equals the perpendicular part of
        /// the weight moved to the cuff (c/l of it).
        #[test]
        fn support_force_balances_gravity(f in -0.5f64..2.5, a in -0.78f64..0.78, psi in -0.5f64..0.5, l in 0.15f64..0.4) {
            let phi = ShoulderAngles { flexion: f, abduction: a };
            let arm = ArmMass { mass: 2.0, centre_of_mass: 0.12 };
            let tau = gravity_torques(phi, psi, arm);
            let force = support_force(phi, l, tau).unwrap();
            let j = jacobian(phi, l);
            let made = j.transpose() * force;
            prop_assert!((made - Vector3::new(tau.x, tau.y, 0.0)).norm() < 1e-9);
            let u = direction(phi);
            let up = base_rotation(psi).inverse() * Vector3::new(0.0, 0.0, GRAVITY * arm.mass);
            let expected = (up - u * u.dot(&up)) * (arm.centre_of_mass / l);
            prop_assert!((force - expected).norm() < 1e-9);
        }
    }

    #[test]
    fn singular_abduction_is_reported() {
        let phi = ShoulderAngles {
            flexion: 0.3,
            abduction: core::f64::consts::FRAC_PI_2,
        };
        assert_eq!(
            support_force(phi, 0.3, Vector2::new(1.0, 1.0)),
            Err(ArmError::Singular)
        );
    }
}
