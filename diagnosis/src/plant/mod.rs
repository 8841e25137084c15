//! The plants the engine diagnoses. A plant is one folder with the same
//! file roles:
//!
//! | file | role |
//! |---|---|
//! | `mod.rs` | what the plant is, its data flow, re-exports |
//! | `model.rs` | the [`crate::model::Model`] of the plant (`ArmModel`, `DriveModel`) and why a log is refused |
//! | `effects.rs` | the candidate effects with their search ranges and the helpers their start points use |
//! | `outcome.rs` | the plant's answer (`diagnose`: the engine's selection as the CLI reports it) |
//! | `blind.rs` | the blind self-check: simulated logs with withheld effects, diagnosed blind |
//!
//! plus what only that plant needs: [`arm::replay`] (the commanded
//! set-point of a log); [`drive::log`] (the drive log format),
//! [`drive::filter`], [`drive::lsq`] and [`drive::sim`] (a simulated
//! drive). Adding a plant is adding a folder.

pub mod arm;
pub mod drive;
