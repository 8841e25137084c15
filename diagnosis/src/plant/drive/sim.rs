//! A simulated single-axis drive under position control, for the blind
//! self-check: a rigid carriage (EMPS-like: 95 kg, −3 N offset) moved by
//! the EMPS position controller along an EMPS-like reference, with any
//! set of withheld effects and seeded noise, logged at 1 kHz in the
//! drive-log format.
//!
//! # Theory of operation
//! The carriage obeys M q̈ = tau − friction(q̇) − offset + f_ext,
//! integrated by semi-implicit Euler at [`SUBSTEPS`] steps per sample. The
//! controller runs once per sample on the *measured* position:
//! tau = G kv (kp (ref − q_m) − v_m), v_m the backward difference of q_m
//! (EMPS gains: G = 35.15 N/V, kp = 160.18 1/s, kv = 243.45 V s/m).
//! The effects act as `super::effects` describes, with physics the model
//! only approximates where a real drive would:
//! * friction acts on the true velocity, the model sees a filtered one;
//! * `latency`: the logged force is the applied force `delay` earlier;
//! * `quantization`: the encoder rounds q to `step`, and the controller
//!   sees the rounded reading;
//! * `compliance` and `backlash` deflect the load side kinematically:
//!   q_load = q − tau / k, or the play operator of q (the load carries no
//!   mass of its own);
//! * noise: encoder σ [`POSITION_NOISE`] on q and q_load (replaced by
//!   the rounding when `quantization` is withheld), force σ
//!   [`FORCE_NOISE`] on the logged tau.

use super::effects::play;
use super::log::DriveLog;
use limb_sim::noise::Gaussian;

/// Sample interval of the log [s] (1 kHz, as EMPS).
pub const INTERVAL: f64 = 1e-3;
/// Integration steps per sample.
pub const SUBSTEPS: usize = 10;
/// Carriage mass [kg].
pub const MASS: f64 = 95.0;
/// Constant force on the carriage [N] (the nominal offset is its negative).
pub const OFFSET: f64 = -3.0;
/// Encoder noise σ [m].
pub const POSITION_NOISE: f64 = 1e-7;
/// Force measurement noise σ [N].
pub const FORCE_NOISE: f64 = 0.5;
/// Controller: actuator gain [N/V], position gain [1/s], velocity gain
/// [V s/m] (EMPS).
const GAINS: (f64, f64, f64) = (35.1507, 160.18, 243.45);
/// Sign smoothing of the simulated friction [m/s]: the model's own, so
/// that a withheld Coulomb law is one the candidates can represent (a
/// sharper simulated sign is represented by Coulomb plus a narrow Stribeck
/// term, and the self-check would count that as a wrong extra).
const SIGN_SMOOTHING: f64 = super::effects::COULOMB_SMOOTHING;

/// One withheld effect with its true parameters (units of
/// [`super::effects`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Truth {
    /// F = fv v.
    Viscous(f64),
    /// F = fc sgn v.
    Coulomb(f64),
    /// F = dc |sgn v| + dv |v|.
    Asymmetric(f64, f64),
    /// F = fs exp(−(v/vs)²) sgn v.
    Stribeck(f64, f64),
    /// Logged force delayed by this many seconds.
    Latency(f64),
    /// Encoder step [m].
    Quantization(f64),
    /// Transmission stiffness [N/m].
    Compliance(f64),
    /// Dead band [m].
    Backlash(f64),
}

impl Truth {
    /// The effect's name as the diagnosis uses it.
    pub fn name(&self) -> &'static str {
        match self {
            Truth::Viscous(_) => "viscous_friction",
            Truth::Coulomb(_) => "coulomb_friction",
            Truth::Asymmetric(..) => "asymmetric_friction",
            Truth::Stribeck(..) => "stribeck_friction",
            Truth::Latency(_) => "latency",
            Truth::Quantization(_) => "quantization",
            Truth::Compliance(_) => "compliance",
            Truth::Backlash(_) => "backlash",
        }
    }

    fn friction(&self, v: f64) -> f64 {
        let sign = (v / SIGN_SMOOTHING).tanh();
        match *self {
            Truth::Viscous(fv) => fv * v,
            Truth::Coulomb(fc) => fc * sign,
            Truth::Asymmetric(dc, dv) => dc * sign.abs() + dv * v.abs(),
            Truth::Stribeck(fs, vs) => fs * (-(v / vs).powi(2)).exp() * sign,
            _ => 0.0,
        }
    }
}

