//! The human arm as a planar two-link chain in frame S (`plant.md`; paper 000
//! eq. 29-30 adapted to frame S).
//!
//! # Theory of operation
//! q1 is the elevation of the upper arm about the shoulder, q2 the elbow
//! flexion, psi = q1 + q2 the forearm elevation. With the shoulder at
//! S = (sx, sz):
//!
//! ```text
//! elbow  E = S + l1 (-cos q1, sin q1)
//! grasp  G = E + l2 (-cos psi, sin psi)
//! ```
//!
//! The robot measures the whole grasp pose (x, z, psi), so the pose-based
//! inverse kinematics is unique: E = G + l2 (cos(psi − δ), -sin(psi − δ)),
//! then q1 from the direction S → E.
//!
//! δ, the *grasp pitch offset*, is the robot's measured pitch minus the
//! forearm's elevation: constant, since the cuff is rigid on the forearm.
//! On `plant.md`'s rod it is 0 (the grasp lies on the forearm's joint line
//! and psi is the forearm's elevation); on a person the cuff sits on the
//! wrist's surface, off the line through the elbow's centre (MyoArm m50:
//! the elbow centre 10.7 mm above the cuff at rest, δ = 0.049 rad), and the
//! robot's pitch is counted from its own start. The estimator measures δ
//! from the forearm phase (`estimation::refine`).
//!
//! The point-based inverse (grasp point only) has two
//! branches (elbow above or below the shoulder–grasp line) and is singular at
//! full extension and at the shoulder; both cases are explicit errors.

use crate::geometry::{Point, Pose};

/// Geometry of a person's arm in frame S.
///
/// # Invariants
/// Only [`ArmGeometry::new`] constructs it: lengths finite and > 0, shoulder
/// finite. Plausibility (anthropometric ranges) is the validator's job.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ArmGeometry {
    upper_arm_length: f64,
    forearm_length: f64,
    shoulder: Point,
    grasp_pitch_offset: f64,
}

/// Human joint angles [rad].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JointAngles {
    /// Upper-arm elevation above the horizontal, q1 [rad].
    pub shoulder_elevation: f64,
    /// Elbow flexion q2 [rad]; negative is hyperextension.
    pub elbow_flexion: f64,
}

impl JointAngles {
    /// Forearm elevation psi = q1 + q2 [rad].
    pub fn forearm_elevation(self) -> f64 {
        self.shoulder_elevation + self.elbow_flexion
    }

    /// True when both angles are finite.
    pub fn is_finite(self) -> bool {
        self.shoulder_elevation.is_finite() && self.elbow_flexion.is_finite()
    }
}

/// Which elbow configuration the point-based inverse kinematics returns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ElbowBranch {
    /// Elbow flexed (q2 ≥ 0): the physiological branch for a lifted arm.
    Flexed,
    /// Elbow hyperextended (q2 ≤ 0).
    Hyperextended,
}

/// Why a kinematic computation has no answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum KinematicsError {
    /// An input was NaN or infinite.
    NonFinite,
    /// A length was zero or negative.
    NonPositiveLength,
    /// The grasp point is farther from the shoulder than l1 + l2, or nearer
    /// than |l1 − l2|.
    OutOfReach,
    /// The grasp point coincides with the shoulder: the direction is undefined.
    AtShoulder,
}

impl ArmGeometry {
    /// An arm with upper-arm length l1 [m], forearm length l2 [m] and the
    /// shoulder at `shoulder` (frame S).
    pub fn new(
        upper_arm_length: f64,
        forearm_length: f64,
        shoulder: Point,
    ) -> Result<Self, KinematicsError> {
        if !(upper_arm_length.is_finite() && forearm_length.is_finite() && shoulder.is_finite()) {
            return Err(KinematicsError::NonFinite);
        }
        if upper_arm_length <= 0.0 || forearm_length <= 0.0 {
            return Err(KinematicsError::NonPositiveLength);
        }
        Ok(Self {
            upper_arm_length,
            forearm_length,
            shoulder,
            grasp_pitch_offset: 0.0,
        })
    }

    /// The same arm with grasp pitch offset δ [rad] (the module's theory of
    /// operation): the robot's pitch reads the forearm's elevation plus δ.
    ///
    /// # Errors
    /// [`KinematicsError::NonFinite`] for a NaN or infinite δ.
    pub fn with_grasp_pitch_offset(self, offset: f64) -> Result<Self, KinematicsError> {
        if !offset.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        Ok(Self {
            grasp_pitch_offset: offset,
            ..self
        })
    }

