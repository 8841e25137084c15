//! Property tests of the estimators and the validator.

use limb_kernel::config::ValidationLimits;
use limb_kernel::estimation::tilt::PlaneTilt;
use limb_kernel::estimation::{
    estimate_arm, fit_circle_geometric, fit_circle_kasa, fit_circle_taubin, hough_circle_chords,
    hough_circle_normals, ArmEstimate, Circle, CircleFitError, FitEvidence, GraspCorrection,
    Method, PointModel,
};
use limb_kernel::geometry::{Point, Pose, Wrench};
use limb_kernel::path::PathSample;
use limb_kernel::validate::validate;
use proptest::prelude::*;

/// Tolerance of the LS fits on noise-free arcs [m].
const EXACT: f64 = 1e-4;

/// Points of a noise-free arc and the forearm elevation whose normal
/// (cos psi, −sin psi) points at the centre: p = c + r (−cos psi, sin psi).
fn arc(centre: Point, radius: f64, start: f64, span: f64, n: usize) -> Vec<(Point, f64)> {
    (0..n)
        .map(|i| {
            let psi = start + span * i as f64 / (n - 1) as f64;
            (
                Point::new(centre.x - radius * psi.cos(), centre.z + radius * psi.sin()),
                psi,
            )
        })
        .collect()
}

fn close(circle: Circle, centre: Point, radius: f64, tolerance: f64) -> bool {
    (circle.radius - radius).abs() <= tolerance && circle.centre.distance(centre) <= tolerance
}

/// Deterministic 53-bit draws: a 64-bit LCG (Knuth's MMIX constants),
/// its top 53 bits, as a fraction of 2^53 in [0, 1).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Deterministic uniform noise in ±`half_width` [m].
fn uniform_noise(seed: u64, half_width: f64) -> impl FnMut() -> f64 {
    let mut draw = lcg(seed);
    move || (draw() - 0.5) * 2.0 * half_width
}

/// Deterministic standard normal draws (Box-Muller on the LCG, each draw
/// moved half a step off 0 so that its logarithm is finite).
fn normal(seed: u64) -> impl FnMut() -> f64 {
    let mut draw = lcg(seed);
    let half_step = 0.5 / (1u64 << 53) as f64;
    let mut uniform = move || draw() + half_step;
    move || (-2.0 * uniform().ln()).sqrt() * (2.0 * core::f64::consts::PI * uniform()).cos()
}

/// Kåsa's and Taubin's fits of the noise-free arc `arc(centre, radius,
/// start, span, n)`, named.
fn algebraic_fits(
    centre: Point,
    radius: f64,
    start: f64,
    span: f64,
    n: usize,
) -> [(&'static str, Result<Circle, CircleFitError>); 2] {
    let points: Vec<Point> = arc(centre, radius, start, span, n)
        .into_iter()
        .map(|(p, _)| p)
        .collect();
    [
        ("kasa", fit_circle_kasa(points.iter().copied())),
        ("taubin", fit_circle_taubin(points.iter().copied())),
    ]
}

proptest! {
    /// Any noise-free arc of ≥ 30° is recovered to 0.1 mm by Kåsa, Taubin and
    /// the geometric fit, and by both bounded Hough variants (exact on
    /// noise-free data, far inside their 1 mm grid).
    #[test]
    fn arcs_of_thirty_degrees_or_more_are_recovered(
        cx in -0.5f64..0.5, cz in -0.5f64..0.5, radius in 0.05f64..0.5,
        start in -3.2f64..3.2, span in std::f64::consts::FRAC_PI_6..5.5, n in 12usize..400,
    ) {
        let centre = Point::new(cx, cz);
        let samples = arc(centre, radius, start, span, n);
        let points = || samples.iter().map(|(p, _)| *p);
        let kasa = fit_circle_kasa(points()).unwrap();
        let taubin = fit_circle_taubin(points()).unwrap();
        let geometric = fit_circle_geometric(points(), taubin).unwrap().circle;
        let normals = hough_circle_normals(n, |i| samples.get(i).copied()).unwrap();
        let chords = hough_circle_chords(n, |i| samples.get(i).map(|(p, _)| *p)).unwrap();
        for (name, fit) in [("kasa", kasa), ("taubin", taubin), ("geometric", geometric),
                            ("hough normals", normals), ("hough chords", chords)] {
            prop_assert!(close(fit, centre, radius, EXACT), "{name}: {fit:?}");
        }
        // The arc seen from the centre between the first and last point
        // (0..π: a longer span is seen the short way round).
        let seen = if span <= std::f64::consts::PI { span } else { std::f64::consts::TAU - span };
        let arc = Circle { centre, radius }.arc(points());
        prop_assert!((arc - seen).abs() < 1e-9, "arc {arc} for a span of {span}");
    }

    /// The fast corrected point equals the fit point under the corrections.
    #[test]
    fn point_model_paths_agree(
        x in -1.0f64..1.0, z in -1.0f64..1.0, psi in -3.2f64..3.2, fx in -50.0f64..50.0,
        fz in -50.0f64..50.0, along in prop_oneof![Just(0.0), 0.0f64..0.5], compliance in 0.0f64..0.01,
        slide in -0.02f64..0.02, ox in -0.02f64..0.02, oz in -0.02f64..0.02,
        index in 0usize..10, slip_index in 0usize..10,
    ) {
        let model = PointModel {
            forearm_length: along,
            correction: GraspCorrection { compliance, slide, offset: Point::new(ox, oz) },
            slip_index,
        };
        let sample = PathSample { time: 0.0, pose: Pose::new(x, z, psi), wrench: Wrench::new(fx, fz, 0.0) };
        let fast = model.point(index, &sample);
        let full = model.fit_point(index, &sample).at(model.correction);
        prop_assert!(fast.distance(full) < 1e-12, "{fast:?} {full:?}");
    }

    /// The fits are total: any points give a circle with a finite positive
    /// radius or a typed error.
    #[test]
    fn fits_never_panic(raw in prop::collection::vec((special(), special(), special()), 0..40)) {
        let points: Vec<Point> = raw.iter().map(|(x, z, _)| Point::new(*x, *z)).collect();
        let with_psi: Vec<(Point, f64)> = raw.iter().map(|(x, z, psi)| (Point::new(*x, *z), *psi)).collect();
        let it = || points.iter().copied();
        let fits = [
            fit_circle_kasa(it()),
            fit_circle_taubin(it()),
            fit_circle_taubin(it()).and_then(|start| fit_circle_geometric(it(), start)).map(|f| f.circle),
            hough_circle_normals(with_psi.len(), |i| with_psi.get(i).copied()),
            hough_circle_chords(points.len(), |i| points.get(i).copied()),
        ];
        for circle in fits.into_iter().flatten() {
            prop_assert!(circle.is_valid());
        }
    }

    /// `estimate_arm` is total on arbitrary paths (NaN, infinities,
    /// duplicates, a single point, all equal, empty).
    #[test]
    fn estimate_arm_never_panics(raw in prop::collection::vec(sample(), 0..200)) {
        for method in [Method::Hough, Method::Ls, Method::Auto] {
            if let Ok(e) = estimate_arm(&raw, method) {
                prop_assert!(e.upper_arm_length.is_finite() && e.forearm_length.is_finite());
            }
        }
    }

    /// Whatever the estimate and grasp start, the default validator accepts
    /// only models inside all its ranges.
    #[test]
    fn validator_never_accepts_a_model_outside_its_ranges(
        l1 in -0.1f64..1.0, l2 in -0.1f64..1.0,
        ex in -0.5f64..1.0, ez in -0.05f64..0.05, sx in -0.5f64..1.5, sz in -0.2f64..0.2,
        arcs in (0.0f64..3.0, 0.0f64..3.0), residuals in (0.0f64..0.01, 0.0f64..0.01),
        disagreement in prop::option::of(0.0f64..0.02),
    ) {
        let estimate = ArmEstimate {
            upper_arm_length: l1,
            forearm_length: l2,
            elbow: Point::new(ex, ez),
            shoulder: Point::new(sx, sz),
            path_shoulder: Point::new(sx, sz),
            path_upper_arm_length: l1,
            grasp_pitch_offset: 0.0,
            method: Method::Auto,
            evidence: FitEvidence {
                forearm_arc: arcs.0,
                upper_arm_arc: arcs.1,
                forearm_residual: residuals.0,
                upper_arm_residual: residuals.1,
                residual_bias: 0.0,
                method_disagreement: disagreement,
                forearm_samples: 100,
                upper_arm_samples: 100,
                outliers: 0,
                resolution: 0.0,
                uncertainty: None,
                play: None,
                compliance: None,
                trunk_compliance: None,
                grasp_slip: None,
                plane_tilt: None,
            },
        };
        let limits = ValidationLimits::default();
        if validate(&estimate, Point::default(), &limits).is_ok() {
            prop_assert!((limits.min_upper_arm_length..=limits.max_upper_arm_length).contains(&l1));
            prop_assert!((limits.min_forearm_length..=limits.max_forearm_length).contains(&l2));
            prop_assert!(arcs.0 >= limits.min_arc && arcs.1 >= limits.min_arc);
            prop_assert!(residuals.0 <= limits.max_residual && residuals.1 <= limits.max_residual);
            prop_assert!(disagreement.is_some() || !limits.require_method_agreement);
            prop_assert!(disagreement.unwrap_or(0.0) <= limits.max_method_disagreement);
            let elbow = Point::new(ex, ez);
            prop_assert!((elbow.distance(Point::default()) - l2).abs() <= limits.max_geometry_mismatch);
            prop_assert!((elbow.distance(Point::new(sx, sz)) - l1).abs() <= limits.max_geometry_mismatch);
        }
    }
}

/// Ordinary values mixed with NaN, infinities, zero and repeats.
fn special() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1.0f64..1.0,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(0.0),
        1 => Just(0.25),
    ]
}