/// An EMPS-like reference: strokes between positions in [0, 0.24] m,
/// each a minimum-jerk move of 1.2–2.5 s followed by a 0.2–0.6 s dwell,
/// drawn from `seed`, for `duration` seconds.
pub fn reference(seed: u64, duration: f64) -> Vec<f64> {
    let mut draw = Uniform::new(seed);
    let samples = (duration / INTERVAL).round() as usize;
    let mut out = Vec::with_capacity(samples);
    let mut from = 0.0;
    while out.len() < samples {
        let to = draw.between(0.0, 0.24);
        let moving = (draw.between(1.2, 2.5) / INTERVAL) as usize;
        let dwell = (draw.between(0.2, 0.6) / INTERVAL) as usize;
        for k in 0..moving {
            let s = k as f64 / moving as f64;
            out.push(from + (to - from) * s.powi(3) * (10.0 - 15.0 * s + 6.0 * s * s));
        }
        out.extend(std::iter::repeat_n(to, dwell));
        from = to;
    }
    out.truncate(samples);
    out
}

/// Uniform draws in (0, 1] from the Gaussian generator (Φ of a draw).
pub struct Uniform(Gaussian);

impl Uniform {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        Self(Gaussian::new(seed))
    }

    /// A draw in [0, 1].
    pub fn unit(&mut self) -> f64 {
        let z = self.0.sample(1.0);
        (0.5 * (1.0 + libm::erf(z / std::f64::consts::SQRT_2))).clamp(0.0, 1.0)
    }

    /// A draw in [lo, hi].
    pub fn between(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// A draw in [lo, hi], even in the logarithm (lo > 0).
    pub fn log_between(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }
}

/// Simulates the drive following `reference` (one value per sample) with
/// the `truth` effects, noise drawn from `seed`. The log always has
/// `q_load` (equal to q up to noise unless a transmission effect acts).
pub fn simulate(reference: &[f64], truth: &[Truth], seed: u64) -> DriveLog {
    let mut noise = Gaussian::new(seed);
    let (gain, kp, kv) = GAINS;
    let step = truth.iter().find_map(|t| match t {
        Truth::Quantization(s) => Some(*s),
        _ => None,
    });
    let delay = truth.iter().find_map(|t| match t {
        Truth::Latency(d) => Some((d / INTERVAL).round() as usize),
        _ => None,
    });
    let read = |q: f64, noise: &mut Gaussian| match step {
        Some(s) => (q / s).round() * s,
        None => q + noise.sample(POSITION_NOISE),
    };
    let dt = INTERVAL / SUBSTEPS as f64;
    let (mut q, mut v) = (reference.first().copied().unwrap_or(0.0), 0.0);
    let mut previous = read(q, &mut noise);
    let n = reference.len();
    let mut log = DriveLog {
        t: Vec::with_capacity(n),
        reference: reference.to_vec(),
        q: Vec::with_capacity(n),
        tau: Vec::with_capacity(n),
        q_load: None,
        f_ext: None,
    };
    let mut applied = Vec::with_capacity(n);
    for (k, target) in reference.iter().enumerate() {
        let measured = read(q, &mut noise);
        let tau = gain * kv * (kp * (target - measured) - (measured - previous) / INTERVAL);
        previous = measured;
        log.t.push(k as f64 * INTERVAL);
        log.q.push(measured);
        applied.push((tau, q));
        for _ in 0..SUBSTEPS {
            let friction: f64 = truth.iter().map(|t| t.friction(v)).sum();
            let a = (tau - friction - OFFSET) / MASS;
            v += a * dt;
            q += v * dt;
        }
    }
    let lag = delay.unwrap_or(0);
    log.tau = (0..n)
        .map(|k| applied[k.saturating_sub(lag)].0 + noise.sample(FORCE_NOISE))
        .collect();
    let shaft: Vec<f64> = applied.iter().map(|a| a.1).collect();
    let mut load = shaft.clone();
    for t in truth {
        match *t {
            Truth::Compliance(k) => {
                for (l, a) in load.iter_mut().zip(&applied) {
                    *l -= a.0 / k;
                }
            }
            Truth::Backlash(width) => load = play(&load, width),
            _ => {}
        }
    }
    log.q_load = Some(load.iter().map(|l| read(*l, &mut noise)).collect());
    log
}

#[cfg(test)]
mod tests {
    use super::{reference, simulate, Truth};

    #[test]
    fn the_controller_tracks_the_reference() {
        let r = reference(1, 6.0);
        assert_eq!(r.len(), 6000);
        assert!(r.iter().all(|x| (-1e-9..=0.24 + 1e-9).contains(x)));
        let log = simulate(&r, &[Truth::Viscous(200.0), Truth::Coulomb(20.0)], 2);
        let worst = log
            .q
            .iter()
            .zip(&r)
            .map(|(q, r)| (q - r).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.01, "{worst}");
        assert!(log.tau.iter().all(|t| t.is_finite()));
    }
}
