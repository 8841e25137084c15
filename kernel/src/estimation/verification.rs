//! Proofs of REQ-EST-001 for the estimators' index arithmetic and buffer
//! bounds. The batch harness (phase detection, look-ahead window, phase
//! ranges, point streaming, the `Ok` branch covered) is written against the
//! public [`estimate_arm`] with [`Method::Ls`]; the kernel itself now
//! estimates online ([`online::OnlineEstimator`]), whose harness covers
//! short paths only (its forearm moments lag a 50-sample window, so its
//! `Ok` branch needs paths beyond a tractable proof).
//!
//! # What is stubbed, and why that is sound
//! Besides the libm stubs (`crate::kani_stubs`), the proof replaces the two
//! circle fits by any result their contracts allow: the robust circle of
//! phase detection ([`PointModel::robust_circle`], Hough + geometric
//! refinement, whose 501-cell accumulator and iterations are far beyond
//! CBMC with symbolic points) and the Kåsa fit ([`fit_circle_kasa`], a 3×3
//! solve). Contracts: a fit of fewer than 3 points is an error; otherwise
//! an error or a valid circle (finite centre, finite radius > 0) with, for
//! the robust fit, a finite non-negative noise level. The proptest
//! `fits_meet_their_stub_contracts` checks both contracts against the real
//! fits. With the fits free, every residual the phase scan computes is any
//! number, so the scan itself is stubbed too, by any end of phase 1 its
//! contract allows ([`departure_contract`], proved of the real scan over
//! any residuals by `verify_req_est_001_departure_scan_keeps_its_contract`):
//! the proof covers every pattern of departures on paths up to [`N`]
//! samples, and the index arithmetic and the ranges handed to the fits are
//! checked for all of them. The fit stubs count their points without making
//! them, and the fit's evidence (arc, RMS residual, residual bias) is any
//! number: making a point and the evidence of any points are proved on
//! their own (`verify_req_est_001_a_point_is_a_number`,
//! `verify_req_est_001_evidence_is_total`). Made in the whole harness,
//! they alone kept its symbolic execution from ending in 10 min, and the
//! points the fits counted took its solver past 22 GiB (real Kani,
//! 2026-12-07).
//!
//! # Path length
//! [`N`] = 24: the shortest path whose two phases can both reach
//! [`MIN_PHASE_SAMPLES`] (10 each) with lift-off and a departure window of
//! at least 10 samples, so the `Ok` branch is reachable; every loop of
//! the estimator runs over the path (at most N), over a look-ahead window
//! (at most N here) or over the 3 rounds, hence unwind N + 1.

use super::moments::{CircleMoments, MomentFit};
#[cfg(kani)]
use super::outlier;
use super::*;
use crate::arm::{ArmGeometry, JointAngles};
use crate::geometry::Wrench;
use crate::kani_stubs::libm_stubbed;
#[cfg(not(kani))]
use limb_kani_stand_in as kani;

/// Longest path the proof considers [samples].
pub(super) const N: usize = 24;

/// The contract of a circle fit's result over `count` points.
pub(super) fn circle_fit_contract(count: usize, fit: &Result<Circle, CircleFitError>) -> bool {
    match fit {
        Ok(circle) => count >= 3 && circle.is_valid(),
        Err(_) => true,
    }
}

/// The contract of the running moments' fit (`CircleMoments::fit`) over
/// `count` points: an error, or a valid circle of at least 4 points with
/// finite uncertainties.
pub(super) fn moment_fit_contract(count: usize, fit: &Result<MomentFit, CircleFitError>) -> bool {
    match fit {
        Ok(fit) => {
            count >= 4
                && fit.count == count
                && fit.circle.is_valid()
                && fit.radius_sd.is_finite()
                && fit.centre_sd.is_finite()
                && fit.rms_residual.is_finite()
        }
        Err(_) => true,
    }
}

