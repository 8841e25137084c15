//! The validator: the only way to obtain a [`ValidatedArm`].
//!
//! # Theory of operation
//! An [`ArmEstimate`] is accepted only when every check below passes; the
//! first failing check is returned as a [`Rejection`] naming it and the
//! offending value. The checks, in order:
//!
//! 1. everything finite;
//! 2. l1 and l2 within anthropometric ranges;
//! 3. enough arc swept in each phase;
//! 4. fit residuals below a bound;
//! 5. independent methods agree (when required);
//! 6. the geometry is consistent with the start pose: the elbow at t = 0 lies
//!    on the table, at distance l2 from the grasp point, and at distance l1
//!    from the shoulder.
//!
//! # Invariants
//! A `ValidatedArm` has private fields and no public constructor: holding one
//! proves [`validate`] accepted it under the limits it carries.

use crate::arm::ArmGeometry;
use crate::estimation::ArmEstimate;
use crate::geometry::Point;

/// Acceptance limits of the validator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ValidationLimits {
    /// Shortest plausible upper arm [m].
    pub min_upper_arm_length: f64,
    /// Longest plausible upper arm [m].
    pub max_upper_arm_length: f64,
    /// Shortest plausible forearm (elbow to grasp point) [m].
    pub min_forearm_length: f64,
    /// Longest plausible forearm (elbow to grasp point) [m].
    pub max_forearm_length: f64,
    /// Smallest arc each phase must sweep [rad].
    pub min_arc: f64,
    /// Largest RMS fit residual [m].
    pub max_residual: f64,
    /// Largest disagreement between independent methods [m].
    pub max_method_disagreement: f64,
    /// Whether an estimate without a second method is rejected.
    pub require_method_agreement: bool,
    /// Tolerance of the start-pose consistency checks [m].
    pub max_geometry_mismatch: f64,
}

impl Default for ValidationLimits {
    /// Ranges cover adult upper arms and forearms with margin (5th-95th
    /// percentile humerus ≈ 0.27-0.37 m, forearm to wrist ≈ 0.23-0.29 m;
    /// the grasp may sit proximal to the wrist), and the paper's dummy
    /// (l1 0.27-0.33 m, l2 0.18-0.20 m).
    fn default() -> Self {
        Self {
            min_upper_arm_length: 0.20,
            max_upper_arm_length: 0.45,
            min_forearm_length: 0.12,
            max_forearm_length: 0.35,
            min_arc: 0.35,
            max_residual: 0.005,
            max_method_disagreement: 0.005,
            require_method_agreement: false,
            max_geometry_mismatch: 0.02,
        }
    }
}

/// Which validation check failed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Rejection {
    /// A value of the estimate or of the limits is NaN or infinite.
    NonFinite,
    /// l1 [m] outside the configured range.
    UpperArmLengthOutOfRange(f64),
    /// l2 [m] outside the configured range.
    ForearmLengthOutOfRange(f64),
    /// Phase-1 arc [rad] below the minimum.
    ForearmArcTooShort(f64),
    /// Phase-2 arc [rad] below the minimum.
    UpperArmArcTooShort(f64),
    /// Phase-1 RMS residual [m] above the maximum.
    ForearmResidualTooLarge(f64),
    /// Phase-2 RMS residual [m] above the maximum.
    UpperArmResidualTooLarge(f64),
    /// Methods disagree by this much [m].
    MethodsDisagree(f64),
    /// Agreement is required but only one method ran.
    NoIndependentMethod,
    /// Start-pose geometry inconsistent by this much [m].
    GeometryInconsistent(f64),
}

/// An arm model that passed validation. Only [`validate`] makes one.
///
/// REQ-VAL-002: it cannot be built any other way; this does not compile:
///
/// ```compile_fail
/// use limb_kernel::validate::ValidatedArm;
/// let forged = ValidatedArm { geometry: todo!(), estimate: todo!() };
/// ```
///
/// and neither can a manipulating state be made without one:
///
/// ```compile_fail
/// use limb_kernel::state::Manipulate;
/// let forged = Manipulate { arm: todo!(), motion: todo!(), started_at: 0.0 };
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ValidatedArm {
    geometry: ArmGeometry,
    estimate: ArmEstimate,
}

impl ValidatedArm {
    /// The validated geometry.
    pub fn geometry(&self) -> &ArmGeometry {
        &self.geometry
    }

    /// The estimate it came from, with its evidence.
    pub fn estimate(&self) -> &ArmEstimate {
        &self.estimate
    }
}

fn outside(value: f64, low: f64, high: f64) -> bool {
    !(low..=high).contains(&value)
}

/// Validates `estimate` recorded from grasp point `grasp_start` (the path's
/// first sample, frame S) against `limits`.
///
/// # Errors
/// The first failing check, with the offending value.
pub fn validate(
    estimate: &ArmEstimate,
    grasp_start: Point,
    limits: &ValidationLimits,
) -> Result<ValidatedArm, Rejection> {
    let e = estimate;
    let v = &e.evidence;
    let finite = [
        e.upper_arm_length,
        e.forearm_length,
        v.forearm_arc,
        v.upper_arm_arc,
        v.forearm_residual,
        v.upper_arm_residual,
        v.method_disagreement.unwrap_or(0.0),
        limits.min_upper_arm_length,
        limits.max_upper_arm_length,
        limits.min_forearm_length,
        limits.max_forearm_length,
        limits.min_arc,
        limits.max_residual,
        limits.max_method_disagreement,
        limits.max_geometry_mismatch,
    ]
    .iter()
    .all(|x| x.is_finite());
    if !(finite && e.elbow.is_finite() && e.shoulder.is_finite() && grasp_start.is_finite()) {
        return Err(Rejection::NonFinite);
    }
    if outside(
        e.upper_arm_length,
        limits.min_upper_arm_length,
        limits.max_upper_arm_length,
    ) {
        return Err(Rejection::UpperArmLengthOutOfRange(e.upper_arm_length));
    }
    if outside(
        e.forearm_length,
        limits.min_forearm_length,
        limits.max_forearm_length,
    ) {
        return Err(Rejection::ForearmLengthOutOfRange(e.forearm_length));
    }
    if v.forearm_arc < limits.min_arc {
        return Err(Rejection::ForearmArcTooShort(v.forearm_arc));
    }
    if v.upper_arm_arc < limits.min_arc {
        return Err(Rejection::UpperArmArcTooShort(v.upper_arm_arc));
    }
    if v.forearm_residual > limits.max_residual {
        return Err(Rejection::ForearmResidualTooLarge(v.forearm_residual));
    }
    if v.upper_arm_residual > limits.max_residual {
        return Err(Rejection::UpperArmResidualTooLarge(v.upper_arm_residual));
    }
    match v.method_disagreement {
        Some(d) if d > limits.max_method_disagreement => return Err(Rejection::MethodsDisagree(d)),
        None if limits.require_method_agreement => return Err(Rejection::NoIndependentMethod),
        _ => {}
    }
    let mismatch = libm::fabs(e.elbow.z)
        .max(libm::fabs(e.elbow.distance(grasp_start) - e.forearm_length))
        .max(libm::fabs(
            e.elbow.distance(e.shoulder) - e.upper_arm_length,
        ));
    if mismatch > limits.max_geometry_mismatch {
        return Err(Rejection::GeometryInconsistent(mismatch));
    }
    let geometry = ArmGeometry::new(e.upper_arm_length, e.forearm_length, e.shoulder)
        .map_err(|_| Rejection::NonFinite)?;
    Ok(ValidatedArm {
        geometry,
        estimate: *e,
    })
}
