//! The concluding refinement of the online estimate, in bounded slices:
//! run while the arm is held still, at most [`SAMPLES_PER_STEP`] path
//! samples per kernel step.
//!
//! # Theory of operation
//! Starting from the online Kåsa circles ([`super::online`]), the
//! refinement makes fixed passes over the recorded phases:
//! 1. [`ITERATIONS`] Gauss-Newton passes of the geometric circle fit
//!    (minimising Σ wᵢ (|pᵢ − c| − r)², Cauchy weights wᵢ with a scale of
//!    [`SCALE_MULTIPLE`] × the previous pass's RMS residual, at least
//!    [`MIN_SCALE`]) on the forearm phase's grasp points: l2, resting elbow;
//! 2. one evidence pass of the forearm phase: RMS geometric residual, the
//!    arc between its first and last point, and the grasp pitch offset δ
//!    (`crate::arm`), the mean over its samples of the pitch minus the
//!    forearm's elevation from the refined resting elbow;
//! 3. one pass of Kåsa moments of the upper-arm phase's elbow points under
//!    the refined l2 and δ (the algebraic answer, and the start of step 4);
//! 4. [`ITERATIONS`] Gauss-Newton passes on those elbow points: the
//!    elbow path's circle (the effective fixed shoulder the monitors use);
//! 5. with a shoulder-rhythm prior ρ (`ValidationLimits::shoulder_rhythm`),
//!    [`ITERATIONS`] Gauss-Newton passes on the elbow points with the
//!    shoulder's own motion taken out, Eᵢ − φᵢ ρ (φᵢ the elbow's angle
//!    since rest about the current estimate, ρ in the arm's rest frame):
//!    l1 and the glenohumeral centre at rest. Without a prior (a fixed
//!    shoulder) they are the elbow path's circle and these passes are
//!    skipped;
//! 6. the upper-arm phase's evidence pass (RMS residual, arc) about the
//!    elbow path's circle.
//!
//! Every pass leaves out the samples that are isolated outliers
//! ([`super::outlier`]); the evidence counts them.
//!
//! `method_disagreement` is the largest difference in l1 or l2 between the
//! algebraic (Kåsa) and the geometric answer: on a circle both agree to
//! noise, on a path that is no circle (a slip, a moving shoulder) they part.
//!
//! # Bounds
//! A pass costs about 60 flops, one square root and (elbow points) one
//! sine and cosine per sample, the forearm's evidence and a rhythm pass
//! one atan2 more; a call does at most `budget` samples (half
//! of it in a rhythm pass) and at most one 3 × 3 solve. A whole refinement
//! is 2 · [`ITERATIONS`] + 3 passes, 3 · [`ITERATIONS`] + 3 with a
//! shoulder-rhythm prior.

use super::circle::{Circle, CircleFitError, ResidualBias};
use super::moments::CircleMoments;
use super::online::{OnlineEstimator, OnlinePhase};
use super::outlier::is_isolated_outlier;
use super::{ArmEstimate, EstimateError, FitEvidence, Method};
use crate::arm::{elbow_from_grasp, pitch_offset_at};
use crate::geometry::{angle_between, Point};
use crate::path::PathSample;
use core::ops::Range;
use nalgebra::{Matrix3, Vector3};

/// Gauss-Newton passes per circle.
pub const ITERATIONS: usize = 5;
/// Path samples a kernel step may process. An elbow point costs a sine, a
/// cosine and a square root: ≈ 12 500 instructions in soft-float `f64` on a
/// Cortex-M7 (64 samples were 817 560 instructions, 1.36 ms at 600 MHz, in
/// `firmware/session.sh`); 16 keep a slice near 0.2 million (≈ 0.35 ms).
/// On the host a slice is ≈ 1 µs (`cargo bench -p limb-verification
/// --bench step`); a refinement is ≈ 700 slices (0.7 s at 1 kHz).
pub const SAMPLES_PER_STEP: usize = 16;
/// Cauchy scale as a multiple of the previous pass's RMS residual.
pub const SCALE_MULTIPLE: f64 = 3.0;
/// Smallest Cauchy scale [m]: 3 × the position noise of `plant.md`.
pub const MIN_SCALE: f64 = 0.3e-3;

