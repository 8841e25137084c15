//! Human joint-limit monitor: the validated model's inverse kinematics of
//! the measured pose must stay within the configured ranges, and the pose
//! must fit the model.

use super::{at_most, within, Limit, Verdict, Violation};
use crate::arm::ArmGeometry;
use crate::config::Interval;
use crate::estimation::online::JointEnvelope;
use crate::geometry::Pose;

/// Joint ranges of the person's arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimitMonitor {
    /// Shoulder elevation q1 [rad].
    pub shoulder_elevation: Interval,
    /// Elbow flexion q2 [rad]; below the range is hyperextension.
    pub elbow_flexion: Interval,
    /// Largest | |E − S| − l1 | [m].
    pub max_model_mismatch: f64,
}

impl JointLimitMonitor {
    /// Verdict on the measured grasp pose under the arm model.
    pub fn check(&self, arm: &ArmGeometry, pose: Pose) -> Verdict {
        let (q, mismatch) = arm
            .inverse_from_pose(pose)
            .map_err(|_| Violation::new(Limit::ModelMismatch, f64::NAN, self.max_model_mismatch))?;
        at_most(Limit::ModelMismatch, mismatch, self.max_model_mismatch)?;
        within(
            Limit::ShoulderElevation,
            q.shoulder_elevation,
            self.shoulder_elevation,
        )?;
        within(Limit::ElbowFlexion, q.elbow_flexion, self.elbow_flexion)
    }

    /// Verdict on the worst-case joints of the provisional model during
    /// Estimate (REQ-MON-011): the largest shoulder elevation must not
    /// exceed its range, the smallest elbow flexion must not go below its
    /// range (hyperextension). No envelope (no provisional model yet) is no
    /// verdict: the lift's prior reach bounds the motion then.
    pub fn check_envelope(&self, envelope: Option<JointEnvelope>) -> Verdict {
        let Some(envelope) = envelope else {
            return Ok(());
        };
        at_most(
            Limit::ShoulderElevation,
            envelope.max_shoulder_elevation,
            self.shoulder_elevation.high,
        )?;
        if envelope.min_elbow_flexion >= self.elbow_flexion.low {
            Ok(())
        } else {
            Err(Violation::new(
                Limit::ElbowFlexion,
                envelope.min_elbow_flexion,
                self.elbow_flexion.low,
            ))
        }
    }
}
