//! The drive plant as a diagnosis [`Model`]: the rigid inverse model of
//! `spec/drive.md` against one drive log.
//!
//! # Signals
//! `tau` (the force, zero-phase filtered like the positions, see
//! [`super::filter`]) and, with a load-side encoder, `transmission`
//! (q − q_load, filtered the same way). Each is divided by its own RMS over
//! the run (the force about zero, the transmission about its mean), and
//! the noise is unknown, so the gap is the normalised RMS error
//! (`nrmse_tau`, or `nrmse_tau_transmission` over both). (Weighting the
//! transmission per unit of its out-of-band noise instead was tried and
//! did worse in the blind self-check: the force's noise is not white —
//! the position loop differentiates the encoder noise — so its
//! out-of-band level overstates its in-band level.)
//!
//! # Sample-and-hold
//! A digital drive holds the force logged at t_k over [t_k, t_k + T):
//! on average it acts half a sample later than it is stamped. The nominal
//! model therefore compares the force logged at t_k with the kinematics
//! at t_k + T/2 (T the median sample interval); `latency` adds to that.
//!
//! # Compared samples
//! The filtered signals carry nothing above the cut-off, so neighbouring
//! samples of a residual are strongly correlated; the model compares one
//! sample in D = ⌊f_s / (2 cut-off)⌋ (Nyquist rate of the filtered band:
//! 100 Hz for a 50 Hz cut-off), so that the engine's information
//! criterion counts about independent terms and does not reward an effect
//! for fitting filtered noise. Filtering and derivatives still use every
//! sample.
//!
//! # Prediction
//! Every prediction is a sum of known terms and columns times linear
//! coefficients ([`super::effects`]), built per signal as a [`Design`];
//! the coefficients are either given (`predict`) or solved by least
//! squares on the fit samples ([`Model::polish`]), so the engine's
//! optimiser searches only the nonlinear parameters (`vs`, `delay`,
//! `step`, `width`). A least-squares value outside its parameter's range
//! is clamped into it.

use super::effects::{candidates, dequantize, encoder_step, play, smooth_sign, RIGID};
use super::filter::{derivative, zero_phase};
use super::log::DriveLog;
use super::lsq::solve;
use crate::locate::median_interval;
use crate::model::{grid, Applied, Data, Hints, Model, ModelError, Series, Signal};

/// Default zero-phase cut-off of positions and force [Hz]: ten times the
/// position loop's bandwidth of a positioning drive's motion (EMPS: a few
/// Hz of reference content) and a decade below the 500 Hz Nyquist
/// frequency of a 1 kHz log, where the encoder's quantization noise,
/// differentiated twice, dominates.
pub const CUTOFF: f64 = 50.0;

/// Smallest signal scale (RMS) [N or m]: keeps a noise-free, constant
/// signal from dividing by zero.
const SMALLEST_SCALE: f64 = 1e-9;

const TAU: Signal = Signal {
    name: "tau",
    unit: "N",
};
const TRANSMISSION: Signal = Signal {
    name: "transmission",
    unit: "m",
};

/// Why a drive log cannot be compared with the rigid model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DriveModelError {
    /// The force is zero throughout: there is nothing to compare.
    #[error("`tau` is zero throughout the log")]
    NoForce,
    /// The cut-off is not below the Nyquist frequency of the log.
    #[error("cut-off {cutoff} Hz is not in (0, {nyquist}) Hz, the log's Nyquist frequency")]
    Cutoff {
        /// Requested cut-off [Hz].
        cutoff: f64,
        /// Half the sampling rate [Hz].
        nyquist: f64,
    },
}

/// Filtered positions and their derivatives.
#[derive(Clone, Debug)]
struct Kinematics {
    q: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
}

impl Kinematics {
    fn of(q: &[f64], t: &[f64], interval: f64, cutoff: f64) -> Self {
        let q = zero_phase(q, interval, cutoff);
        let v = derivative(&q, t);
        let a = derivative(&v, t);
        Self { q, v, a }
    }
}

