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
//! number, so the proof covers every pattern of departures the real fits
//! could produce on paths up to [`N`] samples: the index arithmetic, the
//! look-ahead count and the ranges handed to the fits are checked for all
//! of them.
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
    pub(crate) fn fit_circle_kasa<I: Iterator<Item = Point> + Clone>(
        points: I,
    ) -> Result<Circle, CircleFitError> {
        let count = points.count();
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
    /// REQ-EST-001: for any path of up to [`N`] samples — its length, every
    /// forearm elevation and one arbitrary sample (NaN, infinities) anywhere —
    /// the estimator returns a typed error or an estimate whose phases lie in
    /// the path and hold at least [`MIN_PHASE_SAMPLES`] each, with finite
    /// positive lengths; it never panics (indices, windows, subtraction).
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(25))]
    #[cfg_attr(kani, kani::stub(fit_circle_kasa, stub::fit_circle_kasa))]
    #[cfg_attr(kani, kani::stub(PointModel::robust_circle, stub::robust_circle))]
    pub(super) fn verify_req_est_001_estimator_is_total() {
        let length = usize::from(kani::any::<u8>()) % (N + 1);
        let mut path = short_lift(N);
        if kani::any() {
            // Any forearm elevations: lift-off, the first guess of phase 1
            // and the phase split anywhere.
            for sample in path.iter_mut() {
                sample.pose.psi = kani::any();
            }
        }
        if kani::any() {
            let at = usize::from(kani::any::<u8>()) % N;
            path[at] = kani::any::<PathSample>();
        }
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
