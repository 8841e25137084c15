//! The kernel's online estimation: the phases of the estimation motion and
//! a provisional arm model, updated in O(1) as each path sample is recorded.
//!
//! # Theory of operation
//! [`OnlineEstimator::record`] is called once per recorded sample, with the
//! path recorded so far (the new sample last). It
//! 1. finds lift-off: the first sample with psi > [`LIFT_PSI`];
//! 2. in the forearm phase (elbow resting on the table, the grasp point on
//!    a circle about it), adds grasp points to running Kåsa moments
//!    ([`CircleMoments`]) [`DEPARTURE_WINDOW`] samples late, so the circle
//!    that judges a sample never contains it, and leaves isolated outliers
//!    out ([`super::outlier`]): an unweighted fit over a short arc follows
//!    them out of all proportion, and the same samples' forearm-pose
//!    equations to the grasp's compliance sums ([`super::compliance`]: the
//!    refinement reads the path with the compliance they give). Once the
//!    forearm has swept
//!    [`PROVISIONAL_ARC`] the moments give a provisional forearm (l2, resting
//!    elbow, 1σ uncertainties), if its radius lies in the prior's forearm
//!    range (`ValidationLimits`; a few quantized points fit any circle). A sample whose radial residual exceeds the
//!    departure tolerance is flagged; when [`DEPARTURE_PERCENT`] % of the
//!    last [`DEPARTURE_WINDOW`] samples are flagged the grasp has left the
//!    circle for good (the elbow has lifted), and the forearm phase ends
//!    where that window starts;
//! 3. in the upper-arm phase, adds the elbow point E = G + l2 (cos(psi − δ),
//!    −sin(psi − δ)) (eq. 19-21, l2 the provisional forearm at the split,
//!    δ the grasp pitch offset the provisional resting elbow implies for
//!    the first recorded pose, `crate::arm`) of
//!    each sample that is not an isolated outlier to a second set of
//!    moments, [`OUTLIER_REACH`] samples late (the outlier test needs the
//!    neighbours); after [`PROVISIONAL_ARC`] about its centre they give a
//!    provisional upper arm (l1, shoulder).
//!
//! [`OnlineEstimator::joint_envelope`] turns the provisional model into the
//! worst case of the person's joint angles at a pose: before the upper arm
//! is known the shoulder is anywhere the validator's l1 range allows on the
//! table line through the resting elbow (q1 extreme at the range's ends);
//! after, the provisional shoulder widened by 3σ.
//!
//! # Bounds
//! Per call: at most [`CATCH_UP_PER_SAMPLE`] moment updates (each one elbow
//! point: a sine and a cosine), one 3 × 3 solve and a few trigonometric
//! functions; in the forearm phase, the compliance sums' update (an
//! 11-sample force mean, a sine and a cosine) and, once a provisional
//! forearm is due, one 5 × 5 Cholesky factorisation with its solves and
//! inverse. No loop depends on the path length.

use super::compliance::{grasp_point, smoothed_force, ComplianceSums, PoseFit};
use super::moments::{CircleMoments, MomentFit};
use super::outlier::{is_isolated_outlier, OUTLIER_REACH};
pub use super::phase::{
    DEPARTURE_PERCENT, DEPARTURE_TOLERANCE, DEPARTURE_WINDOW, LIFT_PSI, NOISE_MULTIPLE,
};
use crate::arm::{elbow_from_grasp, pitch_offset_at, JointAngles};
use crate::config::ValidationLimits;
use crate::geometry::{angle_between, Point, Pose, Wrench};
use crate::monitor::joint_limits::JointEnvelope;
use crate::path::PathSample;

/// Arc a phase must sweep before its moments give a provisional circle
/// [rad]: below it the radius of a 0.1 mm-noisy arc is uncertain by
/// centimetres.
pub const PROVISIONAL_ARC: f64 = 0.3;
/// Relative 3σ precision of the radius a provisional upper arm needs: a
/// few points just after the split fit a small, confident-looking circle
/// with a large arc; its radius is uncertain by more than this.
pub const PROVISIONAL_PRECISION: f64 = 0.05;
/// Elbow points the upper-arm moments take per recorded sample: the newest
/// and up to five of the window left pending at the split.
pub const CATCH_UP_PER_SAMPLE: usize = 6;
/// Fewest samples in a provisional fit.
pub const PROVISIONAL_SAMPLES: usize = 20;

