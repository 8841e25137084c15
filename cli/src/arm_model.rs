//! `--arm rod|person`: which arm the kernel's estimator assumes, as the
//! shoulder-rhythm prior of its validation limits
//! (`ValidationLimits::shoulder_rhythm`, `spec/human-arm-model.md`).
//!
//! The prior cannot be learnt from one lift: a shoulder that moves linearly
//! with elevation leaves the elbow's path a circle to within 0.2 mm, only
//! shifted (25 mm on MyoArm) and resized. So it is chosen by what is on the
//! other end: `rod` for `plant.md`'s fixed-shoulder arm (the reference
//! plant and `--plant toy`), `person` for anything else (`--plant myoarm`,
//! `--plant-cmd`, `--plant-tcp`: a person, or a model of one). `--arm`
//! overrides it; `limb estimate --json` prints it (`arm`), and a `limb run
//! --log` carries it in the logged configuration
//! (`validation.shoulder_rhythm`).
//!
//! `limb diagnose --arm` puts the same choice to the diagnosis's sim, as
//! the body the lengths are put on ([`ArmModel::build`]).

use limb_kernel::config::ValidationLimits;
use limb_kernel::KernelConfig;
use serde::Serialize;

/// The arm the estimator assumes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ArmModel {
    /// A fixed shoulder (`plant.md`'s rod): no shoulder rhythm.
    Rod,
    /// A person's shoulder, moving with elevation
    /// (`ValidationLimits::PERSON_SHOULDER_RHYTHM`).
    Person,
}

impl ArmModel {
    /// `config` with this arm's validation limits (the shoulder-rhythm
    /// prior and the resting shoulder's height).
    pub fn apply(self, mut config: KernelConfig) -> KernelConfig {
        let limits = match self {
            ArmModel::Rod => ValidationLimits::default(),
            ArmModel::Person => ValidationLimits::person(),
        };
        config.validation.shoulder_rhythm = limits.shoulder_rhythm;
        config.validation.max_shoulder_height = limits.max_shoulder_height;
        config
    }

    /// The body the diagnosis's sim puts the arm's lengths on: `rod`
    /// plant.md's dummy (uniform rods of 1.55 kg and 1.317 kg), `person`
    /// the reference person's segments scaled to the lengths
    /// (`limb_sim::ArmParameters::person`).
    pub fn build(self) -> limb_sim::ArmBuild {
        match self {
            ArmModel::Rod => limb_sim::ArmBuild::Rod,
            ArmModel::Person => limb_sim::ArmBuild::Person,
        }
    }
}