fn sample() -> impl Strategy<Value = PathSample> {
    (special(), special(), special(), special()).prop_map(|(t, x, z, psi)| PathSample {
        time: t,
        pose: Pose::new(x, z, psi),
        wrench: Wrench::new(x, z, 0.0),
    })
}

/// Degenerate inputs named in the requirements each give a typed error.
#[test]
fn degenerate_inputs_are_typed_errors() {
    let at = |i: usize, x: f64, z: f64, psi: f64| PathSample {
        time: i as f64 * 0.01,
        pose: Pose::new(x, z, psi),
        wrench: Wrench::ZERO,
    };
    let empty: Vec<PathSample> = Vec::new();
    let single = vec![at(0, 0.0, 0.0, 0.0)];
    let equal: Vec<_> = (0..500).map(|i| at(i, 0.1, 0.1, 0.3)).collect();
    let line: Vec<_> = (0..500)
        .map(|i| at(i, i as f64 * 1e-3, i as f64 * 1e-3, 0.3))
        .collect();
    let nan: Vec<_> = (0..500).map(|i| at(i, f64::NAN, 0.0, 0.3)).collect();
    for path in [empty, single, equal, line, nan] {
        for method in [Method::Hough, Method::Ls, Method::Auto] {
            assert!(
                estimate_arm(&path, method).is_err(),
                "{method:?} {:?}",
                path.first()
            );
        }
    }
}

/// On noisy arcs (±4 mm) Taubin's fit stays within 1 mm of the geometric
/// fit, and on a short arc, where Kåsa's fit is pulled toward a smaller
/// circle (its known bias), far closer than Kåsa's: the characteristic
/// polynomial and its Newton iteration must reach the true root (at 0,
/// Taubin's formula gives Kåsa's answer). The noise-free arcs above cannot
/// tell them apart (there the root is 0).
#[test]
fn taubin_is_near_the_geometric_fit_on_noisy_arcs() {
    let mut noise = uniform_noise(0x9E37_79B9_7F4A_7C15, 0.004);
    let (centre, radius) = (Point::new(0.12, -0.05), 0.3);
    for span in [0.7, 1.5, 2.5] {
        let points: Vec<Point> = arc(centre, radius, 0.2, span, 300)
            .into_iter()
            .map(|(p, _)| Point::new(p.x + noise(), p.z + noise()))
            .collect();
        let kasa = fit_circle_kasa(points.iter().copied()).unwrap();
        let taubin = fit_circle_taubin(points.iter().copied()).unwrap();
        let geometric = fit_circle_geometric(points.iter().copied(), taubin)
            .unwrap()
            .circle;
        let off =
            |c: Circle| (c.radius - geometric.radius).abs() + c.centre.distance(geometric.centre);
        assert!(
            off(taubin) < 1e-3,
            "span {span}: {taubin:?} vs {geometric:?}"
        );
        if span < 1.0 {
            assert!(off(taubin) < 0.2 * off(kasa), "{taubin:?} vs {kasa:?}");
        }
    }
}

/// Points on a circle far larger than any arm segment (radius 10 km, a
/// 0.5 m arc: straight for this application) are refused as degenerate,
/// not returned as a huge circle.
#[test]
fn a_circle_beyond_the_largest_radius_is_degenerate() {
    let radius = 1.0e4;
    for (name, fit) in algebraic_fits(Point::new(0.0, -radius), radius, -2.5e-5, 5.0e-5, 50) {
        assert_eq!(fit, Err(CircleFitError::Degenerate), "{name}");
    }
}

/// The largest radius is MAX_RADIUS (1 km), compared as r² ≤ (1 km)²: a
/// 100 m circle (a quarter of it sampled) is still fitted, by both
/// algebraic fits.
#[test]
fn a_circle_inside_the_largest_radius_is_fitted() {
    let radius = 100.0;
    let centre = Point::new(3.0, -radius);
    for (name, fit) in algebraic_fits(centre, radius, 0.0, core::f64::consts::FRAC_PI_2, 50) {
        let circle = fit.unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert!(close(circle, centre, radius, 1e-6), "{name}: {circle:?}");
    }
}

/// Finite points whose squared spreads multiply past f64's range (a
/// 1e60 m circle) are a degenerate geometry, not non-finite data.
#[test]
fn finite_points_far_apart_are_degenerate_not_non_finite() {
    for (name, fit) in algebraic_fits(Point::new(0.0, 0.0), 1.0e60, 0.0, 1.0, 50) {
        assert_eq!(fit, Err(CircleFitError::Degenerate), "{name}");
    }
}

/// A circle is valid only with a finite centre and a finite, positive
/// radius.
#[test]
fn a_circle_is_valid_only_when_finite_with_a_positive_radius() {
    let circle = |x: f64, radius: f64| Circle {
        centre: Point::new(x, 0.0),
        radius,
    };
    assert!(circle(0.1, 0.3).is_valid());
    for (x, radius) in [
        (f64::NAN, 0.3),
        (0.1, f64::INFINITY),
        (0.1, f64::NAN),
        (0.1, 0.0),
        (0.1, -0.3),
    ] {
        assert!(!circle(x, radius).is_valid(), "{x} {radius}");
    }
}