// The departure flags of one window are the bits of a u64.
const _: () = assert!(DEPARTURE_WINDOW <= 64);
/// Where the online estimation is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum OnlinePhase {
    /// Arm at rest, no lift-off yet.
    Resting,
    /// Forearm turning about the resting elbow.
    Forearm,
    /// Upper arm turning about the shoulder.
    UpperArm,
}

/// The phases found and the provisional fits, updated per sample.
///
/// # Invariants
/// `lift <= forearm_added <= forearm_end <= upper_arm_added` once each is
/// set; every index is below the recorded path's length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OnlineEstimator {
    phase: OnlinePhase,
    rest: Option<Pose>,
    pitch_offset: f64,
    lift: usize,
    lift_psi: f64,
    max_psi: f64,
    forearm_moments: CircleMoments,
    compliance: ComplianceSums,
    /// The compliance [m/N] of the provisional forearm, latched at the
    /// split ([`Self::compliance`]).
    grasp_compliance: f64,
    forearm_added: usize,
    departures: u64,
    judged: usize,
    forearm_end: usize,
    forearm: Option<MomentFit>,
    upper_arm_moments: CircleMoments,
    upper_arm_added: usize,
    first_elbow: Point,
    last_elbow: Point,
    upper_arm: Option<MomentFit>,
    upper_arm_arc: f64,
}

impl Default for OnlineEstimator {
    fn default() -> Self {
        Self::new()
    }
}

impl OnlineEstimator {
    /// Nothing recorded.
    pub const fn new() -> Self {
        Self {
            phase: OnlinePhase::Resting,
            rest: None,
            pitch_offset: 0.0,
            lift: 0,
            lift_psi: 0.0,
            max_psi: 0.0,
            forearm_moments: CircleMoments::new(),
            compliance: ComplianceSums::new(),
            grasp_compliance: 0.0,
            forearm_added: 0,
            departures: 0,
            judged: 0,
            forearm_end: 0,
            forearm: None,
            upper_arm_moments: CircleMoments::new(),
            upper_arm_added: 0,
            first_elbow: Point::new(0.0, 0.0),
            last_elbow: Point::new(0.0, 0.0),
            upper_arm: None,
            upper_arm_arc: 0.0,
        }
    }

    /// The phase reached.
    pub fn phase(&self) -> OnlinePhase {
        self.phase
    }

    /// Path index of lift-off and of the forearm phase's end (the upper
    /// arm's first sample); meaningful once the phase is reached.
    pub fn split(&self) -> (usize, usize) {
        (self.lift, self.forearm_end)
    }

    /// The provisional forearm: l2 = radius, resting elbow = centre.
    pub fn forearm(&self) -> Option<&MomentFit> {
        self.forearm.as_ref()
    }

    /// The grasp's compliance [m/N] the provisional forearm was fitted
    /// with, from the split on the one the forearm phase showed
    /// ([`super::compliance`]; 0: a rigid grasp). With one, the provisional
    /// forearm is the forearm-pose model's, samples are judged by it, the
    /// upper arm's elbow points, the joint envelopes ([`Self::grasp`]) and
    /// the refinement read the grasp with it.
    pub fn compliance(&self) -> f64 {
        self.grasp_compliance
    }

    /// The grasp point of a grasp measured at `pose` under external wrench
    /// `wrench` (frame S), under [`Self::compliance`]: G + c f_ext; `pose`
    /// itself through a rigid grasp or under a non-finite force.
    pub fn grasp(&self, pose: Pose, wrench: Wrench) -> Pose {
        let c = self.grasp_compliance;
        if c == 0.0 || !(wrench.fx.is_finite() && wrench.fz.is_finite()) {
            return pose;
        }
        grasp_point(pose, c, Point::new(wrench.fx, wrench.fz))
    }

    /// The provisional grasp pitch offset δ [rad] (`crate::arm`): the
    /// first recorded pose's pitch minus the forearm's elevation from the
    /// provisional resting elbow; 0 before a provisional forearm.
    pub fn pitch_offset(&self) -> f64 {
        self.pitch_offset
    }

