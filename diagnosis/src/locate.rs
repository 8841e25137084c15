//! Where the gap lies: in which signals, over which stretch of time, and
//! in which frequency band when it is periodic.
//!
//! # Theory of operation
//! From the scaled residual r of the nominal sim ([`crate::residual`]):
//! * **Signals**: a signal carries a gap when its sum of r² exceeds what
//!   noise gives by more than [`SIGNIFICANCE`] standard deviations
//!   (Σr² of n noise terms is n ± sqrt(2n) for a floor of 1). With an
//!   unknown noise (floor 0) the signals holding at least a tenth of the
//!   largest mean square are named. Strongest first.
//! * **Time**: e(t) = Σ over the named signals of (r² − floor), averaged
//!   over a centred window of [`WINDOW`] seconds; the gap lies from the
//!   first to the last time e exceeds both the window's noise level
//!   (SIGNIFICANCE · floor · sqrt(2 / terms)) and [`PEAK_SHARE`] of e's
//!   peak (so a gap that grows a hundredfold is placed where it starts).
//! * **Frequency**: the Hann-windowed periodogram of each named signal's
//!   residual (samples taken as evenly spaced at the median interval);
//!   above [`LOWEST_BAND`] Hz (slower is the motion itself), the bins
//!   around the peak that stay above a quarter of it form the band. It is
//!   reported when it holds at least [`BAND_SHARE`] of the residual's
//!   power and its peak stands 10× above the median bin. The signal is
//!   zero-padded to [`PADDING`]× its length and the peak interpolated
//!   (parabola through the log power of the peak bin and its neighbours),
//!   so the peak frequency — the start of a periodic effect's fit — is
//!   far finer than 1 / duration.

use crate::model::{Hints, Model, Series};
use rustfft::{num_complex::Complex, FftPlanner};
use serde::Serialize;

/// Standard deviations of excess over noise that make a gap significant.
pub const SIGNIFICANCE: f64 = 5.0;
/// Smoothing window for the time localisation [s].
pub const WINDOW: f64 = 0.5;
/// Share of the smoothed excess's peak the time window starts at.
pub const PEAK_SHARE: f64 = 0.01;
/// Slowest frequency a band may start at [Hz].
pub const LOWEST_BAND: f64 = 0.15;
/// Zero-padding factor of the periodogram.
pub const PADDING: usize = 8;
/// Share of the residual's power a band must hold to be reported.
pub const BAND_SHARE: f64 = 0.3;

/// Where the gap lies.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Location {
    /// Signals carrying the gap, strongest first (empty: none does).
    pub signals: Vec<String>,
    /// Start of the stretch holding the gap [s] (`None`: no gap).
    pub t_start: Option<f64>,
    /// End of it [s].
    pub t_end: Option<f64>,
    /// Frequency band [Hz] when the gap is periodic.
    pub band_hz: Option<[f64; 2]>,
}

/// Locates the gap in `residual` (scaled, all samples) and returns hints
/// for the fits.
pub fn locate(model: &dyn Model, residual: &Series) -> (Location, Hints) {
    let floor = model.noise_floor();
    let samples = residual.samples();
    let mut excess: Vec<(usize, f64)> = (0..residual.signals())
        .map(|s| {
            let column = residual.column(s);
            let sum: f64 = column.iter().map(|r| r * r).sum();
            let n = column.len().max(1) as f64;
            let z = if floor > 0.0 {
                (sum - n * floor) / (floor * (2.0 * n).sqrt())
            } else {
                sum / n
            };
            (s, z)
        })
        .filter(|(_, z)| z.is_finite())
        .collect();
    excess.sort_by(|a, b| b.1.total_cmp(&a.1));
    let peak = excess.first().map_or(0.0, |e| e.1);
    let named: Vec<usize> = excess
        .iter()
        .filter(|(_, z)| {
            if floor > 0.0 {
                *z > SIGNIFICANCE
            } else {
                *z > 0.0 && *z >= 0.1 * peak
            }
        })
        .map(|(s, _)| *s)
        .collect();
    let mut location = Location {
        signals: named
            .iter()
            .map(|s| model.signals()[*s].name.to_string())
            .collect(),
        ..Location::default()
    };
    let mut hints = Hints::default();
    if named.is_empty() || samples == 0 {
        return (location, hints);
    }
    let times = model.times();
    let interval = median_interval(times);
    let half = ((WINDOW / interval / 2.0).round() as usize).max(1);
    let per_sample: Vec<f64> = (0..samples)
        .map(|i| {
            let row = residual.row(i);
            named.iter().map(|s| row[*s] * row[*s] - floor).sum()
        })
        .collect();
    let mut prefix = vec![0.0; samples + 1];
    for (i, v) in per_sample.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    let smoothed: Vec<f64> = (0..samples)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(half), (i + half + 1).min(samples));
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect();
    let top = smoothed.iter().copied().fold(0.0, f64::max);
    let terms = ((2 * half + 1) * named.len()) as f64;
    let threshold = (SIGNIFICANCE * floor * (2.0 / terms).sqrt()).max(PEAK_SHARE * top);
    let above = |v: &f64| *v > threshold;
    if let (Some(first), Some(last)) = (
        smoothed.iter().position(above),
        smoothed.iter().rposition(above),
    ) {
        location.t_start = Some(times[first]);
        location.t_end = Some(times[last]);
        hints.onset = Some(times[first]);
        hints.end = Some(times[last]);
    }
    let spectra: Vec<Spectrum> = named
        .iter()
        .take(2)
        .filter_map(|s| spectrum(&residual.column(*s), interval))
        .collect();
    // The fit of a periodic effect starts at the strongest signal's peak
    // even when it is not a clean band (a strong torque on an arm that
    // touches the table answers with harmonics too).
    hints.frequency = spectra.first().map(|s| s.peak);
    if let Some(strongest) = spectra
        .iter()
        .filter(|s| s.stands_out)
        .max_by(|a, b| a.share.total_cmp(&b.share))
    {
        hints.frequency = Some(strongest.peak);
        hints.band = Some(strongest.band);
        location.band_hz = Some(strongest.band);
    }
    (location, hints)
}

