//! REQ-VAL-001: the validator never accepts a model outside its ranges.

use limb_kernel::config::ValidationLimits;
use limb_kernel::estimation::{ArmEstimate, FitEvidence, Method};
use limb_kernel::geometry::Point;
use limb_kernel::validate::{resolution_tolerance, validate, Rejection};
use proptest::prelude::*;

fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -0.1..0.6f64,
        1 => any::<f64>(),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
    ]
}

prop_compose! {
    /// Arbitrary fields (NaN and infinities included): mostly rejected.
    fn arbitrary_estimate()(l1 in number(), l2 in number(), ex in number(), ez in number(),
                            sx in number(), sz in number(), arcs in (number(), number()),
                            residuals in (0.0..0.01f64, 0.0..0.01f64, 0.0..0.003f64, -0.01..0.01f64),
                            disagreement in prop::option::of(0.0..0.01f64),
                            resolution in resolution()) -> ArmEstimate {
        estimate(l1, l2, Point::new(ex, ez), Point::new(sx, sz), arcs, residuals, disagreement, resolution)
    }
}

prop_compose! {
    /// A geometrically consistent arm whose lengths, arcs, residuals and
    /// agreement straddle the validator's limits, so each check decides.
    fn straddling_estimate()(l1 in 0.15..0.50f64, l2 in 0.08..0.40f64,
                             lift in -0.03..0.03f64, angle in -0.1..0.1f64,
                             arcs in (0.2..0.6f64, 0.2..0.6f64),
                             residuals in (0.0..0.008f64, 0.0..0.008f64, 0.0..0.002f64, -0.012..0.012f64),
                             disagreement in prop::option::of(0.0..0.008f64),
                             resolution in resolution()) -> ArmEstimate {
        let elbow = Point::new(l2, lift);
        let shoulder = Point::new(elbow.x + l1 * angle.cos(), elbow.z + l1 * angle.sin());
        estimate(l1, l2, elbow, shoulder, arcs, residuals, disagreement, resolution)
    }
}

/// An unquantized sensor's 0, or a quantizer's step up to 8 mm (beyond
/// the RMS residual's bound, where the tolerance stops growing).
fn resolution() -> impl Strategy<Value = f64> {
    prop_oneof![2 => Just(0.0), 1 => 0.0..0.008f64]
}

#[allow(clippy::too_many_arguments)]
fn estimate(
    l1: f64,
    l2: f64,
    elbow: Point,
    shoulder: Point,
    arcs: (f64, f64),
    residuals: (f64, f64, f64, f64),
    disagreement: Option<f64>,
    resolution: f64,
) -> ArmEstimate {
    // The elbow path's circle through the resting elbow, its radius l1
    // minus the rhythm's correction (`residuals.3`).
    let path_l1 = l1 - residuals.3;
    let scale = path_l1 / l1;
    let path_shoulder = Point::new(
        elbow.x + (shoulder.x - elbow.x) * scale,
        elbow.z + (shoulder.z - elbow.z) * scale,
    );
    ArmEstimate {
        upper_arm_length: l1,
        forearm_length: l2,
        elbow,
        shoulder,
        path_shoulder,
        path_upper_arm_length: path_l1,
        grasp_pitch_offset: 0.0,
        method: Method::Auto,
        evidence: FitEvidence {
            forearm_arc: arcs.0,
            upper_arm_arc: arcs.1,
            forearm_residual: residuals.0,
            upper_arm_residual: residuals.1,
            residual_bias: residuals.2,
            method_disagreement: disagreement,
            forearm_samples: 100,
            upper_arm_samples: 100,
            outliers: 0,
            resolution,
            uncertainty: None,
            play: None,
            compliance: None,
            trunk_compliance: None,
            grasp_slip: None,
            plane_tilt: None,
        },
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]
    /// REQ-VAL-001: whatever the estimate, an accepted model has finite
    /// lengths inside the anthropometric ranges, enough arc, small residuals
    /// and residual bias, methods that agree (the bias and the agreement
    /// within half the sensor's resolution where that is more than their
    /// limits, never beyond the RMS residual's bound), a start pose consistent with
    /// the lengths, a shoulder within the profile's resting height and a
    /// rhythm correction within its bound, under either profile (`rod`,
    /// `person`).
    #[test]
    fn req_val_001_validator_never_accepts_outside_ranges(
        e in prop_oneof![arbitrary_estimate(), straddling_estimate()],
        grasp in prop_oneof![Just(Point::new(0.0, 0.0)), (number(), number()).prop_map(|(x, z)| Point::new(x, z))],
        limits in prop_oneof![Just(ValidationLimits::default()), Just(ValidationLimits::person())],
    ) {
        if let Ok(arm) = validate(&e, grasp, &limits) {
            let g = arm.geometry();
            prop_assert!(g.upper_arm_length().is_finite() && g.forearm_length().is_finite());
            prop_assert!((limits.min_upper_arm_length..=limits.max_upper_arm_length).contains(&g.upper_arm_length()));
            prop_assert!((limits.min_forearm_length..=limits.max_forearm_length).contains(&g.forearm_length()));
            prop_assert!(e.evidence.forearm_arc >= limits.min_arc && e.evidence.upper_arm_arc >= limits.min_arc);
            prop_assert!(e.evidence.forearm_residual <= limits.max_residual);
            prop_assert!(e.evidence.upper_arm_residual <= limits.max_residual);
            let tolerance = |limit| resolution_tolerance(limit, e.evidence.resolution, limits.max_residual);
            prop_assert!(e.evidence.residual_bias <= tolerance(limits.max_residual_bias));
            prop_assert!(e.evidence.residual_bias <= limits.max_residual_bias.max(limits.max_residual));
            prop_assert!((e.upper_arm_length - e.path_upper_arm_length).abs() <= limits.max_rhythm_correction);
            prop_assert!((g.upper_arm_length() - e.path_upper_arm_length).abs() == 0.0);
            prop_assert!((e.elbow.distance(grasp) - g.forearm_length()).abs() <= limits.max_geometry_mismatch);
            prop_assert!(e.evidence.method_disagreement.is_none_or(|d| d <= tolerance(limits.max_method_disagreement)));
            prop_assert!(e.evidence.method_disagreement.is_none_or(|d| d <= limits.max_method_disagreement.max(limits.max_residual)));
            prop_assert!((e.elbow.distance(e.shoulder) - g.upper_arm_length()).abs() <= limits.max_geometry_mismatch);
            prop_assert!((e.shoulder.z - e.elbow.z).abs() <= limits.max_shoulder_height);
        }
    }
}

