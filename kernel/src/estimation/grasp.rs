//! Grasp corrections from the logged wrench and forearm angle (frame S).
//!
//! # Theory of operation
//! While the elbow rests (phase 1) every sample satisfies, with the measured
//! psi and u_i = (cos psi_i, −sin psi_i) (grasp → elbow), the forearm-pose
//! model
//!
//! ```text
//! G_i + compliance · f_i + (l2 + slip_i · slide) u_i − slip_i · offset = E0
//! ```
//!
//! (`G_i` logged grasp point, `f_i` logged f_ext, E0 the resting elbow,
//! slip_i = 1 after the slip, 0 before). It is linear in (E0, l2, compliance,
//! slide, offset), so one pass builds 7 × 7 normal equations; a few
//! reweighted rounds ([`POSE_ROUNDS`], Cauchy weights) make it robust to
//! outliers: O(POSE_ROUNDS · n) work, O(1) memory.
//!
//! * **Compliance** (`grasp_compliance`): the end-effector leads the wrist by
//!   F/k = −f_ext/k, so the wrist is G + f_ext/k. It is kept only when
//!   freeing it cuts the model's RMS residual below [`COMPLIANCE_GAIN`] × the
//!   rigid one: on a rigid grasp the term is barely identifiable and would
//!   trade noise for bias.
//! * **Slip** (`grasp_slip`): after a slip the grasp path jumps to another
//!   circle: radius l2 + slide (the grasp slid along the forearm) about
//!   E0 + offset (the grasp frame moved). The phase split ends at the jump;
//!   [`detect_slip`] accepts it as a slip when the samples after it again
//!   follow the forearm-pose model with a resting elbow, for at least
//!   [`MIN_SLIP_SAMPLES`], and the jump is at least [`MIN_SLIP`].

use super::circle::CircleFitError;
use super::geometric::{NOISE_MULTIPLE, ROBUST_SCALE};
use super::phase::{detect_phases_from, Phases};
use super::{EstimateError, PointModel};
use crate::geometry::Point;
use crate::path::PathSample;
use core::ops::Range;
use nalgebra::{SMatrix, SVector};

/// Reweighting rounds of the forearm-pose fit: one plain least-squares
/// solve, then Cauchy-weighted solves (scale as in [`super::geometric`]).
pub(super) const POSE_ROUNDS: usize = 4;
/// Largest ratio of compliant to rigid RMS residual at which the compliance
/// is kept (dimensionless).
pub(super) const COMPLIANCE_GAIN: f64 = 0.5;
/// Samples a post-jump stretch needs to count as a slip (1 s at 100 Hz).
pub const MIN_SLIP_SAMPLES: usize = 100;
/// Smallest jump that is corrected as a slip [m]: 20 × the position noise.
pub(super) const MIN_SLIP: f64 = 2.0e-3;
/// Largest RMS residual of the forearm-pose model after the jump for it to
/// count as a slip [m]: a lifting elbow leaves the model by centimetres.
pub(super) const SLIP_CONSISTENCY: f64 = 1.0e-3;

/// Grasp corrections shared by all samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct GraspCorrection {
    /// Grasp compliance 1/k [m/N].
    pub compliance: f64,
    /// Slide of the grasp along the forearm, away from the elbow, after the
    /// slip [m].
    pub slide: f64,
    /// Jump of the grasp frame after the slip [m].
    pub offset: Point,
}

/// Which corrections a forearm-pose fit may change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FreeCorrections {
    /// Fit the compliance.
    pub compliance: bool,
    /// Fit the slip (slide and offset).
    pub slip: bool,
}

/// One sample seen by a fit, before the corrections.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FitPoint {
    /// Point without corrections [m].
    pub base: Point,
    /// Logged force f_ext [N].
    pub force: Point,
    /// Unit forearm direction grasp → elbow, (cos psi, −sin psi).
    pub forearm: Point,
    /// Whether the sample is after the slip.
    pub slipped: bool,
}

impl FitPoint {
    /// The point under `correction` [m].
    pub fn at(&self, correction: GraspCorrection) -> Point {
        let (slide, offset) = if self.slipped {
            (correction.slide, correction.offset)
        } else {
            (0.0, Point::default())
        };
        Point::new(
            self.base.x + correction.compliance * self.force.x + slide * self.forearm.x - offset.x,
            self.base.z + correction.compliance * self.force.z + slide * self.forearm.z - offset.z,
        )
    }
}

