//! Zero-phase low-pass filtering and the derivatives of the inverse model.
//!
//! # Theory of operation
//! Encoder positions are differentiated twice for the inverse model
//! tau = M q̈ + …, which amplifies their noise by (2π f)². Positions are
//! therefore low-passed by a second-order Butterworth section (bilinear
//! transform, cut-off `cutoff` Hz) run forward and then backward over the
//! record: the magnitude response is that of a fourth-order Butterworth
//! squared-magnitude (−6 dB at the cut-off) and the phase is exactly zero,
//! so the filtered signal neither leads nor lags the force. Both ends are
//! padded with the record's odd reflection about its end value (as
//! `filtfilt` does), which keeps the end transients out of the record
//! (the end samples themselves keep their own noise).
//! Velocity and acceleration are then centred differences on the real
//! time stamps.
//!
//! The force is passed through the same filter ("parallel filtering" of
//! inverse-dynamics identification): both sides of the inverse model then
//! carry the same band, and the comparison is made in [0, cut-off].
//!
//! The filter assumes even sampling at the record's median interval.

/// Low-passes `x` (sampled every `interval` seconds) with zero phase at
/// `cutoff` Hz (see the module docs). A cut-off at or above the Nyquist
/// frequency, or a non-positive one, leaves `x` unchanged.
pub fn zero_phase(x: &[f64], interval: f64, cutoff: f64) -> Vec<f64> {
    let n = x.len();
    let ratio = cutoff * interval;
    if n < 3 || !(ratio > 0.0 && ratio < 0.5) {
        return x.to_vec();
    }
    // Reflection long enough for the filter to settle: three time
    // constants of the cut-off, at most the record.
    let pad = ((3.0 / ratio).ceil() as usize).clamp(1, n - 1);
    let (first, last) = (x[0], x[n - 1]);
    let mut padded: Vec<f64> = Vec::with_capacity(n + 2 * pad);
    padded.extend((1..=pad).rev().map(|i| 2.0 * first - x[i]));
    padded.extend_from_slice(x);
    padded.extend((1..=pad).map(|i| 2.0 * last - x[n - 1 - i]));
    let section = Section::butterworth(ratio);
    section.run(&mut padded);
    padded.reverse();
    section.run(&mut padded);
    padded.reverse();
    padded[pad..pad + n].to_vec()
}

/// A second-order IIR section y = (b0 x + b1 x₋₁ + b2 x₋₂ − a1 y₋₁ − a2 y₋₂).
struct Section {
    b: [f64; 3],
    a: [f64; 2],
}

impl Section {
    /// Butterworth low-pass at `ratio` = cut-off / sampling rate (in (0, ½)).
    fn butterworth(ratio: f64) -> Self {
        let k = (std::f64::consts::PI * ratio).tan();
        let root2 = std::f64::consts::SQRT_2;
        let norm = 1.0 / (1.0 + root2 * k + k * k);
        let b0 = k * k * norm;
        Self {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - root2 * k + k * k) * norm],
        }
    }

    /// Filters `x` in place, starting at rest at its first value (unit DC
    /// gain, so a constant passes unchanged).
    fn run(&self, x: &mut [f64]) {
        let Some(&start) = x.first() else { return };
        let (mut x1, mut x2, mut y1, mut y2) = (start, start, start, start);
        for v in x.iter_mut() {
            let y =
                self.b[0] * *v + self.b[1] * x1 + self.b[2] * x2 - self.a[0] * y1 - self.a[1] * y2;
            (x2, x1, y2, y1) = (x1, *v, y1, y);
            *v = y;
        }
    }
}

/// Centred-difference derivative of `x` over `t` (one-sided at the ends).
pub fn derivative(x: &[f64], t: &[f64]) -> Vec<f64> {
    let n = x.len().min(t.len());
    (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let dt = t[hi] - t[lo];
            if dt > 0.0 {
                (x[hi] - x[lo]) / dt
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{derivative, zero_phase};
    use std::f64::consts::PI;

    #[test]
    fn passes_slow_motion_without_lag_and_removes_fast_noise() {
        let dt = 0.001;
        let t: Vec<f64> = (0..4000).map(|i| i as f64 * dt).collect();
        let slow: Vec<f64> = t.iter().map(|t| (2.0 * PI * 0.5 * t).sin()).collect();
        let noisy: Vec<f64> = slow
            .iter()
            .enumerate()
            .map(|(i, s)| s + 0.01 * (2.0 * PI * 200.0 * i as f64 * dt).sin())
            .collect();
        let filtered = zero_phase(&noisy, dt, 20.0);
        // The odd reflection pins each end to its own (noisy) sample, so
        // the first and last 0.1 s are not held to the bound.
        let error = (100..3900)
            .map(|i| (filtered[i] - slow[i]).abs())
            .fold(0.0, f64::max);
        assert!(error < 2e-4, "{error}");
        let v = derivative(&filtered, &t);
        assert!((v[2000] - 2.0 * PI * 0.5 * (2.0 * PI * 0.5 * t[2000]).cos()).abs() < 1e-2);
        let constant = zero_phase(&[1.0; 10], dt, 20.0);
        assert!(constant.iter().all(|c| (c - 1.0).abs() < 1e-12));
    }
}
