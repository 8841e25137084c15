//! Isolated outliers: samples that leave a smooth recorded path alone.
//!
//! # Theory of operation
//! The estimation motion is smooth at the recording rate: between two
//! neighbouring path samples (10 ms, [`crate::path::PATH_SAMPLE_PERIOD`])
//! the grasp moves a millimetre or less and psi a few milliradians. A
//! sensor glitch (a bad frame, a flipped bit) throws one sample, or two in
//! a row, far off. An unweighted fit over a short arc is pulled by such a
//! sample out of all proportion: 5 cm outliers on every 37th sample put
//! the online provisional forearm on a 4 cm circle (a probe on
//! `noisy/case3.csv`).
//!
//! Sample `i` is an **isolated outlier** when its grasp point lies more
//! than [`OUTLIER_DISTANCE`] from the componentwise median of the
//! [`OUTLIER_WINDOW`] samples `i − 2 ..= i + 2` (itself included), or its
//! psi more than [`OUTLIER_PSI`] from their median psi. With at most two
//! outliers among the five, the medians stay on the path. A sample
//! without two recorded neighbours on each side (the first and last two of
//! a path) is never judged an outlier; one with them whose pose is not
//! finite (NaN, ±∞: never recorded by the kernel, whose watchdog refuses
//! such frames, but possible in a path read from a log) always is. A stretch of several corrupted
//! samples in a row is not isolated: the robust (Cauchy-weighted) fits
//! handle those.
//!
//! # Bounds
//! Three medians of five numbers (a sort of a five-element array each) and
//! a squared distance per judged sample; no square root, no allocation, no
//! loop over the path.

use crate::path::PathSample;
use core::ops::Range;

/// Samples the medians are taken over: the sample and two on each side.
pub const OUTLIER_WINDOW: usize = 5;
/// Neighbours the judgement needs on each side of a sample.
pub const OUTLIER_REACH: usize = OUTLIER_WINDOW / 2;
/// Distance of the grasp point from the window's median point beyond
/// which a sample is an outlier [m]: 50 × the position noise of
/// `plant.md`, 10 × the 0.5 mm a grasp moves between two samples at the
/// estimation motion's default peak speed (0.05 m/s).
pub const OUTLIER_DISTANCE: f64 = 5.0e-3;
/// Difference of psi from the window's median psi beyond which a sample is
/// an outlier [rad]: 50 × the psi noise of `plant.md` (1 mrad).
pub const OUTLIER_PSI: f64 = 0.05;

/// True when `path[index]` is an isolated outlier (module doc) or, with a
/// full window, not finite; false for an index without [`OUTLIER_REACH`]
/// samples on each side.
pub fn is_isolated_outlier(path: &[PathSample], index: usize) -> bool {
    // Checked both ways: an index near `usize::MAX` has no window either.
    let Some(window) = index
        .checked_sub(OUTLIER_REACH)
        .and_then(|first| path.get(first..first.checked_add(OUTLIER_WINDOW)?))
    else {
        return false;
    };
    let Some(sample) = path.get(index) else {
        return false;
    };
    // A sample off every finite path (NaN or an infinity, which the
    // kernel's watchdog never records but a path read from a log may hold)
    // is an outlier: it is left out of the fits. Judged here, so that the
    // differences below are of a finite sample and a median and never
    // make a NaN (∞ − ∞); finite samples are judged as before.
    if !sample.pose.is_finite() {
        return true;
    }
    let median = |of: fn(&PathSample) -> f64| {
        let mut values = [0.0; OUTLIER_WINDOW];
        for (value, sample) in values.iter_mut().zip(window) {
            *value = of(sample);
        }
        values.sort_unstable_by(f64::total_cmp);
        values[OUTLIER_REACH]
    };
    let dx = sample.pose.x - median(|s| s.pose.x);
    let dz = sample.pose.z - median(|s| s.pose.z);
    let dpsi = sample.pose.psi - median(|s| s.pose.psi);
    // Squared distances: no square root per sample (a soft-float library
    // call on a Cortex-M7 without a double FPU). A squared sum that
    // overflows to infinity is beyond the gate, as the distance is.
    dx * dx + dz * dz > OUTLIER_DISTANCE * OUTLIER_DISTANCE || libm::fabs(dpsi) > OUTLIER_PSI
}