/// The forearm-pose model fitted over phase 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForearmPose {
    /// Resting elbow E0 [m].
    pub elbow: Point,
    /// Forearm length before any slip [m].
    pub forearm_length: f64,
    /// Fitted corrections.
    pub correction: GraspCorrection,
    /// RMS distance of the corrected elbow points from E0 [m].
    pub rms: f64,
    /// Cauchy scale of the next reweighting round [m].
    pub robust_scale: f64,
}

/// Fits the forearm-pose model to `path[range]`; corrections not in `free`
/// keep their values in `model`.
///
/// # Errors
/// Fewer than three samples, singular equations, non-finite result.
pub fn fit_forearm_pose(
    path: &[PathSample],
    range: Range<usize>,
    model: &PointModel,
    free: FreeCorrections,
) -> Result<ForearmPose, EstimateError> {
    let grasp = model.along_forearm(0.0);
    // Isolated outliers are left out (`outlier.rs`): an unweighted first
    // round and the plain RMS the compliance and slip decisions compare
    // would follow them.
    let indices = super::outlier::kept(path, range);
    let points = indices
        .clone()
        .filter_map(|index| path.get(index).map(|sample| grasp.fit_point(index, sample)));
    if points.clone().take(3).count() < 3 {
        return Err(EstimateError::ForearmPhaseTooShort);
    }
    let mut pose: Option<ForearmPose> = None;
    for _ in 0..POSE_ROUNDS {
        let next = solve_forearm_pose(points.clone(), model.correction, free, pose)?;
        let elbow_path = PointModel {
            correction: next.correction,
            ..grasp.along_forearm(next.forearm_length)
        };
        let elbow_points = indices
            .clone()
            .filter_map(|index| elbow_path.point_at(path, index));
        let rms = rms_distance(elbow_points, next.elbow);
        if !rms.is_finite() {
            return Err(EstimateError::ForearmFit(CircleFitError::NonFinite));
        }
        // The first round is unweighted: its scale comes from the plain RMS.
        let robust_scale = if pose.is_none() {
            ROBUST_SCALE.max(NOISE_MULTIPLE * rms)
        } else {
            next.robust_scale
        };
        pose = Some(ForearmPose {
            rms,
            robust_scale,
            ..next
        });
    }
    pose.ok_or(EstimateError::ForearmPhaseTooShort)
}

/// One weighted least-squares solve of the forearm-pose model; weights are
/// Cauchy on the distance of each corrected elbow point from E0 under
/// `previous` (all 1 without one).
fn solve_forearm_pose<I: Iterator<Item = FitPoint>>(
    points: I,
    fixed_values: GraspCorrection,
    free: FreeCorrections,
    previous: Option<ForearmPose>,
) -> Result<ForearmPose, EstimateError> {
    // θ = (E0x, E0z, l2, compliance, slide, offset x, offset z).
    let mut normal = SMatrix::<f64, 7, 7>::zeros();
    let mut rhs = SVector::<f64, 7>::zeros();
    let (mut weighted_square, mut weight_sum) = (0.0, 0.0);
    for p in points {
        let (weight, distance) = previous.map_or((1.0, 0.0), |pose| {
            let wrist = p.at(pose.correction);
            let elbow = Point::new(
                wrist.x + pose.forearm_length * p.forearm.x,
                wrist.z + pose.forearm_length * p.forearm.z,
            );
            let distance = elbow.distance(pose.elbow);
            let u = distance / pose.robust_scale;
            (1.0 / (1.0 + u * u), distance)
        });
        weighted_square += weight * distance * distance;
        weight_sum += weight;
        let s = if p.slipped { 1.0 } else { 0.0 };
        let x_row = [-1.0, 0.0, p.forearm.x, p.force.x, s * p.forearm.x, -s, 0.0];
        let z_row = [0.0, -1.0, p.forearm.z, p.force.z, s * p.forearm.z, 0.0, -s];
        for (row, offset) in [(x_row, p.base.x), (z_row, p.base.z)] {
            let row = SVector::<f64, 7>::from(row);
            normal += row * row.transpose() * weight;
            rhs -= row * (offset * weight);
        }
    }
    let fixed = [
        (3, free.compliance, fixed_values.compliance),
        (4, free.slip, fixed_values.slide),
        (5, free.slip, fixed_values.offset.x),
        (6, free.slip, fixed_values.offset.z),
    ];
    for (index, is_free, value) in fixed {
        if !is_free {
            rhs -= normal.column(index) * value;
            normal.row_mut(index).fill(0.0);
            normal.column_mut(index).fill(0.0);
            normal[(index, index)] = 1.0;
            rhs[index] = value;
        }
    }
    let theta = crate::linear::solve(normal.transpose().into(), rhs.into())
        .ok_or(EstimateError::ForearmFit(CircleFitError::Degenerate))?;
    if !theta.iter().all(|v| v.is_finite()) {
        return Err(EstimateError::ForearmFit(CircleFitError::NonFinite));
    }
    Ok(ForearmPose {
        elbow: Point::new(theta[0], theta[1]),
        forearm_length: theta[2],
        correction: GraspCorrection {
            compliance: theta[3],
            slide: theta[4],
            offset: Point::new(theta[5], theta[6]),
        },
        rms: 0.0,
        robust_scale: if weight_sum > 0.0 {
            ROBUST_SCALE.max(NOISE_MULTIPLE * libm::sqrt(weighted_square / weight_sum))
        } else {
            ROBUST_SCALE
        },
    })
}