/// The contract of the robust fit's result over `count` points.
pub(super) fn robust_fit_contract(
    count: usize,
    fit: &Result<GeometricFit, CircleFitError>,
) -> bool {
    match fit {
        Ok(fit) => {
            circle_fit_contract(count, &Ok(fit.circle)) && fit.noise.is_finite() && fit.noise >= 0.0
        }
        Err(_) => true,
    }
}

/// What the phase scan ([`phase::departure_from`]) must give on a path of
/// `len` samples from `lift`: no departure, or an end of phase 1 in
/// `lift..=len` (the ranges `detect_phases_from` cuts rely on it).
fn departure_contract(len: usize, lift: usize, departure: Option<usize>) -> bool {
    departure.is_none_or(|end| lift <= end && end <= len)
}

/// Kani stubs of the fits: any result the contract allows.
#[cfg(kani)]
mod stub {
    use super::*;

    fn any_circle() -> Circle {
        Circle {
            centre: Point::new(kani::any(), kani::any()),
            radius: kani::any(),
        }
    }

    /// Stub of [`fit_circle_kasa`].
    ///
    /// The points are counted by the iterator's upper size bound, not
    /// made: a bound above the count only allows more results (the
    /// estimator's iterators, a slice mapped, know their length exactly).
    /// Making each point is [`verify_req_est_001_a_point_is_a_number`]'s.
    pub(crate) fn fit_circle_kasa<I: Iterator<Item = Point> + Clone>(
        points: I,
    ) -> Result<Circle, CircleFitError> {
        let count = points.size_hint().1.unwrap_or(usize::MAX);
        let fit = if kani::any() {
            Ok(any_circle())
        } else {
            Err(CircleFitError::Degenerate)
        };
        kani::assume(circle_fit_contract(count, &fit));
        fit
    }

    /// Stub of `CircleMoments::fit`: any result its contract allows.
    pub(crate) fn moment_fit(moments: &CircleMoments) -> Result<MomentFit, CircleFitError> {
        let count = moments.count();
        let fit = if kani::any() {
            Ok(MomentFit {
                circle: any_circle(),
                radius_sd: kani::any(),
                centre_sd: kani::any(),
                rms_residual: kani::any(),
                count,
            })
        } else {
            Err(CircleFitError::Degenerate)
        };
        kani::assume(moment_fit_contract(count, &fit));
        fit
    }

    /// Stub of [`outlier::is_isolated_outlier`]: either verdict, for any
    /// path and index (the test's own totality is REQ-EST-005's harness,
    /// `verify_req_est_005_outlier_test_is_total`).
    pub(crate) fn any_verdict(_path: &[PathSample], _index: usize) -> bool {
        kani::any()
    }

    /// Stub of [`phase::departure_from`]: any end of phase 1 its contract
    /// allows ([`departure_contract`], proved of the scan itself by
    /// `verify_req_est_001_departure_scan_keeps_its_contract`); the
    /// residuals are not read.
    pub(crate) fn departure_from(
        len: usize,
        lift: usize,
        _residual: impl Fn(usize) -> f64,
        _departure_tolerance: f64,
        _settled_tolerance: f64,
    ) -> Option<usize> {
        let departure = if kani::any() { Some(kani::any()) } else { None };
        kani::assume(departure_contract(len, lift, departure));
        departure
    }

    /// Stub of [`Circle::arc`], [`Circle::rms_residual`] and
    /// [`Circle::residual_bias`]: any number (the evidence is reported,
    /// not indexed; each function's own totality is
    /// `verify_req_est_001_evidence_is_total`'s). The points are not read.
    pub(crate) fn any_evidence<I: Iterator<Item = Point>>(_circle: &Circle, _points: I) -> f64 {
        kani::any()
    }

    /// Stub of [`PointModel::robust_circle`].
    pub(crate) fn robust_circle(
        _model: &PointModel,
        path: &[PathSample],
        range: Range<usize>,
    ) -> Result<GeometricFit, CircleFitError> {
        let count = path.get(range).map_or(0, <[PathSample]>::len);
        let fit = if kani::any() {
            Ok(GeometricFit {
                circle: any_circle(),
                noise: kani::any(),
            })
        } else {
            Err(CircleFitError::Degenerate)
        };
        kani::assume(robust_fit_contract(count, &fit));
        fit
    }
}