/// Taubin's fit checked against its definition, solved another way: with
/// the points centred, the circle A(w − w̄) + Bx + Cz = 0 (w = x² + z²)
/// minimises the mean algebraic distance vᵀSv (S: the covariance of
/// (w, x, z)) under Taubin's gradient constraint vᵀNv = 1, N = diag(4w̄, 1,
/// 1): the generalised eigenvector of the smallest eigenvalue, here from
/// nalgebra's symmetric eigen-decomposition of N^-½ S N^-½. The fit's
/// characteristic polynomial and Newton iteration must give the same
/// circle, on arcs noisy enough (±20 mm) that the root is far from 0, and
/// on points scattered ±150 mm about the arc, where the root is so far
/// from 0 that a Newton step with a wrong slope stops 0.5 µm short.
#[test]
fn taubin_is_the_generalised_eigenvector_of_its_constraint() {
    for half_width in [0.02, 0.15] {
        let mut noise = uniform_noise(0x2545_F491_4F6C_DD1D, half_width);
        for (span, n) in [(0.7, 300), (1.5, 200), (2.5, 100), (4.0, 60)] {
            let points: Vec<Point> = arc(Point::new(0.12, -0.05), 0.3, 0.2, span, n)
                .into_iter()
                .map(|(p, _)| Point::new(p.x + noise(), p.z + noise()))
                .collect();
            let count = points.len() as f64;
            let mean = |f: &dyn Fn(&Point) -> f64| points.iter().map(f).sum::<f64>() / count;
            let (mx, mz) = (mean(&|p| p.x), mean(&|p| p.z));
            let centred: Vec<(f64, f64, f64)> = points
                .iter()
                .map(|p| {
                    let (x, z) = (p.x - mx, p.z - mz);
                    (x, z, x * x + z * z)
                })
                .collect();
            let m =
                |f: &dyn Fn(&(f64, f64, f64)) -> f64| centred.iter().map(f).sum::<f64>() / count;
            let w_mean = m(&|c| c.2);
            let s = nalgebra::Matrix3::new(
                m(&|c| (c.2 - w_mean) * (c.2 - w_mean)),
                m(&|c| (c.2 - w_mean) * c.0),
                m(&|c| (c.2 - w_mean) * c.1),
                m(&|c| (c.2 - w_mean) * c.0),
                m(&|c| c.0 * c.0),
                m(&|c| c.0 * c.1),
                m(&|c| (c.2 - w_mean) * c.1),
                m(&|c| c.0 * c.1),
                m(&|c| c.1 * c.1),
            );
            let scale = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(
                1.0 / (4.0 * w_mean).sqrt(),
                1.0,
                1.0,
            ));
            let eigen = (scale * s * scale).symmetric_eigen();
            let smallest = eigen.eigenvalues.imin();
            let v = scale * eigen.eigenvectors.column(smallest);
            let (a, b, c) = (v[0], v[1], v[2]);
            let expected = Circle {
                centre: Point::new(mx - b / (2.0 * a), mz - c / (2.0 * a)),
                radius: ((b * b + c * c) / (4.0 * a * a) + w_mean).sqrt(),
            };
            let taubin = fit_circle_taubin(points.iter().copied()).unwrap();
            assert!(
                close(taubin, expected.centre, expected.radius, 1e-9),
                "span {span}: {taubin:?} vs {expected:?}"
            );
            // The noise moves the fit well off the noise-free circle, so the
            // root is far from Kåsa's (at 0).
            let kasa = fit_circle_kasa(points.iter().copied()).unwrap();
            assert!(
                !close(kasa, expected.centre, expected.radius, 1e-4),
                "span {span}: Kåsa {kasa:?} is Taubin's {expected:?}"
            );
        }
    }
}

/// Two points are too few for any circle fit: each says so by name rather
/// than failing later on a singular step.
#[test]
fn two_points_are_too_few_for_every_fit() {
    let two = [Point::new(0.1, 0.0), Point::new(0.0, 0.1)];
    let start = Circle {
        centre: Point::new(0.0, 0.0),
        radius: 0.1,
    };
    assert_eq!(
        fit_circle_kasa(two.iter().copied()),
        Err(CircleFitError::TooFewPoints)
    );
    assert_eq!(
        fit_circle_taubin(two.iter().copied()),
        Err(CircleFitError::TooFewPoints)
    );
    assert_eq!(
        fit_circle_geometric(two.iter().copied(), start).map(|f| f.circle),
        Err(CircleFitError::TooFewPoints)
    );
}

/// The least spread the algebraic fits accept (a mean squared distance
/// from the centroid of 1e-12 m²) is inclusive: four points 1 µm around
/// their centroid (exactly that spread in binary) are still a circle.
#[test]
fn points_at_exactly_the_least_spread_are_fitted() {
    let d = 1e-6;
    let four = [
        Point::new(-d, 0.0),
        Point::new(d, 0.0),
        Point::new(0.0, -d),
        Point::new(0.0, d),
    ];
    for (name, fit) in [
        ("kasa", fit_circle_kasa(four.iter().copied())),
        ("taubin", fit_circle_taubin(four.iter().copied())),
    ] {
        let circle = fit.unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert!(
            close(circle, Point::new(0.0, 0.0), d, 1e-12),
            "{name}: {circle:?}"
        );
    }
}

/// The arm of [`noise_free_lift`] [m].
const NOISE_FREE_L1: f64 = 0.3;
const NOISE_FREE_L2: f64 = 0.2;
/// Samples at rest before [`noise_free_lift`]'s forearm turns.
const NOISE_FREE_REST: usize = 50;

/// A noise-free two-phase lift at 100 Hz: an arm (l1 0.3 m, l2 0.2 m, the
/// shoulder off both axes, so that a mixed-up coordinate cannot pass) flat
/// on the table rests 50 samples, lifts its forearm 1.2 rad about the
/// elbow over 1 000, then its upper arm 0.8 rad about the shoulder over
/// 1 000. Returns the arm, the path, the lift-off index and the forearm
/// phase's true end.
fn noise_free_lift() -> (limb_kernel::arm::ArmGeometry, Vec<PathSample>, usize, usize) {
    use limb_kernel::arm::{ArmGeometry, JointAngles};
    let (l1, l2) = (NOISE_FREE_L1, NOISE_FREE_L2);
    let arm = ArmGeometry::new(l1, l2, Point::new(l1 + l2 + 0.03, 0.1)).unwrap();
    let (rest, forearm, upper_arm): (usize, usize, usize) = (NOISE_FREE_REST, 1000, 1000);
    let angles = (0..rest + forearm + upper_arm).map(|i| {
        let forearm_part = (i.saturating_sub(rest).min(forearm)) as f64 / forearm as f64;
        let upper_part = (i.saturating_sub(rest + forearm)) as f64 / upper_arm as f64;
        JointAngles {
            shoulder_elevation: 0.8 * upper_part,
            elbow_flexion: 1.2 * forearm_part,
        }
    });
    let path: Vec<PathSample> = angles
        .enumerate()
        .map(|(i, q)| PathSample {
            time: i as f64 * 0.01,
            pose: arm.forward(q),
            wrench: Wrench::ZERO,
        })
        .collect();
    let lift = path.iter().position(|s| s.pose.psi > 0.05).unwrap();
    (arm, path, lift, rest + forearm)
}

/// The whole refinement of `path` with the forearm phase `forearm` (no
/// shoulder-rhythm prior), in one call per pass.
fn refined(path: &[PathSample], forearm: core::ops::Range<usize>) -> ArmEstimate {
    use limb_kernel::estimation::refine::{Progress, Refinement};
    use limb_kernel::path::PATH_CAPACITY;
    let mut refinement =
        Refinement::new(forearm, path.len(), &ValidationLimits::default(), 0.0, 1.0);
    (0..100)
        .find_map(|_| match refinement.advance(path, PATH_CAPACITY) {
            Progress::Done(outcome) => Some(outcome.expect("refined")),
            Progress::Running(_) => None,
        })
        .expect("the refinement finished")
}