/// RMS distance of `points` from `elbow` [m]; 0 for no points.
fn rms_distance<I: Iterator<Item = Point>>(points: I, elbow: Point) -> f64 {
    let (count, sum) = points.fold((0usize, 0.0), |(count, sum), p| {
        let d = p.distance(elbow);
        (count + 1, sum + d * d)
    });
    if count == 0 {
        0.0
    } else {
        libm::sqrt(sum / count as f64)
    }
}

/// The compliance worth correcting on `path[range]` (phase 1), or 0 m/N.
///
/// # Errors
/// The forearm-pose fit failed.
pub fn detect_compliance(path: &[PathSample], range: Range<usize>) -> Result<f64, EstimateError> {
    let rigid = FreeCorrections::default();
    let rigid = fit_forearm_pose(path, range.clone(), &PointModel::GRASP, rigid)?;
    let free = FreeCorrections {
        compliance: true,
        slip: false,
    };
    let compliant = fit_forearm_pose(path, range, &PointModel::GRASP, free)?;
    Ok(if compliant.rms < COMPLIANCE_GAIN * rigid.rms {
        compliant.correction.compliance
    } else {
        0.0
    })
}

/// Checks whether phase 1 of `phases` ended in a slip rather than in the
/// elbow lifting; if so returns the model with the fitted slip.
///
/// # Errors
/// A forearm-pose fit failed.
pub fn detect_slip(
    path: &[PathSample],
    phases: &Phases,
    model: &PointModel,
) -> Result<Option<PointModel>, EstimateError> {
    let jump = phases.forearm.end;
    let Ok(after) = detect_phases_from(path, model, jump) else {
        return Ok(None);
    };
    if after.forearm.len() < MIN_SLIP_SAMPLES {
        return Ok(None);
    }
    let rigid = FreeCorrections {
        compliance: false,
        slip: false,
    };
    let after_pose = fit_forearm_pose(path, after.forearm.clone(), model, rigid)?;
    if after_pose.rms > SLIP_CONSISTENCY {
        return Ok(None);
    }
    let slipped = PointModel {
        slip_index: jump,
        ..*model
    };
    let free = FreeCorrections {
        compliance: false,
        slip: true,
    };
    let pose = fit_forearm_pose(
        path,
        phases.forearm.start..after.forearm.end,
        &slipped,
        free,
    )?;
    let c = pose.correction;
    let size = libm::fabs(c.slide).max(libm::hypot(c.offset.x, c.offset.z));
    Ok((size >= MIN_SLIP).then_some(PointModel {
        correction: c,
        ..slipped
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Pose, Wrench};
    use crate::path::GraspPath;

    /// Resting elbow E0 and forearm length l2 of the synthetic phase 1 [m].
    const ELBOW: Point = Point::new(0.25, 0.05);
    const FOREARM: f64 = 0.22;

    /// Phase 1 of a lift: ψ from 0 to 0.6 rad over `n` samples at 100 Hz
    /// about [`ELBOW`], the grasp at G = E0 − (l2 + s·slide) u + s·offset
    /// (s = 1 from `slip_at` on), plus `noise(i)` [m].
    fn phase_one(
        n: usize,
        slip_at: usize,
        slip: (f64, Point),
        noise: impl Fn(usize) -> Point,
    ) -> GraspPath {
        (0..n)
            .map(|i| {
                let psi = 0.6 * i as f64 / n as f64;
                let u = Point::new(libm::cos(psi), -libm::sin(psi));
                let (slide, offset) = if i >= slip_at {
                    slip
                } else {
                    (0.0, Point::default())
                };
                let reach = FOREARM + slide;
                let e = noise(i);
                PathSample {
                    time: i as f64 * 0.01,
                    pose: Pose::new(
                        ELBOW.x - reach * u.x + offset.x + e.x,
                        ELBOW.z - reach * u.z + offset.z + e.z,
                        psi,
                    ),
                    wrench: Wrench::ZERO,
                }
            })
            .collect()
    }

    fn quiet(_: usize) -> Point {
        Point::default()
    }

    /// Uniform ±`half_width` [m] per coordinate from a fixed LCG.
    fn uniform(half_width: f64) -> impl Fn(usize) -> Point {
        move |i| {
            let draw = |k: u64| {
                let x = k
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            };
            let k = i as u64 * 2 + 7;
            Point::new(half_width * draw(k), half_width * draw(k * 31 + 1))
        }
    }

    /// Fewer than three samples are too short a phase, by name, not a
    /// singular solve.
    #[test]
    fn two_samples_are_too_short_a_forearm_phase() {
        let path = phase_one(200, usize::MAX, (0.0, Point::default()), quiet);
        let rigid = FreeCorrections::default();
        assert_eq!(
            fit_forearm_pose(&path, 0..2, &PointModel::GRASP, rigid),
            Err(EstimateError::ForearmPhaseTooShort)
        );
        assert!(fit_forearm_pose(&path, 0..3, &PointModel::GRASP, rigid).is_ok());
    }

    /// The Cauchy scale the fit hands on follows the noise it sees: with
    /// ±3 mm of noise it is NOISE_MULTIPLE × the weighted RMS distance,
    /// well above its 1 mm floor (a scale stuck at the floor would weigh
    /// the inliers as outliers).
    #[test]
    fn the_robust_scale_follows_the_noise() {
        let path = phase_one(300, usize::MAX, (0.0, Point::default()), uniform(3e-3));
        let pose = fit_forearm_pose(
            &path,
            0..300,
            &PointModel::GRASP,
            FreeCorrections::default(),
        )
        .unwrap_or_else(|e| panic!("{e:?}"));
        assert!(
            pose.robust_scale > 2.0 * ROBUST_SCALE && pose.robust_scale < 3.0 * pose.rms,
            "{pose:?}"
        );
        assert!(pose.elbow.distance(ELBOW) < 2e-3, "{pose:?}");
    }

    /// A slip (10 mm slide, grasp frame moved by (4, −3) mm) is recovered
    /// exactly from noise-free data, each component with its sign.
    #[test]
    fn a_slip_is_recovered_component_by_component() {
        let (slide, offset) = (0.01, Point::new(0.004, -0.003));
        let path = phase_one(300, 120, (slide, offset), quiet);
        let model = PointModel {
            slip_index: 120,
            ..PointModel::GRASP
        };
        let free = FreeCorrections {
            compliance: false,
            slip: true,
        };
        let pose =
            fit_forearm_pose(&path, 0..300, &model, free).unwrap_or_else(|e| panic!("{e:?}"));
        let c = pose.correction;
        let off = [
            c.slide - slide,
            c.offset.x - offset.x,
            c.offset.z - offset.z,
            pose.forearm_length - FOREARM,
            pose.elbow.distance(ELBOW),
        ];
        assert!(off.iter().all(|e| e.abs() < 1e-9), "{off:?}");
    }
}
