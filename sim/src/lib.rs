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
//! [`noise`] (the seeded Gaussian generator), [`scripted`] (the estimation
//! run), [`log`] (the CSV log format: writer and the strict reader; with
//! the `std` feature), [`robot`] (the plant as the robot of a
//! `limb-session` session, shared by `limb run` and the firmware).
//!
//! # Targets
//! Without its default `std` feature the crate is `no_std` (it needs
//! `alloc` only for error texts, effect parsing and the latency buffer;
//! a nominal session allocates nothing): the firmware runs the same plant
//! on a Cortex-M7. All transcendental functions the plant uses come from
//! `libm` on every target, so host and target compute the same bits. The
//! diagnosis's helpers behind the `std` feature
//! ([`effects::Parameter::value`], [`effects::Parameter::unit_of`],
//! [`effects::measurement::measured`]) use the host's functions, as the
//! diagnosis always has.

#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]

extern crate alloc;

pub mod closed_loop;
pub mod contact;
pub mod dynamics;
pub mod effects;
#[cfg(feature = "std")]
pub mod log;
pub mod noise;
pub mod params;
pub mod plant;
pub mod robot;
pub mod scripted;
pub mod sensing;

pub use effects::{Effect, EffectError, Effects};
pub use params::{
    ArmBuild, ArmParameters, MassDistribution, PersonSegment, PlantParameters, RobotParameters,
    BENCHMARK_ARMS, PERSON_FOREARM, PERSON_UPPER_ARM,
};
pub use plant::{Plant, Truth};
pub use sensing::{Measurement, ANGLE_NOISE, FORCE_NOISE, POSITION_NOISE, STEP, TORQUE_NOISE};