/// A noise-free estimation path of `n` samples at 100 Hz for l1 0.30 m,
/// l2 0.20 m: the first 14 turn the forearm about the resting elbow (psi
/// 0.06 to 0.5 rad), the rest lift the upper arm (q1 up by 0.06 rad a
/// sample).
pub(super) fn short_lift(n: usize) -> [PathSample; N] {
    let arm = ArmGeometry::new(0.30, 0.20, Point::new(0.50, 0.0)).expect("a valid arm");
    let mut path = [PathSample::default(); N];
    for (i, sample) in path.iter_mut().enumerate().take(n) {
        let k = i as f64;
        let q = if i < 14 {
            JointAngles {
                shoulder_elevation: 0.0,
                elbow_flexion: 0.06 + k * (0.44 / 13.0),
            }
        } else {
            JointAngles {
                shoulder_elevation: (k - 13.0) * 0.06,
                elbow_flexion: 0.5,
            }
        };
        *sample = PathSample {
            time: k * 0.01,
            pose: arm.forward(q),
            wrench: Wrench::ZERO,
        };
    }
    path
}

libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
    /// REQ-EST-001: for any path of up to [`N`] samples — its length and
    /// every field of every sample (NaN, infinities) —
    /// the estimator returns a typed error or an estimate whose phases lie in
    /// the path and hold at least [`MIN_PHASE_SAMPLES`] each, with finite
    /// positive lengths; it never panics (indices, windows, subtraction).
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(25))]
    #[cfg_attr(kani, kani::stub(fit_circle_kasa, stub::fit_circle_kasa))]
    #[cfg_attr(kani, kani::stub(PointModel::robust_circle, stub::robust_circle))]
    #[cfg_attr(kani, kani::stub(phase::departure_from, stub::departure_from))]
    #[cfg_attr(kani, kani::stub(Circle::arc, stub::any_evidence))]
    #[cfg_attr(kani, kani::stub(Circle::rms_residual, stub::any_evidence))]
    #[cfg_attr(kani, kani::stub(Circle::residual_bias, stub::any_evidence))]
    pub(super) fn verify_req_est_001_estimator_is_total() {
        let length = usize::from(kani::any::<u8>()) % (N + 1);
        // Any samples (lift-off, the first guess of phase 1 and the phase
        // split anywhere; NaN and infinities in any field). Under Kani
        // always: the short lift is one of them, and made under the libm
        // stubs it is no constant but 24 forward kinematics of any sines
        // (with it as the other choice the proof peaked at 11.6 GiB, 10.9
        // without; 7.5 GiB with MiniSAT's preprocessor off, as
        // `verification/kani-run.sh` runs this harness: real Kani,
        // 2026-12-07). The sampling stand-in's random samples never reach
        // an estimate: it takes the short lift half the time.
        let path = if cfg!(kani) || kani::any() {
            let mut path = [PathSample::default(); N];
            for sample in path.iter_mut() {
                *sample = kani::any();
            }
            path
        } else {
            short_lift(N)
        };
        let path = &path[..length];
        let result = estimate_arm(path, Method::Ls);
        if let Ok(estimate) = result {
            let e = estimate.evidence;
            assert!(e.forearm_samples >= MIN_PHASE_SAMPLES && e.upper_arm_samples >= MIN_PHASE_SAMPLES);
            assert!(e.forearm_samples + e.upper_arm_samples <= path.len());
            assert!(estimate.upper_arm_length.is_finite() && estimate.upper_arm_length > 0.0);
            assert!(estimate.forearm_length.is_finite() && estimate.forearm_length > 0.0);
        }
        kani::cover!(result.is_ok(), "estimator: estimate");
        kani::cover!(
            result == Err(EstimateError::ForearmPhaseTooShort),
            "estimator: phase 1 too short"
        );
        kani::cover!(
            result == Err(EstimateError::NonFiniteSample),
            "estimator: non-finite sample"
        );
    }
}