/// REQ-EST-007: the refinement ends the forearm phase on its refined
/// circle. Given a split 20 samples (0.2 s) late, into the upper arm's
/// turn (as the online split comes on a quantizer's staircase), the
/// forearm phase keeps only the 7 of them within the departure tolerance
/// (measured), its evidence stays clean (block bias 0.009 mm) and the arm
/// is recovered (l1 0.02, l2 0.05 mm); with all 20 kept (the end pass
/// off by hand) this fails. Known limit: the tolerance is 4 × the forearm
/// fit's unweighted RMS, which late samples inflate; 60 samples late, it
/// keeps 33 and the estimate is refused (`residual_bias` 2.6 mm).
#[test]
fn req_est_007_a_late_split_is_ended_on_the_refined_circle() {
    let (_, path, lift, forearm_end) = noise_free_lift();
    let late = refined(&path, lift..forearm_end + 20);
    let kept = late.evidence.forearm_samples - (forearm_end - lift);
    assert!(kept <= 7, "{kept} late samples kept: {:?}", late.evidence);
    assert!(late.evidence.residual_bias < 0.05e-3, "{:?}", late.evidence);
    assert!((late.forearm_length - NOISE_FREE_L2).abs() < 0.1e-3);
    assert!((late.upper_arm_length - NOISE_FREE_L1).abs() < 0.1e-3);
}

/// The refinement recovers [`noise_free_lift`]'s arm to within 1e-9 m
/// (lengths, shoulder, elbow) and its arcs. (The Gauss-Newton step's
/// quadratic convergence from a start off the circle: `refine.rs`'s unit
/// test.)
#[test]
fn the_refinement_recovers_a_noise_free_arm() {
    let (l1, l2) = (NOISE_FREE_L1, NOISE_FREE_L2);
    let (arm, path, lift, forearm_end) = noise_free_lift();
    let elbow = Point::new(l2 + 0.03, 0.1);
    let estimate = refined(&path, lift..forearm_end);
    let off = [
        (estimate.upper_arm_length - l1).abs(),
        (estimate.forearm_length - l2).abs(),
        estimate.shoulder.distance(arm.shoulder()),
        estimate.elbow.distance(elbow),
    ];
    assert!(off.iter().all(|&e| e < 1e-9), "{off:?}: {estimate:?}");
    // The evidence arcs: the forearm's turn over its phase, the upper
    // arm's 0.8 · 999/1000 rad over its own.
    let forearm_turn = path[forearm_end - 1].pose.psi - path[lift].pose.psi;
    let arcs = [
        (estimate.evidence.forearm_arc, forearm_turn),
        (estimate.evidence.upper_arm_arc, 0.8 * 0.999),
    ];
    assert!(
        arcs.iter().all(|(got, want)| (got - want).abs() < 1e-9),
        "{arcs:?}"
    );
}

/// A refinement whose forearm phase holds fewer than `MIN_PHASE_SAMPLES`
/// samples says so by name, and so does one whose upper-arm phase does.
#[test]
fn a_refinement_over_too_short_a_phase_is_refused_by_name() {
    use limb_kernel::estimation::refine::{Progress, Refinement};
    use limb_kernel::estimation::{EstimateError, MIN_PHASE_SAMPLES};
    use limb_kernel::path::PATH_CAPACITY;
    let points = arc(Point::new(0.2, 0.0), 0.2, 0.0, 1.5, 200);
    let path: Vec<PathSample> = points
        .iter()
        .enumerate()
        .map(|(i, (p, psi))| PathSample {
            time: i as f64 * 0.01,
            pose: Pose::new(p.x, p.z, *psi),
            wrench: Wrench::ZERO,
        })
        .collect();
    let run = |forearm: core::ops::Range<usize>, len: usize| {
        let mut refinement = Refinement::new(forearm, len, &ValidationLimits::default(), 0.0, 1.0);
        (0..100)
            .find_map(|_| match refinement.advance(&path[..len], PATH_CAPACITY) {
                Progress::Done(outcome) => Some(outcome.map(|_| ())),
                Progress::Running(_) => None,
            })
            .expect("finished")
    };
    let short = MIN_PHASE_SAMPLES - 1;
    assert_eq!(run(0..short, 150), Err(EstimateError::ForearmPhaseTooShort));
    // Exactly the least is enough, for either phase.
    assert_eq!(run(0..MIN_PHASE_SAMPLES, 150), Ok(()));
    assert_eq!(run(0..100, 100 + MIN_PHASE_SAMPLES), Ok(()));
    assert_eq!(
        run(0..100, 100 + short),
        Err(EstimateError::UpperArmPhaseTooShort)
    );
}

/// The moment fit's stated uncertainty is the spread it actually has: over
/// 1 600 arcs (r 0.3 m, 1 rad, 100 points) with 1 mm Gaussian noise, the
/// reported 1σ of the radius and of the centre (the larger coordinate's)
/// match the empirical standard deviations of the fits within 7 % (the
/// empirical SD of 1 600 fits is itself ±1.8 %; measured 2-3 % low, and
/// 9-10 % low with the radius's gradient in d off by r², the mutant
/// `moments.rs:128:82`; at r = 0.25 m a mutant a·4r = a/4r hid), and the
/// RMS residual matches the noise within 5 %, for arcs starting
/// beside the centre and above it (the fit's coordinates start at the
/// first point, so each arc weighs another term of the radius's gradient).
/// The joint envelope's spread and the provisional upper arm's precision
/// rest on these.
#[test]
fn the_moment_fit_states_the_uncertainty_it_has() {
    use limb_kernel::estimation::moments::{CircleMoments, MomentFit};
    let mut noise = normal(0x5DEE_CE66_D1CE_4E5B);
    let (centre, radius, sigma) = (Point::new(0.1, -0.2), 0.3, 1e-3);
    let sd = |values: &[f64]| {
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt()
    };
    for start in [0.3, core::f64::consts::FRAC_PI_2] {
        let fits: Vec<MomentFit> = (0..1600)
            .map(|_| {
                let mut moments = CircleMoments::new();
                for (p, _) in arc(centre, radius, start, 1.0, 100) {
                    assert!(moments.add(Point::new(p.x + sigma * noise(), p.z + sigma * noise())));
                }
                moments.fit().expect("fit")
            })
            .collect();
        let mean_of = |f: &dyn Fn(&MomentFit) -> f64| fits.iter().map(f).sum::<f64>() / 1600.0;
        let of = |f: &dyn Fn(&MomentFit) -> f64| fits.iter().map(f).collect::<Vec<f64>>();
        let radius_ratio = mean_of(&|f| f.radius_sd) / sd(&of(&|f| f.circle.radius));
        let centre_spread = sd(&of(&|f| f.circle.centre.x)).max(sd(&of(&|f| f.circle.centre.z)));
        let centre_ratio = mean_of(&|f| f.centre_sd) / centre_spread;
        let residual_ratio = mean_of(&|f| f.rms_residual) / sigma;
        for (what, ratio, within) in [
            ("radius", radius_ratio, 0.07),
            ("centre", centre_ratio, 0.07),
            ("residual", residual_ratio, 0.05),
        ] {
            assert!(
                (ratio - 1.0).abs() < within,
                "start {start}: {what} {ratio}"
            );
        }
    }
}