/// REQ-VAL-001: a consistent estimate is accepted, so the property above
/// is not vacuous.
#[test]
fn req_val_001_a_consistent_estimate_is_accepted() {
    let e = ArmEstimate {
        upper_arm_length: 0.30,
        forearm_length: 0.20,
        elbow: Point::new(0.20, 0.0),
        shoulder: Point::new(0.50, 0.0),
        path_shoulder: Point::new(0.50, 0.0),
        path_upper_arm_length: 0.30,
        grasp_pitch_offset: 0.0,
        method: Method::Auto,
        evidence: FitEvidence {
            forearm_arc: 1.2,
            upper_arm_arc: 1.2,
            forearm_residual: 0.001,
            upper_arm_residual: 0.001,
            residual_bias: 0.0,
            method_disagreement: Some(0.001),
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
    assert!(validate(&e, Point::new(0.0, 0.0), &ValidationLimits::default()).is_ok());
}

/// REQ-EST-007, REQ-VAL-001: on a path read by a quantizer of step q the
/// residual bias and the methods' disagreement may exceed their configured
/// limits (1 mm each) up to q / 2, never beyond the RMS residual's 2 mm
/// bound; on an unquantized path (q = 0) the limits hold as configured;
/// the shoulder's height (1 mm for plant.md's rod) is never widened.
#[test]
fn req_est_007_a_quantized_path_is_judged_against_half_its_step() {
    let limits = ValidationLimits::default();
    let judged = |bias: f64, disagreement: f64, height: f64, resolution: f64| {
        let (l1, l2) = (0.30, 0.20);
        let angle = (height / l1).asin();
        let e = estimate(
            l1,
            l2,
            Point::new(l2, 0.0),
            Point::new(l2 + l1 * angle.cos(), height),
            (1.2, 1.2),
            (0.001, 0.001, bias, 0.0),
            Some(disagreement),
            resolution,
        );
        validate(&e, Point::new(0.0, 0.0), &limits).map(|_| ())
    };
    let q = 0.0043;
    assert_eq!(judged(0.0011, 0.0005, 0.0, q), Ok(()));
    assert_eq!(judged(0.0005, 0.0018, 0.0, q), Ok(()));
    assert!(matches!(
        judged(0.0005, 0.0005, -0.0018, q),
        Err(Rejection::ShoulderOffTable(_))
    ));
    assert_eq!(
        judged(0.0011, 0.0005, 0.0, 0.0),
        Err(Rejection::ResidualBias(0.0011))
    );
    assert_eq!(
        judged(0.0005, 0.0018, 0.0, 0.0),
        Err(Rejection::MethodsDisagree(0.0018))
    );
    assert!(matches!(
        judged(0.0005, 0.0005, -0.0018, 0.0),
        Err(Rejection::ShoulderOffTable(_))
    ));
    // Half of a 2 mm step is the configured 1 mm: no wider.
    assert_eq!(
        judged(0.0011, 0.0005, 0.0, 0.002),
        Err(Rejection::ResidualBias(0.0011))
    );
    // A 10 mm step widens to the RMS bound's 2 mm, not to 5 mm.
    assert_eq!(judged(0.0019, 0.0019, 0.0, 0.010), Ok(()));
    assert_eq!(
        judged(0.0021, 0.0005, 0.0, 0.010),
        Err(Rejection::ResidualBias(0.0021))
    );
}
