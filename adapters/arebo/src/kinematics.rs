//! AREBO's kinematic chain (paper 2.1; spec `arebo.md`).
//!
//! # Theory of operation
//! Six revolute joints, standard DH (Rz(θ+offset)·Tz(d)·Tx(a)·Rx(α)):
//!
//! | i | a  | α     | d | θ offset |
//! |---|----|-------|---|----------|
//! | 1 | 0  | +π/2  | 0 | 0        |
//! | 2 | r1 | 0     | 0 | 0        |
//! | 3 | r2 | 0     | 0 | 0        |
//! | 4 | 0  | −π/2  | 0 | −π/2     |
//! | 5 | 0  | +π/2  | 0 | +π/2     |
//! | 6 | 0  | 0     | 0 | +π/2     |
//!
//! The 2023 design makes joints 4-6 a spherical joint at the endpoint
//! (the 2021 offset r3 is 0), so the endpoint p_r (frame R0, m) depends on
//! θ1..θ3 only:
//! p_r = (cos θ1 · T, sin θ1 · T, r1 sin θ2 + r2 sin(θ2+θ3)),
//! T = r1 cos θ2 + r2 cos(θ2+θ3).
//! θ1 turns about the vertical z_R0, so it carries no gravity load.
//!
//! The endpoint Jacobian is 3×6 with zero columns 4-6: a force at the
//! spherical joint's centre makes no torque about its axes, so
//! τ_int = Jᵀ f_int has τ4 = τ5 = τ6 = 0 (paper 2.3.1).
//!
//! # Inverse kinematics
//! Four branches ([`ShoulderBranch`] × [`ElbowBranch`]). Singular where
//! the endpoint is on the z_R0 axis (θ1 undefined), and where the arm is
//! stretched or folded (θ3 = 0 or π: one direction of motion lost); both
//! are reported as typed errors, never as NaN.

use nalgebra::{Rotation3, SMatrix, Vector3};

/// Proximal link length r1 [m] (paper 3.1, optimised).
pub const LINK_1: f64 = 0.333;
/// Distal link length r2 [m] (paper 3.1, optimised).
pub const LINK_2: f64 = 0.381;

/// Distance from the z_R0 axis [m] below which θ1 is treated as undefined.
pub const AXIS_SINGULARITY: f64 = 1e-6;
/// |sin θ3| below which the arm counts as stretched/folded (singular).
pub const ELBOW_SINGULARITY: f64 = 1e-6;

/// The six joint angles θ1..θ6 [rad], each in [−π, π].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointAngles(pub [f64; 6]);

/// The three actuated joint angles θ1..θ3 [rad].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActuatedAngles(pub [f64; 3]);

/// 3×6 endpoint Jacobian ∂p_r/∂θ [m/rad], frame R0.
pub type Jacobian = SMatrix<f64, 3, 6>;

/// Which side of the z_R0 axis link 1 faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShoulderBranch {
    /// θ1 = atan2(y, x): the links reach toward the endpoint (T > 0).
    Front,
    /// θ1 = atan2(y, x) ± π: the links reach over the top (T < 0).
    Back,
}

/// Sign of the elbow angle θ3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElbowBranch {
    /// θ3 > 0.
    Positive,
    /// θ3 < 0.
    Negative,
}

/// Why inverse kinematics has no (unique) answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IkError {
    /// A coordinate is NaN or infinite.
    NonFinite,
    /// The endpoint is farther than r1 + r2 or nearer than |r1 − r2|.
    Unreachable,
    /// The endpoint lies on the z_R0 axis: θ1 is arbitrary.
    OnBaseAxis,
    /// The arm is stretched or folded (θ3 = 0 or π): both elbow branches
    /// coincide and the Jacobian loses rank.
    ElbowSingular,
}

/// Endpoint p_r of the actuated chain [m], frame R0.
pub fn endpoint(q: ActuatedAngles) -> Vector3<f64> {
    let [t1, t2, t3] = q.0;
    let reach = LINK_1 * libm::cos(t2) + LINK_2 * libm::cos(t2 + t3);
    Vector3::new(
        libm::cos(t1) * reach,
        libm::sin(t1) * reach,
        LINK_1 * libm::sin(t2) + LINK_2 * libm::sin(t2 + t3),
    )
}