/// Which pass is running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Pass {
    /// Geometric fit of the forearm phase, iteration `0..ITERATIONS`.
    Forearm(usize),
    /// Residual, arc and grasp pitch offset of the forearm phase.
    ForearmEvidence,
    /// Kåsa moments of the upper-arm phase's elbow points.
    UpperArmMoments,
    /// Geometric fit of the upper-arm phase, iteration `0..ITERATIONS`.
    UpperArm(usize),
    /// Geometric fit of the upper-arm phase with the shoulder's rhythm
    /// taken out, iteration `0..ITERATIONS`.
    Rhythm(usize),
    /// Residual and arc of the upper-arm phase.
    UpperArmEvidence,
    /// Finished (or failed).
    Done,
}

/// Weighted Gauss-Newton sums of one pass, with the evidence of the phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct PassSums {
    normal: [f64; 6],
    gradient: [f64; 3],
    weighted_squares: f64,
    weights: f64,
    squares: f64,
    count: usize,
    first: Option<Point>,
    last: Point,
    pitch_offsets: f64,
    bias: ResidualBias,
}

impl PassSums {
    fn add(&mut self, circle: &Circle, scale: f64, point: Point) {
        let dx = point.x - circle.centre.x;
        let dz = point.z - circle.centre.z;
        let distance = libm::hypot(dx, dz);
        if !(distance.is_finite() && distance > 0.0) {
            return;
        }
        let residual = distance - circle.radius;
        let weight = 1.0 / (1.0 + (residual / scale) * (residual / scale));
        let j = [-dx / distance, -dz / distance, -1.0];
        let n = &mut self.normal;
        n[0] += weight * j[0] * j[0];
        n[1] += weight * j[0] * j[1];
        n[2] += weight * j[0] * j[2];
        n[3] += weight * j[1] * j[1];
        n[4] += weight * j[1] * j[2];
        n[5] += weight * j[2] * j[2];
        for (g, jk) in self.gradient.iter_mut().zip(j) {
            *g += weight * jk * residual;
        }
        self.weighted_squares += weight * residual * residual;
        self.weights += weight;
        self.squares += residual * residual;
        self.bias.add(residual);
        self.count += 1;
        self.first.get_or_insert(point);
        self.last = point;
    }

    /// The circle after one Gauss-Newton step from `circle`.
    fn step(&self, circle: &Circle) -> Result<Circle, CircleFitError> {
        let n = &self.normal;
        let normal = Matrix3::new(n[0], n[1], n[2], n[1], n[3], n[4], n[2], n[4], n[5]);
        let delta = normal.try_inverse().ok_or(CircleFitError::Degenerate)?
            * -Vector3::new(self.gradient[0], self.gradient[1], self.gradient[2]);
        let next = Circle {
            centre: Point::new(circle.centre.x + delta[0], circle.centre.z + delta[1]),
            radius: circle.radius + delta[2],
        };
        if next.is_valid() {
            Ok(next)
        } else {
            Err(CircleFitError::NonFinite)
        }
    }

    fn rms(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            libm::sqrt(self.squares / self.count as f64)
        }
    }

    fn weighted_rms(&self) -> f64 {
        if self.weights > 0.0 {
            libm::sqrt(self.weighted_squares / self.weights)
        } else {
            f64::INFINITY
        }
    }
}

/// Outcome of one slice of work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// More passes to run.
    Running(Pass),
    /// The refined, unvalidated estimate, or why there is none.
    Done(Result<ArmEstimate, EstimateError>),
}

/// A refinement in progress.
///
/// # Invariants
/// `cursor` lies in the range of the running pass; the circles are valid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refinement {
    forearm_range: (usize, usize),
    upper_arm_range: (usize, usize),
    pass: Pass,
    cursor: usize,
    sums: PassSums,
    scale: f64,
    moments: CircleMoments,
    forearm_kasa: Circle,
    forearm: Circle,
    upper_arm_kasa: Circle,
    upper_arm: Circle,
    rhythm: [f64; 2],
    rest: Circle,
    forearm_evidence: (f64, f64),
    forearm_bias: f64,
    pitch_offset: f64,
    /// Isolated outliers left out of (the forearm, the upper-arm) phase.
    outliers: (usize, usize),
    outcome: Option<Result<ArmEstimate, EstimateError>>,
}

