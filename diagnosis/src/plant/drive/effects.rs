//! The candidate unmodelled effects of a drive (`spec/drive.md`), with
//! their physics and bounded parameters.
//!
//! Units are those of a linear axis (m, N); for a rotary axis read rad for
//! m and N m for N (the mass is then an inertia, kg m²). v = q̇ and a = q̈
//! are the zero-phase-filtered velocity and acceleration
//! ([`super::filter`]); sgn(v) = tanh(v / [`COULOMB_SMOOTHING`]) is the
//! sign with a smooth crossing.
//!
//! | name | added to the prediction | parameters |
//! |---|---|---|
//! | `rigid` (nominal) | tau = M a + offset − f_ext | `mass`, `offset` (and `transmission_offset`: q − q_load = constant) |
//! | `viscous_friction` | + Fv v | `fv` [N s/m] ≥ 0 |
//! | `coulomb_friction` | + Fc sgn(v) | `fc` [N] ≥ 0 |
//! | `asymmetric_friction` | + Dc abs(sgn v) + Dv abs(v) | `dc` [N], `dv` [N s/m]: half the difference between the forward and backward Coulomb levels and slopes (the mean asymmetry while moving is the nominal offset; `dc` is what moving adds over standing) |
//! | `stribeck_friction` | + Fs exp(−(v / vs)²) sgn(v) | `fs` [N] ≥ 0, `vs` [m/s] |
//! | `latency` | the whole force prediction delayed: tau(t) = pred(t − d) | `delay` [s] |
//! | `quantization` | positions read through an encoder of step Δ: the kinematics are rebuilt from the instants the reading changes (the true position crosses the level boundary there) | `step` [m] |
//! | `compliance` (with `q_load`) | q − q_load = offset + tau / k: the transmission deflects in proportion to the force it carries | `k` [N/m] |
//! | `backlash` (with `q_load`) | q − q_load = offset + (q − play(q)): the load follows the actuator through a dead band of width b | `width` [m] |
//!
//! f_ext is a force on the load along +q: the load's balance
//! M a = tau − friction + f_ext gives tau = M a + friction − f_ext.
//!
//! `mass`, `offset`, `fv`, `fc`, `dc`, `dv`, `fs`, 1/`k` and the
//! transmission offset enter linearly and are solved by least squares
//! ([`super::model`]); `vs`, `delay`, `step` and `width` are searched.

use crate::model::{Candidate, Parameter, Scale};

/// Velocity over which the Coulomb sign goes from −0.76 to +0.76 (tanh of
/// ±1) [m/s or rad/s]: far below the motions of a positioning drive (EMPS
/// moves at up to 0.2 m/s) and above the encoder's velocity noise.
pub const COULOMB_SMOOTHING: f64 = 1e-3;

/// Name of the nominal sim's own candidate.
pub const RIGID: &str = "rigid";

/// The candidates, `rigid` first (the nominal sim's base). `compliance`
/// and `backlash` need a load-side encoder and are offered only
/// `with_load`.
///
/// Ranges: masses up to 10 t (or kg m²) and forces up to 100 kN cover
/// any single-axis drive a person's arm is moved by; `delay` from 0.1 ms
/// (a tenth of a 1 kHz sample) to 0.2 s; encoder steps from 10 nm to
/// 1 mm; transmission stiffness from 100 N/m to 10⁹ N/m; dead bands from
/// 1 µm to 10 mm.
pub fn candidates(with_load: bool) -> Vec<Candidate> {
    use Scale::Logarithmic;
    let one = |name, parameters| Candidate { name, parameters };
    let parameter = Parameter::new;
    let mut rigid = vec![
        parameter(
            "mass",
            "kg",
            0.0,
            1e4,
            "moving mass (inertia of a rotary axis)",
        ),
        parameter(
            "offset",
            "N",
            -1e5,
            1e5,
            "constant force (mean friction asymmetry, gravity)",
        ),
    ];
    if with_load {
        rigid.push(parameter(
            "transmission_offset",
            "m",
            -1.0,
            1.0,
            "constant difference q − q_load",
        ));
    }
    let mut all = vec![
        one(RIGID, rigid),
        one(
            "viscous_friction",
            vec![parameter(
                "fv",
                "N s/m",
                0.0,
                1e5,
                "viscous friction coefficient",
            )],
        ),
        one(
            "coulomb_friction",
            vec![parameter("fc", "N", 0.0, 1e5, "Coulomb friction level")],
        ),
        one(
            "asymmetric_friction",
            vec![
                parameter(
                    "dc",
                    "N",
                    -1e5,
                    1e5,
                    "half the forward less backward Coulomb level",
                ),
                parameter(
                    "dv",
                    "N s/m",
                    -1e5,
                    1e5,
                    "half the forward less backward viscous slope",
                ),
            ],
        ),
        one(
            "stribeck_friction",
            vec![
                parameter("fs", "N", 0.0, 1e5, "Stribeck excess at standstill"),
                parameter("vs", "m/s", 1e-4, 1.0, "Stribeck velocity").scaled(Logarithmic),
            ],
        ),
        one(
            "latency",
            vec![
                parameter("delay", "s", 1e-4, 0.2, "delay of the measured force")
                    .scaled(Logarithmic),
            ],
        ),
        one(
            "quantization",
            vec![parameter("step", "m", 1e-8, 1e-3, "encoder step").scaled(Logarithmic)],
        ),
    ];
    if with_load {
        all.push(one(
            "compliance",
            vec![parameter("k", "N/m", 1e2, 1e9, "transmission stiffness").scaled(Logarithmic)],
        ));
        all.push(one(
            "backlash",
            vec![parameter("width", "m", 1e-6, 1e-2, "transmission dead band").scaled(Logarithmic)],
        ));
    }
    all
}

