//! The arm plant of `plant.md` as a diagnosis [`Model`]: the reference
//! plant (`limb-sim`) with the given arm lengths and every other
//! parameter at its default is the sim; a log in the plant.md format is
//! the real data.
//!
//! # Alignment
//! Sim and log share the commanded motion: the log's set-point columns
//! (`xd`, `zd`, `psid`) must follow the estimation motion of `plant.md`
//! within [`COMMAND_TOLERANCE`] (else the log is not of this motion and
//! is refused), and each log sample is compared with the sim at the
//! integration step nearest its time stamp. Ground-truth columns are
//! never read.
//!
//! # Predictions
//! The nominal sim is run once, noise off, keeping what the robot senses
//! at every 0.5 ms step. Measurement-side effects (`backlash`,
//! `quantization`, `latency`, `grasp_compliance`, `plane_tilt`) are then
//! applied to that record in the plant's own order (compliance and tilt,
//! delay, backlash, rounding), which costs microseconds; dynamics-side
//! effects (`joint_friction`, `mass_mismatch`, `shoulder_drift`,
//! `active_torque`, `grasp_slip`) re-run the plant with the effect.
//! Quantization is predicted as the *expected* rounded reading
//! E[round((v + n) / step) · step] over the measurement noise n, since
//! the real sensor rounds its noisy reading.

use crate::model::{
    grid, Applied, Candidate, Data, Hints, Model, ModelError, Parameter, Scale, Series, Signal,
};
use limb_kernel::geometry::Pose;
use limb_kernel::motion::{EstimationMotion, EstimationMotionParameters};
use limb_sim::effects::{descriptor, Effect, Effects, Quantization};
use limb_sim::log::Record;
use limb_sim::{
    Measurement, Plant, PlantParameters, ANGLE_NOISE, FORCE_NOISE, POSITION_NOISE, STEP,
    TORQUE_NOISE,
};
use thiserror::Error;