    /// The provisional upper arm (l1 = radius, shoulder = centre), once it
    /// has swept [`PROVISIONAL_ARC`] and its radius is known to
    /// [`PROVISIONAL_PRECISION`] (3σ).
    pub fn upper_arm(&self) -> Option<&MomentFit> {
        self.upper_arm.as_ref().filter(|fit| {
            self.upper_arm_arc >= PROVISIONAL_ARC
                && 3.0 * fit.radius_sd <= PROVISIONAL_PRECISION * fit.circle.radius
        })
    }

    /// Arc swept so far by the forearm (psi above lift-off) and by the upper
    /// arm about its provisional shoulder [rad].
    pub fn arcs(&self) -> (f64, f64) {
        (self.max_psi - self.lift_psi, self.upper_arm_arc)
    }

    /// Updates the estimation with the last sample of `path`; `prior`'s
    /// forearm range bounds the provisional forearm (a fit outside it is
    /// none yet).
    pub fn record(&mut self, path: &[PathSample], prior: &ValidationLimits) {
        let Some((index, sample)) = path.len().checked_sub(1).zip(path.last()) else {
            return;
        };
        if !(sample.pose.is_finite() && sample.wrench.is_finite()) {
            return;
        }
        self.rest.get_or_insert(sample.pose);
        match self.phase {
            OnlinePhase::Resting => {
                if sample.pose.psi > LIFT_PSI {
                    self.phase = OnlinePhase::Forearm;
                    self.lift = index;
                    self.lift_psi = sample.pose.psi;
                    self.max_psi = sample.pose.psi;
                    self.forearm_added = index;
                }
            }
            OnlinePhase::Forearm => self.record_forearm(path, index, sample, prior),
            OnlinePhase::UpperArm => self.catch_up(path, index),
        }
    }

    fn record_forearm(
        &mut self,
        path: &[PathSample],
        index: usize,
        sample: &PathSample,
        prior: &ValidationLimits,
    ) {
        self.max_psi = self.max_psi.max(sample.pose.psi);
        // The moments lag the newest sample by the departure window.
        if self.forearm_added + DEPARTURE_WINDOW <= index {
            if let Some(old) = path.get(self.forearm_added) {
                if !is_isolated_outlier(path, self.forearm_added) {
                    self.forearm_moments.add(old.pose.point());
                    if let Some(force) = smoothed_force(path, self.forearm_added) {
                        self.compliance.add(old.pose, force);
                    }
                }
            }
            self.forearm_added += 1;
        }
        let swept = self.max_psi - self.lift_psi >= PROVISIONAL_ARC;
        let provisional = swept && self.forearm_moments.count() >= PROVISIONAL_SAMPLES;
        // The forearm-pose model of the sums as they now are, solved once
        // for this sample, and only when something reads it.
        let pose_fit: Option<PoseFit> = if provisional || self.forearm.is_some() {
            self.compliance.fit()
        } else {
            None
        };
        if provisional {
            // A forearm outside the plausible range is no provisional
            // forearm yet: the set-point stays within the prior reach, and
            // no joint envelope is built on it. Seen: 18 distinct points
            // of a sensor quantized at 4 mm fit a 0.06 m circle to a
            // 0.19 m forearm, whose envelope read the elbow at −0.62 rad
            // while it stood at +0.36 rad, and the monitor stopped.
            // Through a compliant grasp the raw path is no circle (a
            // 0.19 m forearm's fits 0.32 m, a softer one's none in the
            // plausible range): the forearm-pose model with the compliance
            // is the provisional forearm, and its δ the pitch offset.
            let plausible = prior.min_forearm_length..=prior.max_forearm_length;
            let fit = match pose_fit {
                Some(pose) => Some(pose.moment_fit()),
                None => self.forearm_moments.fit().ok(),
            };
            if let Some(fit) = fit.filter(|fit| plausible.contains(&fit.circle.radius)) {
                self.forearm = Some(fit);
                self.grasp_compliance = pose_fit.map_or(0.0, |pose| pose.compliance);
                if let Some(pose) = pose_fit {
                    self.pitch_offset = pose.pitch_offset();
                } else if let Some(rest) = self.rest {
                    self.pitch_offset = pitch_offset_at(rest, fit.circle.centre);
                }
            }
        }
        let Some(fit) = self.forearm else {
            return;
        };
        // Through a compliant grasp the raw path is no circle (a 0.19 m
        // forearm's fitted 0.32 m, the elbow's lift judged against it
        // came early or never): the sample is judged by the forearm-pose
        // model instead, its elbow point's distance from the resting
        // elbow. A rigid grasp keeps the circle's radial residual.
        let by_pose = pose_fit.and_then(|pose| {
            smoothed_force(path, index).map(|force| (pose.residual(sample.pose, force), pose.rms))
        });
        let (residual, rms) = by_pose.unwrap_or_else(|| {
            (
                libm::fabs(sample.pose.point().distance(fit.circle.centre) - fit.circle.radius),
                fit.rms_residual,
            )
        });
        let tolerance = DEPARTURE_TOLERANCE.max(NOISE_MULTIPLE * rms);
        // NaN counts as departed.
        let within = residual <= tolerance;
        self.departures = (self.departures << 1) | u64::from(!within);
        self.judged = self.judged.saturating_add(1);
        let window_mask = (1u64 << DEPARTURE_WINDOW) - 1;
        let flagged = (self.departures & window_mask).count_ones() as usize;
        if self.judged >= DEPARTURE_WINDOW && flagged * 100 >= DEPARTURE_WINDOW * DEPARTURE_PERCENT
        {
            self.forearm_end = (index + 1)
                .saturating_sub(DEPARTURE_WINDOW)
                .max(self.forearm_added);
            self.phase = OnlinePhase::UpperArm;
            self.grasp_compliance = pose_fit.map_or(0.0, |pose| pose.compliance);
            self.upper_arm_added = self.forearm_end;
            self.catch_up(path, index);
        }
    }