/// How a linear coefficient maps to the parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Link {
    /// The coefficient is the parameter.
    Direct,
    /// The coefficient is 1 / parameter (stiffness from compliance).
    Reciprocal,
}

/// One column of a design: coefficient × column, the coefficient being
/// parameter `parameter` of effect `effect` (index into the applied list).
struct Term {
    effect: usize,
    parameter: usize,
    link: Link,
    column: Vec<f64>,
}

/// One signal's prediction: `known` + Σ coefficient × column.
struct Design {
    known: Vec<f64>,
    terms: Vec<Term>,
}

impl Design {
    fn new(known: Vec<f64>) -> Self {
        Self {
            known,
            terms: Vec::new(),
        }
    }

    fn add(&mut self, effect: usize, parameter: usize, link: Link, column: Vec<f64>) {
        self.terms.push(Term {
            effect,
            parameter,
            link,
            column,
        });
    }

    fn evaluate(&self, applied: &[Applied]) -> Vec<f64> {
        let mut out = self.known.clone();
        for term in &self.terms {
            let value = applied
                .get(term.effect)
                .and_then(|a| a.values.get(term.parameter))
                .copied()
                .unwrap_or(0.0);
            let coefficient = match term.link {
                Link::Direct => value,
                Link::Reciprocal if value > 0.0 => 1.0 / value,
                Link::Reciprocal => 0.0,
            };
            for (o, c) in out.iter_mut().zip(&term.column) {
                *o += coefficient * c;
            }
        }
        out
    }
}

/// The rigid drive model compared with one drive log.
pub struct DriveModel {
    /// Every sample's time [s].
    t: Vec<f64>,
    /// The compared samples (every D-th).
    keep: Vec<usize>,
    raw_q: Vec<f64>,
    interval: f64,
    cutoff: f64,
    kinematics: Kinematics,
    tau: Vec<f64>,
    f_ext: Option<Vec<f64>>,
    data: Data,
}