libm_stubbed! { [sin, cos]
    /// REQ-EST-001: a point of the batch estimator's fits — the grasp
    /// itself ([`PointModel::GRASP`]) or the elbow a fitted forearm length
    /// away ([`PointModel::along_forearm`], any finite length) — of any
    /// finite sample is a number: never NaN, never a panic (it may
    /// overflow to ±∞ near `f64::MAX`). The batch harness's fit stubs
    /// count the points without making them.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_est_001_a_point_is_a_number() {
        let sample: PathSample = kani::any();
        kani::assume(sample.time.is_finite() && sample.pose.is_finite() && sample.wrench.is_finite());
        let length: f64 = kani::any();
        kani::assume(length.is_finite());
        let model = if kani::any() {
            PointModel::GRASP
        } else {
            PointModel::GRASP.along_forearm(length)
        };
        // The index only decides a slip (at `slip_index`, here never
        // before `usize::MAX`).
        let index = if kani::any() {
            usize::MAX
        } else {
            usize::from(kani::any::<u8>())
        };
        let point = model.point(index, &sample);
        assert!(!point.x.is_nan() && !point.z.is_nan());
        kani::cover!(point.is_finite(), "point: finite");
    }
}

/// Points the evidence harness gives the evidence functions.
const EVIDENCE_POINTS: usize = 4;

libm_stubbed! { [hypot, sqrt, atan2]
    /// REQ-EST-001: the evidence of a fit — its arc, RMS residual and
    /// residual bias over up to [`EVIDENCE_POINTS`] points — for any
    /// valid circle (what the fits' contracts give) and any points but
    /// NaN (what [`verify_req_est_001_a_point_is_a_number`] proves of the
    /// estimator's points: infinities included) never panics and makes no
    /// NaN; the arc lies in 0..=π. Over any circle and any points the
    /// distances made ∞ − ∞ (an infinite point less an infinite centre):
    /// the domain was wrong, not the functions, which the estimator never
    /// gives such a circle (real Kani, 2026-12-07). The
    /// batch harness stubs these three by any number. Four points reach
    /// every branch but the bias's block close, which needs half a block
    /// ([`super::circle::BIAS_BLOCK`] / 2 = 25 points): over 25 symbolic
    /// points the proof was undecided in 10 min (9.9 M clauses), and the
    /// batch harness's paths of up to [`N`] = 24 samples never close a
    /// block either; the close is the proptest
    /// `req_val_001_residual_bias_is_the_worst_block_mean`'s.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(6))]
    pub(super) fn verify_req_est_001_evidence_is_total() {
        // Drawn into the domain rather than assumed there (the sampling
        // stand-in would reject most draws); every value of the domain is
        // still drawn.
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let positive = |v: f64| if v.is_finite() && v > 0.0 { v } else { 1.0 };
        let not_nan = |v: f64| if v.is_nan() { 0.0 } else { v };
        let circle = Circle {
            centre: Point::new(finite(kani::any()), finite(kani::any())),
            radius: positive(kani::any()),
        };
        let given: [Point; EVIDENCE_POINTS] =
            core::array::from_fn(|_| Point::new(not_nan(kani::any()), not_nan(kani::any())));
        let count = usize::from(kani::any::<u8>()) % (EVIDENCE_POINTS + 1);
        let points = || given.iter().copied().take(count);
        let arc = circle.arc(points());
        let rms = circle.rms_residual(points());
        let bias = circle.residual_bias(points());
        assert!(arc.is_nan() || (0.0..=core::f64::consts::PI).contains(&arc));
        kani::cover!(arc > 0.0, "evidence: an arc");
        kani::cover!(rms > 0.0, "evidence: a residual");
        // Below half a block no block is judged.
        assert_eq!(bias, 0.0);
    }
}