    /// Grasp pitch offset δ [rad]: measured pitch minus forearm elevation.
    pub fn grasp_pitch_offset(&self) -> f64 {
        self.grasp_pitch_offset
    }

    /// Upper-arm length l1 [m].
    pub fn upper_arm_length(&self) -> f64 {
        self.upper_arm_length
    }

    /// Forearm length l2 (elbow to grasp point) [m].
    pub fn forearm_length(&self) -> f64 {
        self.forearm_length
    }

    /// Shoulder centre in frame S [m].
    pub fn shoulder(&self) -> Point {
        self.shoulder
    }

    /// Elbow position for joint angles `q` (paper eq. 30).
    pub fn elbow(&self, q: JointAngles) -> Point {
        let q1 = q.shoulder_elevation;
        Point::new(
            self.shoulder.x - self.upper_arm_length * libm::cos(q1),
            self.shoulder.z + self.upper_arm_length * libm::sin(q1),
        )
    }

    /// Grasp pose for joint angles `q` (forward kinematics).
    pub fn forward(&self, q: JointAngles) -> Pose {
        let elbow = self.elbow(q);
        let psi = q.forearm_elevation();
        Pose::new(
            elbow.x - self.forearm_length * libm::cos(psi),
            elbow.z + self.forearm_length * libm::sin(psi),
            psi + self.grasp_pitch_offset,
        )
    }

    /// Elbow position implied by a measured grasp pose (paper eq. 19-21):
    /// E = G + l2 (cos(psi − δ), −sin(psi − δ)).
    pub fn elbow_from_pose(&self, pose: Pose) -> Point {
        elbow_from_grasp(pose, self.forearm_length, self.grasp_pitch_offset)
    }

    /// Joint angles from a measured grasp pose (paper eq. 29 in frame S),
    /// with the residual | |E − S| − l1 | [m] that says how well the pose fits
    /// this arm. Unique: psi fixes the forearm direction.
    pub fn inverse_from_pose(&self, pose: Pose) -> Result<(JointAngles, f64), KinematicsError> {
        if !pose.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        let elbow = self.elbow_from_pose(pose);
        let dx = self.shoulder.x - elbow.x;
        let dz = elbow.z - self.shoulder.z;
        let reach = libm::hypot(dx, dz);
        if reach <= f64::EPSILON * self.upper_arm_length {
            return Err(KinematicsError::AtShoulder);
        }
        let q1 = libm::atan2(dz, dx);
        let q = JointAngles {
            shoulder_elevation: q1,
            elbow_flexion: pose.psi - self.grasp_pitch_offset - q1,
        };
        Ok((q, libm::fabs(reach - self.upper_arm_length)))
    }