    /// Adds the elbow points of `path[upper_arm_added..=index]`, at most
    /// [`CATCH_UP_PER_SAMPLE`] of them, oldest first, and refits. At the
    /// split the window's [`DEPARTURE_WINDOW`] samples are pending; they are
    /// absorbed over the next ten samples (0.1 s) instead of in one step
    /// (50 elbow points, each a sine and a cosine: 0.8 million instructions
    /// in soft-float `f64` on a Cortex-M7).
    fn catch_up(&mut self, path: &[PathSample], index: usize) {
        for _ in 0..CATCH_UP_PER_SAMPLE {
            // A sample is judged once it has its neighbours.
            if self.upper_arm_added + OUTLIER_REACH > index {
                break;
            }
            self.add_elbow(path, self.upper_arm_added);
        }
        self.update_upper_arm();
    }

    /// Adds the elbow point of `path[index]` under the provisional forearm.
    fn add_elbow(&mut self, path: &[PathSample], index: usize) {
        let (Some(forearm), Some(sample)) = (self.forearm, path.get(index)) else {
            return;
        };
        self.upper_arm_added = index + 1;
        if is_isolated_outlier(path, index) {
            return;
        }
        let mut grasp = sample.pose;
        if self.grasp_compliance != 0.0 {
            let Some(force) = smoothed_force(path, index) else {
                return;
            };
            grasp = grasp_point(grasp, self.grasp_compliance, force);
        }
        let elbow = elbow_from_grasp(grasp, forearm.circle.radius, self.pitch_offset);
        if self.upper_arm_moments.count() == 0 {
            self.first_elbow = elbow;
        }
        if self.upper_arm_moments.add(elbow) {
            self.last_elbow = elbow;
        }
    }

    fn update_upper_arm(&mut self) {
        if self.upper_arm_moments.count() < PROVISIONAL_SAMPLES {
            return;
        }
        if let Ok(fit) = self.upper_arm_moments.fit() {
            self.upper_arm = Some(fit);
            self.upper_arm_arc =
                angle_between(fit.circle.centre, self.first_elbow, self.last_elbow);
        }
    }

    /// Worst-case joint angles at the grasp measured (or commanded) at
    /// `pose` under external wrench `wrench` (frame S) under the
    /// provisional model, with the prior l1 range of `prior`; `None`
    /// before a provisional forearm exists or for a non-finite pose.
    ///
    /// The grasp is read through the measured compliance ([`Self::grasp`]):
    /// through a soft cuff the robot's pose is not the arm's, and the only
    /// envelope there is reads the arm's (a caller cannot judge the joints
    /// at the robot's pose by mistake).
    pub fn joint_envelope(
        &self,
        pose: Pose,
        wrench: Wrench,
        prior: &ValidationLimits,
    ) -> Option<JointEnvelope> {
        self.envelope_at_grasp(self.grasp(pose, wrench), prior)
    }

