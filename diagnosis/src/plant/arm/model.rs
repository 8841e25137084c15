//! The arm plant of `plant.md` as a diagnosis [`Model`]: the reference
//! plant (`limb-sim`) with every parameter at its default but the arm
//! lengths is the sim; a log in the plant.md format is the real data.
//! The arm lengths are fitted with the effects unless given (see
//! [`super::effects`]).
//!
//! # Alignment
//! The sim is driven by the log's own commanded set-point (`xd, zd,
//! psid`, see [`super::replay`]), so any logged motion can be compared;
//! each log sample is compared with the sim at the integration step
//! nearest its time stamp. Ground-truth columns are never read.
//!
//! # Predictions
//! The nominal sim is run once per arm (noise off; the last few arms are
//! kept), keeping what the robot senses at every 0.5 ms step.
//! Measurement-side effects (`backlash`, `quantization`, `latency`,
//! `grasp_compliance`, `plane_tilt`) are then applied to that record by
//! limb-sim's measurement chain ([`limb_sim::effects::measurement`]) in
//! the plant's own order (compliance and tilt, delay, backlash, rounding),
//! which costs microseconds; dynamics-side effects (`joint_friction`,
//! `mass_mismatch`, `shoulder_drift`, `active_torque`, `grasp_slip`)
//! re-run the plant with the effect. Quantization is predicted as the
//! *expected* rounded reading E[round((v + n) / step) · step] over the
//! measurement noise n, since the real sensor rounds its noisy reading.

use super::effects::{
    arm_candidate, candidates, kernel_estimate, resolution, Start, ARM, HEIGHT_RANGE, HEIGHT_SHARE,
};
use super::replay::Replay;
use crate::model::{grid, Applied, Data, Hints, Model, ModelError, Series, Signal};
use limb_kernel::motion::SetPoint;
use limb_sim::effects::measurement::{self, reading, Reading, MEASUREMENT_SIDE};
use limb_sim::effects::{Effect, Effects, ShoulderHeight};
use limb_sim::log::Record;
use limb_sim::{
    ArmBuild, ArmParameters, Plant, PlantParameters, ANGLE_NOISE, FORCE_NOISE, POSITION_NOISE,
    STEP, TORQUE_NOISE,
};
use std::sync::{Arc, Mutex};
use thiserror::Error;

/// Longest log the model accepts [s]: the motion plus a minute of hold
/// bounds the simulation work.
pub const LONGEST_LOG: f64 = 90.0;

/// Why a log cannot be compared with the sim.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ArmError {
    /// Arm lengths not finite and positive.
    #[error("arm lengths must be finite and positive: {0}")]
    Arm(String),
    /// No samples.
    #[error("the log has no samples")]
    Empty,
    /// The log's first row has no commanded set-point: nothing says where
    /// the robot was sent, so the motion cannot be replayed.
    #[error("no commanded pose at t = {time} s (column {column} missing or empty): the commanded motion cannot be replayed")]
    NoCommand {
        /// The set-point column missing.
        column: &'static str,
        /// Time of the row [s].
        time: f64,
    },
    /// Time stamps outside [0, LONGEST_LOG] or two in one integration step.
    #[error("sample {sample}: time {time} s is outside [0, {LONGEST_LOG}] s or shares a 0.5 ms step with the sample before")]
    Time {
        /// 0-based sample.
        sample: usize,
        /// Its time [s].
        time: f64,
    },
    /// The nominal sim failed.
    #[error("the sim failed: {0}")]
    Sim(String),
}

const ALL_SIGNALS: [Signal; 7] = [
    Signal {
        name: "x",
        unit: "m",
    },
    Signal {
        name: "z",
        unit: "m",
    },
    Signal {
        name: "psi",
        unit: "rad",
    },
    Signal {
        name: "y",
        unit: "m",
    },
    Signal {
        name: "fx",
        unit: "N",
    },
    Signal {
        name: "fz",
        unit: "N",
    },
    Signal {
        name: "ty",
        unit: "N m",
    },
];
const ALL_SCALES: [f64; 7] = [
    POSITION_NOISE,
    POSITION_NOISE,
    ANGLE_NOISE,
    POSITION_NOISE,
    FORCE_NOISE,
    FORCE_NOISE,
    TORQUE_NOISE,
];
/// Column of `y` in [`Reading`] (dropped when the log has no `y`).
const LATERAL: usize = 3;

/// Fitted lengths are snapped to this grid [m] (far below what any log
/// resolves) so the same arm always finds its cached nominal record.
const LENGTH_GRAIN: f64 = 1e-9;
/// Nominal records kept (the arms most recently asked for).
const CACHED_ARMS: usize = 6;
/// The arm the sim is built with: lengths given by the user, or fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lengths {
    /// Held fixed: l1, l2 [m].
    Given(f64, f64),
    /// Fitted with the effects, starting at the kernel's estimate.
    Fitted,
}

/// An arm the sim is built with: l1, l2 and the shoulder's height above
/// the elbow at rest [m] (0 on plant.md's dummy, and wherever the height
/// is not fitted).
type Arm = [f64; ARM_PARAMETERS];
/// Parameters of an [`Arm`]: the most a person's build fits.
const ARM_PARAMETERS: usize = 3;
/// Half the step of each arm parameter's finite difference [m].
const ARM_DIFFERENCES: Arm = [2e-4; ARM_PARAMETERS];

