//! `mass_mismatch`: the forearm's mass is `factor` times the modelled
//! 1.317 kg (its inertia scales with it, as a uniform rod's does).

use super::Parameter;

/// Parameters: factor [1].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "factor",
    "1",
    0.2,
    5.0,
    "forearm mass / modelled mass",
)];

/// Forearm mass error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassMismatch {
    /// Mass ratio [1].
    pub factor: f64,
}