/// REQ-EST-001: the phase scan ([`phase::departure_from`]) on a path of
/// any length up to [`N`] from any start, over any residuals (each
/// sample's one number, NaN and infinities included) and any tolerances,
/// never panics and ends phase 1 inside the path
/// ([`departure_contract`]). The scan alone, because the batch harness
/// over the whole estimator is undecided; with its look-ahead count
/// subtracted unchecked, this one was too (602 s: that the count never
/// goes below 0 is a counting argument over the window), so the count
/// saturates.
#[cfg_attr(kani, kani::proof)]
#[cfg_attr(kani, kani::unwind(25))]
pub(super) fn verify_req_est_001_departure_scan_keeps_its_contract() {
    let len = usize::from(kani::any::<u8>()) % (N + 1);
    let lift = usize::from(kani::any::<u8>()) % (N + 1);
    let residuals: [f64; N] = core::array::from_fn(|_| kani::any());
    let departure = phase::departure_from(len, lift, |i| residuals[i], kani::any(), kani::any());
    assert!(departure_contract(len, lift, departure));
    kani::cover!(departure.is_some(), "scan: a departure");
    kani::cover!(departure.is_none(), "scan: none");
}

/// Samples the online-estimator harness records (the forearm moments lag
/// [`DEPARTURE_WINDOW`] = 50 samples, so its `Ok` branch — a split and a
/// provisional upper arm — needs far longer paths: that is the batch
/// harness's and the session tests' to cover).
pub(super) const ONLINE_SAMPLES: usize = 4;

