//! What the simulated device's cuff holds: the shoulder joint model
//! following a trajectory (the paper's experiments), or the kernel's
//! reference arm held at the wrist ([`HeldArm`]).

use crate::held_arm::HeldArm;
use crate::human::ShoulderAngles;
use crate::sim::{self, Setup, ShoulderJointModel};
use nalgebra::Vector3;

/// A trajectory the device's SJM follows (simulated time [s]).
pub type DeviceTrajectory = Box<dyn Fn(f64) -> (ShoulderAngles, [f64; 2]) + Send>;

/// What the simulated device's cuff holds.
pub trait Person: Send {
    /// Advances one stream period with the robot pushing the cuff with
    /// `force` [N, R0]; `moved`: periods since the person started.
    fn advance(&mut self, moved: usize, force: &Vector3<f64>);
    /// The cuff centre [m, R0].
    fn cuff(&self) -> Vector3<f64>;
    /// The cuff's roll axis z_R5 [R0], when the person turns it (θ4, θ5
    /// then follow it; otherwise they read 0).
    fn cuff_axis(&self) -> Option<Vector3<f64>> {
        None
    }
    /// The person's own angles for the record (the SJM's φ; the held
    /// arm's shoulder elevation q1 as `flexion`, elbow flexion q2 as
    /// `abduction`).
    fn angles(&self) -> ShoulderAngles;
}

/// The shoulder joint model following a trajectory from the person's
/// start (the paper's experiments).
pub(super) struct Shoulder {
    sjm: ShoulderJointModel,
    trajectory: DeviceTrajectory,
}

impl Shoulder {
    /// The SJM of `setup` at rest at the trajectory's start.
    pub(super) fn new(setup: Setup, trajectory: DeviceTrajectory) -> Self {
        Self {
            sjm: ShoulderJointModel::new(setup, trajectory(0.0).0),
            trajectory,
        }
    }
}

impl Person for Shoulder {
    fn advance(&mut self, moved: usize, force: &Vector3<f64>) {
        for k in 0..5 {
            let t = (moved * 5 + k) as f64 * sim::PHYSICS_STEP;
            self.sjm.step((self.trajectory)(t), force);
        }
    }

    fn cuff(&self) -> Vector3<f64> {
        self.sjm.endpoint()
    }

    fn angles(&self) -> ShoulderAngles {
        self.sjm.angles()
    }
}

/// The kernel's reference arm held at the wrist ([`HeldArm`]).
impl Person for HeldArm {
    fn advance(&mut self, _: usize, force: &Vector3<f64>) {
        HeldArm::advance(self, force, sim::SAMPLE_PERIOD);
    }

    fn cuff(&self) -> Vector3<f64> {
        HeldArm::cuff(self)
    }

    fn cuff_axis(&self) -> Option<Vector3<f64>> {
        Some(self.forearm())
    }

    fn angles(&self) -> ShoulderAngles {
        let [q1, q2] = self.joints();
        ShoulderAngles {
            flexion: q1,
            abduction: q2,
        }
    }
}
