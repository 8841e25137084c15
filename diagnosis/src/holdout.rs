//! Which samples a fit may see and which are held out to score it.
//!
//! One log is split on its time axis into blocks of [`HoldOut::block`]
//! seconds that alternate fit, held-out, fit, ... (from the first
//! sample). Alternating blocks rather than one cut keep every phase of the
//! motion (rest, lift, hold) on both sides, so an effect that shows only
//! in one phase (a slip at 10 s, the hold's static deflection) is both
//! fitted and scored. Two logs of the same system (a fit run and a
//! validation run) need no split: each is used whole.

use thiserror::Error;

/// The alternating-block split of one log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoldOut {
    /// Block length [s].
    pub block: f64,
    /// Fewest samples each side must hold.
    pub min_samples: usize,
}

impl Default for HoldOut {
    /// 1 s blocks and at least 100 samples on each side (1 s at the arm
    /// logs' 100 Hz).
    fn default() -> Self {
        Self {
            block: 1.0,
            min_samples: 100,
        }
    }
}

/// A log too short (or too sparse) to hold anything out.
#[derive(Clone, Debug, PartialEq, Error)]
#[error(
    "the log is too short to hold data out: {fit} fit and {held} held-out samples \
     in {block} s blocks (each side needs at least {needed} samples and two blocks)"
)]
pub struct TooShort {
    /// Samples on the fit side.
    pub fit: usize,
    /// Samples on the held-out side.
    pub held: usize,
    /// Block length [s].
    pub block: f64,
    /// Samples each side needs.
    pub needed: usize,
}

/// Fit and held-out masks over one log's samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Masks {
    /// `true` for samples the fit sees.
    pub fit: Vec<bool>,
    /// `true` for samples held out from the fit.
    pub held: Vec<bool>,
}

impl HoldOut {
    /// Splits samples at `times` [s].
    ///
    /// # Errors
    /// [`TooShort`] when either side has fewer than `min_samples` samples
    /// or spans fewer than two blocks, or the block length is not positive.
    pub fn split(&self, times: &[f64]) -> Result<Masks, TooShort> {
        let start = times.first().copied().unwrap_or(0.0);
        let blocks: Vec<u64> = times
            .iter()
            .map(|t| {
                let b = ((t - start) / self.block).floor();
                if b.is_finite() && b >= 0.0 {
                    b as u64
                } else {
                    0
                }
            })
            .collect();
        let fit: Vec<bool> = blocks.iter().map(|b| b % 2 == 0).collect();
        let held: Vec<bool> = fit.iter().map(|f| !f).collect();
        let count = |mask: &[bool]| mask.iter().filter(|m| **m).count();
        let last_block = blocks.last().copied().unwrap_or(0);
        let (fit_count, held_count) = (count(&fit), count(&held));
        let usable = self.block > 0.0
            && self.block.is_finite()
            && last_block >= 3
            && fit_count >= self.min_samples
            && held_count >= self.min_samples;
        if !usable {
            return Err(TooShort {
                fit: fit_count,
                held: held_count,
                block: self.block,
                needed: self.min_samples,
            });
        }
        Ok(Masks { fit, held })
    }
}

#[cfg(test)]
mod tests {
    use super::HoldOut;

    #[test]
    fn alternates_one_second_blocks() {
        let times: Vec<f64> = (0..500).map(|i| i as f64 * 0.01).collect();
        let masks = HoldOut::default().split(&times).unwrap();
        assert!(masks.fit[0] && masks.fit[99] && masks.held[100] && masks.held[199]);
        assert!(masks.fit[200] && masks.held[300] && masks.fit[400]);
        assert!(masks.fit.iter().zip(&masks.held).all(|(f, h)| f != h));
    }

    #[test]
    fn refuses_a_log_too_short_to_hold_out() {
        let times: Vec<f64> = (0..250).map(|i| i as f64 * 0.01).collect();
        let error = HoldOut::default().split(&times).unwrap_err();
        assert_eq!(error.needed, 100);
        assert!(HoldOut::default().split(&[]).is_err());
    }
}