libm_stubbed! { [hypot, sqrt, atan2, sin, cos]
    /// REQ-EST-001: the kernel's online estimator, fed any path of up to
    /// [`ONLINE_SAMPLES`] samples one at a time (every value any number, NaN
    /// and infinities included), never panics, keeps its split inside the
    /// recorded path and reaches the forearm phase only after a lift-off.
    /// Unwind 12: the harness records 4 samples; a record call loops only when
    /// a forearm phase of 50 judged samples ends; the longest loop is the
    /// configuration check's over 11 positive values (`all_positive`).
    ///
    /// Stubbed besides libm, soundly by their contracts: the moments' fit
    /// ([`moment_fit_contract`], checked against the real fit by
    /// `req_est_001_fits_meet_their_stub_contracts`; any fit of the points
    /// counted), so the moments need only count their points
    /// (`CircleMoments::count_finite`), and the outlier test (either verdict).
    /// CBMC's symbolic execution does not see that a few samples never reach
    /// them (the indices are symbolic after the phases merge): with 8 samples
    /// and none of these stubs it spent its 600 s and 11.7 GiB in the outlier
    /// test's medians, the 3 × 3 solve and the sums' products; with them, 600 s
    /// and 4.5 GiB in the solver. 4 samples reach both covers (a lift-off
    /// needs 2) and are decided in under 3 min.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(12))]
    #[cfg_attr(kani, kani::stub(CircleMoments::fit, stub::moment_fit))]
    #[cfg_attr(kani, kani::stub(CircleMoments::add, CircleMoments::count_finite))]
    #[cfg_attr(kani, kani::stub(outlier::is_isolated_outlier, stub::any_verdict))]
    pub(super) fn verify_req_est_001_online_estimator_is_total() {
        let mut path = [PathSample::default(); ONLINE_SAMPLES];
        let mut online = online::OnlineEstimator::new();
        for end in 1..=ONLINE_SAMPLES {
            let sample = if kani::any() {
                kani::any::<PathSample>()
            } else {
                // A rising forearm: lift-off under the sampling stand-in too.
                PathSample {
                    time: end as f64 * 0.01,
                    pose: crate::geometry::Pose::new(0.0, 0.0, end as f64 * 0.02),
                    wrench: Wrench::ZERO,
                }
            };
            path[end - 1] = sample;
            online.record(&path[..end], &crate::config::ValidationLimits::default());
            let (lift, forearm_end) = online.split();
            match online.phase() {
                online::OnlinePhase::Resting => {}
                online::OnlinePhase::Forearm => {
                    assert!(lift < end, "lift-off outside the recorded path");
                    assert!(
                        path[lift].pose.psi > online::LIFT_PSI,
                        "lift-off below LIFT_PSI"
                    );
                }
                online::OnlinePhase::UpperArm => {
                    assert!(
                        lift <= forearm_end && forearm_end <= end,
                        "split outside the path"
                    );
                }
            }
        }
        kani::cover!(
            online.phase() == online::OnlinePhase::Forearm,
            "online: forearm phase"
        );
        kani::cover!(
            online.phase() == online::OnlinePhase::Resting,
            "online: no lift-off"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pose;
    use proptest::prelude::*;

    #[test]
    fn harnesses_under_the_stand_in() {
        kani::check("estimator", 3_000, verify_req_est_001_estimator_is_total);
        kani::check("evidence", 3_000, verify_req_est_001_evidence_is_total);
        kani::check("point", 3_000, verify_req_est_001_a_point_is_a_number);
        kani::check(
            "departure scan",
            3_000,
            verify_req_est_001_departure_scan_keeps_its_contract,
        );
        kani::check(
            "online estimator",
            5_000,
            verify_req_est_001_online_estimator_is_total,
        );
    }

    #[test]
    fn a_path_beyond_the_capacity_is_refused() {
        use crate::path::PATH_CAPACITY;
        let lift = short_lift(N);
        let mut long = [PathSample::default(); PATH_CAPACITY + 1];
        long[..N].copy_from_slice(&lift);
        assert_eq!(
            estimate_arm(&long, Method::Ls),
            Err(EstimateError::PathTooLong)
        );
        assert_ne!(
            estimate_arm(&long[..PATH_CAPACITY], Method::Ls),
            Err(EstimateError::PathTooLong)
        );
    }

    #[test]
    fn the_short_lift_is_estimated() {
        let path = short_lift(N);
        let estimate = estimate_arm(&path, Method::Ls).expect("the short lift is estimated");
        assert!(
            (estimate.forearm_length - 0.20).abs() < 1e-6,
            "{estimate:?}"
        );
        assert!(
            (estimate.upper_arm_length - 0.30).abs() < 1e-6,
            "{estimate:?}"
        );
    }

    proptest! {
        /// REQ-EST-001: the real fits meet the contracts the proof assumes
        /// of them, on arbitrary points (NaN, infinities, repeats) and on
        /// noisy arcs.
        #[test]
        fn req_est_001_fits_meet_their_stub_contracts(
            raw in prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64, any::<u8>()), 0..30),
            radius in 0.05..0.5f64, noise in 0.0..1e-3f64,
        ) {
            let points: [Point; 30] = core::array::from_fn(|i| match raw.get(i) {
                Some(&(x, z, 0)) => Point::new(x * f64::NAN, z),
                Some(&(x, _, 1)) => Point::new(x, f64::INFINITY),
                Some(&(x, z, k)) if k < 128 => Point::new(x, z),
                Some(&(x, _, _)) => {
                    let angle = x * 1.5;
                    Point::new(radius * libm::cos(angle) + noise * x, radius * libm::sin(angle))
                }
                None => Point::default(),
            });
            let count = raw.len();
            let points = &points[..count];
            prop_assert!(circle_fit_contract(count, &fit_circle_kasa(points.iter().copied())));
            let path: [PathSample; 30] = core::array::from_fn(|i| PathSample {
                pose: Pose::new(points.get(i).map_or(0.0, |p| p.x), points.get(i).map_or(0.0, |p| p.z), 0.0),
                ..PathSample::default()
            });
            let fit = PointModel::GRASP.robust_circle(&path[..count], 0..count);
            prop_assert!(robust_fit_contract(count, &fit), "{:?}", fit);
            let mut moments = CircleMoments::new();
            for point in points {
                moments.add(*point);
            }
            let fit = moments.fit();
            prop_assert!(moment_fit_contract(moments.count(), &fit), "{:?}", fit);
        }
    }
}