/// The unsigned angle between two points seen from a centre anywhere in
/// frame S [rad, 0..π], symmetric in the two points.
#[test]
fn angle_between_is_the_unsigned_angle_at_the_centre() {
    use limb_kernel::geometry::angle_between;
    let centre = Point::new(0.7, -0.4);
    let at =
        |angle: f64, r: f64| Point::new(centre.x + r * angle.cos(), centre.z + r * angle.sin());
    for (a, b, expected) in [
        (
            0.0,
            core::f64::consts::FRAC_PI_2,
            core::f64::consts::FRAC_PI_2,
        ),
        (0.3, 0.3 + core::f64::consts::PI, core::f64::consts::PI),
        (1.0, 1.0, 0.0),
        (2.0, 2.5, 0.5),
        (-0.2, 0.4, 0.6),
    ] {
        let (p, q) = (at(a, 0.3), at(b, 0.2));
        assert!(
            (angle_between(centre, p, q) - expected).abs() < 1e-12,
            "{a} {b}"
        );
        assert!(
            (angle_between(centre, q, p) - expected).abs() < 1e-12,
            "{a} {b}"
        );
    }
}

/// A normals sample on a circle about `centre`: the point at forearm
/// elevation `psi` and radius `radius`, with its normal toward the centre.
fn on_circle(centre: Point, radius: f64, psi: f64) -> (Point, f64) {
    (
        Point::new(centre.x - radius * psi.cos(), centre.z + radius * psi.sin()),
        psi,
    )
}

/// Both Hough transforms take up to `PATH_CAPACITY` points, refuse one
/// more by name, and ask for no point past the count they were given.
#[test]
fn the_hough_transforms_take_a_full_path_and_no_more() {
    use limb_kernel::path::PATH_CAPACITY;
    let centre = Point::new(0.3, 0.05);
    let psi = |i: usize| 0.1 + 1.5 * i as f64 / PATH_CAPACITY as f64;
    for count in [PATH_CAPACITY, PATH_CAPACITY + 1] {
        let normals = hough_circle_normals(count, |i| {
            assert!(i < count, "sample {i} of {count} asked for");
            Some(on_circle(centre, 0.25, psi(i)))
        });
        let chords = hough_circle_chords(count, |i| {
            assert!(i < count, "point {i} of {count} asked for");
            Some(on_circle(centre, 0.25, psi(i)).0)
        });
        if count == PATH_CAPACITY {
            for (name, fit) in [("normals", normals), ("chords", chords)] {
                let circle = fit.unwrap_or_else(|e| panic!("{name}: {e:?}"));
                assert!(close(circle, centre, 0.25, 1e-6), "{name}: {circle:?}");
            }
        } else {
            assert_eq!(normals, Err(CircleFitError::TooManyPoints));
            assert_eq!(chords, Err(CircleFitError::TooManyPoints));
        }
    }
}

/// Normals less than 3° apart meet too far off to say anything: an arc of
/// 2° casts no vote (a degenerate answer), one of 10° is found.
#[test]
fn nearly_parallel_normals_cast_no_vote() {
    let centre = Point::new(0.3, 0.05);
    for (span, found) in [(2f64.to_radians(), false), (10f64.to_radians(), true)] {
        let fit = hough_circle_normals(100, |i| {
            Some(on_circle(centre, 0.25, 0.2 + span * i as f64 / 99.0))
        });
        if found {
            assert!(close(fit.unwrap(), centre, 0.25, 1e-6), "{fit:?}");
        } else {
            assert_eq!(fit, Err(CircleFitError::Degenerate));
        }
    }
}

/// Chords of exactly the shortest voting length (5 mm) vote: three points
/// 5 mm apart at a right angle give their circumcircle.
#[test]
fn chords_of_the_shortest_length_vote() {
    let three = [
        Point::new(0.0, 0.0),
        Point::new(0.005, 0.0),
        Point::new(0.005, 0.005),
    ];
    let circle = hough_circle_chords(3, |i| three.get(i).copied()).unwrap();
    assert!(
        close(
            circle,
            Point::new(0.0025, 0.0025),
            0.005 / 2f64.sqrt(),
            1e-12
        ),
        "{circle:?}"
    );
}

/// The coarse peak is the densest window of five 1 mm cells, not the
/// tallest cell: fifteen votes spread over 100-104 mm outweigh thirteen
/// stacked on 200-201 mm (the fine mean then takes the wide cluster,
/// give or take its edge cell).
#[test]
fn the_hough_peak_is_the_densest_window_of_cells() {
    let centre = Point::new(0.4, 0.1);
    // Each pair (i, i + half) meets at the centre on its own radius.
    let mut radii: Vec<f64> = (0..5).flat_map(|j| [0.100 + 0.001 * j as f64; 3]).collect();
    radii.extend([0.200; 7]);
    radii.extend([0.201; 6]);
    let half = radii.len();
    let sample = |i: usize| {
        let radius = radii[i % half];
        let psi = 0.3 * (i % half) as f64 / half as f64 + if i < half { 0.0 } else { 1.2 };
        Some(on_circle(centre, radius, psi))
    };
    let circle = hough_circle_normals(2 * half, sample).unwrap();
    assert!((circle.radius - 0.102).abs() < 1e-3, "{circle:?}");
    assert!(circle.centre.distance(centre) < 1e-9, "{circle:?}");
}

/// A lift whose forearm turns past the first fit's arc within a few
/// samples of lift-off leaves too short a forearm phase, and the batch
/// split says so by name rather than failing in the fit.
#[test]
fn a_forearm_phase_of_a_few_samples_is_too_short() {
    use limb_kernel::estimation::{detect_phases, EstimateError, PointModel};
    let psi = |i: usize| {
        if i < 100 {
            0.0
        } else {
            (0.1 * (i - 99) as f64).min(1.5)
        }
    };
    let path: Vec<PathSample> = (0..400)
        .map(|i| {
            let (p, _) = arc(Point::new(0.2, 0.0), 0.2, psi(i), 0.0, 2)[0];
            PathSample {
                time: i as f64 * 0.01,
                pose: Pose::new(p.x, p.z, psi(i)),
                wrench: Wrench::ZERO,
            }
        })
        .collect();
    assert_eq!(
        detect_phases(&path, &PointModel::GRASP).err(),
        Some(EstimateError::ForearmPhaseTooShort)
    );
}

/// A point model's points over any range are its points one by one: the
/// slip applies from its path index on, wherever the range starts (ranges
/// before, across and after the slip), and the fit points' corrected
/// values are the same points.
#[test]
fn a_point_model_reads_each_sample_by_its_path_index() {
    let path: Vec<PathSample> = (0..60)
        .map(|i| PathSample {
            time: i as f64 * 0.01,
            pose: Pose::new(0.01 * i as f64, 0.002 * i as f64, 0.02 * i as f64),
            wrench: Wrench::new(1.0, -2.0 + 0.1 * i as f64, 0.0),
        })
        .collect();
    let model = PointModel {
        forearm_length: 0.2,
        correction: GraspCorrection {
            compliance: 1e-3,
            slide: 0.01,
            offset: Point::new(0.003, -0.002),
        },
        slip_index: 30,
    };
    for range in [5..25, 20..45, 30..60, 41..59] {
        let one_by_one: Vec<Point> = range.clone().map(|i| model.point(i, &path[i])).collect();
        let points: Vec<Point> = model.points(&path, range.clone()).collect();
        let fitted: Vec<Point> = model
            .fit_points(&path, range.clone())
            .map(|p| p.at(model.correction))
            .collect();
        assert_eq!(points, one_by_one, "{range:?}");
        for (f, p) in fitted.iter().zip(&one_by_one) {
            assert!(f.distance(*p) < 1e-15, "{range:?}: {f:?} vs {p:?}");
        }
    }
}