/// Nominal records of the arms asked for most recently, newest last.
type NominalCache = Mutex<Vec<(Arm, Arc<Vec<Reading>>)>>;
/// Exact predictions at the linearisation's reference arm of the effect
/// sets asked for most recently (the polish and the cost of one point
/// predict the same set), newest last.
type PredictionCache = Mutex<Vec<(Vec<Applied>, Arc<Series>)>>;
/// Exact predictions kept.
const CACHED_PREDICTIONS: usize = 8;
/// Index of the shoulder's height in an [`Arm`].
const HEIGHT: usize = 2;

/// The prediction linearised in the arm around a reference arm:
/// P(effects, l) ≈ P(effects, l₀) + J (l − l₀), J the derivative by l1,
/// l2 (and the shoulder's height, when fitted) at l₀ (central
/// differences; forward at the height's lower bound) of the prediction with the effects
/// the reference was solved with (none for the first reference). With
/// the nominal sim's derivative instead, the lengths' Gauss–Newton
/// settles only linearly under an effect that changes how the readings
/// move with the arm: a grasp compliance of 206 N/m turns the
/// force-driven deflection into part of the sensitivity, and the
/// lengths crept 1-3 mm a step, 16 mm short of the arm after the refits
/// (blind seed 161803, log 5).
#[derive(Debug)]
struct Linearisation {
    reference: Arm,
    /// The effects (no base) `jacobian` is the derivative of.
    effects: Vec<Applied>,
    /// The reference was solved with a grasp slip among the effects: it is
    /// the arm before the slip.
    before_slip: bool,
    /// ∂P/∂l1, ∂P/∂l2 (and ∂P/∂height when the height is fitted).
    jacobian: Vec<Series>,
}

/// Least information [1/m², in noise variances] a residual set must hold
/// of an arm parameter for the parameter to be solved: a metre's change
/// that moves the sum of squared scaled residuals by less than one noise
/// variance is no information (the l1 column of a log whose upper arm
/// never left the table is 0, or finite differences' rounding; a length
/// the log does tell has 10⁸ or more).
const LEAST_INFORMATION: f64 = 1.0;

/// The normal equations of a weighted least-squares change of the arm's
/// parameters (l1, l2, and the shoulder's height when it is fitted):
/// terms added one residual at a time, then solved.
#[derive(Debug)]
pub(super) struct LengthSolve {
    dims: usize,
    normal: [[f64; ARM_PARAMETERS]; ARM_PARAMETERS],
    right: Arm,
}

impl LengthSolve {
    /// The equations of `dims` parameters (2 or [`ARM_PARAMETERS`], 3).
    pub(super) fn new(dims: usize) -> Self {
        Self {
            dims: dims.clamp(2, ARM_PARAMETERS),
            normal: [[0.0; ARM_PARAMETERS]; ARM_PARAMETERS],
            right: [0.0; ARM_PARAMETERS],
        }
    }

    /// Adds residual `r` with derivative `j` by the parameters, weight
    /// 1/`sigma`².
    pub(super) fn add(&mut self, j: &[f64], r: f64, sigma: f64) {
        let w = 1.0 / (sigma * sigma);
        let n = self.dims.min(j.len());
        for x in 0..n {
            self.right[x] += w * j[x] * r;
            for y in 0..n {
                self.normal[x][y] += w * j[x] * j[y];
            }
        }
    }

    /// The change of the parameters that fits the residuals best (the
    /// unused ones 0); a parameter the residuals hold no information of
    /// (below [`LEAST_INFORMATION`]) is held (0): its step would be the
    /// noise's. `None` when the informative parameters cannot be told
    /// apart (singular) or the equations are not finite.
    pub(super) fn solve(&self) -> Option<Arm> {
        let informative = self.informative();
        if informative.len() == self.dims {
            return self.solve_for(&self.right);
        }
        let (reduced, right) = self.reduced(&informative, &self.right);
        let x = eliminate(&reduced, &right, informative.len())?;
        let mut out = [0.0; ARM_PARAMETERS];
        for (position, k) in informative.iter().enumerate() {
            out[*k] = x[position];
        }
        Some(out)
    }

    /// The diagonal of the inverse of the normal equations over the
    /// informative parameters: with residuals of unit weight, each one's
    /// variance when the others are solved with it. `None` for a
    /// parameter with no information, and for all when the informative
    /// ones cannot be told apart (singular).
    pub(super) fn inverse_diagonal(&self) -> [Option<f64>; ARM_PARAMETERS] {
        let mut out = [None; ARM_PARAMETERS];
        let informative = self.informative();
        let (reduced, _) = self.reduced(&informative, &self.right);
        for (position, k) in informative.iter().enumerate() {
            let mut unit = [0.0; ARM_PARAMETERS];
            unit[position] = 1.0;
            let Some(x) = eliminate(&reduced, &unit, informative.len()) else {
                return [None; ARM_PARAMETERS];
            };
            out[*k] = Some(x[position]);
        }
        out
    }

    /// The parameters the residuals hold information of: a diagonal of
    /// the normal equations of at least [`LEAST_INFORMATION`].
    fn informative(&self) -> Vec<usize> {
        (0..self.dims)
            .filter(|k| self.normal[*k][*k] >= LEAST_INFORMATION)
            .collect()
    }

    /// The normal equations and right side `b` of the `kept` parameters
    /// alone, in their order.
    fn reduced(&self, kept: &[usize], b: &Arm) -> ([[f64; ARM_PARAMETERS]; ARM_PARAMETERS], Arm) {
        let mut normal = [[0.0; ARM_PARAMETERS]; ARM_PARAMETERS];
        let mut right = [0.0; ARM_PARAMETERS];
        for (row, p) in kept.iter().enumerate() {
            right[row] = b[*p];
            for (column, q) in kept.iter().enumerate() {
                normal[row][column] = self.normal[*p][*q];
            }
        }
        (normal, right)
    }

