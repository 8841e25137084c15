//! `grasp_compliance`: the grasp is a spring of stiffness `k` [N/m] between
//! the robot's end-effector and the wrist. The arm still moves with the
//! wrist; the robot's logged position leads the wrist by F / k, F being the
//! force the robot applies to the arm (F = −f_ext). psi is not affected.

use super::Parameter;

/// Parameters: k [N/m].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new("k", "N/m", 50.0, 1.0e6, "grasp stiffness")];

/// Compliant grasp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GraspCompliance {
    /// Stiffness [N/m].
    pub k: f64,
}

impl GraspCompliance {
    /// End-effector pose for wrist pose `pose` and logged f_ext `wrench`.
    pub fn end_effector(&self, pose: [f64; 3], wrench: [f64; 3]) -> [f64; 3] {
        [
            pose[0] - wrench[0] / self.k,
            pose[1] - wrench[1] / self.k,
            pose[2],
        ]
    }
}
