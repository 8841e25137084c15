//! The mapping between the robot base frame and the kernel's sagittal
//! frame S (the paper's Σ_S), recorded at grasp time.
//!
//! Theory of operation: when the grasp is closed, the flange pose F₀ =
//! (R₀, p₀) is recorded. Frame S has its origin at p₀ (the grasp point is
//! the flange origin: no tool offset), its z axis along the base z axis (up:
//! the robot base is mounted upright on the table's plane) and its x axis
//! horizontal at `heading` rad about base z (configured: the direction from
//! the wrist toward the shoulder). So R_S = Rz(heading) and
//!
//! ```text
//! p = p₀ + R_S (x, y, z)            (y: lateral, out of the sagittal plane)
//! R = R_S Ry(ψ) R_Sᵀ R₀             (ψ: rotation about S's y axis since grasp)
//! ```
//!
//! A kernel pose (x, z, ψ) becomes a flange target with y = 0 and no other
//! rotation; a measured flange pose becomes (x, z, ψ) by projection (the
//! lateral and out-of-plane parts are dropped, their size is available).
//! Wrenches: a frame-S wrench (fx, fz, ty) is the base wrench
//! (R_S (fx, 0, fz); R_S (0, ty, 0)) at the flange origin, and back by
//! projection.

use limb_kernel::geometry::{Pose, Wrench};
use nalgebra::{Matrix3, Vector3, Vector6};

use crate::kinematics::FlangePose;

/// Frame S in the robot base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspFrame {
    grasp: FlangePose,
    axes: Matrix3<f64>,
}

fn rotation_y(angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

impl GraspFrame {
    /// Records frame S at the flange pose `grasp`; `heading` [rad] is the
    /// angle of S's x axis (toward the shoulder) about base z.
    pub fn record(grasp: FlangePose, heading: f64) -> Self {
        let (s, c) = heading.sin_cos();
        Self {
            grasp,
            axes: Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
        }
    }

    /// The flange pose recorded at grasp time.
    pub fn grasp(&self) -> FlangePose {
        self.grasp
    }

    /// The kernel pose (x, z [m], ψ [rad], frame S) of a flange pose, and
    /// the lateral offset y [m] the projection dropped.
    pub fn pose_in_s(&self, flange: &FlangePose) -> (Pose, f64) {
        let offset = self.axes.transpose() * (flange.position - self.grasp.position);
        let relative =
            self.axes.transpose() * flange.rotation * self.grasp.rotation.transpose() * self.axes;
        let psi = relative[(0, 2)].atan2(relative[(0, 0)]);
        (Pose::new(offset.x, offset.z, psi), offset.y)
    }

    /// The flange pose of kernel pose `pose` (frame S), lateral offset 0.
    pub fn flange_target(&self, pose: Pose) -> FlangePose {
        FlangePose {
            rotation: self.axes
                * rotation_y(pose.psi)
                * self.axes.transpose()
                * self.grasp.rotation,
            position: self.grasp.position + self.axes * Vector3::new(pose.x, 0.0, pose.z),
        }
    }

    /// A frame-S wrench as a base-frame wrench (force [N]; moment [N m]).
    pub fn wrench_to_base(&self, wrench: Wrench) -> Vector6<f64> {
        let force = self.axes * Vector3::new(wrench.fx, 0.0, wrench.fz);
        let moment = self.axes * Vector3::new(0.0, wrench.ty, 0.0);
        Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
    }

    /// The frame-S part (fx, fz, ty) of a base-frame wrench.
    pub fn wrench_in_s(&self, wrench: &Vector6<f64>) -> Wrench {
        let force = self.axes.transpose() * wrench.fixed_rows::<3>(0);
        let moment = self.axes.transpose() * wrench.fixed_rows::<3>(3);
        Wrench::new(force.x, force.z, moment.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward;

    #[test]
    fn pose_round_trips_through_the_flange() {
        let frame = GraspFrame::record(forward(&[0.2, 0.6, 0.0, -1.4, 0.0, 1.0, 0.3]), 2.5);
        let pose = Pose::new(0.12, 0.25, -0.4);
        let (back, lateral) = frame.pose_in_s(&frame.flange_target(pose));
        assert!((back.x - pose.x).abs() < 1e-12);
        assert!((back.z - pose.z).abs() < 1e-12);
        assert!((back.psi - pose.psi).abs() < 1e-12);
        assert!(lateral.abs() < 1e-12);
        let (origin, _) = frame.pose_in_s(&frame.grasp());
        assert!(origin.x.abs() + origin.z.abs() + origin.psi.abs() < 1e-12);
    }

    #[test]
    fn wrench_round_trips_through_the_base() {
        let frame = GraspFrame::record(forward(&[0.0; 7]), -0.7);
        let wrench = Wrench::new(3.0, -12.0, 0.4);
        let back = frame.wrench_in_s(&frame.wrench_to_base(wrench));
        assert!((back.fx - 3.0).abs() < 1e-12);
        assert!((back.fz + 12.0).abs() < 1e-12);
        assert!((back.ty - 0.4).abs() < 1e-12);
    }
}