    /// The change x with `normal` x = `b`.
    fn solve_for(&self, b: &Arm) -> Option<Arm> {
        let a = &self.normal;
        if self.dims == 2 {
            let mut x = [0.0; ARM_PARAMETERS];
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            if !(det.is_finite() && det.abs() > 0.0) {
                return None;
            }
            x[0] = (a[1][1] * b[0] - a[0][1] * b[1]) / det;
            x[1] = (a[0][0] * b[1] - a[1][0] * b[0]) / det;
            return Some(x);
        }
        eliminate(a, b, self.dims)
    }
}

/// The x with `a` x = `b` in the first `n` parameters (the others 0):
/// Gaussian elimination with partial pivoting, each row scaled by its
/// diagonal first (the parameters' units differ). `None` when singular
/// or not finite.
fn eliminate(a: &[[f64; ARM_PARAMETERS]; ARM_PARAMETERS], b: &Arm, n: usize) -> Option<Arm> {
    let n = n.min(ARM_PARAMETERS);
    let mut x = [0.0; ARM_PARAMETERS];
    let mut m = *a;
    let mut rhs = *b;
    let scale: Vec<f64> = (0..n).map(|i| m[i][i].abs().sqrt()).collect();
    if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return None;
    }
    for i in 0..n {
        rhs[i] /= scale[i];
        for k in 0..n {
            m[i][k] /= scale[i] * scale[k];
        }
    }
    for column in 0..n {
        let pivot =
            (column..n).max_by(|p, q| m[*p][column].abs().total_cmp(&m[*q][column].abs()))?;
        m.swap(column, pivot);
        rhs.swap(column, pivot);
        let diagonal = m[column][column];
        if !(diagonal.is_finite() && diagonal.abs() > 1e-12) {
            return None;
        }
        let pivot_row = m[column];
        for row in column + 1..n {
            let factor = m[row][column] / diagonal;
            for (target, p) in m[row].iter_mut().zip(&pivot_row).take(n).skip(column) {
                *target -= factor * p;
            }
            rhs[row] -= factor * rhs[column];
        }
    }
    for row in (0..n).rev() {
        let known: f64 = (row + 1..n).map(|k| m[row][k] * x[k]).sum();
        x[row] = (rhs[row] - known) / m[row][row];
    }
    for (value, s) in x.iter_mut().zip(&scale) {
        *value /= s;
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Name of the effect whose prediction is anchored apart (see
/// [`ArmModel::anchor`]).
const GRASP_SLIP: &str = "grasp_slip";

/// `value` [m] on the [`LENGTH_GRAIN`] grid.
fn snap(value: f64) -> f64 {
    (value / LENGTH_GRAIN).round() * LENGTH_GRAIN
}

/// The reference plant compared with one log.
pub struct ArmModel {
    lengths: Lengths,
    /// The body the lengths are put on (plant.md's dummy or a person).
    build: ArmBuild,
    /// Where the fit of the arm starts (the kernel's estimate).
    start: Option<Start>,
    /// The commanded set-point at every integration step to the last
    /// sample's (replayed once; every plant run reads it).
    set_points: Vec<SetPoint>,
    data: Data,
    columns: Vec<usize>,
    steps: Vec<usize>,
    nominal: NominalCache,
    linearisation: Mutex<Option<Arc<Linearisation>>>,
    predictions: PredictionCache,
}

impl ArmModel {
    /// The sim of an arm of `lengths` on `build` against `records`, driven
    /// by their commanded set-point. `y` is compared when every record has
    /// it.
    ///
    /// # Errors
    /// See [`ArmError`].
    pub fn new(lengths: Lengths, build: ArmBuild, records: &[Record]) -> Result<Self, ArmError> {
        if let Lengths::Given(l1, l2) = lengths {
            Self::parameters(build, l1, l2)
                .check()
                .map_err(ArmError::Arm)?;
        }
        if records.is_empty() {
            return Err(ArmError::Empty);
        }
        let lateral = records.iter().all(|r| r.lateral.is_some());
        let columns: Vec<usize> = (0..ALL_SIGNALS.len())
            .filter(|c| lateral || *c != LATERAL)
            .collect();
        let mut steps: Vec<usize> = Vec::with_capacity(records.len());
        let mut observed = Series::with_capacity(columns.len(), records.len());
        for (sample, record) in records.iter().enumerate() {
            let time = record.time;
            let bad_time = ArmError::Time { sample, time };
            if !(0.0..=LONGEST_LOG).contains(&time) {
                return Err(bad_time);
            }
            let step = (time / STEP).round() as usize;
            if steps.last().is_some_and(|last| *last >= step) {
                return Err(bad_time);
            }
            steps.push(step);
            let all = [
                record.pose.x,
                record.pose.z,
                record.pose.psi,
                record.lateral.unwrap_or(0.0),
                record.wrench.fx,
                record.wrench.fz,
                record.wrench.ty,
            ];
            let row: Vec<f64> = columns.iter().map(|c| all[*c]).collect();
            observed
                .push(&row)
                .map_err(|e| ArmError::Sim(e.to_string()))?;
        }
        let set_points = Replay::new(records)?.set_points(steps.last().copied().unwrap_or(0));
        let duration = records.last().map_or(0.0, |r| r.time);
        let start = match lengths {
            Lengths::Given(..) => None,
            Lengths::Fitted => kernel_estimate(records),
        };
        let mut candidates = candidates(duration);
        if lengths == Lengths::Fitted {
            candidates.push(arm_candidate(
                start.map(|s| s.lengths),
                build == ArmBuild::Person,
            ));
        }
        let model = Self {
            lengths,
            build,
            start,
            set_points,
            data: Data {
                signals: columns.iter().map(|c| ALL_SIGNALS[*c]).collect(),
                scales: columns.iter().map(|c| ALL_SCALES[*c]).collect(),
                times: records.iter().map(|r| r.time).collect(),
                observed,
                candidates,
            },
            columns,
            steps,
            nominal: Mutex::new(Vec::new()),
            linearisation: Mutex::new(None),
            predictions: Mutex::new(Vec::new()),
        };
        let arm = model.initial();
        let nominal = model
            .nominal(arm)
            .map_err(|e| ArmError::Sim(e.to_string()))?;
        if nominal.iter().flatten().any(|v| !v.is_finite()) {
            return Err(ArmError::Sim("the nominal sim is not finite".into()));
        }
        if lengths == Lengths::Fitted {
            model
                .linearise(arm, &[])
                .map_err(|e| ArmError::Sim(e.to_string()))?;
        }
        Ok(model)
    }

    /// Linearises the prediction of `effects` (no base) around arm
    /// `reference`, the arm solved with them.
    fn linearise(&self, reference: Arm, effects: &[&Applied]) -> Result<(), ModelError> {
        let derivative = |i: usize| -> Result<Series, ModelError> {
            let h = ARM_DIFFERENCES[i];
            let (mut plus, mut minus) = (reference, reference);
            plus[i] += h;
            // The height's lower bound is a flat arm: a forward
            // difference there.
            let central = i != HEIGHT || reference[i] - h >= HEIGHT_RANGE[0];
            if central {
                minus[i] -= h;
            }
            let width = if central { 2.0 * h } else { h };
            let plus = self.exact(plus, effects)?;
            let minus = self.exact(minus, effects)?;
            let mut out = Series::with_capacity(plus.signals(), plus.samples());
            for k in 0..plus.samples() {
                let row: Vec<f64> = plus
                    .row(k)
                    .iter()
                    .zip(minus.row(k))
                    .map(|(p, m)| (p - m) / width)
                    .collect();
                out.push(&row)?;
            }
            Ok(out)
        };
        let jacobian = (0..self.dims())
            .map(derivative)
            .collect::<Result<Vec<_>, _>>()?;
        if let Ok(mut slot) = self.linearisation.lock() {
            *slot = Some(Arc::new(Linearisation {
                reference,
                effects: effects.iter().map(|a| (*a).clone()).collect(),
                before_slip: effects.iter().any(|a| self.is_slip(a)),
                jacobian,
            }));
        }
        if let Ok(mut cache) = self.predictions.lock() {
            cache.clear();
        }
        Ok(())
    }

    /// How many of the arm's parameters are fitted: l1 and l2, and on a
    /// person's build the shoulder's height.
    fn dims(&self) -> usize {
        if self.lengths == Lengths::Fitted && self.build == ArmBuild::Person {
            ARM_PARAMETERS
        } else {
            2
        }
    }

    /// The arm the fit starts at (the given one when given).
    fn initial(&self) -> Arm {
        let mut arm = [0.0; ARM_PARAMETERS];
        match (self.lengths, self.start) {
            (Lengths::Given(l1, l2), _) => (arm[0], arm[1]) = (l1, l2),
            (Lengths::Fitted, Some(start)) => {
                (arm[0], arm[1]) = start.lengths;
                if self.dims() > HEIGHT {
                    arm[HEIGHT] = start.height;
                }
            }
            (Lengths::Fitted, None) => (arm[0], arm[1]) = (0.3, 0.2),
        }
        arm
    }

    fn current_linearisation(&self) -> Option<Arc<Linearisation>> {
        self.linearisation.lock().ok().and_then(|l| l.clone())
    }

    /// The exact prediction of `effects` (no base) for arm `arm`.
    fn exact(&self, arm: Arm, applied: &[&Applied]) -> Result<Series, ModelError> {
        let list = self.effects(applied)?;
        let effects = Effects::new(&list).map_err(|e| ModelError::Effects(e.to_string()))?;
        if list.iter().all(|e| MEASUREMENT_SIDE.contains(&e.name())) {
            self.measured(&self.nominal(arm)?, &effects)
        } else {
            self.simulated(arm, effects)
        }
    }

    /// Where the exact prediction of `applied` (no base) is anchored: the
    /// reference arm, except for a grasp slip predicted around a reference
    /// solved without one. Such a reference is the arm the whole log pulls
    /// to: a least-squares fit of the forearm to a log whose forearm is l2
    /// before the slip and l2 + shift after it lands near l2 + shift · f,
    /// f the share of the forearm's information (Σ (∂P/∂l2)² / σ² over
    /// the samples) after the slip. Predicting the slip at that arm would
    /// put the forearm after the slip `shift` · (1 − f) too long and leave
    /// the linearisation to bridge a centimetre; anchored at l2 − shift ·
    /// f, the slip's own prediction starts from the forearm before it.
    fn anchor(&self, lin: &Linearisation, applied: &[&Applied]) -> Arm {
        let slip = applied.iter().find_map(|a| {
            let candidate = self.data.candidates.get(a.candidate)?;
            match (candidate.name, a.values.as_slice()) {
                (GRASP_SLIP, [shift, at]) => Some((*shift, *at)),
                _ => None,
            }
        });
        let Some((shift, at)) = slip.filter(|_| !lin.before_slip) else {
            return lin.reference;
        };
        let scales = &self.data.scales;
        let (mut after, mut all) = (0.0, 0.0);
        for (i, time) in self.data.times.iter().enumerate() {
            let information: f64 = lin.jacobian[1]
                .row(i)
                .iter()
                .zip(scales)
                .map(|(j, sigma)| (j / sigma).powi(2))
                .sum();
            all += information;
            if *time >= at {
                after += information;
            }
        }
        let share = if all > 0.0 { after / all } else { 0.0 };
        let mut arm = lin.reference;
        arm[1] -= shift * share;
        arm
    }

    /// The exact prediction of `applied` (no base) at `anchor` (cached).
    fn at_reference(&self, anchor: Arm, applied: &[&Applied]) -> Result<Arc<Series>, ModelError> {
        let key: Vec<Applied> = applied.iter().map(|a| (*a).clone()).collect();
        if let Ok(cache) = self.predictions.lock() {
            if let Some((_, p)) = cache.iter().find(|(k, _)| *k == key) {
                return Ok(Arc::clone(p));
            }
        }
        let prediction = Arc::new(self.exact(anchor, applied)?);
        if let Ok(mut cache) = self.predictions.lock() {
            if cache.len() >= CACHED_PREDICTIONS {
                cache.remove(0);
            }
            cache.push((key, Arc::clone(&prediction)));
        }
        Ok(prediction)
    }

    /// `applied` is a grasp slip.
    fn is_slip(&self, applied: &Applied) -> bool {
        self.data
            .candidates
            .get(applied.candidate)
            .is_some_and(|c| c.name == GRASP_SLIP)
    }

    /// The lengths the model was built with.
    pub fn lengths(&self) -> Lengths {
        self.lengths
    }

    /// The body the lengths are put on.
    pub fn build(&self) -> ArmBuild {
        self.build
    }

    /// The kernel's estimate the fit of the lengths starts at, when the
    /// lengths are fitted and the kernel could estimate them.
    pub fn start(&self) -> Option<(f64, f64)> {
        self.start.map(|s| s.lengths)
    }

    /// How finely the log tells each length [m] (l1, l2), with the
    /// effects `chosen` (the base among them) leaving a held-out gap of
    /// `gap` [σ]: the change of the length that, with the arm's other
    /// parameters solved with it and the effects held, raises the gap on
    /// the `held` samples by `rise` [σ] (the least gain an effect must
    /// show to be named: a length moved by less is as well supported by
    /// the log as the fitted one). From the linearisation at `chosen`
    /// (re-made there): the sum of squares rises by Δ² / (N⁻¹)ₖₖ, N the
    /// held-out samples' normal matrix in the arm's parameters. A length
    /// the held-out samples hold nothing of (its predictions do not move
    /// with it: an upper arm that never left the table) is `None`, as
    /// are both when N cannot tell them apart or the linearisation
    /// cannot be made at `chosen`. `None` when the lengths are given.
    pub fn resolution(
        &self,
        chosen: &[Applied],
        held: &[bool],
        gap: f64,
        rise: f64,
    ) -> Option<[Option<f64>; 2]> {
        if self.lengths != Lengths::Fitted {
            return None;
        }
        let lin = self
            .recentre(chosen)
            .then(|| self.current_linearisation())
            .flatten();
        let Some(lin) = lin else {
            return Some([None, None]);
        };
        let (information, terms) =
            self.normal_equations(&lin, held, self.data.times.len(), |_, _| 0.0);
        let variance = information.inverse_diagonal();
        let sum_of_squares = ((gap + rise).powi(2) - gap.powi(2)) * terms as f64;
        let length = |k: usize| {
            variance[k]
                .map(|v| (sum_of_squares * v).sqrt())
                .filter(|r| r.is_finite())
        };
        Some([length(0), length(1)])
    }

    /// The normal equations of the arm's parameters over the `mask`ed
    /// samples of the first `samples`, with `lin`'s derivative and the
    /// residual `residual(sample, signal)`, each of weight 1/σ²; and how
    /// many terms they hold. Sample by sample, signal by signal.
    fn normal_equations(
        &self,
        lin: &Linearisation,
        mask: &[bool],
        samples: usize,
        residual: impl Fn(usize, usize) -> f64,
    ) -> (LengthSolve, usize) {
        let dims = lin.jacobian.len();
        let mut solve = LengthSolve::new(dims);
        let mut j = [0.0; ARM_PARAMETERS];
        let mut terms = 0;
        for i in (0..samples).filter(|i| mask.get(*i).copied().unwrap_or(false)) {
            for (s, sigma) in self.data.scales.iter().enumerate() {
                for (d, jd) in j.iter_mut().enumerate().take(dims) {
                    *jd = lin.jacobian[d].row(i)[s];
                }
                solve.add(&j[..dims], residual(i, s), *sigma);
                terms += 1;
            }
        }
        (solve, terms)
    }

    /// The arm in `applied` (the base's values: l1, l2 and on a person's
    /// build the shoulder's height), else the given one, else the start;
    /// and the effects without the base.
    pub fn arm_of<'a>(&self, applied: &'a [Applied]) -> (Arm, Vec<&'a Applied>) {
        let base = self.base();
        let mut arm = self.initial();
        let mut effects = Vec::with_capacity(applied.len());
        for a in applied {
            if Some(a.candidate) == base {
                for (slot, value) in arm.iter_mut().zip(&a.values) {
                    *slot = *value;
                }
            } else {
                effects.push(a);
            }
        }
        (arm, effects)
    }

    /// The plant's parameters for an arm `l1`, `l2` on `build` (noise off).
    fn parameters(build: ArmBuild, l1: f64, l2: f64) -> PlantParameters {
        let mut params = PlantParameters::new(snap(l1), snap(l2));
        params.arm = ArmParameters::built(
            build,
            params.arm.upper_arm_length,
            params.arm.forearm_length,
        );
        params.noise = false;
        params
    }

    /// Runs `plant` over the log's commanded motion, calling `keep` with
    /// the step and what it senses at every step.
    fn run(&self, mut plant: Plant, mut keep: impl FnMut(usize, Reading)) {
        for (k, set_point) in self.set_points.iter().enumerate() {
            plant.set(*set_point);
            keep(k, reading(&plant.measure()));
            plant.step();
        }
    }

    /// The plant of `arm` with `effects` (noise off): on a raised
    /// shoulder (height above 0) with `shoulder_height` added.
    fn plant(&self, arm: Arm, mut effects: Effects) -> Result<Plant, ModelError> {
        let height = snap(arm[HEIGHT]);
        if height != 0.0 {
            effects.shoulder_height = Some(ShoulderHeight { height });
        }
        Plant::with_effects(Self::parameters(self.build, arm[0], arm[1]), effects)
            .map_err(ModelError::Simulation)
    }

    /// The nominal record of `arm`: what the robot senses at every step,
    /// noise off (cached).
    fn nominal(&self, arm: Arm) -> Result<Arc<Vec<Reading>>, ModelError> {
        let key = arm.map(snap);
        if let Ok(cache) = self.nominal.lock() {
            if let Some((_, record)) = cache.iter().find(|(k, _)| *k == key) {
                return Ok(Arc::clone(record));
            }
        }
        let plant = self.plant(arm, Effects::default())?;
        let mut record = Vec::with_capacity(self.steps.last().map_or(1, |s| s + 1));
        self.run(plant, |_, s| record.push(s));
        let record = Arc::new(record);
        if let Ok(mut cache) = self.nominal.lock() {
            if cache.len() >= CACHED_ARMS {
                cache.remove(0);
            }
            cache.push((key, Arc::clone(&record)));
        }
        Ok(record)
    }

    fn effects(&self, applied: &[&Applied]) -> Result<Vec<Effect>, ModelError> {
        applied
            .iter()
            .map(|a| {
                let candidate =
                    self.data.candidates.get(a.candidate).ok_or_else(|| {
                        ModelError::Effects(format!("no candidate {}", a.candidate))
                    })?;
                let pairs: Vec<(&str, f64)> = candidate
                    .parameters
                    .iter()
                    .map(|p| p.name)
                    .zip(a.values.iter().copied())
                    .collect();
                Effect::new(candidate.name, &pairs).map_err(|e| ModelError::Effects(e.to_string()))
            })
            .collect()
    }

    fn series(&self, rows: impl Iterator<Item = Reading>) -> Result<Series, ModelError> {
        let mut out = Series::with_capacity(self.columns.len(), self.steps.len());
        let mut row = vec![0.0; self.columns.len()];
        for all in rows {
            for (value, column) in row.iter_mut().zip(&self.columns) {
                *value = all[*column];
            }
            out.push(&row)?;
        }
        Ok(out)
    }

    /// Measurement-side effects applied to the nominal record of an arm.
    fn measured(&self, nominal: &[Reading], effects: &Effects) -> Result<Series, ModelError> {
        self.series(measurement::measured(nominal, &self.steps, effects))
    }

    /// The plant of `arm` re-run with `effects`, noise off.
    fn simulated(&self, arm: Arm, effects: Effects) -> Result<Series, ModelError> {
        let plant = self.plant(arm, effects)?;
        let mut rows = Vec::with_capacity(self.steps.len());
        let mut next = self.steps.iter().peekable();
        self.run(plant, |k, s| {
            if next.peek().is_some_and(|step| **step == k) {
                next.next();
                rows.push(s);
            }
        });
        self.series(rows.into_iter())
    }
}

impl Model for ArmModel {
    fn data(&self) -> &Data {
        &self.data
    }

    fn noise_floor(&self) -> f64 {
        1.0
    }

    fn gap_metric(&self) -> &'static str {
        "held_out_excess_rms_sigma"
    }

    fn base(&self) -> Option<usize> {
        (self.lengths == Lengths::Fitted).then(|| self.data.candidates.len() - 1)
    }

    fn predict(&self, applied: &[Applied]) -> Result<Series, ModelError> {
        let (arm, applied) = self.arm_of(applied);
        let Some(lin) = self.current_linearisation() else {
            return self.exact(arm, &applied);
        };
        let anchor = self.anchor(&lin, &applied);
        let at = self.at_reference(anchor, &applied)?;
        let delta: Arm = std::array::from_fn(|k| arm[k] - anchor[k]);
        let mut out = Series::with_capacity(at.signals(), at.samples());
        let mut row = vec![0.0; at.signals()];
        for i in 0..at.samples() {
            let (j1, j2) = (lin.jacobian[0].row(i), lin.jacobian[1].row(i));
            for (s, value) in row.iter_mut().enumerate() {
                *value = at.row(i)[s] + j1[s] * delta[0] + j2[s] * delta[1];
            }
            for (j, d) in lin.jacobian.iter().zip(&delta).skip(2) {
                for (s, value) in row.iter_mut().enumerate() {
                    *value += j.row(i)[s] * d;
                }
            }
            out.push(&row)?;
        }
        Ok(out)
    }

    /// Solves the arm lengths by linear least squares on the `mask`ed
    /// samples, the effects held (the prediction is linear in them, see
    /// [`Linearisation`]).
    fn polish(&self, applied: &[Applied], mask: &[bool]) -> Option<Vec<Applied>> {
        let base = self.base()?;
        let lin = self.current_linearisation()?;
        let (_, effects) = self.arm_of(applied);
        let anchor = self.anchor(&lin, &effects);
        let at = self.at_reference(anchor, &effects).ok()?;
        let observed = &self.data.observed;
        let dims = lin.jacobian.len();
        let (solve, _) = self.normal_equations(&lin, mask, at.samples(), |i, s| {
            observed.row(i)[s] - at.row(i)[s]
        });
        let delta = solve.solve()?;
        let parameters = &self.data.candidates[base].parameters;
        let mut values: Vec<f64> = anchor[..dims]
            .iter()
            .zip(delta)
            .zip(parameters)
            .map(|((r, d), p)| (r + d).clamp(p.min, p.max))
            .collect();
        if let [l1, _, height] = values.as_mut_slice() {
            *height = height.min(HEIGHT_SHARE * *l1);
        }
        let mut polished = applied.to_vec();
        match polished.iter_mut().find(|a| a.candidate == base) {
            Some(arm) => arm.values = values,
            None => polished.insert(
                0,
                Applied {
                    candidate: base,
                    values,
                },
            ),
        }
        Some(polished)
    }

    /// The arm lengths: [`Model::polish`] solves them from the anchor,
    /// whatever lengths it is handed.
    fn solves(&self, candidate: usize) -> bool {
        self.base() == Some(candidate)
    }

    fn recentre(&self, applied: &[Applied]) -> bool {
        if self.lengths != Lengths::Fitted {
            return false;
        }
        let (arm, effects) = self.arm_of(applied);
        let same = self
            .current_linearisation()
            .is_some_and(|l| l.reference == arm && l.effects.iter().eq(effects.iter().copied()));
        same || self.linearise(arm, &effects).is_ok()
    }

    fn starts(&self, candidate: usize, hints: &Hints) -> Vec<Vec<f64>> {
        let Some(c) = self.data.candidates.get(candidate) else {
            return Vec::new();
        };
        let measurement_side = MEASUREMENT_SIDE.contains(&c.name);
        match (c.name, c.parameters.as_slice()) {
            // The kernel's estimate (the centre) and a coarse grid around it.
            // (A person's: the centre alone; the solve finds the rest.)
            (ARM, parameters) => grid(parameters.len(), if parameters.len() > 2 { 1 } else { 3 }),
            ("active_torque", [amp, freq]) => {
                // The cost is periodic-multimodal in the frequency, with
                // a valley about 1 / (10 · duration) Hz wide whatever the
                // frequency. With a spectral peak in the residual: a comb
                // of frequencies a third of that apart over the peak
                // ±5 % and its band (a strong torque on an arm that
                // touches the table shifts the peak off the torque's
                // frequency: by 3.8 % and 14 % in self-check logs 197 and
                // 165 of seed 7), at most `TEETH` of them, each at a small
                // and a large amplitude: at the right frequency an
                // amplitude below twice the true one beats the nominal
                // sim (for a linear response), and the refinement walks
                // the amplitude; the large one serves a strong, non-linear
                // response. Always also a log-spaced comb over 0.1-5 Hz at
                // two amplitudes, for a torque too weak to own the
                // residual's peak.
                const TEETH: usize = 160;
                let times = self.times();
                let duration = times.last().zip(times.first()).map_or(1.0, |(b, a)| b - a);
                let spacing = 1.0 / (30.0 * duration.max(1.0));
                let around_peak = hints.frequency.into_iter().flat_map(|f| {
                    let (mut lo, mut hi) = (0.95 * f, 1.05 * f);
                    if let Some([a, b]) = hints.band {
                        (lo, hi) = (lo.min(a), hi.max(b));
                    }
                    let teeth = (((hi - lo) / spacing).ceil() as usize).clamp(1, TEETH);
                    (0..teeth).flat_map(move |k| {
                        let f = lo + (k as f64 + 0.5) * (hi - lo) / teeth as f64;
                        [0.1, 0.6].map(|a| vec![amp.unit_of(a), freq.unit_of(f)])
                    })
                });
                let comb = (0..12).flat_map(|k| {
                    let fu = freq.unit_of(0.1 * 50f64.powf(f64::from(k) / 11.0));
                    [0.1, 0.6].map(|a| vec![amp.unit_of(a), fu])
                });
                around_peak.chain(comb).collect()
            }
            // At the residual's onset (the sim's arm is the arm before
            // the slip) and just before its end (the fitted arm is the
            // arm after the slip, so the residual lies before it).
            // And at the forearm's change point (see `forearm_change`),
            // with the change it implies: a slip in mid-log leaves the
            // residual beyond the noise from start to end.
            (GRASP_SLIP, [shift, at]) => {
                let mut anchors: Vec<f64> = Vec::new();
                if let Some(onset) = hints.onset {
                    anchors.extend([0.0, 0.15, 0.3].map(|d| onset + d));
                }
                if let Some(end) = hints.end {
                    anchors.extend([-0.6, -0.3, 0.0].map(|d| end + d));
                }
                let change = hints
                    .residual
                    .as_deref()
                    .and_then(|r| self.forearm_change(r));
                if anchors.is_empty() && change.is_none() {
                    return grid(2, 5);
                }
                let shifts = [-0.03, -0.01, -0.003, 0.003, 0.01, 0.03];
                let mut starts: Vec<Vec<f64>> = anchors
                    .iter()
                    .flat_map(|time| {
                        let au = at.unit_of(*time);
                        shifts.map(|s| vec![shift.unit_of(s), au])
                    })
                    .collect();
                if let Some((time, change)) = change {
                    for t in [-0.05, 0.0, 0.05].map(|d| time + d) {
                        let au = at.unit_of(t);
                        starts.push(vec![shift.unit_of(change), au]);
                        starts.extend(shifts.map(|s| vec![shift.unit_of(s), au]));
                    }
                }
                starts
            }
            ("quantization", [pos, ang]) => {
                // Rounded readings sit on a lattice: its spacing is the
                // step, to the precision the optimiser cannot reach from
                // a grid (the cost has a minimum per lattice alignment).
                let position = resolution(
                    &[self.data.observed.column(0), self.data.observed.column(1)].concat(),
                );
                let angle = resolution(&self.data.observed.column(2));
                let mut starts = grid(2, 11);
                starts.push(vec![pos.unit_of(position), ang.unit_of(angle)]);
                starts
            }
            (_, [_]) if measurement_side => grid(1, 33),
            (_, [_, _]) if measurement_side => grid(2, 11),
            (_, parameters) => grid(parameters.len(), if parameters.len() <= 1 { 9 } else { 5 }),
        }
    }
}

