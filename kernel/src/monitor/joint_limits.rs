//! Human joint-limit monitor: the validated model's inverse kinematics of
//! the measured pose must stay within the configured ranges, and the pose
//! must fit the model.

use super::{at_most, within, Limit, Verdict, Violation};
use crate::arm::ArmGeometry;
use crate::config::Interval;
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
}

/// Proof of the decidable part of REQ-MON-005.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    use crate::kani_inputs::{any_pose, validated_arm, HOLD};
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-MON-005: a non-finite pose trips as a model mismatch, a passing
    /// pose is finite, and a trip names a joint-limit or model limit.
    pub fn check_joint_verdict(pose: Pose, verdict: Verdict) -> Result<(), &'static str> {
        match verdict {
            Ok(()) if pose.is_finite() => Ok(()),
            Ok(()) => Err("a non-finite pose passed the joint-limit monitor"),
            Err(v) if !pose.is_finite() && v.limit != Limit::ModelMismatch => {
                Err("a non-finite pose tripped on another limit than the model")
            }
            Err(v) => match v.limit {
                Limit::ModelMismatch | Limit::ShoulderElevation | Limit::ElbowFlexion => Ok(()),
                _ => Err("the joint-limit monitor named another limit"),
            },
        }
    }

    /// REQ-MON-005: for any measured pose under a validated model the
    /// joint-limit monitor is total, trips on NaN and infinities and names
    /// what it tripped on. That it trips exactly outside the joint ranges is
    /// numerical (inverse kinematics through atan2): the proptest property
    /// `arbitrary_sessions_keep_every_safety_property` checks it against an
    /// independent model. Unwind 16: the validator that makes the fixed
    /// arm checks 15 values for finiteness.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(16))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    #[cfg_attr(kani, kani::stub(libm::atan2, crate::kani_stubs::stub::atan2))]
    #[cfg_attr(kani, kani::stub(libm::sin, crate::kani_stubs::stub::sin))]
    #[cfg_attr(kani, kani::stub(libm::cos, crate::kani_stubs::stub::cos))]
    pub fn verify_req_mon_005_joint_limit_monitor_is_total() {
        let l = SafetyLimits::default();
        let monitor = JointLimitMonitor {
            shoulder_elevation: l.shoulder_elevation,
            elbow_flexion: l.elbow_flexion,
            max_model_mismatch: l.max_model_mismatch,
        };
        let arm = validated_arm();
        let pose = if kani::any() { any_pose() } else { HOLD };
        let verdict = monitor.check(arm.geometry(), pose);
        assert_eq!(check_joint_verdict(pose, verdict), Ok(()));
        kani::cover!(verdict.is_ok(), "joint limits: passes");
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::ModelMismatch),
            "joint limits: model mismatch"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "joint-limit monitor",
                20_000,
                verify_req_mon_005_joint_limit_monitor_is_total,
            );
        }
    }
}