impl Refinement {
    /// Starts from the online forearm circle over `forearm` and the phase
    /// split; the upper-arm phase runs from `forearm.end` to `path_len`;
    /// `rhythm` is the shoulder-rhythm prior [m/rad]
    /// (`ValidationLimits::shoulder_rhythm`; non-finite components count
    /// as 0).
    pub fn new(
        forearm_circle: Circle,
        forearm: Range<usize>,
        path_len: usize,
        rhythm: [f64; 2],
    ) -> Self {
        Self {
            forearm_range: (forearm.start, forearm.end),
            upper_arm_range: (forearm.end, path_len.max(forearm.end)),
            pass: Pass::Forearm(0),
            cursor: 0,
            sums: PassSums::default(),
            scale: f64::INFINITY,
            moments: CircleMoments::new(),
            forearm_kasa: forearm_circle,
            forearm: forearm_circle,
            upper_arm_kasa: forearm_circle,
            upper_arm: forearm_circle,
            rhythm: rhythm.map(|r| if r.is_finite() { r } else { 0.0 }),
            rest: forearm_circle,
            forearm_evidence: (0.0, 0.0),
            forearm_bias: 0.0,
            pitch_offset: 0.0,
            outliers: (0, 0),
            outcome: None,
        }
    }

    /// The refinement of `online`'s estimate over a path of `path_len`
    /// samples, once its upper-arm phase has begun, under shoulder-rhythm
    /// prior `rhythm` [m/rad] ([`Refinement::new`]); `None` before.
    pub fn after(online: &OnlineEstimator, path_len: usize, rhythm: [f64; 2]) -> Option<Self> {
        let forearm = online.forearm()?;
        let (lift, forearm_end) = online.split();
        (online.phase() == OnlinePhase::UpperArm)
            .then(|| Self::new(forearm.circle, lift..forearm_end, path_len, rhythm))
    }

    /// The pass running now.
    pub fn pass(&self) -> Pass {
        self.pass
    }

    /// Processes at most `budget` samples of `path` (the recorded path the
    /// online estimate was made from) and at most one pass end.
    pub fn advance(&mut self, path: &[PathSample], budget: usize) -> Progress {
        if let Some(outcome) = self.outcome {
            return Progress::Done(outcome);
        }
        let range = match self.pass {
            Pass::Forearm(_) | Pass::ForearmEvidence => span(self.forearm_range),
            Pass::UpperArmMoments
            | Pass::UpperArm(_)
            | Pass::Rhythm(_)
            | Pass::UpperArmEvidence => span(self.upper_arm_range),
            Pass::Done => return self.finish(Err(EstimateError::UpperArmPhaseTooShort)),
        };
        // A rhythm sample costs an elbow point and an atan2 more: half the
        // budget keeps the step's cost below the elbow passes'.
        let budget = match self.pass {
            Pass::Rhythm(_) => budget.div_ceil(2),
            _ => budget,
        };
        let start = range.start.saturating_add(self.cursor);
        let end = start.saturating_add(budget).min(range.end);
        for index in start..end {
            let Some(sample) = path.get(index) else {
                return self.finish(Err(EstimateError::PathTooLong));
            };
            if is_isolated_outlier(path, index) {
                // Counted once per phase, in its evidence pass.
                match self.pass {
                    Pass::ForearmEvidence => self.outliers.0 += 1,
                    Pass::UpperArmEvidence => self.outliers.1 += 1,
                    _ => {}
                }
                continue;
            }
            match self.pass {
                Pass::Forearm(_) => self
                    .sums
                    .add(&self.forearm, self.scale, sample.pose.point()),
                Pass::ForearmEvidence => {
                    self.sums
                        .add(&self.forearm, f64::INFINITY, sample.pose.point());
                    self.sums.pitch_offsets += pitch_offset_at(sample.pose, self.forearm.centre);
                }
                Pass::UpperArmMoments => {
                    self.moments.add(self.elbow(sample));
                }
                Pass::UpperArm(_) => {
                    let elbow = self.elbow(sample);
                    self.sums.add(&self.upper_arm, self.scale, elbow);
                }
                Pass::Rhythm(_) => {
                    let elbow = self.without_rhythm(self.elbow(sample));
                    self.sums.add(&self.rest, self.scale, elbow);
                }
                Pass::UpperArmEvidence => {
                    let elbow = self.elbow(sample);
                    self.sums.add(&self.upper_arm, f64::INFINITY, elbow);
                }
                Pass::Done => {}
            }
        }
        self.cursor = end - range.start;
        if end < range.end {
            return Progress::Running(self.pass);
        }
        match self.end_pass(range.len()) {
            Ok(pass) => {
                self.pass = pass;
                self.cursor = 0;
                self.sums = PassSums::default();
                Progress::Running(pass)
            }
            Err(error) => self.finish(Err(error)),
        }
    }