/// One standard-DH transform: rotation and translation of frame i in i−1.
fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> (Rotation3<f64>, Vector3<f64>) {
    let rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), theta)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), alpha);
    let (s, c) = (libm::sin(theta), libm::cos(theta));
    (rotation, Vector3::new(a * c, a * s, d))
}

/// DH rows (a, α, θ offset) of joints 1..5 (d = 0 in the 2023 design).
const DH_ROWS: [(f64, f64, f64); 5] = [
    (0.0, core::f64::consts::FRAC_PI_2, 0.0),
    (LINK_1, 0.0, 0.0),
    (LINK_2, 0.0, 0.0),
    (
        0.0,
        -core::f64::consts::FRAC_PI_2,
        -core::f64::consts::FRAC_PI_2,
    ),
    (
        0.0,
        core::f64::consts::FRAC_PI_2,
        core::f64::consts::FRAC_PI_2,
    ),
];

/// Pose of frame R5 in R0 from θ1..θ5 (θ6 is not measured on AREBO, so
/// the cuff's roll about z_R5 is unknown): orientation and origin [m].
/// The origin equals [`endpoint`].
pub fn frame_5(q: &JointAngles) -> (Rotation3<f64>, Vector3<f64>) {
    let mut rotation = Rotation3::identity();
    let mut origin = Vector3::zeros();
    for (row, theta) in DH_ROWS.iter().zip(q.0.iter()) {
        let (a, alpha, offset) = *row;
        let (r, t) = dh(theta + offset, 0.0, a, alpha);
        origin += rotation * t;
        rotation *= r;
    }
    (rotation, origin)
}

/// Endpoint Jacobian ∂p_r/∂θ [m/rad], frame R0; columns 4-6 are zero.
pub fn jacobian(q: ActuatedAngles) -> Jacobian {
    let [t1, t2, t3] = q.0;
    let (s1, c1) = (libm::sin(t1), libm::cos(t1));
    let (s2, c2) = (libm::sin(t2), libm::cos(t2));
    let (s23, c23) = (libm::sin(t2 + t3), libm::cos(t2 + t3));
    let reach = LINK_1 * c2 + LINK_2 * c23;
    let d_reach_2 = -LINK_1 * s2 - LINK_2 * s23;
    let d_reach_3 = -LINK_2 * s23;
    let mut j = Jacobian::zeros();
    j[(0, 0)] = -s1 * reach;
    j[(1, 0)] = c1 * reach;
    j[(0, 1)] = c1 * d_reach_2;
    j[(1, 1)] = s1 * d_reach_2;
    j[(2, 1)] = LINK_1 * c2 + LINK_2 * c23;
    j[(0, 2)] = c1 * d_reach_3;
    j[(1, 2)] = s1 * d_reach_3;
    j[(2, 2)] = LINK_2 * c23;
    j
}

/// Joint torques τ = Jᵀ f [N m] of an endpoint force `force` [N], frame
/// R0; only the three actuated joints are returned (τ4..τ6 = 0).
pub fn joint_torques(q: ActuatedAngles, force: &Vector3<f64>) -> Vector3<f64> {
    let j = jacobian(q);
    Vector3::new(
        j.column(0).dot(force),
        j.column(1).dot(force),
        j.column(2).dot(force),
    )
}

/// θ4, θ5 [rad] that point z_R5 along `axis` (frame R0, any length) with
/// the actuated joints at `q`: the inverse of [`frame_5`]'s z axis. In
/// frame R3, z_R5 = (cos a sin b, sin a sin b, cos b) with a = θ4 − π/2,
/// b = θ5 + π/2, b ∈ [0, π]. `None` for a zero or non-finite axis; along
/// z_R3 (b = 0 or π) θ4 is undefined and 0 is taken.
pub fn distal_angles(q: ActuatedAngles, axis: &Vector3<f64>) -> Option<[f64; 2]> {
    let norm = axis.norm();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    let mut rotation = Rotation3::identity();
    for (row, theta) in DH_ROWS.iter().zip(q.0.iter()) {
        let (a, alpha, offset) = *row;
        rotation *= dh(theta + offset, 0.0, a, alpha).0;
    }
    let v = rotation.inverse() * (axis / norm);
    let b = libm::acos(v.z.clamp(-1.0, 1.0));
    let a = if libm::hypot(v.x, v.y) > AXIS_SINGULARITY {
        libm::atan2(v.y, v.x)
    } else {
        0.0
    };
    let half_pi = core::f64::consts::FRAC_PI_2;
    Some([wrap(a + half_pi), b - half_pi])
}