    /// [`Self::joint_envelope`] at the arm's grasp point `pose` itself.
    fn envelope_at_grasp(&self, pose: Pose, prior: &ValidationLimits) -> Option<JointEnvelope> {
        let forearm = self.forearm?;
        if !pose.is_finite() {
            return None;
        }
        let offset = self.pitch_offset;
        let elbow = elbow_from_grasp(pose, forearm.circle.radius, offset);
        let shoulder_elevation =
            |shoulder: Point| libm::atan2(elbow.z - shoulder.z, shoulder.x - elbow.x);
        let plausible = |fit: &&MomentFit| {
            (prior.min_upper_arm_length..=prior.max_upper_arm_length).contains(&fit.circle.radius)
        };
        let max_q1 = match self.upper_arm().filter(plausible) {
            Some(upper) => {
                let shoulder = upper.circle.centre;
                let reach = elbow.distance(shoulder).max(f64::EPSILON);
                let spread = 3.0 * (upper.centre_sd + forearm.radius_sd) / reach;
                shoulder_elevation(shoulder) + spread
            }
            None => {
                let resting = forearm.circle.centre;
                let near = Point::new(resting.x + prior.min_upper_arm_length, resting.z);
                let far = Point::new(resting.x + prior.max_upper_arm_length, resting.z);
                shoulder_elevation(near).max(shoulder_elevation(far))
            }
        };
        let q = JointAngles {
            shoulder_elevation: max_q1,
            elbow_flexion: pose.psi - offset - max_q1,
        };
        q.is_finite().then_some(JointEnvelope {
            max_shoulder_elevation: q.shoulder_elevation,
            min_elbow_flexion: q.elbow_flexion,
        })
    }
}

/// Stubs for the harnesses of a lift's first step (`kernel::verification`):
/// a fresh estimate is Resting, so its first [`OnlineEstimator::record`]
/// updates neither later phase, and it has no provisional forearm, so no
/// joint envelope. The phases' stubs fail the proof if they are reached
/// (Kani reports their assertions UNREACHABLE, i.e. passed, only when no
/// path of the harness gets there); the envelope's asserts that there is
/// no provisional forearm and answers as the function then does.
#[cfg(kani)]
pub(crate) mod stub {
    use super::*;

    /// Stub of `OnlineEstimator::record_forearm`.
    pub(crate) fn record_forearm(
        _: &mut OnlineEstimator,
        _: &[PathSample],
        _: usize,
        _: &PathSample,
        _: &ValidationLimits,
    ) {
        kani::assert(
            false,
            "a fresh estimate's first sample updated the forearm phase",
        );
    }

    /// Stub of [`OnlineEstimator::joint_envelope`]: `None`, the function's
    /// answer without a provisional forearm, which it asserts. The lift
    /// asks for envelopes at up to eight poses a step (its hold's
    /// bisection): made in the proof, each one's trigonometry on a
    /// symbolic estimate (symbolic execution cannot fold the fresh
    /// estimate's `None` out of the kernel's state) kept the Estimate
    /// step undecided in 10 min.
    pub(crate) fn joint_envelope(
        online: &OnlineEstimator,
        _: Pose,
        _: Wrench,
        _: &ValidationLimits,
    ) -> Option<JointEnvelope> {
        kani::assert(
            online.forearm().is_none(),
            "a fresh estimate had a provisional forearm",
        );
        None
    }