    /// Joint angles placing the grasp point at `grasp`, on the chosen elbow
    /// branch. Errors at the singular configurations instead of returning a
    /// meaningless angle.
    pub fn inverse_from_point(
        &self,
        grasp: Point,
        branch: ElbowBranch,
    ) -> Result<JointAngles, KinematicsError> {
        if !grasp.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        let (l1, l2) = (self.upper_arm_length, self.forearm_length);
        // Vector shoulder → grasp, expressed with +x toward the person's hand.
        let ux = self.shoulder.x - grasp.x;
        let uz = grasp.z - self.shoulder.z;
        let d = libm::hypot(ux, uz);
        if d <= f64::EPSILON * (l1 + l2) {
            return Err(KinematicsError::AtShoulder);
        }
        if d > l1 + l2 || d < libm::fabs(l1 - l2) {
            return Err(KinematicsError::OutOfReach);
        }
        // Law of cosines for the elbow flexion, clamped only against rounding
        // (d is already inside the reachable annulus).
        let cos_q2 = ((d * d - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
        let q2_magnitude = libm::acos(cos_q2);
        let q2 = match branch {
            ElbowBranch::Flexed => q2_magnitude,
            ElbowBranch::Hyperextended => -q2_magnitude,
        };
        let q1 = libm::atan2(uz, ux) - libm::atan2(l2 * libm::sin(q2), l1 + l2 * libm::cos(q2));
        Ok(JointAngles {
            shoulder_elevation: q1,
            elbow_flexion: q2,
        })
    }
}

/// The elbow implied by grasp pose `pose` (frame S), forearm length
/// `forearm` [m] and grasp pitch offset `offset` [rad] (eq. 19-21 with the
/// forearm's elevation psi − δ): E = G + l2 (cos(psi − δ), −sin(psi − δ)).
pub fn elbow_from_grasp(pose: Pose, forearm: f64, offset: f64) -> Point {
    let elevation = pose.psi - offset;
    Point::new(
        pose.x + forearm * libm::cos(elevation),
        pose.z - forearm * libm::sin(elevation),
    )
}

/// The grasp pitch offset δ [rad] that puts the elbow at `elbow` for
/// grasp pose `pose` (both frame S): the pose's pitch minus the elevation
/// of the forearm from `elbow` to the grasp point, wrapped to [−π, π]
/// (one atan2: the refinement computes it for every forearm sample).
pub fn pitch_offset_at(pose: Pose, elbow: Point) -> f64 {
    use core::f64::consts::{PI, TAU};
    let elevation = libm::atan2(pose.z - elbow.z, elbow.x - pose.x);
    let offset = pose.psi - elevation;
    if libm::fabs(offset) <= PI {
        offset
    } else {
        offset - TAU * libm::round(offset / TAU)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn arm(l1: f64, l2: f64) -> ArmGeometry {
        ArmGeometry::new(l1, l2, Point::new(l1 + l2, 0.0)).unwrap()
    }

    #[test]
    fn extended_arm_grasp_is_origin() {
        let pose = arm(0.3, 0.2).forward(JointAngles::default());
        assert!(pose.x.abs() < 1e-12 && pose.z.abs() < 1e-12 && pose.psi == 0.0);
    }

    /// |S − G| = 0.3 + 0.2 = 0.5 m exactly in binary floating point: the
    /// edge of the reach belongs to it (the straight arm), not beyond it.
    #[test]
    fn a_grasp_at_exactly_full_reach_is_the_straight_arm() {
        match arm(0.3, 0.2).inverse_from_point(Point::new(0.0, 0.0), ElbowBranch::Flexed) {
            Ok(q) => assert!(
                q.shoulder_elevation.abs() < 1e-7 && q.elbow_flexion.abs() < 1e-7,
                "{q:?}"
            ),
            Err(e) => panic!("full reach refused: {e:?}"),
        }
    }

    /// The singular distance scales with the arm, ε·(l1 + l2) = 1.1e-16 m
    /// for l1 = l2 = 0.25 m: a grasp one rounding step (5.6e-17 m) from the
    /// shoulder is at the shoulder, not a folded elbow with an arbitrary q1.
    #[test]
    fn a_grasp_one_rounding_step_from_the_shoulder_is_at_the_shoulder() {
        let below_half = 0.5 - f64::EPSILON / 4.0;
        assert_eq!(
            arm(0.25, 0.25).inverse_from_point(Point::new(below_half, 0.0), ElbowBranch::Flexed),
            Err(KinematicsError::AtShoulder)
        );
    }

    #[test]
    fn construction_rejects_bad_numbers() {
        let s = Point::new(0.5, 0.0);
        assert_eq!(
            ArmGeometry::new(f64::NAN, 0.2, s),
            Err(KinematicsError::NonFinite)
        );
        assert_eq!(
            ArmGeometry::new(0.3, 0.0, s),
            Err(KinematicsError::NonPositiveLength)
        );
        assert_eq!(
            arm(0.3, 0.2).inverse_from_point(Point::new(2.0, 0.0), ElbowBranch::Flexed),
            Err(KinematicsError::OutOfReach)
        );
        assert_eq!(
            arm(0.3, 0.2).inverse_from_point(Point::new(0.5, 0.0), ElbowBranch::Flexed),
            Err(KinematicsError::AtShoulder)
        );
    }

    /// The shoulder singularity is a reach within the lengths' own
    /// rounding (ε · l1): an elbow exactly on the shoulder has no
    /// direction, one 0.22 fm off it still has one.
    #[test]
    fn only_an_elbow_within_rounding_of_the_shoulder_is_singular() {
        let arm = arm(0.3, 0.2);
        assert_eq!(
            arm.inverse_from_pose(Pose::new(0.3, 0.0, 0.0)),
            Err(KinematicsError::AtShoulder)
        );
        // x + l2 = 0.5 m + 2 ulp: the elbow 2.2e-16 m beyond the shoulder.
        let (q, residual) = arm
            .inverse_from_pose(Pose::new(0.300_000_000_000_000_2, 0.0, 0.0))
            .unwrap();
        assert!(q.is_finite() && residual < 0.31, "{q:?} {residual}");
    }

    /// The folded elbow (q2 = π) is solved at both edges where it lives: a
    /// grasp exactly |l1 − l2| from the shoulder (the inner edge of the
    /// reach, exact in binary) and, for equal lengths, a grasp 2.2e-16 m
    /// from the shoulder (beyond the singular threshold ε · (l1 + l2),
    /// 1.1e-16 m). Just inside the inner edge is out of reach; on the
    /// shoulder, or 1e-17 m from one at the origin, is singular even though
    /// |l1 − l2| = 0.
    #[test]
    fn the_folded_elbow_is_solved_at_the_edges_of_its_reach() {
        let at_origin = ArmGeometry::new(0.25, 0.25, Point::new(0.0, 0.0)).unwrap();
        for (arm, grasp, tolerance) in [
            (arm(0.5, 0.25), Point::new(0.5, 0.0), 1e-12),
            (arm(0.25, 0.25), Point::new(0.5 - f64::EPSILON, 0.0), 1e-6),
        ] {
            let q = arm.inverse_from_point(grasp, ElbowBranch::Flexed).unwrap();
            let off = (q.elbow_flexion - core::f64::consts::PI).abs();
            assert!(off < tolerance, "{grasp:?}: {q:?}");
        }
        for (arm, grasp, error) in [
            (
                arm(0.5, 0.25),
                Point::new(0.500_000_001, 0.0),
                KinematicsError::OutOfReach,
            ),
            (
                arm(0.25, 0.25),
                Point::new(0.5, 0.0),
                KinematicsError::AtShoulder,
            ),
            (
                at_origin,
                Point::new(-1e-17, 0.0),
                KinematicsError::AtShoulder,
            ),
        ] {
            assert_eq!(
                arm.inverse_from_point(grasp, ElbowBranch::Flexed),
                Err(error)
            );
        }
    }

    #[test]
    fn joint_angles_are_finite_only_when_both_are() {
        let q = |shoulder_elevation, elbow_flexion| JointAngles {
            shoulder_elevation,
            elbow_flexion,
        };
        assert!(q(0.1, -0.2).is_finite());
        assert!(!q(f64::NAN, 0.0).is_finite());
        assert!(!q(0.0, f64::INFINITY).is_finite());
    }

    proptest! {
        #[test]
        fn pose_inverse_round_trips(l1 in 0.2..0.4f64, l2 in 0.15..0.3f64,
                                    q1 in 0.0..1.5f64, q2 in -0.2..2.5f64) {
            let arm = arm(l1, l2);
            let q = JointAngles { shoulder_elevation: q1, elbow_flexion: q2 };
            let (back, residual) = arm.inverse_from_pose(arm.forward(q)).unwrap();
            prop_assert!(residual < 1e-9);
            prop_assert!((back.shoulder_elevation - q1).abs() < 1e-9);
            prop_assert!((back.elbow_flexion - q2).abs() < 1e-9);
        }

        /// Both branches: a flexed elbow (q2 > 0) and a hyperextended one
        /// (q2 < 0) come back from the grasp point alone, given the branch.
        #[test]
        fn point_inverse_round_trips_on_its_branch(l1 in 0.2..0.4f64, l2 in 0.15..0.3f64,
                                                    q1 in 0.0..1.5f64, flexion in 0.05..2.5f64,
                                                    hyperextended in any::<bool>()) {
            let arm = arm(l1, l2);
            let (q2, branch) = if hyperextended {
                (-flexion, ElbowBranch::Hyperextended)
            } else {
                (flexion, ElbowBranch::Flexed)
            };
            let q = JointAngles { shoulder_elevation: q1, elbow_flexion: q2 };
            let back = arm.inverse_from_point(arm.forward(q).point(), branch).unwrap();
            prop_assert!((back.shoulder_elevation - q1).abs() < 1e-6);
            prop_assert!((back.elbow_flexion - q2).abs() < 1e-6);
        }
    }
}

/// Proofs that the kinematics the monitors and the target check rely on
/// are total (REQ-MON-005, REQ-SM-003, REQ-VAL-001).
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::kani_inputs::{FOREARM, HOLD, SHOULDER, UPPER_ARM};
    use crate::kani_stubs::libm_stubbed;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    fn fixed_arm() -> ArmGeometry {
        ArmGeometry::new(UPPER_ARM, FOREARM, SHOULDER).expect("the fixed arm is valid")
    }

    /// REQ-VAL-001: an arm is built exactly from finite values with
    /// positive lengths, for any lengths and shoulder.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_val_001_arm_geometry_needs_finite_positive_lengths() {
        let (l1, l2): (f64, f64) = (kani::any(), kani::any());
        let shoulder = Point::new(kani::any(), kani::any());
        let arm = ArmGeometry::new(l1, l2, shoulder);
        let valid =
            l1.is_finite() && l2.is_finite() && shoulder.is_finite() && l1 > 0.0 && l2 > 0.0;
        assert_eq!(arm.is_ok(), valid);
        if let Ok(arm) = arm {
            assert!(arm.upper_arm_length() == l1 && arm.forearm_length() == l2);
        }
        kani::cover!(arm.is_ok(), "arm: built");
        kani::cover!(
            arm == Err(KinematicsError::NonPositiveLength),
            "arm: non-positive"
        );
    }

    libm_stubbed! { [hypot, atan2, sin, cos]
        /// REQ-MON-005: the pose inverse kinematics of any measured pose is an
        /// answer with a non-negative residual and angles that are not NaN, or
        /// a typed error (NaN and infinities included).
        #[cfg_attr(kani, kani::proof)]
        pub(super) fn verify_req_mon_005_pose_inverse_is_total() {
            let pose = if kani::any() { kani::any::<Pose>() } else { HOLD };
            match fixed_arm().inverse_from_pose(pose) {
                Ok((q, residual)) => {
                    assert!(pose.is_finite());
                    assert!(residual >= 0.0, "the residual is negative or NaN");
                    assert!(!q.shoulder_elevation.is_nan() && !q.elbow_flexion.is_nan());
                    kani::cover!(true, "pose inverse: answers");
                }
                Err(e) => {
                    assert!(e == KinematicsError::NonFinite || e == KinematicsError::AtShoulder);
                    assert!(pose.is_finite() || e == KinematicsError::NonFinite);
                    kani::cover!(true, "pose inverse: refuses");
                }
            }
        }
    }

    libm_stubbed! { [hypot, atan2, acos, sin, cos]
        /// REQ-SM-003: the point inverse kinematics (manipulation targets) of
        /// any grasp point, on either branch, is a pair of angles that are not
        /// NaN or a typed error.
        #[cfg_attr(kani, kani::proof)]
        pub(super) fn verify_req_sm_003_point_inverse_is_total() {
            let grasp = if kani::any() {
                Point::new(kani::any(), kani::any())
            } else {
                HOLD.point()
            };
            let branch = if kani::any() {
                ElbowBranch::Flexed
            } else {
                ElbowBranch::Hyperextended
            };
            match fixed_arm().inverse_from_point(grasp, branch) {
                Ok(q) => {
                    assert!(grasp.is_finite());
                    assert!(!q.shoulder_elevation.is_nan() && !q.elbow_flexion.is_nan());
                    kani::cover!(true, "point inverse: answers");
                }
                Err(e) => {
                    assert!(grasp.is_finite() || e == KinematicsError::NonFinite);
                    kani::cover!(
                        e == KinematicsError::OutOfReach,
                        "point inverse: out of reach"
                    );
                }
            }
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// Both inverses round-trip for a shoulder off the table line too
        /// (every other test puts it at z = 0).
        #[test]
        fn inverses_round_trip_with_a_raised_shoulder() {
            let arm = ArmGeometry::new(0.3, 0.2, Point::new(0.5, 0.07)).expect("valid");
            let q = JointAngles {
                shoulder_elevation: 0.7,
                elbow_flexion: 0.9,
            };
            let pose = arm.forward(q);
            let (back, residual) = arm.inverse_from_pose(pose).expect("reachable");
            assert!(residual < 1e-12);
            let point = arm
                .inverse_from_point(pose.point(), ElbowBranch::Flexed)
                .expect("reachable");
            for (a, b) in [
                (back.shoulder_elevation, q.shoulder_elevation),
                (back.elbow_flexion, q.elbow_flexion),
                (point.shoulder_elevation, q.shoulder_elevation),
                (point.elbow_flexion, q.elbow_flexion),
            ] {
                assert!((a - b).abs() < 1e-9, "{a} vs {b}");
            }
        }

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "arm geometry",
                20_000,
                verify_req_val_001_arm_geometry_needs_finite_positive_lengths,
            );
            kani::check(
                "pose inverse",
                20_000,
                verify_req_mon_005_pose_inverse_is_total,
            );
            kani::check(
                "point inverse",
                20_000,
                verify_req_sm_003_point_inverse_is_total,
            );
        }
    }
}