/// A circle's RMS residual is the root mean square of the points' signed
/// distances from it, 0 for no points.
#[test]
fn a_circle_s_rms_residual_is_over_every_point() {
    let circle = Circle {
        centre: Point::new(0.3, -0.1),
        radius: 0.2,
    };
    let at = |angle: f64, r: f64| Point::new(0.3 + r * angle.cos(), -0.1 + r * angle.sin());
    let points = [at(0.0, 0.21), at(1.0, 0.19), at(2.0, 0.23), at(3.0, 0.2)];
    let expected = ((0.01f64.powi(2) + 0.01f64.powi(2) + 0.03f64.powi(2)) / 4.0).sqrt();
    assert!((circle.rms_residual(points.iter().copied()) - expected).abs() < 1e-12);
    assert_eq!(circle.rms_residual(core::iter::empty()), 0.0);
}

/// A slip is only corrected when the grasp follows the resting-elbow model
/// for `MIN_SLIP_SAMPLES` after the jump: on a lift whose grasp slides
/// 10 mm along the forearm at ψ ≈ 0.7 rad, the slip is found when the
/// forearm then turns on for 150 samples before the elbow lifts, and not
/// when it does so for only 50 (a short stretch is no evidence of a
/// resting elbow).
#[test]
fn a_slip_needs_a_long_enough_stretch_after_the_jump() {
    use limb_kernel::arm::{ArmGeometry, JointAngles};
    use limb_kernel::estimation::{detect_phases, detect_slip, PointModel, MIN_SLIP_SAMPLES};
    let (l1, l2, slide) = (0.3, 0.2, 0.01);
    let arm = ArmGeometry::new(l1, l2, Point::new(l1 + l2 + 0.03, 0.1)).unwrap();
    let (rest, before, upper_arm) = (50, 200, 400);
    let lift = |after: usize| -> Vec<PathSample> {
        (0..rest + before + after + upper_arm)
            .map(|i| {
                let (q2, slipped) = if i < rest + before {
                    (0.7 * i.saturating_sub(rest) as f64 / before as f64, false)
                } else {
                    let k = (i - rest - before).min(after);
                    (0.7 + 0.6 * k as f64 / after as f64, true)
                };
                let q1 = 0.8 * i.saturating_sub(rest + before + after) as f64 / upper_arm as f64;
                let mut pose = arm.forward(JointAngles {
                    shoulder_elevation: q1,
                    elbow_flexion: q2,
                });
                if slipped {
                    // The grasp slid `slide` away from the elbow.
                    pose.x -= slide * pose.psi.cos();
                    pose.z += slide * pose.psi.sin();
                }
                PathSample {
                    time: i as f64 * 0.01,
                    pose,
                    wrench: Wrench::ZERO,
                }
            })
            .collect()
    };
    let slip_of = |after: usize| {
        let path = lift(after);
        let phases = detect_phases(&path, &PointModel::GRASP).expect("phases");
        let jump = phases.forearm.end;
        assert!(
            jump.abs_diff(rest + before) <= 1,
            "after {after}: split at {jump}"
        );
        detect_slip(&path, &phases, &PointModel::GRASP).expect("slip fit")
    };
    const { assert!(50 < MIN_SLIP_SAMPLES && MIN_SLIP_SAMPLES < 150) };
    let found = slip_of(150).expect("a slip with 150 samples after it");
    assert!((found.correction.slide - slide).abs() < 1e-6, "{found:?}");
    assert_eq!(slip_of(50), None);
}