    /// Concludes the pass that just covered all of its `samples`; returns
    /// the next one (or the estimate).
    fn end_pass(&mut self, samples: usize) -> Result<Pass, EstimateError> {
        let too_short = |pass: Pass| match pass {
            Pass::Forearm(_) | Pass::ForearmEvidence => EstimateError::ForearmPhaseTooShort,
            _ => EstimateError::UpperArmPhaseTooShort,
        };
        if samples < super::MIN_PHASE_SAMPLES {
            return Err(too_short(self.pass));
        }
        Ok(match self.pass {
            Pass::Forearm(iteration) => {
                self.forearm = self
                    .gauss_newton(self.forearm)
                    .map_err(EstimateError::ForearmFit)?;
                if iteration + 1 < ITERATIONS {
                    Pass::Forearm(iteration + 1)
                } else {
                    Pass::ForearmEvidence
                }
            }
            Pass::UpperArmMoments => {
                let fit = self.moments.fit().map_err(EstimateError::UpperArmFit)?;
                self.upper_arm_kasa = fit.circle;
                self.upper_arm = fit.circle;
                self.scale = f64::INFINITY;
                Pass::UpperArm(0)
            }
            Pass::UpperArm(iteration) => {
                self.upper_arm = self
                    .gauss_newton(self.upper_arm)
                    .map_err(EstimateError::UpperArmFit)?;
                if iteration + 1 < ITERATIONS {
                    Pass::UpperArm(iteration + 1)
                } else {
                    self.rest = self.upper_arm;
                    if self.rhythm == [0.0, 0.0] {
                        Pass::UpperArmEvidence
                    } else {
                        // The elbow points move by up to φ ρ from the
                        // path's circle: no Cauchy scale from its fit.
                        self.scale = f64::INFINITY;
                        Pass::Rhythm(0)
                    }
                }
            }
            Pass::Rhythm(iteration) => {
                self.rest = self
                    .gauss_newton(self.rest)
                    .map_err(EstimateError::UpperArmFit)?;
                if iteration + 1 < ITERATIONS {
                    Pass::Rhythm(iteration + 1)
                } else {
                    Pass::UpperArmEvidence
                }
            }
            Pass::ForearmEvidence => {
                self.forearm_evidence = (self.phase_arc(&self.forearm), self.sums.rms());
                self.forearm_bias = self.sums.bias.worst();
                // count ≥ 1: the pass had at least MIN_PHASE_SAMPLES samples
                // and an all-outlier phase leaves the mean at 0.
                self.pitch_offset = self.sums.pitch_offsets / self.sums.count.max(1) as f64;
                if !self.pitch_offset.is_finite() {
                    return Err(EstimateError::ForearmFit(CircleFitError::NonFinite));
                }
                Pass::UpperArmMoments
            }
            Pass::UpperArmEvidence => {
                let estimate = self.estimate(
                    self.phase_arc(&self.upper_arm),
                    self.sums.rms(),
                    self.sums.bias.worst(),
                );
                self.outcome = Some(Ok(estimate));
                Pass::Done
            }
            Pass::Done => Pass::Done,
        })
    }