/// sgn(v) with the smooth crossing of [`COULOMB_SMOOTHING`].
pub fn smooth_sign(v: f64) -> f64 {
    (v / COULOMB_SMOOTHING).tanh()
}

/// The play (dead-band) operator: the follower stays put until `q` is
/// more than `width / 2` away, then is dragged along at that distance.
/// Starts at `q[0]`.
pub fn play(q: &[f64], width: f64) -> Vec<f64> {
    let half = 0.5 * width.max(0.0);
    let mut follower = q.first().copied().unwrap_or(0.0);
    q.iter()
        .map(|&x| {
            follower = follower.clamp(x - half, x + half);
            follower
        })
        .collect()
}

/// Positions read through an encoder of resolution `step`, rebuilt from
/// the instants the reading changes: between samples i−1 and i the level
/// index changes, so the true position crossed the boundary between the
/// two levels at about (t[i−1] + t[i]) / 2; the rebuilt position
/// interpolates linearly between such crossings (and holds the reading
/// before the first and after the last).
///
/// Readings that do not sit on the lattice of `step` (within a millionth
/// of a step) were not rounded at that step: they are returned unchanged,
/// so the effect changes nothing unless the log really is quantized.
pub fn dequantize(q: &[f64], t: &[f64], step: f64) -> Vec<f64> {
    let on_lattice = |x: &f64| ((x / step) - (x / step).round()).abs() < 1e-6;
    if step.is_nan() || step <= 0.0 || q.len() != t.len() || !q.iter().all(on_lattice) {
        return q.to_vec();
    }
    let level: Vec<f64> = q.iter().map(|x| (x / step).round()).collect();
    let knots: Vec<(f64, f64)> = (1..q.len())
        .filter(|&i| level[i] != level[i - 1])
        .map(|i| {
            (
                0.5 * (t[i - 1] + t[i]),
                0.5 * (level[i - 1] + level[i]) * step,
            )
        })
        .collect();
    let mut next = 0usize;
    t.iter()
        .zip(q)
        .map(|(&time, &reading)| {
            while next < knots.len() && knots[next].0 <= time {
                next += 1;
            }
            match (
                next.checked_sub(1).and_then(|k| knots.get(k)),
                knots.get(next),
            ) {
                (Some(&(t0, x0)), Some(&(t1, x1))) => x0 + (x1 - x0) * (time - t0) / (t1 - t0),
                _ => reading,
            }
        })
        .collect()
}

/// The encoder step the readings `q` suggest: the smallest non-zero change
/// between consecutive readings (of a quantized log, one step; of an
/// unrounded one, something far below any step that would matter).
pub fn encoder_step(q: &[f64]) -> Option<f64> {
    q.windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0 && d.is_finite())
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::{candidates, dequantize, encoder_step, play};

    #[test]
    fn every_parameter_is_bounded_and_load_effects_need_a_load() {
        for with_load in [false, true] {
            let all = candidates(with_load);
            assert!(all.iter().flat_map(|c| &c.parameters).all(|p| p.is_valid()));
            assert_eq!(all.iter().any(|c| c.name == "compliance"), with_load);
        }
    }

    #[test]
    fn play_holds_inside_the_dead_band() {
        let out = play(&[0.0, 0.4, 1.0, 0.8, 0.0], 1.0);
        assert_eq!(out, vec![0.0, 0.0, 0.5, 0.5, 0.5]);
    }

    #[test]
    fn dequantize_recovers_a_slow_ramp() {
        let t: Vec<f64> = (0..1000).map(|i| i as f64 * 0.001).collect();
        let truth: Vec<f64> = t.iter().map(|t| 0.01 * t).collect();
        let read: Vec<f64> = truth.iter().map(|x| (x / 1e-4).round() * 1e-4).collect();
        let rebuilt = dequantize(&read, &t, 1e-4);
        let error = |x: &[f64]| {
            (100..900)
                .map(|i| (x[i] - truth[i]).abs())
                .fold(0.0, f64::max)
        };
        // Crossings are placed to half a sample (0.5 ms × 0.01 m/s); the
        // reading itself is off by up to half a step (50 µm).
        assert!(error(&rebuilt) < 6e-6 && error(&read) > 4e-5);
        assert!((encoder_step(&read).unwrap_or(0.0) - 1e-4).abs() < 1e-12);
        // Off the lattice: nothing to rebuild.
        assert_eq!(dequantize(&truth, &t, 1e-4), truth);
    }
}