impl ArmModel {
    /// Where the forearm of the log most likely changes, and by how much:
    /// `residual` (scaled, of the effects the slip would join: the
    /// engine's hint), split at each sample into a part before and a part
    /// after, each fitted by a change of the forearm alone along the
    /// length Jacobian (∂P/∂l2, per signal over σ); the split that
    /// explains the most gives the time [s] and the change [m] (after
    /// less before). `None` without a linearisation or a split with
    /// information on both sides. Start points only, from the whole log
    /// like the engine's hints: the fit and its score do not depend on it
    /// beyond where the search begins.
    fn forearm_change(&self, residual: &Series) -> Option<(f64, f64)> {
        let lin = self.current_linearisation()?;
        let scales = &self.data.scales;
        let samples = residual.samples().min(lin.jacobian[1].samples());
        let (mut along, mut information) = (vec![0.0; samples], vec![0.0; samples]);
        for i in 0..samples {
            let rows = lin.jacobian[1].row(i).iter().zip(residual.row(i));
            for ((j, r), sigma) in rows.zip(scales) {
                let j = j / sigma;
                if j.is_finite() && r.is_finite() {
                    along[i] += j * r;
                    information[i] += j * j;
                }
            }
        }
        let (total_along, total_information): (f64, f64) =
            (along.iter().sum(), information.iter().sum());
        let least = 0.01 * total_information;
        let (mut before_along, mut before_information) = (0.0, 0.0);
        let mut best: Option<(f64, usize, f64)> = None;
        for k in 0..samples {
            let (after_along, after_information) = (
                total_along - before_along,
                total_information - before_information,
            );
            if before_information > least && after_information > least {
                let explained = before_along * before_along / before_information
                    + after_along * after_along / after_information;
                let change = after_along / after_information - before_along / before_information;
                if best.is_none_or(|(e, _, _)| explained > e) {
                    best = Some((explained, k, change));
                }
            }
            before_along += along[k];
            before_information += information[k];
        }
        let (_, k, change) = best?;
        let time = *self.data.times.get(k)?;
        (time.is_finite() && change.is_finite()).then_some((time, change))
    }
}

