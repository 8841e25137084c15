//! Robot-side kinematics of the KUKA LBR iiwa 7 R800: forward kinematics,
//! the geometric Jacobian, a damped least-squares inverse, and the
//! wrench ↔ joint-torque maps.
//!
//! Theory of operation: the published link data of the iiwa 7 R800 as a
//! standard Denavit–Hartenberg chain (all link lengths `a` zero):
//!
//! | joint | d [m] | α [rad] |
//! |---|---|---|
//! | 1 | d_bs = 0.340 | −π/2 |
//! | 2 | 0 | +π/2 |
//! | 3 | d_se = 0.400 | +π/2 |
//! | 4 | 0 | −π/2 |
//! | 5 | d_ew = 0.400 | −π/2 |
//! | 6 | 0 | +π/2 |
//! | 7 | d_wf = 0.126 | 0 |
//!
//! At q = 0 the arm stands straight up and the flange is at
//! (0, 0, 1.266) m in the robot base frame. Every pose and wrench here is in
//! the robot **base frame** (m, rad; N, N m), taken at the **flange origin**
//! (no tool). The Jacobian rows are (linear velocity; angular velocity).
//!
//! The client uses these on `measuredJointPosition` in every FRI version
//! (one code path; 2.5+ `measuredCartesianPose` is not used, see README).

use core::f64::consts::FRAC_PI_2;
use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};

use crate::session::JointVector;

/// Base → shoulder offset d_bs [m].
pub const BASE_TO_SHOULDER: f64 = 0.34;
/// Shoulder → elbow offset d_se [m].
pub const SHOULDER_TO_ELBOW: f64 = 0.40;
/// Elbow → wrist offset d_ew [m].
pub const ELBOW_TO_WRIST: f64 = 0.40;
/// Wrist → flange offset d_wf [m].
pub const WRIST_TO_FLANGE: f64 = 0.126;

const OFFSETS: [f64; 7] = [
    BASE_TO_SHOULDER,
    0.0,
    SHOULDER_TO_ELBOW,
    0.0,
    ELBOW_TO_WRIST,
    0.0,
    WRIST_TO_FLANGE,
];
const TWISTS: [f64; 7] = [
    -FRAC_PI_2, FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2, 0.0,
];

/// Damping λ of the least-squares inverse (m, rad): small enough that the
/// converged solution is exact to 1e-10, large enough to stay bounded near
/// a singularity.
const INVERSE_DAMPING: f64 = 1e-6;
/// Largest joint change of one inverse iteration [rad].
const INVERSE_MAX_STEP: f64 = 0.2;

/// The geometric Jacobian at the flange, base frame: rows (v; ω).
pub type Jacobian = SMatrix<f64, 6, 7>;

/// A flange pose in the robot base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlangePose {
    /// Orientation of the flange frame in the base frame.
    pub rotation: Matrix3<f64>,
    /// Flange origin in the base frame [m].
    pub position: Vector3<f64>,
}

/// The inverse did not converge.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("inverse kinematics did not converge: residual {residual} (m/rad)")]
pub struct InverseError {
    /// Remaining pose error norm (m and rad mixed).
    pub residual: f64,
}