/// The indices of `range` that are not isolated outliers of `path`.
pub fn kept(path: &[PathSample], range: Range<usize>) -> impl Iterator<Item = usize> + Clone + '_ {
    range.filter(move |&index| !is_isolated_outlier(path, index))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Pose, Wrench};
    use crate::path::GraspPath;

    /// A grasp moving along a line at 1 mm and 5 mrad per sample, with
    /// `glitch(i)` added to sample `i` [m, m, rad].
    fn path(glitch: impl Fn(usize) -> Pose) -> GraspPath {
        (0..40)
            .map(|i| {
                let s = i as f64;
                let g = glitch(i);
                PathSample {
                    time: s * 0.01,
                    pose: Pose::new(1e-3 * s + g.x, -0.5e-3 * s + g.z, 5e-3 * s + g.psi),
                    wrench: Wrench::ZERO,
                }
            })
            .collect()
    }

    #[test]
    fn a_smooth_path_has_no_outliers() {
        let smooth = path(|_| Pose::default());
        assert!((0..45).all(|i| !is_isolated_outlier(&smooth, i)));
    }

    /// One or two glitched samples in a row, in position or in psi, are
    /// outliers; their neighbours are not; glitches just inside the gates
    /// are not outliers. (A glitch moves the median by up to one sample's
    /// motion, 10 % of the gate here, so the glitches beyond it are 1.2 ×.)
    #[test]
    fn glitches_of_one_or_two_samples_are_outliers_and_only_they() {
        let d = OUTLIER_DISTANCE;
        for (glitched, offset) in [
            (&[10usize][..], Pose::new(0.0, 1.2 * d, 0.0)),
            (&[10, 11][..], Pose::new(-1.5 * d, 1.5 * d, 0.0)),
            (&[20][..], Pose::new(0.0, 0.0, 1.2 * OUTLIER_PSI)),
            (&[20, 21][..], Pose::new(0.05, -0.03, -0.2)),
        ] {
            let p = path(|i| {
                if glitched.contains(&i) {
                    offset
                } else {
                    Pose::default()
                }
            });
            for i in 0..40 {
                assert_eq!(
                    is_isolated_outlier(&p, i),
                    glitched.contains(&i),
                    "{glitched:?} {offset:?}: sample {i}"
                );
            }
        }
        let inside = path(|i| {
            if i == 10 {
                Pose::new(0.0, 0.99 * d, 0.99 * OUTLIER_PSI)
            } else {
                Pose::default()
            }
        });
        assert!(!is_isolated_outlier(&inside, 10));
    }

    /// The gates are strict: on a grasp at rest, a glitch exactly
    /// [`OUTLIER_DISTANCE`] or exactly [`OUTLIER_PSI`] off (the median is
    /// the resting pose, so the difference is exact) is not an outlier.
    #[test]
    fn a_glitch_exactly_at_a_gate_is_not_an_outlier() {
        let at_rest = |glitch: Pose| -> GraspPath {
            (0..9)
                .map(|i| PathSample {
                    time: i as f64 * 0.01,
                    pose: if i == 4 { glitch } else { Pose::default() },
                    wrench: Wrench::ZERO,
                })
                .collect()
        };
        for (at, beyond) in [
            (
                Pose::new(0.0, OUTLIER_DISTANCE, 0.0),
                Pose::new(0.0, OUTLIER_DISTANCE * (1.0 + f64::EPSILON), 0.0),
            ),
            (
                Pose::new(0.0, 0.0, OUTLIER_PSI),
                Pose::new(0.0, 0.0, OUTLIER_PSI * (1.0 + f64::EPSILON)),
            ),
        ] {
            assert!(!is_isolated_outlier(&at_rest(at), 4), "{at:?}");
            assert!(is_isolated_outlier(&at_rest(beyond), 4), "{beyond:?}");
        }
    }

    /// The first and last two samples have no full window: never outliers.
    #[test]
    fn the_ends_of_a_path_are_not_judged() {
        let p = path(|i| {
            if !(2..38).contains(&i) {
                Pose::new(1.0, 1.0, 1.0)
            } else {
                Pose::default()
            }
        });
        assert!([0, 1, 38, 39].iter().all(|&i| !is_isolated_outlier(&p, i)));
        assert!(!is_isolated_outlier(&p, usize::MAX));
    }
}

