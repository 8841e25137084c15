//! `spasticity`: a velocity-dependent increase in the elbow's resistance
//! to stretch (Lance 1980: "a motor disorder characterised by a
//! velocity-dependent increase in tonic stretch reflexes"), as a
//! stretch reflex with a threshold speed and a loop delay.
//!
//! # Model
//! The reflex sees the elbow's speed [`REFLEX_DELAY`] ago and, beyond
//! the threshold speed, resists it in proportion to the excess (the
//! threshold-and-gain form of the stretch-reflex models of Jobin &
//! Levin 2000, "Regulation of stretch reflex threshold in elbow flexors
//! in children with cerebral palsy", Dev. Med. Child Neurol. 42:531-540,
//! and of the velocity-threshold models used in tone assessment):
//!
//! ```text
//! v = q̇2(t − δ)
//! τ2 = −gain · sign(v) · max(0, |v| − threshold)              [N m]
//! ```
//!
//! Both directions are resisted (a stretch of the flexors on extension,
//! of the extensors on flexion: the plant's lift flexes the elbow). The
//! shoulder is left alone: the lift moves it slowly.
//!
//! # Magnitudes
//! δ = 40 ms: short- and long-latency stretch reflexes of the arm come
//! 30-60 ms after the stretch. Threshold speeds of a spastic elbow are a
//! few degrees to tens of degrees per second (0.03-1 rad/s); the plant's
//! lift flexes the elbow at 0.1-0.2 rad/s at most, so only the low end
//! shows in it. Gains 0.5-20 N m s/rad (a reflex torque of a few N m at
//! a fast stretch). Allowed: gain 0-50 N m s/rad, threshold 0-2 rad/s.

use super::Parameter;

/// Parameters: gain [N m s/rad], threshold [rad/s].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new(
        "gain",
        "N m s/rad",
        0.0,
        50.0,
        "reflex torque per elbow speed beyond the threshold",
    ),
    Parameter::new(
        "threshold",
        "rad/s",
        0.0,
        2.0,
        "elbow speed at which the stretch reflex starts",
    ),
];

/// Delay of the stretch reflex [s].
pub const REFLEX_DELAY: f64 = 0.04;

/// Velocity-dependent elbow reflex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spasticity {
    /// Gain [N m s/rad].
    pub gain: f64,
    /// Threshold speed [rad/s].
    pub threshold: f64,
}

impl Spasticity {
    /// The delay in integration steps of `dt` [s] (at least one).
    pub fn steps(dt: f64) -> usize {
        (libm::round(REFLEX_DELAY / dt) as usize).max(1)
    }

    /// The reflex torque at the elbow for the elbow speed `delayed`
    /// [rad/s] the reflex sees (δ ago) [N m].
    pub fn torque(&self, delayed: f64) -> f64 {
        let excess = libm::fabs(delayed) - self.threshold;
        if excess > 0.0 {
            -self.gain * excess * delayed.signum()
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Spasticity;

    #[test]
    fn resists_only_beyond_the_threshold() {
        let s = Spasticity {
            gain: 10.0,
            threshold: 0.05,
        };
        assert_eq!(s.torque(0.04), 0.0);
        assert_eq!(s.torque(-0.05), 0.0);
        assert!((s.torque(0.15) + 1.0).abs() < 1e-12);
        assert!((s.torque(-0.15) - 1.0).abs() < 1e-12);
        assert_eq!(Spasticity::steps(0.0005), 80);
    }
}