/// A noise-free lift of a person's arm (`spec/human-arm-model.md`): the
/// grasp off the forearm's joint line (the robot's pitch reads the
/// forearm's elevation plus δ), the shoulder `height` above the resting
/// elbow, and the glenohumeral centre moving by φ ρ as the elbow turns by
/// φ about its position at rest (ρ in the arm's rest frame). The forearm
/// turns 1.2 rad about the resting elbow, then the elbow 0.8 rad about the
/// shoulder, the forearm keeping its flexion; 100 Hz.
fn persons_lift(l1: f64, l2: f64, height: f64, offset: f64, rhythm: [f64; 2]) -> Vec<PathSample> {
    let (rest, forearm, upper_arm) = (50usize, 1000usize, 1000usize);
    let q1_rest = -(height / l1).asin();
    let elbow = Point::new(l2, 0.02);
    let shoulder = Point::new(elbow.x + l1 * q1_rest.cos(), elbow.z - l1 * q1_rest.sin());
    let (ex, ez) = ((elbow.x - shoulder.x) / l1, (elbow.z - shoulder.z) / l1);
    let (dx, dz) = (ez, -ex);
    let [along, rise] = rhythm;
    let (rx, rz) = (along * ex + rise * dx, along * ez + rise * dz);
    (0..rest + forearm + upper_arm)
        .map(|i| {
            let forearm_part = (i.saturating_sub(rest).min(forearm)) as f64 / forearm as f64;
            let phi = 0.8 * (i.saturating_sub(rest + forearm)) as f64 / upper_arm as f64;
            // The elbow at angle φ about the resting shoulder, l1 from the
            // moved one: E = S + t u, |t u − φ ρ| = l1.
            let (ux, uz) = (
                ex * phi.cos() + dx * phi.sin(),
                ez * phi.cos() + dz * phi.sin(),
            );
            let along_u = phi * (ux * rx + uz * rz);
            let t =
                along_u + (along_u * along_u - phi * phi * (rx * rx + rz * rz) + l1 * l1).sqrt();
            let e = Point::new(shoulder.x + t * ux, shoulder.z + t * uz);
            // The humerus's elevation (from the moved shoulder), and the
            // forearm's: the humerus's plus the elbow's flexion.
            let humerus = (e.z - (shoulder.z + phi * rz)).atan2((shoulder.x + phi * rx) - e.x);
            let elevation = humerus - q1_rest + 1.2 * forearm_part;
            PathSample {
                time: i as f64 * 0.01,
                pose: Pose::new(
                    e.x - l2 * elevation.cos(),
                    e.z + l2 * elevation.sin(),
                    elevation + offset,
                ),
                wrench: Wrench::ZERO,
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// REQ-EST-006: on a person's lift the kernel's estimator measures the
    /// grasp pitch offset, and with the arm's rhythm as its prior recovers
    /// l1 (glenohumeral centre at rest to elbow), l2 and the shoulder at
    /// rest; without the prior (a fixed shoulder) the shoulder is that of
    /// the elbow path, off by about the rhythm's reach.
    #[test]
    fn req_est_006_a_persons_arm_is_recovered_under_its_rhythm(
        l1 in 0.24f64..0.34, l2 in 0.18f64..0.25, height in -0.02f64..0.06,
        offset in -0.1f64..0.1, along in -0.03f64..0.0, rise in -0.02f64..0.0,
    ) {
        let path = persons_lift(l1, l2, height, offset, [along, rise]);
        let q1_rest = -(height / l1).asin();
        let shoulder = Point::new(l2 + l1 * q1_rest.cos(), 0.02 - l1 * q1_rest.sin());
        prop_assert!((shoulder.z - 0.02 - height).abs() < 1e-12);
        let e = limb_kernel::estimation::estimate_online(&path, &ValidationLimits { shoulder_rhythm: [along, rise], ..ValidationLimits::default() }, &PlaneTilt::new()).unwrap();
        // Not exact: the refinement's end pass keeps the first upper-arm
        // samples still within its 1 mm tolerance of the forearm circle
        // (one sample 0.17 mm off left l2 5.9 µm and δ 3.1 µrad off; worst
        // of 3 000 lifts 7.6 µm and 2.8 µrad).
        prop_assert!((e.grasp_pitch_offset - offset).abs() < 2e-5, "{e:?}");
        prop_assert!((e.forearm_length - l2).abs() < 2e-5, "{e:?}");
        prop_assert!((e.upper_arm_length - l1).abs() < 2e-4, "{} {l1}", e.upper_arm_length);
        prop_assert!(e.shoulder.distance(shoulder) < 5e-4, "{:?} {shoulder:?}", e.shoulder);
        // The rhythm's correction of l1 is bounded by the validator
        // (6 mm); this property is about the fit, not that bound.
        let limits = ValidationLimits {
            shoulder_rhythm: [along, rise],
            max_rhythm_correction: 0.1,
            ..ValidationLimits::person()
        };
        prop_assert!(validate(&e, path[0].pose.point(), &limits).is_ok());
        let fixed = limb_kernel::estimation::estimate_online(&path, &ValidationLimits::default(), &PlaneTilt::new()).unwrap();
        let reach = 0.8 * along.hypot(rise);
        prop_assert!(fixed.shoulder.distance(shoulder) > 0.3 * reach, "{fixed:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// REQ-EST-008: the kernel's estimate of a person's lift (white noise
    /// of σ on the grasp point, σ / l2 on its pitch) reports the standard
    /// uncertainty of l1 and l2: finite, not negative, below 1 nm without
    /// noise, and with noise at least a tenth of σ / √n (no fit of n
    /// samples knows a radius better).
    #[test]
    fn req_est_008_the_uncertainty_is_reported_finite_and_vanishes_without_noise(
        l1 in 0.24f64..0.34, l2 in 0.18f64..0.25, sigma in 0.0f64..5e-4,
        noise_free in any::<bool>(), seed in any::<u64>(),
    ) {
        let sigma = if noise_free { 0.0 } else { sigma };
        let mut draw = normal(seed);
        let path: Vec<PathSample> = persons_lift(l1, l2, 0.0, 0.0, [0.0, 0.0])
            .into_iter()
            .map(|mut s| {
                s.pose = Pose::new(
                    s.pose.x + sigma * draw(),
                    s.pose.z + sigma * draw(),
                    s.pose.psi + sigma / l2 * draw(),
                );
                s
            })
            .collect();
        let e = limb_kernel::estimation::estimate_online(&path, &ValidationLimits::default(), &PlaneTilt::new()).unwrap();
        let u = e.evidence.uncertainty.expect("the online estimator measures it");
        for value in [u.upper_arm, u.forearm] {
            prop_assert!(value.is_finite() && value >= 0.0, "{u:?}");
            if sigma == 0.0 {
                prop_assert!(value < 1e-9, "{u:?}");
            } else {
                prop_assert!(value >= 0.1 * sigma / (path.len() as f64).sqrt(), "{u:?} at {sigma}");
            }
        }
    }
}

proptest! {
    /// REQ-VAL-001 (the residual-bias evidence): the worst block mean is
    /// the largest |mean| of the full blocks of `BIAS_BLOCK` residuals and of
    /// a last block of at least half a block; a shorter tail is not judged;
    /// a NaN residual makes it NaN.
    #[test]
    fn req_val_001_residual_bias_is_the_worst_block_mean(
        blocks in prop::collection::vec(-0.01f64..0.01, 1..6),
        tail in 0usize..limb_kernel::estimation::BIAS_BLOCK,
        tail_value in -0.01f64..0.01,
    ) {
        use limb_kernel::estimation::{ResidualBias, BIAS_BLOCK};
        let mut bias = ResidualBias::default();
        for &mean in &blocks {
            // Block values alternating ±1 mm about the block's mean.
            for k in 0..BIAS_BLOCK {
                bias.add(mean + if k % 2 == 0 { 1e-3 } else { -1e-3 });
            }
        }
        for _ in 0..tail {
            bias.add(tail_value);
        }
        let mut want = blocks.iter().fold(0.0f64, |w, m| w.max(m.abs()));
        if tail * 2 >= BIAS_BLOCK {
            want = want.max(tail_value.abs());
        }
        prop_assert!((bias.worst() - want).abs() < 1e-12, "{} {want}", bias.worst());
        bias.add(f64::NAN);
        for _ in 0..BIAS_BLOCK {
            bias.add(0.0);
        }
        prop_assert!(bias.worst().is_nan());
    }
}

/// A path of the given psi readings, 10 ms apart, the grasp at rest.
fn psi_path(psi: &[f64]) -> Vec<PathSample> {
    psi.iter()
        .enumerate()
        .map(|(i, &psi)| PathSample {
            time: i as f64 * 0.01,
            pose: Pose::new(0.0, 0.0, psi),
            wrench: Wrench::ZERO,
        })
        .collect()
}

proptest! {
    /// REQ-EST-009: a psi that never falls by the hysteresis (a lift: any
    /// steps up, pauses, dips of noise under 10 mrad) has no turn: every
    /// sample is read as recorded (no share of the play). A psi that then
    /// falls on from its highest reading by more than the hysteresis is
    /// read with all of the play from the sample that goes past it, and
    /// from the highest reading to the one before with the share
    /// interpolated in time.
    #[test]
    fn req_est_009_the_reader_finds_the_turns_and_only_them(
        steps in prop::collection::vec(0.0..0.02f64, 2..200),
        dips in prop::collection::vec(-0.0049..0.0049f64, 200),
        fall in prop::collection::vec(0.002..0.02f64, 1..100),
    ) {
        use limb_kernel::estimation::play::{PlayReader, HYSTERESIS};
        let mut rising = Vec::new();
        let mut level = 0.3;
        for (step, dip) in steps.iter().zip(&dips) {
            level += step;
            rising.push(level + dip);
        }
        // Dips of ±4.9 mrad about a non-decreasing level never fall 10 mrad
        // below the highest reading.
        let path = psi_path(&rising);
        let mut reader = PlayReader::new();
        for index in 0..path.len() {
            prop_assert_eq!(reader.read(&path, index), Some(0.0));
        }
        prop_assert_eq!(reader.read(&path, path.len()), None);

        // A lift, then a fall from its top.
        let top = rising.iter().copied().fold(f64::MIN, f64::max);
        let peak = rising.iter().position(|&p| p == top).expect("a top");
        let mut psi = rising[..=peak].to_vec();
        let mut value = top;
        for drop in &fall {
            value -= drop;
            psi.push(value);
        }
        let path = psi_path(&psi);
        let switch = psi
            .iter()
            .skip(peak)
            .position(|&p| p < top - HYSTERESIS)
            .map(|i| i + peak);
        let mut reader = PlayReader::new();
        for index in 0..path.len() {
            let expected = match switch {
                Some(switch) if index >= switch => 1.0,
                Some(switch) if index >= peak => {
                    (path[index].time - path[peak].time) / (path[switch].time - path[peak].time)
                }
                _ => 0.0,
            };
            let read = reader.read(&path, index).expect("a sample of the path");
            prop_assert!((read - expected).abs() < 1e-12, "sample {}: {} for {}", index, read, expected);
        }
    }
}

/// A noise-free lift of an arm flat on the table (shoulder at the resting
/// elbow's height, plant.md's posture) whose trunk yields: the forearm
/// turns 1.2 rad about the resting elbow over 1 000 samples while the
/// table holds the shoulder, then the upper arm 0.9 rad over 1 000, the
/// whole arm displaced by c f with the robot's force f (the arm's on the
/// robot, as the sensor reads it), the yield taking 50 samples to settle
/// after the elbow leaves the table. `jump`: a step of the grasp point
/// (m, along x) from that sample of the upper-arm phase on. 100 Hz.
fn trunk_lift(l1: f64, l2: f64, compliance: f64, jump: Option<(usize, f64)>) -> Vec<PathSample> {
    use limb_kernel::arm::{ArmGeometry, JointAngles};
    let (rest, forearm, upper_arm) = (50usize, 1000usize, 1000usize);
    let arm = ArmGeometry::new(l1, l2, Point::new(l1 + l2, 0.0)).unwrap();
    (0..rest + forearm + upper_arm)
        .map(|i| {
            let forearm_part = (i.saturating_sub(rest).min(forearm)) as f64 / forearm as f64;
            let lifted = i.saturating_sub(rest + forearm);
            let u = lifted as f64 / upper_arm as f64;
            let q = JointAngles {
                shoulder_elevation: 0.9 * u,
                elbow_flexion: 1.2 * forearm_part,
            };
            // The lift's force: the forearm's weight first, then the
            // upper arm's (plant.md's lift: fx -26 -> +3 N, fz -19 -> +2 N).
            let force = if lifted == 0 {
                Point::new(-20.0 * forearm_part, -18.0 * forearm_part)
            } else {
                Point::new(-25.0 + 30.0 * u, -20.0 + 22.0 * u * u)
            };
            let settled = (lifted as f64 / 50.0).min(1.0);
            let mut pose = arm.forward(q);
            pose.x += settled * compliance * force.x;
            pose.z += settled * compliance * force.z;
            if let Some((at, step)) = jump {
                if lifted >= at {
                    pose.x += step;
                }
            }
            PathSample {
                time: i as f64 * 0.01,
                pose,
                wrench: Wrench::new(force.x, force.z, 0.0),
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// REQ-EST-012: on a lift whose trunk yields (600-3 000 N/m), the
    /// online estimate of plant.md's posture (the default limits) reads
    /// the yield out and recovers l1, l2, the shoulder at rest and the
    /// trunk's compliance, validated (measured: c 0.69-0.88 % small, the
    /// prior's pull towards none, l1 0.009-0.061 mm long, the softest trunk
    /// the worst; l2 exact); a person's limits (no posture) do not
    /// look for it. With one jump of the grasp point (a slip, 4-15 mm) in
    /// the upper-arm phase no trunk is fitted at all: a trunk's yield
    /// explains such a jump too (`MAX_TRUNK_STEP`).
    #[test]
    fn req_est_012_a_yielding_trunk_is_recovered(
        l1 in 0.24f64..0.34, l2 in 0.18f64..0.25, k in 600.0f64..3000.0,
        at in 200usize..800, step in 0.004f64..0.015,
    ) {
        let compliance = -1.0 / k;
        let path = trunk_lift(l1, l2, compliance, None);
        let limits = ValidationLimits::default();
        let e = limb_kernel::estimation::estimate_online(&path, &limits, &PlaneTilt::new()).unwrap();
        let c = e.evidence.trunk_compliance.unwrap();
        prop_assert!((c - compliance).abs() < 0.01 * compliance.abs(), "{c} {compliance}");
        prop_assert!((e.upper_arm_length - l1).abs() < 1e-4, "{} {l1}", e.upper_arm_length);
        prop_assert!((e.forearm_length - l2).abs() < 5e-5, "{} {l2}", e.forearm_length);
        prop_assert!(e.shoulder.distance(Point::new(l1 + l2, 0.0)) < 1e-4, "{:?}", e.shoulder);
        prop_assert!(validate(&e, path[0].pose.point(), &limits).is_ok(), "{:?}", e.evidence);
        let person = ValidationLimits { shoulder_rhythm: [0.0, 0.0], ..ValidationLimits::person() };
        let e = limb_kernel::estimation::estimate_online(&path, &person, &PlaneTilt::new()).unwrap();
        prop_assert_eq!(e.evidence.trunk_compliance, Some(0.0));
        let slipped = trunk_lift(l1, l2, compliance, Some((at, step)));
        let e = limb_kernel::estimation::estimate_online(&slipped, &limits, &PlaneTilt::new()).unwrap();
        prop_assert_eq!(e.evidence.trunk_compliance, Some(0.0));
    }
}

/// A noise-free lift (as [`trunk_lift`]'s, a fixed shoulder) whose grasp
/// slides `shift` [m] along the forearm at sample `at`: from then on the
/// arm is the shared truth's arm after a slip, l2 + shift with its
/// shoulder moved by `shift` along x (its resting grasp S's origin).
fn slipped_lift(l1: f64, l2: f64, shift: f64, at: usize) -> Vec<PathSample> {
    use limb_kernel::arm::{ArmGeometry, JointAngles};
    let (rest, forearm, upper_arm) = (50usize, 1000usize, 1000usize);
    let before = ArmGeometry::new(l1, l2, Point::new(l1 + l2, 0.0)).unwrap();
    let after = ArmGeometry::new(l1, l2 + shift, Point::new(l1 + l2 + shift, 0.0)).unwrap();
    (0..rest + forearm + upper_arm)
        .map(|i| {
            let forearm_part = (i.saturating_sub(rest).min(forearm)) as f64 / forearm as f64;
            let u = (i.saturating_sub(rest + forearm)) as f64 / upper_arm as f64;
            let q = JointAngles {
                shoulder_elevation: 0.9 * u,
                elbow_flexion: 1.2 * forearm_part,
            };
            let arm = if i < at { before } else { after };
            PathSample {
                time: i as f64 * 0.01,
                pose: arm.forward(q),
                wrench: Wrench::ZERO,
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// REQ-EST-013: a grasp that slides 5-15 mm either way along the
    /// forearm once, late in the forearm's turn or during the upper arm's
    /// (samples 700-1 900 of 2 050), is read out: the online estimate of
    /// plant.md's posture is the arm held after the slip (l1, l2 + shift,
    /// its shoulder), validated, the slide measured, all to 1 µm; a slip
    /// within 0.5 s of the split may be refused (measured: a 14 mm slip
    /// there read 8-10 mm wrong, a 5 mm one 0.8 mm: refused) or validated
    /// within 3 mm (measured up to 0.36 mm), never accepted further off;
    /// without the slip the same lift reports none.
    #[test]
    fn req_est_013_a_grasp_slip_is_read_out(
        l1 in 0.24f64..0.34, l2 in 0.18f64..0.25,
        shift in prop_oneof![-0.015f64..-0.005, 0.005f64..0.015], at in 700usize..1900,
    ) {
        let limits = ValidationLimits::default();
        let path = slipped_lift(l1, l2, shift, at);
        let e = limb_kernel::estimation::estimate_online(&path, &limits, &PlaneTilt::new()).unwrap();
        let slide = e.evidence.grasp_slip.unwrap();
        let off = [
            (slide - shift).abs(),
            (e.upper_arm_length - l1).abs(),
            (e.forearm_length - (l2 + shift)).abs(),
            e.shoulder.distance(Point::new(l1 + l2 + shift, 0.0)),
        ];
        // A slip within 0.5 s of the split (the forearm phase's end,
        // sample 1 050) ends the online forearm phase at the jump or lands
        // in its range: refused, or validated within the withheld bar's
        // 3 mm (measured in the cases found: up to 0.36 mm, the shoulder
        // of a slip at sample 1 055). Elsewhere: read out exactly.
        let near_split = (1000..1100).contains(&at);
        let verdict = validate(&e, path[0].pose.point(), &limits);
        prop_assert!(verdict.is_ok() || near_split, "{verdict:?}: {:?}", e.evidence);
        if verdict.is_ok() {
            let bound = if near_split { 3e-3 } else { 1e-6 };
            prop_assert!(off.iter().all(|&o| o < bound), "{off:?}: {:?}", e.evidence);
        }
        let clean = slipped_lift(l1, l2, 0.0, at);
        let e = limb_kernel::estimation::estimate_online(&clean, &limits, &PlaneTilt::new()).unwrap();
        prop_assert_eq!(e.evidence.grasp_slip, Some(0.0));
    }
}