/// Proof of REQ-EST-005's outlier test: total, and it judges only samples
/// with a full window.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::geometry::Pose;
    use crate::kani_inputs::any_frame_or_at;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// Samples of the harness's path: one more than a window, so that a
    /// sample can have a full window or miss one on either side.
    const SAMPLES: usize = OUTLIER_WINDOW + 1;

    /// REQ-EST-005: a verdict of "outlier" is given only to a sample with
    /// [`OUTLIER_REACH`] recorded samples on each side.
    pub(super) fn check_verdict(
        len: usize,
        index: usize,
        outlier: bool,
    ) -> Result<(), &'static str> {
        if outlier && (index < OUTLIER_REACH || index + OUTLIER_REACH >= len) {
            return Err("a sample without a full window was judged an outlier");
        }
        Ok(())
    }

    /// REQ-EST-005: for any path of up to [`SAMPLES`] frames (any numbers,
    /// NaN and infinities included) and any index, the outlier test returns
    /// without a panic and without making a NaN, judges only samples with
    /// a full window, and judges a non-finite one an outlier. Unwind 7: the
    /// longest loops are the sort and the copy of the five-sample window.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(7))]
    pub(super) fn verify_req_est_005_outlier_test_is_total() {
        let mut path = [PathSample::default(); SAMPLES];
        for (i, sample) in path.iter_mut().enumerate() {
            // A path moving 1 mm per sample, or any frame.
            let s = i as f64 * 1e-3;
            *sample = any_frame_or_at(Pose::new(s, -s, s), s);
        }
        let len = usize::from(kani::any::<u8>()) % (SAMPLES + 1);
        let index = usize::from(kani::any::<u8>()) % (SAMPLES + 2);
        let path = &path[..len];
        let outlier = is_isolated_outlier(path, index);
        assert_eq!(check_verdict(len, index, outlier), Ok(()));
        let judged = index >= OUTLIER_REACH && index + OUTLIER_REACH < len;
        if judged && !path[index].pose.is_finite() {
            assert!(outlier, "a non-finite judged sample was kept");
        }
        kani::cover!(outlier, "outlier test: an outlier");
        kani::cover!(
            !outlier && judged,
            "outlier test: a judged sample that is not one"
        );
        kani::cover!(index >= len, "outlier test: an index beyond the path");
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::geometry::Wrench;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "outlier test",
                20_000,
                verify_req_est_005_outlier_test_is_total,
            );
        }

        proptest! {
            /// REQ-EST-005: on a smooth path (any direction, up to 1 mm
            /// and 5 mrad per sample) with glitches at least three samples
            /// apart, each at least twice the gates off, exactly the
            /// glitched samples with a full window are outliers.
            #[test]
            fn req_est_005_isolated_glitches_are_exactly_the_outliers(
                step in (-1e-3f64..1e-3, -1e-3f64..1e-3, -5e-3f64..5e-3),
                glitches in proptest::collection::btree_set(0usize..40, 0..8),
                size in (2.0f64..20.0, 0.0f64..core::f64::consts::TAU, prop::bool::ANY),
            ) {
                let glitches: heapless::Vec<usize, 8> = glitches
                    .iter()
                    .copied()
                    .scan(None, |last: &mut Option<usize>, i| {
                        let keep = last.is_none_or(|l| i >= l + 3);
                        if keep {
                            *last = Some(i);
                        }
                        Some(keep.then_some(i))
                    })
                    .flatten()
                    .collect();
                let (scale, angle, in_psi) = size;
                let path: crate::path::GraspPath = (0..40)
                    .map(|i| {
                        let s = i as f64;
                        let mut pose = Pose::new(step.0 * s, step.1 * s, step.2 * s);
                        if glitches.contains(&i) {
                            if in_psi {
                                pose.psi += scale * OUTLIER_PSI;
                            } else {
                                pose.x += scale * OUTLIER_DISTANCE * libm::cos(angle);
                                pose.z += scale * OUTLIER_DISTANCE * libm::sin(angle);
                            }
                        }
                        PathSample { time: s * 0.01, pose, wrench: Wrench::ZERO }
                    })
                    .collect();
                for i in 0..40 {
                    let outlier = is_isolated_outlier(&path, i);
                    prop_assert_eq!(check_verdict(path.len(), i, outlier), Ok(()));
                    let judged = (OUTLIER_REACH..40 - OUTLIER_REACH).contains(&i);
                    prop_assert_eq!(outlier, judged && glitches.contains(&i), "sample {}", i);
                }
            }
        }
    }
}