fn rms(x: &[f64], about: f64) -> f64 {
    (x.iter().map(|v| (v - about).powi(2)).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

impl DriveModel {
    /// The rigid model of `log`, filtered at `cutoff` Hz ([`CUTOFF`] is the
    /// default).
    ///
    /// # Errors
    /// See [`DriveModelError`].
    pub fn new(log: &DriveLog, cutoff: f64) -> Result<Self, DriveModelError> {
        let interval = median_interval(&log.t);
        let nyquist = 0.5 / interval;
        if !(cutoff > 0.0 && cutoff < nyquist) {
            return Err(DriveModelError::Cutoff { cutoff, nyquist });
        }
        let filter = |x: &[f64]| zero_phase(x, interval, cutoff);
        let tau = filter(&log.tau);
        let tau_scale = rms(&tau, 0.0);
        if tau_scale.is_nan() || tau_scale <= 0.0 {
            return Err(DriveModelError::NoForce);
        }
        let transmission = log.q_load.as_ref().map(|load| {
            let gap: Vec<f64> = log.q.iter().zip(load).map(|(q, l)| q - l).collect();
            filter(&gap)
        });
        let mut signals = vec![TAU];
        let mut scales = vec![tau_scale];
        if let Some(gap) = &transmission {
            let mean = gap.iter().sum::<f64>() / gap.len().max(1) as f64;
            signals.push(TRANSMISSION);
            scales.push(rms(gap, mean).max(SMALLEST_SCALE));
        }
        let every = ((0.5 / (interval * cutoff)).floor() as usize).max(1);
        let keep: Vec<usize> = (0..tau.len()).step_by(every).collect();
        let mut observed = Series::with_capacity(signals.len(), keep.len());
        for &i in &keep {
            let row: Vec<f64> = std::iter::once(tau[i])
                .chain(transmission.as_ref().map(|g| g[i]))
                .collect();
            // One value per signal by construction.
            let _ = observed.push(&row);
        }
        let times = keep.iter().map(|i| log.t[*i]).collect();
        Ok(Self {
            kinematics: Kinematics::of(&log.q, &log.t, interval, cutoff),
            keep,
            t: log.t.clone(),
            raw_q: log.q.clone(),
            interval,
            cutoff,
            f_ext: log.f_ext.as_deref().map(filter),
            tau,
            data: Data {
                signals,
                scales,
                times,
                observed,
                candidates: candidates(log.q_load.is_some()),
            },
        })
    }

    /// The zero-phase cut-off in use [Hz].
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    fn name(&self, applied: &Applied) -> Result<&'static str, ModelError> {
        self.data
            .candidates
            .get(applied.candidate)
            .map(|c| c.name)
            .ok_or_else(|| ModelError::Effects(format!("no candidate {}", applied.candidate)))
    }

    /// The designs of every signal for `applied` (coefficients unset).
    fn designs(&self, applied: &[Applied]) -> Result<Vec<Design>, ModelError> {
        let value = |name: &str, index: usize| -> Result<Option<f64>, ModelError> {
            for a in applied {
                if self.name(a)? == name {
                    return Ok(a.values.get(index).copied());
                }
            }
            Ok(None)
        };
        let rebuilt;
        let kin = match value("quantization", 0)? {
            Some(step) => {
                let q = dequantize(&self.raw_q, &self.t, step);
                rebuilt = Kinematics::of(&q, &self.t, self.interval, self.cutoff);
                &rebuilt
            }
            None => &self.kinematics,
        };
        let n = self.t.len();
        let known = match &self.f_ext {
            Some(f) => f.iter().map(|f| -f).collect(),
            None => vec![0.0; n],
        };
        let mut tau = Design::new(known);
        let mut transmission = (self.data.signals.len() > 1).then(|| Design::new(vec![0.0; n]));
        let map = |f: &dyn Fn(f64) -> f64| kin.v.iter().map(|v| f(*v)).collect::<Vec<f64>>();
        for (index, a) in applied.iter().enumerate() {
            let direct = Link::Direct;
            match self.name(a)? {
                RIGID => {
                    tau.add(index, 0, direct, kin.a.clone());
                    tau.add(index, 1, direct, vec![1.0; n]);
                    if let Some(design) = transmission.as_mut() {
                        design.add(index, 2, direct, vec![1.0; n]);
                    }
                }
                "viscous_friction" => tau.add(index, 0, direct, kin.v.clone()),
                "coulomb_friction" => tau.add(index, 0, direct, map(&smooth_sign)),
                "asymmetric_friction" => {
                    tau.add(index, 0, direct, map(&|v| smooth_sign(v).abs()));
                    tau.add(index, 1, direct, map(&f64::abs));
                }
                "stribeck_friction" => {
                    let vs = a.values.get(1).copied().unwrap_or(1.0);
                    let shape = move |v: f64| (-(v / vs).powi(2)).exp() * smooth_sign(v);
                    tau.add(index, 0, direct, map(&shape));
                }
                "compliance" => {
                    if let Some(design) = transmission.as_mut() {
                        design.add(index, 0, Link::Reciprocal, self.tau.clone());
                    }
                }
                "backlash" => {
                    if let Some(design) = transmission.as_mut() {
                        let width = a.values.first().copied().unwrap_or(0.0);
                        let follower = play(&kin.q, width);
                        for ((k, q), f) in design.known.iter_mut().zip(&kin.q).zip(follower) {
                            *k += q - f;
                        }
                    }
                }
                "latency" | "quantization" => {}
                other => return Err(ModelError::Effects(format!("unknown effect {other}"))),
            }
        }
        let delay = value("latency", 0)?.unwrap_or(0.0) - 0.5 * self.interval;
        {
            let shift = |x: &mut Vec<f64>| *x = delayed(x, &self.t, delay);
            shift(&mut tau.known);
            tau.terms
                .iter_mut()
                .for_each(|term| shift(&mut term.column));
        }
        Ok(std::iter::once(tau).chain(transmission).collect())
    }
}

/// `x(t − delay)` at every `t` (a negative delay advances), linearly
/// interpolated and held beyond either end.
fn delayed(x: &[f64], t: &[f64], delay: f64) -> Vec<f64> {
    let mut k = 0usize;
    t.iter()
        .map(|&time| {
            let at = time - delay;
            while k + 1 < t.len() && t[k + 1] <= at {
                k += 1;
            }
            match (x.get(k), x.get(k + 1), t.get(k), t.get(k + 1)) {
                (Some(&x0), Some(&x1), Some(&t0), Some(&t1)) if at > t0 => {
                    x0 + (x1 - x0) * ((at - t0) / (t1 - t0)).min(1.0)
                }
                (Some(&x0), ..) => x0,
                _ => 0.0,
            }
        })
        .collect()
}

impl Model for DriveModel {
    fn data(&self) -> &Data {
        &self.data
    }

    fn noise_floor(&self) -> f64 {
        0.0
    }

    fn gap_metric(&self) -> &'static str {
        if self.data.signals.len() > 1 {
            "nrmse_tau_transmission"
        } else {
            "nrmse_tau"
        }
    }

    fn base(&self) -> Option<usize> {
        Some(0)
    }

    fn predict(&self, applied: &[Applied]) -> Result<Series, ModelError> {
        let columns: Vec<Vec<f64>> = self
            .designs(applied)?
            .iter()
            .map(|d| d.evaluate(applied))
            .collect();
        let mut out = Series::with_capacity(columns.len(), self.keep.len());
        let mut row = vec![0.0; columns.len()];
        for &i in &self.keep {
            for (r, c) in row.iter_mut().zip(&columns) {
                *r = c.get(i).copied().unwrap_or(f64::NAN);
            }
            out.push(&row)?;
        }
        Ok(out)
    }

    fn polish(&self, applied: &[Applied], mask: &[bool]) -> Option<Vec<Applied>> {
        let designs = self.designs(applied).ok()?;
        let mut polished = applied.to_vec();
        for (signal, design) in designs.iter().enumerate() {
            let pick = |x: &[f64]| -> Vec<f64> {
                self.keep
                    .iter()
                    .map(|i| x.get(*i).copied().unwrap_or(0.0))
                    .collect()
            };
            let known = pick(&design.known);
            let target: Vec<f64> = self
                .data
                .observed
                .column(signal)
                .iter()
                .zip(&known)
                .map(|(o, k)| o - k)
                .collect();
            let picked: Vec<Vec<f64>> = design.terms.iter().map(|t| pick(&t.column)).collect();
            let columns: Vec<&[f64]> = picked.iter().map(Vec::as_slice).collect();
            let theta = solve(&columns, &target, mask);
            for (term, coefficient) in design.terms.iter().zip(theta) {
                let parameter = self.data.candidates[polished[term.effect].candidate]
                    .parameters
                    .get(term.parameter)?;
                let value = match term.link {
                    Link::Direct => coefficient,
                    Link::Reciprocal if coefficient > 0.0 => 1.0 / coefficient,
                    Link::Reciprocal => parameter.max,
                };
                *polished[term.effect].values.get_mut(term.parameter)? =
                    value.clamp(parameter.min, parameter.max);
            }
        }
        Some(polished)
    }

    fn starts(&self, candidate: usize, _hints: &Hints) -> Vec<Vec<f64>> {
        match self.data.candidates.get(candidate).map(|c| c.name) {
            // Only linear parameters: least squares finds them from anywhere.
            Some(RIGID | "viscous_friction" | "coulomb_friction" | "asymmetric_friction") => {
                let dimension = self.data.candidates[candidate].parameters.len();
                vec![vec![0.5; dimension]]
            }
            // One searched parameter (`fs` is solved): a fine grid on `vs`.
            Some("stribeck_friction") => grid(1, 9).into_iter().map(|u| vec![0.5, u[0]]).collect(),
            // Rounded readings: the step is the lattice they sit on (off
            // it the effect does nothing, so a grid would find nothing).
            Some("quantization") => {
                let parameter = &self.data.candidates[candidate].parameters[0];
                encoder_step(&self.raw_q)
                    .map(|step| vec![vec![parameter.unit_of(step)]])
                    .unwrap_or_else(|| grid(1, 3))
            }
            Some(_) => grid(1, 17),
            None => Vec::new(),
        }
    }
}