/// Wraps an angle into [−π, π].
pub fn wrap(angle: f64) -> f64 {
    let tau = 2.0 * core::f64::consts::PI;
    let wrapped = angle - tau * libm::floor((angle + core::f64::consts::PI) / tau);
    if wrapped > core::f64::consts::PI {
        wrapped - tau
    } else {
        wrapped
    }
}

/// θ1..θ3 [rad] placing the endpoint at `p` [m, frame R0] on the given
/// branches.
///
/// # Errors
/// [`IkError`] for non-finite input, an unreachable point, and the two
/// singularities (endpoint on z_R0; arm stretched or folded).
pub fn inverse(
    p: &Vector3<f64>,
    shoulder: ShoulderBranch,
    elbow: ElbowBranch,
) -> Result<ActuatedAngles, IkError> {
    if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
        return Err(IkError::NonFinite);
    }
    let radial = libm::hypot(p.x, p.y);
    if radial < AXIS_SINGULARITY {
        return Err(IkError::OnBaseAxis);
    }
    let cos_3 =
        (radial * radial + p.z * p.z - LINK_1 * LINK_1 - LINK_2 * LINK_2) / (2.0 * LINK_1 * LINK_2);
    if !(-1.0..=1.0).contains(&cos_3) {
        return Err(IkError::Unreachable);
    }
    let sin_3_magnitude = libm::sqrt(1.0 - cos_3 * cos_3);
    if sin_3_magnitude < ELBOW_SINGULARITY {
        return Err(IkError::ElbowSingular);
    }
    let sin_3 = match elbow {
        ElbowBranch::Positive => sin_3_magnitude,
        ElbowBranch::Negative => -sin_3_magnitude,
    };
    let (theta_1, reach) = match shoulder {
        ShoulderBranch::Front => (libm::atan2(p.y, p.x), radial),
        ShoulderBranch::Back => (wrap(libm::atan2(p.y, p.x) + core::f64::consts::PI), -radial),
    };
    let theta_3 = libm::atan2(sin_3, cos_3);
    let theta_2 =
        wrap(libm::atan2(p.z, reach) - libm::atan2(LINK_2 * sin_3, LINK_1 + LINK_2 * cos_3));
    Ok(ActuatedAngles([theta_1, theta_2, theta_3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// θ4, θ5 from [`distal_angles`] point z_R5 along the axis asked for.
        #[test]
        fn distal_angles_point_z5_along_the_axis(
            t1 in -1.5..1.5f64, t2 in -0.8..1.2f64, t3 in 0.3..2.5f64,
            x in -1.0..1.0f64, y in -1.0..1.0f64, z in -1.0..1.0f64,
        ) {
            let axis = Vector3::new(x, y, z);
            proptest::prop_assume!(axis.norm() > 1e-3);
            let q = ActuatedAngles([t1, t2, t3]);
            let [t4, t5] = distal_angles(q, &axis).unwrap();
            let (r, _) = frame_5(&JointAngles([t1, t2, t3, t4, t5, 0.0]));
            proptest::prop_assert!((r * Vector3::z() - axis.normalize()).norm() < 1e-9);
        }
    }
    use proptest::prelude::*;

    fn angle() -> impl Strategy<Value = f64> {
        -core::f64::consts::PI..core::f64::consts::PI
    }

    fn branches(q: ActuatedAngles) -> (ShoulderBranch, ElbowBranch) {
        let [_, t2, t3] = q.0;
        let reach = LINK_1 * libm::cos(t2) + LINK_2 * libm::cos(t2 + t3);
        let shoulder = if reach >= 0.0 {
            ShoulderBranch::Front
        } else {
            ShoulderBranch::Back
        };
        let elbow = if t3 >= 0.0 {
            ElbowBranch::Positive
        } else {
            ElbowBranch::Negative
        };
        (shoulder, elbow)
    }

    proptest! {
        /// FK ∘ IK on the branch the angles came from returns the angles
        /// (away from the singularities, which IK reports instead).
        #[test]
        fn fk_ik_round_trip(t1 in angle(), t2 in angle(), t3 in angle()) {
            let q = ActuatedAngles([t1, t2, t3]);
            let p = endpoint(q);
            let (shoulder, elbow) = branches(q);
            prop_assume!(libm::fabs(libm::sin(t3)) > 1e-3);
            prop_assume!(libm::hypot(p.x, p.y) > 1e-3);
            let back = inverse(&p, shoulder, elbow).unwrap();
            prop_assert!(((endpoint(back)) - p).norm() < 1e-9);
            for (a, b) in back.0.iter().zip(q.0.iter()) {
                prop_assert!(libm::fabs(wrap(a - b)) < 1e-6, "{:?} vs {:?}", back, q);
            }
        }

        /// Every branch of IK lands on the requested point.
        #[test]
        fn every_branch_reaches(t1 in angle(), t2 in angle(), t3 in angle()) {
            let p = endpoint(ActuatedAngles([t1, t2, t3]));
            prop_assume!(libm::fabs(libm::sin(t3)) > 1e-3 && libm::hypot(p.x, p.y) > 1e-3);
            for shoulder in [ShoulderBranch::Front, ShoulderBranch::Back] {
                for elbow in [ElbowBranch::Positive, ElbowBranch::Negative] {
                    let q = inverse(&p, shoulder, elbow).unwrap();
                    prop_assert!((endpoint(q) - p).norm() < 1e-9);
                }
            }
        }

        /// The analytic Jacobian matches central finite differences of FK.
        #[test]
        fn jacobian_matches_finite_differences(t1 in angle(), t2 in angle(), t3 in angle()) {
            let q = [t1, t2, t3];
            let j = jacobian(ActuatedAngles(q));
            let h = 1e-6;
            for i in 0..3 {
                let (mut plus, mut minus) = (q, q);
                plus[i] += h;
                minus[i] -= h;
                let numeric = (endpoint(ActuatedAngles(plus)) - endpoint(ActuatedAngles(minus))) / (2.0 * h);
                prop_assert!((numeric - j.column(i)).norm() < 1e-8);
            }
            for i in 3..6 {
                prop_assert!(j.column(i).norm() == 0.0);
            }
        }

        /// The DH chain's frame 5 origin is the closed-form endpoint, for
        /// any θ4, θ5 (spherical joint at the endpoint).
        #[test]
        fn dh_chain_matches_closed_form(t in proptest::array::uniform6(angle())) {
            let (_, origin) = frame_5(&JointAngles(t));
            prop_assert!((origin - endpoint(ActuatedAngles([t[0], t[1], t[2]]))).norm() < 1e-12);
        }

        /// IK never panics and never returns non-finite angles.
        #[test]
        fn inverse_is_total(x in proptest::num::f64::ANY, y in proptest::num::f64::ANY, z in proptest::num::f64::ANY) {
            if let Ok(q) = inverse(&Vector3::new(x, y, z), ShoulderBranch::Front, ElbowBranch::Positive) {
                prop_assert!(q.0.iter().all(|a| a.is_finite()));
            }
        }
    }

    #[test]
    fn singularities_are_reported() {
        let on_axis = Vector3::new(0.0, 0.0, 0.5);
        assert_eq!(
            inverse(&on_axis, ShoulderBranch::Front, ElbowBranch::Positive),
            Err(IkError::OnBaseAxis)
        );
        let stretched = endpoint(ActuatedAngles([0.3, 0.2, 0.0]));
        assert_eq!(
            inverse(&stretched, ShoulderBranch::Front, ElbowBranch::Positive),
            Err(IkError::ElbowSingular)
        );
        let far = Vector3::new(1.0, 0.0, 0.0);
        assert_eq!(
            inverse(&far, ShoulderBranch::Front, ElbowBranch::Negative),
            Err(IkError::Unreachable)
        );
    }
}
