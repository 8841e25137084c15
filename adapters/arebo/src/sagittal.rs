//! Frame S, the kernel's sagittal frame, placed in AREBO's base frame R0:
//! poses and forces between the two (the robot's translation of frames
//! and commands, the held arm's placement on the device).
//!
//! S's origin is a point of R0 (for a session, the cuff centre at the
//! first frame), +z = z_R0 (up), +x horizontal at `heading` about z_R0
//! (toward the shoulder), +y = z × x (lateral); a grasp pose's ψ is the
//! forearm axis's angle above −x_S (ψ > 0 when the hand is above the
//! elbow). Metres and radians.

use limb_kernel::geometry::{Pose, Wrench};
use nalgebra::{Rotation3, Vector3};

/// Frame S in R0: its origin a point of R0 (a session's: the cuff centre
/// at the first frame), x toward the shoulder at `heading` about z_R0,
/// z up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SagittalFrame {
    /// Origin of S in R0 [m].
    pub origin: Vector3<f64>,
    /// R0 → S rotation (about z_R0 by −heading).
    to_s: Rotation3<f64>,
}

impl SagittalFrame {
    /// Frame S at `origin` (R0, m) with its x axis at `heading` [rad]
    /// about z_R0.
    pub fn new(origin: Vector3<f64>, heading: f64) -> Self {
        Self {
            origin,
            to_s: Rotation3::from_axis_angle(&Vector3::z_axis(), -heading),
        }
    }

    /// Grasp pose in S and lateral y [m] of a cuff at `centre` (R0) whose
    /// forearm axis (elbow → hand) is `forearm` (R0, any length).
    pub fn pose(&self, centre: &Vector3<f64>, forearm: &Vector3<f64>) -> (Pose, f64) {
        let p = self.to_s * (centre - self.origin);
        let a = self.to_s * forearm;
        (Pose::new(p.x, p.z, libm::atan2(a.z, -a.x)), p.y)
    }

    /// A force in R0 expressed in S (x, z components and y).
    pub fn in_s(&self, force: &Vector3<f64>) -> Vector3<f64> {
        self.to_s * force
    }

    /// A vector in S expressed in R0.
    pub fn from_s(&self, vector: &Vector3<f64>) -> Vector3<f64> {
        self.to_s.inverse() * vector
    }

    /// The force (fx, fz) of a planar wrench in S, in R0 (ty dropped).
    pub fn to_r0(&self, wrench: &Wrench) -> Vector3<f64> {
        self.from_s(&Vector3::new(wrench.fx, 0.0, wrench.fz))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cuff moved by (dx, dz) in S along S's axes, its forearm at ψ,
    /// reads back as that pose, lateral 0.
    #[test]
    fn a_cuff_in_the_sagittal_plane_reads_as_its_pose_in_s() {
        let s = SagittalFrame::new(Vector3::new(0.4, 0.1, -0.2), 2.0);
        let x = Vector3::new(libm::cos(2.0), libm::sin(2.0), 0.0);
        let z = Vector3::z();
        for (dx, dz, psi) in [(0.0, 0.0, 0.0), (0.05, 0.12, 0.7), (-0.02, 0.3, -0.2)] {
            let centre = s.origin + x * dx + z * dz;
            // Elbow → hand: (−cos ψ, sin ψ) in S.
            let forearm = -x * libm::cos(psi) + z * libm::sin(psi);
            let (pose, lateral) = s.pose(&centre, &(forearm * 3.0));
            assert!((pose.x - dx).abs() < 1e-12, "{pose:?}");
            assert!((pose.z - dz).abs() < 1e-12, "{pose:?}");
            assert!((pose.psi - psi).abs() < 1e-12, "{pose:?}");
            assert!(lateral.abs() < 1e-12);
        }
    }
}