/// Median sample interval [s] (1 when there are fewer than two samples).
pub fn median_interval(times: &[f64]) -> f64 {
    let mut d: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return 1.0;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

/// The spectral peak of a residual above [`LOWEST_BAND`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Spectrum {
    /// Interpolated peak frequency [Hz].
    peak: f64,
    /// Bins around the peak above a quarter of it [Hz].
    band: [f64; 2],
    /// Share of the residual's power in the band.
    share: f64,
    /// The band holds [`BAND_SHARE`] and its peak stands 10× above the
    /// median bin: it is reported.
    stands_out: bool,
}

/// The spectrum of `signal` sampled every `interval` seconds (`None` for
/// too short a signal or no power).
fn spectrum(signal: &[f64], interval: f64) -> Option<Spectrum> {
    let n = signal.len();
    if n < 16 || interval.is_nan() || interval <= 0.0 {
        return None;
    }
    let mean = signal.iter().sum::<f64>() / n as f64;
    let padded = n * PADDING;
    let mut buffer: Vec<Complex<f64>> = signal
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64).cos();
            Complex::new((v - mean) * w, 0.0)
        })
        .chain(std::iter::repeat(Complex::new(0.0, 0.0)))
        .take(padded)
        .collect();
    FftPlanner::new()
        .plan_fft_forward(padded)
        .process(&mut buffer);
    let resolution = 1.0 / (padded as f64 * interval);
    let power: Vec<f64> = buffer[..padded / 2].iter().map(|c| c.norm_sqr()).collect();
    let total: f64 = power.iter().skip(1).sum();
    let lowest = ((LOWEST_BAND / resolution).ceil() as usize).max(1);
    if total <= 0.0 || lowest + 1 >= power.len() {
        return None;
    }
    let (peak, peak_power) = power
        .iter()
        .enumerate()
        .skip(lowest)
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(k, p)| (k, *p))?;
    let mut sorted: Vec<f64> = power[lowest..].to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let (mut lo, mut hi) = (peak, peak);
    while lo > lowest && power[lo - 1] > peak_power / 4.0 {
        lo -= 1;
    }
    while hi + 1 < power.len() && power[hi + 1] > peak_power / 4.0 {
        hi += 1;
    }
    // Parabolic interpolation of the log power around the peak bin.
    let offset = match (power.get(peak.wrapping_sub(1)), power.get(peak + 1)) {
        (Some(&left), Some(&right)) if left > 0.0 && right > 0.0 && peak > 0 => {
            let (a, b, c) = (left.ln(), peak_power.ln(), right.ln());
            let denominator = a - 2.0 * b + c;
            if denominator < 0.0 {
                (0.5 * (a - c) / denominator).clamp(-0.5, 0.5)
            } else {
                0.0
            }
        }
        _ => 0.0,
    };
    let share = power[lo..=hi].iter().sum::<f64>() / total;
    Some(Spectrum {
        peak: (peak as f64 + offset) * resolution,
        band: [lo as f64 * resolution, hi as f64 * resolution],
        share,
        stands_out: share >= BAND_SHARE && peak_power > 10.0 * median,
    })
}

#[cfg(test)]
mod tests {
    use super::spectrum;

    #[test]
    fn finds_a_sinusoid_and_ignores_a_slow_drift() {
        let interval = 0.01;
        let sine: Vec<f64> = (0..3000)
            .map(|i| (2.0 * std::f64::consts::PI * 1.3 * i as f64 * interval).sin())
            .collect();
        let s = spectrum(&sine, interval).unwrap();
        let [lo, hi] = s.band;
        assert!((s.peak - 1.3).abs() < 0.002 && lo <= 1.3 && 1.3 <= hi && s.share > 0.8);
        assert!(s.stands_out);
        let drift: Vec<f64> = (0..3000).map(|i| (i as f64 * interval).powi(2)).collect();
        assert!(!spectrum(&drift, interval).unwrap().stands_out);
    }
}