    /// `circle` after the Gauss-Newton step of the pass just summed; the
    /// next pass's Cauchy scale from its weighted RMS residual.
    fn gauss_newton(&mut self, circle: Circle) -> Result<Circle, CircleFitError> {
        let next = self.sums.step(&circle)?;
        self.scale = (SCALE_MULTIPLE * self.sums.weighted_rms()).max(MIN_SCALE);
        Ok(next)
    }

    fn phase_arc(&self, circle: &Circle) -> f64 {
        self.sums.first.map_or(0.0, |first| {
            angle_between(circle.centre, first, self.sums.last)
        })
    }

    fn estimate(
        &self,
        upper_arm_arc: f64,
        upper_arm_residual: f64,
        upper_arm_bias: f64,
    ) -> ArmEstimate {
        let disagreement = libm::fabs(self.forearm.radius - self.forearm_kasa.radius).max(
            libm::fabs(self.upper_arm.radius - self.upper_arm_kasa.radius),
        );
        ArmEstimate {
            upper_arm_length: self.rest.radius,
            forearm_length: self.forearm.radius,
            elbow: self.forearm.centre,
            shoulder: self.rest.centre,
            path_upper_arm_length: self.upper_arm.radius,
            path_shoulder: self.upper_arm.centre,
            grasp_pitch_offset: self.pitch_offset,
            method: Method::Online,
            evidence: FitEvidence {
                forearm_arc: self.forearm_evidence.0,
                upper_arm_arc,
                forearm_residual: self.forearm_evidence.1,
                upper_arm_residual,
                residual_bias: max_or_nan(self.forearm_bias, upper_arm_bias),
                method_disagreement: Some(disagreement),
                forearm_samples: span(self.forearm_range)
                    .len()
                    .saturating_sub(self.outliers.0),
                upper_arm_samples: span(self.upper_arm_range)
                    .len()
                    .saturating_sub(self.outliers.1),
                outliers: self.outliers.0 + self.outliers.1,
            },
        }
    }

    /// `elbow` with the shoulder's own motion since rest taken out under
    /// the rhythm prior: E − φ ρ, with ρ in the arm's rest frame (unit e₀
    /// from the current glenohumeral estimate S to the resting elbow, and
    /// d = e₀ turned toward the elbow's rise) and φ the elbow's angle since
    /// rest seen from S (the rhythm's parameter, `spec/human-arm-model.md`).
    /// At the fixed point S = S_rest the corrected points lie on the circle
    /// (S_rest, l1) exactly.
    fn without_rhythm(&self, elbow: Point) -> Point {
        let centre = self.rest.centre;
        let rest = self.forearm.centre;
        let (ax, az) = (rest.x - centre.x, rest.z - centre.z);
        let norm = libm::hypot(ax, az);
        if !(norm.is_finite() && norm > 0.0) {
            return elbow;
        }
        let (ex, ez) = (ax / norm, az / norm);
        let (dx, dz) = (ez, -ex);
        let (vx, vz) = (elbow.x - centre.x, elbow.z - centre.z);
        let [along, rise] = self.rhythm;
        let (rx, rz) = (along * ex + rise * dx, along * ez + rise * dz);
        let angle = libm::atan2(vx * dx + vz * dz, vx * ex + vz * ez);
        Point::new(elbow.x - angle * rx, elbow.z - angle * rz)
    }

    /// The elbow of `sample` under the refined forearm and δ.
    fn elbow(&self, sample: &PathSample) -> Point {
        elbow_from_grasp(sample.pose, self.forearm.radius, self.pitch_offset)
    }

    fn finish(&mut self, outcome: Result<ArmEstimate, EstimateError>) -> Progress {
        self.pass = Pass::Done;
        self.outcome = Some(outcome);
        Progress::Done(outcome)
    }
}

/// The larger of `a` and `b`, NaN when either is.
pub(crate) fn max_or_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

fn span((start, end): (usize, usize)) -> Range<usize> {
    start..end.max(start)
}