fn rotation_z(angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

fn rotation_x(angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

/// Axis of joint i and origin of frame i−1 (base frame), i = 1..7.
type JointAxes = [(Vector3<f64>, Vector3<f64>); 7];

/// Joint axes and origins of the chain, and the flange pose.
fn chain(q: &JointVector) -> (JointAxes, FlangePose) {
    let mut rotation = Matrix3::identity();
    let mut position = Vector3::zeros();
    let mut joints = [(Vector3::zeros(), Vector3::zeros()); 7];
    for (i, joint) in joints.iter_mut().enumerate() {
        *joint = (rotation.column(2).into_owned(), position);
        position += rotation * Vector3::new(0.0, 0.0, OFFSETS[i]);
        rotation = rotation * rotation_z(q[i]) * rotation_x(TWISTS[i]);
    }
    (joints, FlangePose { rotation, position })
}

/// Flange pose at joint angles `q` [rad].
pub fn forward(q: &JointVector) -> FlangePose {
    chain(q).1
}

/// Geometric Jacobian at the flange origin, base frame, at `q` [rad].
pub fn jacobian(q: &JointVector) -> Jacobian {
    jacobian_and_flange(q).0
}

/// The Jacobian and the flange pose from one pass over the chain.
fn jacobian_and_flange(q: &JointVector) -> (Jacobian, FlangePose) {
    let (joints, flange) = chain(q);
    let mut jacobian = Jacobian::zeros();
    for (i, (axis, origin)) in joints.iter().enumerate() {
        let linear = axis.cross(&(flange.position - origin));
        jacobian.fixed_view_mut::<3, 1>(0, i).copy_from(&linear);
        jacobian.fixed_view_mut::<3, 1>(3, i).copy_from(axis);
    }
    (jacobian, flange)
}

/// Pose error (position [m]; small rotation vector [rad]) from `actual` to
/// `target`, base frame.
pub fn pose_error(target: &FlangePose, actual: &FlangePose) -> Vector6<f64> {
    let relative = target.rotation * actual.rotation.transpose();
    let rotation = 0.5
        * Vector3::new(
            relative[(2, 1)] - relative[(1, 2)],
            relative[(0, 2)] - relative[(2, 0)],
            relative[(1, 0)] - relative[(0, 1)],
        );
    let position = target.position - actual.position;
    Vector6::new(
        position.x, position.y, position.z, rotation.x, rotation.y, rotation.z,
    )
}

/// Joint angles reaching `target`, by damped least squares started at
/// `seed` (the last solution: the minimum-norm step keeps the redundant
/// elbow where it was). `tolerance` on the pose error norm (m, rad).
///
/// # Errors
/// [`InverseError`] when `iterations` do not reach `tolerance` or the
/// result is not finite.
pub fn inverse(
    target: &FlangePose,
    seed: &JointVector,
    tolerance: f64,
    iterations: usize,
) -> Result<JointVector, InverseError> {
    let mut q = *seed;
    let mut residual = f64::INFINITY;
    for _ in 0..=iterations {
        let (j, flange) = jacobian_and_flange(&q);
        let error = pose_error(target, &flange);
        residual = error.norm();
        if residual <= tolerance {
            return Ok(q);
        }
        if !residual.is_finite() {
            break;
        }
        let damped = j * j.transpose() + Matrix6::identity() * INVERSE_DAMPING.powi(2);
        let Some(solved) = damped.lu().solve(&error) else {
            break;
        };
        let step = j.transpose() * solved;
        let scale = (INVERSE_MAX_STEP / step.amax()).min(1.0);
        for (angle, delta) in q.iter_mut().zip(step.iter()) {
            *angle += scale * delta;
        }
    }
    Err(InverseError { residual })
}

/// Joint torques [N m] that balance `wrench` (force [N]; moment [N m]) at
/// the flange, base frame: τ = Jᵀ F.
pub fn joint_torque_from_wrench(q: &JointVector, wrench: &Vector6<f64>) -> JointVector {
    let torque = jacobian(q).transpose() * wrench;
    let mut out = [0.0; 7];
    out.copy_from_slice(torque.as_slice());
    out
}

/// The flange wrench (force [N]; moment [N m], base frame) whose joint
/// torques best match `torque` [N m] in least squares:
/// F = (J Jᵀ)⁻¹ J τ. `None` at a singular configuration.
pub fn wrench_from_joint_torque(q: &JointVector, torque: &JointVector) -> Option<Vector6<f64>> {
    let j = jacobian(q);
    let tau = SMatrix::<f64, 7, 1>::from_column_slice(torque);
    let wrench = (j * j.transpose()).lu().solve(&(j * tau))?;
    wrench.iter().all(|v| v.is_finite()).then_some(wrench)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CONFIGURATION: JointVector = [0.3, 0.7, -0.2, -1.3, 0.4, 1.1, 0.5];

    #[test]
    fn upright_flange_height_is_the_sum_of_offsets() {
        let flange = forward(&[0.0; 7]);
        assert!((flange.position - Vector3::new(0.0, 0.0, 1.266)).norm() < 1e-12);
        assert!((flange.rotation - Matrix3::identity()).norm() < 1e-12);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let j = jacobian(&CONFIGURATION);
        let base = forward(&CONFIGURATION);
        let h = 1e-7;
        for i in 0..7 {
            let mut q = CONFIGURATION;
            q[i] += h;
            let column = pose_error(&forward(&q), &base) / h;
            assert!((column - j.column(i)).norm() < 1e-5, "column {i}");
        }
    }

    #[test]
    fn inverse_recovers_a_nearby_configuration() {
        let mut target_q = CONFIGURATION;
        target_q[1] += 0.05;
        target_q[3] -= 0.04;
        let target = forward(&target_q);
        let q = inverse(&target, &CONFIGURATION, 1e-10, 20).unwrap();
        assert!(pose_error(&target, &forward(&q)).norm() < 1e-10);
    }

    #[test]
    fn wrench_round_trips_through_joint_torque() {
        let wrench = Vector6::new(3.0, -2.0, 10.0, 0.1, 0.5, -0.2);
        let torque = joint_torque_from_wrench(&CONFIGURATION, &wrench);
        let back = wrench_from_joint_torque(&CONFIGURATION, &torque).unwrap();
        assert!((back - wrench).norm() < 1e-9);
    }
}