#[cfg(test)]
mod tests {
    use super::LengthSolve;

    /// Residuals of a linear model r = J x, one per row of `rows` (J's
    /// row), noise σ 1.
    fn solve_of(dims: usize, rows: &[[f64; 3]], x: [f64; 3]) -> LengthSolve {
        let mut solve = LengthSolve::new(dims);
        for j in rows {
            let r: f64 = j.iter().zip(x).map(|(a, b)| a * b).sum();
            solve.add(&j[..dims], r, 1.0);
        }
        solve
    }

    const ROWS: [[f64; 3]; 4] = [
        [1.0, 0.5, 2.0],
        [0.2, 1.0, -1.0],
        [1.5, -0.3, 0.4],
        [0.1, 0.7, 0.9],
    ];

    #[test]
    fn the_solve_finds_a_linear_models_parameters() {
        let x = [0.01, -0.02, 0.03];
        let found = solve_of(3, &ROWS, x).solve().unwrap();
        for (f, t) in found.iter().zip(x) {
            assert!((f - t).abs() < 1e-12, "{found:?}");
        }
    }

    /// A parameter no residual moves with (an upper arm that never left
    /// the table) is held at 0 and the others are solved without it;
    /// solved with it, the equations are singular and nothing would move.
    #[test]
    fn the_solve_holds_a_parameter_the_residuals_do_not_see() {
        let blind: Vec<[f64; 3]> = ROWS.iter().map(|r| [0.0, r[1], r[2]]).collect();
        let found = solve_of(3, &blind, [0.0, -0.02, 0.03]).solve().unwrap();
        assert_eq!(found[0], 0.0);
        assert!((found[1] + 0.02).abs() < 1e-12 && (found[2] - 0.03).abs() < 1e-12);
        let variance = solve_of(3, &blind, [0.0; 3]).inverse_diagonal();
        assert!(variance[0].is_none() && variance[1].is_some() && variance[2].is_some());
    }

    /// The inverse's diagonal is the inverse's: N · N⁻¹'s columns checked
    /// through the solve of each unit vector.
    #[test]
    fn the_inverse_diagonal_is_the_normal_matrixs_inverses() {
        let solve = solve_of(3, &ROWS, [0.0; 3]);
        let variance = solve.inverse_diagonal();
        for (k, v) in variance.iter().enumerate().take(3) {
            let mut unit = [0.0; 3];
            unit[k] = 1.0;
            let column = solve.solve_for(&unit).unwrap();
            let v = v.unwrap();
            assert!(
                (v - column[k]).abs() <= 1e-12 * v.abs(),
                "{k}: {v} {column:?}"
            );
            // N · column = unit.
            for (row, expected) in solve.normal.iter().zip(unit).take(3) {
                let product: f64 = row.iter().zip(column).map(|(a, b)| a * b).sum();
                assert!((product - expected).abs() < 1e-9, "{product} {expected}");
            }
        }
    }
}
