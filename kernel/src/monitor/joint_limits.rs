//! Human joint-limit monitor: the validated model's inverse kinematics of
//! the measured pose must stay within the configured ranges, and the pose
//! must fit the model.

use super::{at_most, within, Limit, Verdict, Violation};
use crate::arm::ArmGeometry;
use crate::config::{Interval, SafetyLimits};
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
    /// The monitor of the configured `limits`.
    pub fn from_limits(limits: &SafetyLimits) -> Self {
        Self {
            shoulder_elevation: limits.shoulder_elevation,
            elbow_flexion: limits.elbow_flexion,
            max_model_mismatch: limits.max_model_mismatch,
        }
    }

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

/// Proofs of the decidable part of REQ-MON-005 and of REQ-MON-011.
/// The worst case of the person's joint angles at a pose under the
/// provisional model [rad].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct JointEnvelope {
    /// Largest shoulder elevation q1 the model allows.
    pub max_shoulder_elevation: f64,
    /// Smallest elbow flexion q2 (most hyperextended) the model allows.
    pub min_elbow_flexion: f64,
}

#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    use crate::kani_inputs::{validated_arm, HOLD};
    use crate::kani_stubs::libm_stubbed;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-MON-005: a non-finite pose trips as a model mismatch, a passing
    /// pose is finite, and a trip names a joint-limit or model limit.
    pub(super) fn check_joint_verdict(pose: Pose, verdict: Verdict) -> Result<(), &'static str> {
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

    libm_stubbed! { [hypot, atan2, sin, cos]
        /// REQ-MON-005: for any measured pose under a validated model the
        /// joint-limit monitor is total, trips on NaN and infinities and names
        /// what it tripped on. That it trips exactly outside the joint ranges is
        /// numerical (inverse kinematics through atan2): the proptest property
        /// `arbitrary_sessions_keep_every_safety_property` checks it against an
        /// independent model. Unwind 24: the validator that makes the fixed
        /// arm checks 22 values for finiteness (22 iterations and the
        /// loop's exit; 24 as the validator's own proof).
        #[cfg_attr(kani, kani::proof)]
        #[cfg_attr(kani, kani::unwind(24))]
        pub(super) fn verify_req_mon_005_joint_limit_monitor_is_total() {
            let l = SafetyLimits::default();
            let monitor = JointLimitMonitor::from_limits(&l);
            let arm = validated_arm();
            let pose = if kani::any() { kani::any::<Pose>() } else { HOLD };
            let verdict = monitor.check(arm.geometry(), pose);
            assert_eq!(check_joint_verdict(pose, verdict), Ok(()));
            kani::cover!(verdict.is_ok(), "joint limits: passes");
            kani::cover!(
                verdict.is_err_and(|v| v.limit == Limit::ModelMismatch),
                "joint limits: model mismatch"
            );
        }
    }

    /// REQ-MON-011: the Estimate verdict on the provisional model's worst
    /// case trips exactly when the largest shoulder elevation is above the
    /// range or the smallest elbow flexion below it (NaN included), naming
    /// that joint; no envelope yet is no verdict.
    pub(super) fn check_envelope_verdict(
        monitor: &JointLimitMonitor,
        envelope: JointEnvelope,
        verdict: Verdict,
    ) -> Result<(), &'static str> {
        let shoulder_ok = envelope.max_shoulder_elevation <= monitor.shoulder_elevation.high;
        let elbow_ok = envelope.min_elbow_flexion >= monitor.elbow_flexion.low;
        match verdict {
            Ok(()) if shoulder_ok && elbow_ok => Ok(()),
            Ok(()) => Err("a worst case beyond a joint limit passed"),
            Err(_) if shoulder_ok && elbow_ok => Err("a worst case within the limits tripped"),
            Err(v) if v.limit == Limit::ShoulderElevation && !shoulder_ok => Ok(()),
            Err(v) if v.limit == Limit::ElbowFlexion && !elbow_ok => Ok(()),
            Err(_) => Err("the envelope trip names a joint within its limit"),
        }
    }

    /// REQ-MON-011: for any worst-case joints (NaN and infinities
    /// included) the Estimate joint-limit monitor trips exactly beyond the
    /// limits, and passes while no provisional model exists. Comparisons
    /// only: no loop, no libm.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_mon_011_envelope_monitor_trips_beyond_limits() {
        let l = SafetyLimits::default();
        let monitor = JointLimitMonitor::from_limits(&l);
        let envelope = JointEnvelope {
            max_shoulder_elevation: kani::any(),
            min_elbow_flexion: kani::any(),
        };
        let verdict = monitor.check_envelope(Some(envelope));
        assert_eq!(check_envelope_verdict(&monitor, envelope, verdict), Ok(()));
        assert_eq!(monitor.check_envelope(None), Ok(()));
        kani::cover!(verdict.is_ok(), "envelope monitor: passes");
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::ElbowFlexion),
            "envelope monitor: hyperextension trips"
        );
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::ShoulderElevation),
            "envelope monitor: shoulder trips"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "envelope monitor",
                20_000,
                verify_req_mon_011_envelope_monitor_trips_beyond_limits,
            );
            kani::check(
                "joint-limit monitor",
                20_000,
                verify_req_mon_005_joint_limit_monitor_is_total,
            );
        }
    }
}