    /// Stub of `OnlineEstimator::catch_up`.
    pub(crate) fn catch_up(_: &mut OnlineEstimator, _: &[PathSample], _: usize) {
        kani::assert(
            false,
            "a fresh estimate's first sample updated the upper-arm phase",
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A forearm of `radius` turning from rest about its resting elbow at
    /// 1 kHz (psi 0 → 0.6 rad in 1.2 s after 0.1 s at rest), recorded
    /// sample by sample under `prior`.
    fn forearm_turn(radius: f64, prior: &ValidationLimits) -> OnlineEstimator {
        cuffed_forearm_turn(radius, 0.0, prior)
    }

    /// As [`forearm_turn`], the grasp measured through a cuff of
    /// compliance `c` [m/N] under a force that falls as the forearm rises.
    fn cuffed_forearm_turn(radius: f64, c: f64, prior: &ValidationLimits) -> OnlineEstimator {
        let mut path = [PathSample::default(); 1300];
        let mut online = OnlineEstimator::new();
        for (k, sample) in path.iter_mut().enumerate() {
            let psi = 0.6 * ((k as f64 - 100.0) / 1200.0).clamp(0.0, 1.0);
            *sample = PathSample {
                time: k as f64 * 1e-3,
                pose: Pose::new(
                    radius - radius * libm::cos(psi) + c * 0.5 * libm::sin(psi),
                    radius * libm::sin(psi) - c * 6.0 * libm::cos(psi),
                    psi,
                ),
                wrench: Wrench::new(-0.5 * libm::sin(psi), 6.0 * libm::cos(psi), 0.0),
            };
        }
        for end in 1..=path.len() {
            online.record(&path[..end], prior);
        }
        online
    }

    /// REQ-MON-011: a provisional forearm exists only within the
    /// validator's forearm range: a 0.06 m circle (what 18 quantized
    /// points of a 0.19 m forearm fitted) gives none under the default
    /// range (0.12-0.35 m), one when the range admits it, and a 0.20 m
    /// forearm gives one, to its radius.
    #[test]
    fn req_mon_011_a_forearm_outside_the_plausible_range_is_not_provisional() {
        let default = ValidationLimits::default();
        assert!(forearm_turn(0.06, &default).forearm().is_none());
        let wide = ValidationLimits {
            min_forearm_length: 0.05,
            ..default
        };
        let small = forearm_turn(0.06, &wide);
        assert!(small.forearm().is_some(), "{small:?}");
        let plausible = forearm_turn(0.20, &default);
        let fit = plausible.forearm().expect("a provisional forearm");
        assert!((fit.circle.radius - 0.20).abs() < 1e-6, "{fit:?}");
    }

    /// REQ-EST-010: through a cuff of 700 N/m the provisional forearm is
    /// the forearm-pose model's (l2 within 1 mm; the raw path's circle is
    /// not the forearm), its compliance is measured, and a grasp is read
    /// as G + c f_ext; through a rigid grasp the compliance is 0 and a
    /// grasp is read as measured (the same bits).
    #[test]
    fn req_est_010_a_cuffed_forearm_is_the_pose_model_s() {
        let prior = ValidationLimits::default();
        let cuffed = cuffed_forearm_turn(0.19, 1.0 / 700.0, &prior);
        let forearm = cuffed.forearm().expect("a provisional forearm");
        assert!((forearm.circle.radius - 0.19).abs() < 1e-3, "{forearm:?}");
        assert!((cuffed.compliance() * 700.0 - 1.0).abs() < 0.03);
        let pose = Pose::new(0.1, 0.05, 0.3);
        let wrench = Wrench::new(1.0, -5.0, 0.0);
        let read = cuffed.grasp(pose, wrench);
        let c = cuffed.compliance();
        assert_eq!(read, Pose::new(0.1 + c, 0.05 - 5.0 * c, 0.3));
        let rigid = forearm_turn(0.19, &prior);
        assert_eq!(rigid.compliance(), 0.0);
        assert_eq!(rigid.grasp(pose, wrench), pose);
    }

    /// REQ-EST-010: the joints are judged at the arm's grasp, not the
    /// robot's pose: through the 700 N/m cuff the envelope is the one at
    /// G + c f_ext and differs from the one at the measured pose; through
    /// a rigid grasp both are the same.
    #[test]
    fn req_est_010_the_joints_are_judged_where_the_cuff_holds_the_arm() {
        let prior = ValidationLimits::default();
        let cuffed = cuffed_forearm_turn(0.19, 1.0 / 700.0, &prior);
        let (pose, wrench) = (Pose::new(0.05, 0.12, 0.9), Wrench::new(2.0, -8.0, 0.0));
        let judged = cuffed.joint_envelope(pose, wrench, &prior).unwrap();
        let at_grasp = cuffed
            .envelope_at_grasp(cuffed.grasp(pose, wrench), &prior)
            .unwrap();
        let at_robot = cuffed.envelope_at_grasp(pose, &prior).unwrap();
        assert_eq!(judged, at_grasp);
        assert!(
            (judged.min_elbow_flexion - at_robot.min_elbow_flexion).abs() > 1e-3,
            "{judged:?} {at_robot:?}"
        );
        let rigid = forearm_turn(0.19, &prior);
        assert_eq!(
            rigid.joint_envelope(pose, wrench, &prior),
            rigid.envelope_at_grasp(pose, &prior)
        );
    }
}
