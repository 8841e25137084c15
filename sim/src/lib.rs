//! # limb-sim
//!
//! The reference plant of `../shared/spec/plant.md` (v1): a Cartesian
//! impedance robot holding the wrist of a passive two-link arm that lies on
//! a table, integrated with semi-implicit Euler at 0.5 ms, measured with
//! seeded noise. This is "the sim" of the project: the kernel is developed
//! against it and `limb run` closes the kernel's loop on it.
//!
//! Modules: [`closed_loop`] (advancing the plant one control period),
//! [`params`] (arm and robot parameters, plant.md defaults),
//! [`dynamics`] (M, C, g, J, J̇ q̇ of the arm), [`contact`] (the table's two
//! unilateral constraints), [`plant`] (state, step, measurement),
//! [`noise`] (the seeded Gaussian generator), [`operator`] (the requests a
//! person makes of the kernel in a closed-loop session), [`scripted`] (the estimation
//! run), [`log`] (the CSV log format: writer and the strict reader).

#![forbid(unsafe_code)]

pub mod closed_loop;
pub mod contact;
pub mod dynamics;
pub mod effects;
pub mod log;
pub mod noise;
pub mod operator;
pub mod params;
pub mod plant;
pub mod scripted;

pub use effects::{Effect, EffectError, Effects};
pub use params::{ArmParameters, PlantParameters, RobotParameters, BENCHMARK_ARMS};
pub use plant::{
    Measurement, Plant, Truth, ANGLE_NOISE, FORCE_NOISE, POSITION_NOISE, STEP, TORQUE_NOISE,
};