/// Largest difference between the log's set-point and the sim's commanded
/// motion: position [m] and angle [rad] (10× the pose noise; the log's
/// six decimals are far finer).
pub const COMMAND_TOLERANCE: (f64, f64) = (1e-3, 1e-2);
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
    /// The log lacks the set-point columns the alignment needs.
    #[error("sample {sample} (t = {time} s) has no commanded pose (xd, zd, psid): sim and log cannot be aligned")]
    NoCommand {
        /// 0-based sample.
        sample: usize,
        /// Its time [s].
        time: f64,
    },
    /// The log's commanded motion is not the sim's.
    #[error("the log's commanded motion departs from the sim's at t = {time} s: {signal} = {logged} in the log, {sim} in the sim (tolerance {tolerance})")]
    CommandMismatch {
        /// Time [s].
        time: f64,
        /// Set-point column.
        signal: &'static str,
        /// Logged value.
        logged: f64,
        /// Sim's value.
        sim: f64,
        /// Allowed difference.
        tolerance: f64,
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

/// Sensed channels of one instant: x, z, psi, y, fx, fz, ty.
type Sensed = [f64; 7];

fn sensed(m: &Measurement) -> Sensed {
    [
        m.pose.x,
        m.pose.z,
        m.pose.psi,
        m.lateral,
        m.wrench.fx,
        m.wrench.fz,
        m.wrench.ty,
    ]
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
/// Column of `y` in [`Sensed`] (dropped when the log has no `y`).
const LATERAL: usize = 3;

/// Effects that only change what is measured.
const MEASUREMENT_SIDE: [&str; 5] = [
    "backlash",
    "quantization",
    "latency",
    "grasp_compliance",
    "plane_tilt",
];

fn parameter(
    name: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    scale: Scale,
) -> Parameter {
    Parameter {
        name,
        unit,
        min,
        max,
        scale,
    }
}

/// The candidates with their search ranges: inside the effect's range of
/// `limb_sim::effects::CATALOGUE`, logarithmic for quantities spanning
/// decades, starting just above zero where zero means "no effect".
/// `grasp_slip.at` spans the log (`duration` seconds).
pub fn candidates(duration: f64) -> Vec<Candidate> {
    use Scale::{Linear, Logarithmic};
    let one = |name, parameters| Candidate { name, parameters };
    vec![
        one(
            "joint_friction",
            vec![
                parameter("coulomb", "N m", 0.002, 5.0, Logarithmic),
                parameter("viscous", "N m s/rad", 0.002, 5.0, Logarithmic),
            ],
        ),
        one(
            "backlash",
            vec![parameter("width", "rad", 0.0005, 0.2, Logarithmic)],
        ),
        one(
            "quantization",
            vec![
                parameter("pos", "m", 1e-5, 0.05, Logarithmic),
                parameter("ang", "rad", 1e-4, 0.2, Logarithmic),
            ],
        ),
        one(
            "latency",
            vec![parameter("delay", "s", 0.0005, 0.5, Logarithmic)],
        ),
        one(
            "grasp_compliance",
            vec![parameter("k", "N/m", 50.0, 1e6, Logarithmic)],
        ),
        one(
            "mass_mismatch",
            vec![parameter("factor", "1", 0.2, 5.0, Logarithmic)],
        ),
        one(
            "plane_tilt",
            vec![parameter("angle", "rad", -1.0, 1.0, Linear)],
        ),
        one(
            "shoulder_drift",
            vec![parameter("k", "N/m", 100.0, 1e6, Logarithmic)],
        ),
        one(
            "active_torque",
            vec![
                parameter("amp", "N m", 0.005, 5.0, Logarithmic),
                parameter("freq", "Hz", 0.05, 10.0, Logarithmic),
            ],
        ),
        one(
            "grasp_slip",
            vec![
                parameter("shift", "m", -0.05, 0.05, Linear),
                parameter("at", "s", 0.0, duration.clamp(1.0, 60.0), Linear),
            ],
        ),
    ]
}

/// The reference plant compared with one log.
pub struct ArmModel {
    params: PlantParameters,
    motion: EstimationMotion,
    data: Data,
    columns: Vec<usize>,
    steps: Vec<usize>,
    nominal: Vec<Sensed>,
}

impl ArmModel {
    /// The sim of an arm of lengths `l1`, `l2` [m] against `records`.
    /// `y` is compared when every record has it.
    ///
    /// # Errors
    /// See [`ArmError`].
    pub fn new(l1: f64, l2: f64, records: &[Record]) -> Result<Self, ArmError> {
        let mut params = PlantParameters::new(l1, l2);
        params.noise = false;
        params.check().map_err(ArmError::Arm)?;
        if records.is_empty() {
            return Err(ArmError::Empty);
        }
        let motion = EstimationMotion::new(Pose::default(), &EstimationMotionParameters::default())
            .map_err(|e| ArmError::Sim(format!("estimation motion: {e:?}")))?;
        let lateral = records.iter().all(|r| r.lateral.is_some());
        let columns: Vec<usize> = (0..ALL_SIGNALS.len())
            .filter(|c| lateral || *c != LATERAL)
            .collect();
        let mut steps: Vec<usize> = Vec::with_capacity(records.len());
        let mut observed = Series::with_capacity(columns.len(), records.len());
        for (sample, record) in records.iter().enumerate() {
            let time = record.time;
            let step = (time / STEP).round();
            let bad_time = ArmError::Time { sample, time };
            if !(0.0..=LONGEST_LOG).contains(&time) {
                return Err(bad_time);
            }
            let step = step as usize;
            if steps.last().is_some_and(|last| *last >= step) {
                return Err(bad_time);
            }
            steps.push(step);
            let command = record.command.ok_or(ArmError::NoCommand { sample, time })?;
            let sim = motion.at(step as f64 * STEP).pose;
            let (position, angle) = COMMAND_TOLERANCE;
            for (signal, logged, sim, tolerance) in [
                ("xd", command.x, sim.x, position),
                ("zd", command.z, sim.z, position),
                ("psid", command.psi, sim.psi, angle),
            ] {
                if (logged - sim).abs() > tolerance {
                    return Err(ArmError::CommandMismatch {
                        time,
                        signal,
                        logged,
                        sim,
                        tolerance,
                    });
                }
            }
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
        let last = steps.last().copied().unwrap_or(0);
        let mut plant = Plant::new(params).map_err(ArmError::Sim)?;
        let mut nominal = Vec::with_capacity(last + 1);
        for k in 0..=last {
            plant.set(motion.at(k as f64 * STEP));
            nominal.push(sensed(&plant.measure()));
            plant.step();
        }
        if nominal.iter().flatten().any(|v| !v.is_finite()) {
            return Err(ArmError::Sim("the nominal sim is not finite".into()));
        }
        let duration = records.last().map_or(0.0, |r| r.time);
        Ok(Self {
            params,
            motion,
            data: Data {
                signals: columns.iter().map(|c| ALL_SIGNALS[*c]).collect(),
                scales: columns.iter().map(|c| ALL_SCALES[*c]).collect(),
                times: records.iter().map(|r| r.time).collect(),
                observed,
                candidates: candidates(duration),
            },
            columns,
            steps,
            nominal,
        })
    }

    fn effects(&self, applied: &[Applied]) -> Result<Vec<Effect>, ModelError> {
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

    fn series(&self, rows: impl Iterator<Item = Sensed>) -> Result<Series, ModelError> {
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

    /// Measurement-side effects applied to the nominal record.
    fn measured(&self, effects: &Effects) -> Result<Series, ModelError> {
        let delay = effects.latency.map_or(0, |l| l.steps());
        let mut follower = 0.0;
        let rows = self.steps.iter().map(|&step| {
            let mut s = self.nominal[step.saturating_sub(delay)];
            let mut pose = [s[0], s[1], s[2]];
            if let Some(compliance) = effects.grasp_compliance {
                pose = compliance.end_effector(pose, [s[4], s[5], s[6]]);
            }
            if let Some(tilt) = effects.plane_tilt {
                let (sin, cos) = tilt.angle.sin_cos();
                s[3] = pose[1] * sin;
                pose[1] *= cos;
            }
            if let Some(backlash) = effects.backlash {
                follower = backlash.follow(follower, pose[2]);
                pose[2] = follower;
            }
            if let Some(q) = effects.quantization {
                pose = expected_rounding(&q, pose);
            }
            [pose[0], pose[1], pose[2], s[3], s[4], s[5], s[6]]
        });
        self.series(rows)
    }

    /// The plant re-run with `effects`, noise off.
    fn simulated(&self, effects: Effects) -> Result<Series, ModelError> {
        let mut plant =
            Plant::with_effects(self.params, effects).map_err(ModelError::Simulation)?;
        let last = self.steps.last().copied().unwrap_or(0);
        let mut rows = Vec::with_capacity(self.steps.len());
        let mut next = self.steps.iter().peekable();
        for k in 0..=last {
            plant.set(self.motion.at(k as f64 * STEP));
            if next.peek().is_some_and(|s| **s == k) {
                next.next();
                rows.push(sensed(&plant.measure()));
            }
            plant.step();
        }
        self.series(rows.into_iter())
    }
}

/// E[round((v + n) / step) · step] for n ~ N(0, σ²), per pose channel
/// (σ of `plant.md`). For a step under 1.5 σ the expectation differs
/// from v by less than 1e-4 σ (the bias's Fourier series decays as
/// exp(−2π²σ²/step²)), so such a step is not modelled.
fn expected_rounding(q: &Quantization, pose: [f64; 3]) -> [f64; 3] {
    let one = |value: f64, step: f64, sigma: f64| -> f64 {
        if step <= 1.5 * sigma {
            return value;
        }
        let centre = (value / step).round();
        // Steps farther than 6σ from the value have no probability left:
        // at most 11 terms (step > 1.5 σ bounds the count).
        let reach = (6.0 * sigma / step).ceil() as i64 + 1;
        let cdf = |x: f64| 0.5 * (1.0 + libm::erf(x / (sigma * std::f64::consts::SQRT_2)));
        let mut mean = 0.0;
        for k in -reach..=reach {
            let level = centre + k as f64;
            let lo = (level - 0.5) * step - value;
            let hi = (level + 0.5) * step - value;
            mean += level * step * (cdf(hi) - cdf(lo));
        }
        mean
    };
    [
        one(pose[0], q.pos, POSITION_NOISE),
        one(pose[1], q.pos, POSITION_NOISE),
        one(pose[2], q.ang, ANGLE_NOISE),
    ]
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

    fn predict(&self, applied: &[Applied]) -> Result<Series, ModelError> {
        let list = self.effects(applied)?;
        let effects = Effects::new(&list).map_err(|e| ModelError::Effects(e.to_string()))?;
        let prediction = if list.iter().all(|e| MEASUREMENT_SIDE.contains(&e.name())) {
            self.measured(&effects)?
        } else {
            self.simulated(effects)?
        };
        Ok(prediction)
    }

    fn starts(&self, candidate: usize, hints: &Hints) -> Vec<Vec<f64>> {
        let Some(c) = self.data.candidates.get(candidate) else {
            return Vec::new();
        };
        let measurement_side = MEASUREMENT_SIDE.contains(&c.name);
        match (c.name, c.parameters.as_slice()) {
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
            ("grasp_slip", [shift, at]) => match hints.onset {
                Some(onset) => [0.0, 0.15, 0.3]
                    .iter()
                    .flat_map(|delay| {
                        let au = at.unit_of(onset + delay);
                        [-0.03, -0.01, -0.003, 0.003, 0.01, 0.03]
                            .map(|s| vec![shift.unit_of(s), au])
                    })
                    .collect(),
                None => grid(2, 5),
            },
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

/// The spacing of the lattice `values` sit on: the median gap between
/// neighbouring distinct values (tiny for unrounded data).
fn resolution(values: &[f64]) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let mut gaps: Vec<f64> = sorted.windows(2).map(|w| w[1] - w[0]).collect();
    if gaps.is_empty() {
        return 0.0;
    }
    gaps.sort_by(f64::total_cmp);
    gaps[gaps.len() / 2]
}

/// Every candidate names an effect of the sim's catalogue, with the same
/// parameter names and units, searched inside the catalogue's range.
pub fn candidates_match_catalogue(candidates: &[Candidate]) -> Result<(), String> {
    for c in candidates {
        let d = descriptor(c.name).ok_or_else(|| format!("{} is not a sim effect", c.name))?;
        if d.parameters.len() != c.parameters.len() {
            return Err(format!("{}: parameter count differs", c.name));
        }
        for (p, q) in c.parameters.iter().zip(d.parameters) {
            if p.name != q.name
                || p.unit != q.unit
                || p.min < q.min
                || p.max > q.max
                || !p.is_valid()
            {
                return Err(format!(
                    "{}.{}: name, unit or range differs from the sim's",
                    c.name, p.name
                ));
            }
        }
    }
    Ok(())
}
