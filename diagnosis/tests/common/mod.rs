//! What the arm diagnosis's regression tests share: a log of the
//! reference plant with withheld effects (as the blind self-check draws
//! one), diagnosed without its arm lengths.

use limb_diagnosis::plant::arm::blind::simulate;
use limb_diagnosis::plant::arm::{diagnose, ArmBuild, Diagnosis, Lengths};
use limb_sim::effects::Effect;

/// The log of arm (`l1`, `l2`) [m] with noise seed `seed` and `effects`,
/// diagnosed with the lengths fitted (two threads).
pub fn diagnosed(l1: f64, l2: f64, seed: u64, effects: &[Effect]) -> Diagnosis {
    let records = simulate(l1, l2, seed, effects).unwrap();
    diagnose(Lengths::Fitted, ArmBuild::Rod, &records, 2, &|_| {})
        .unwrap()
        .diagnosis
}

/// The corrected arm's larger length error against (`l1`, `l2`) [m].
pub fn arm_error(d: &Diagnosis, l1: f64, l2: f64) -> f64 {
    (d.arm.l1 - l1).abs().max((d.arm.l2 - l2).abs())
}
