//! # limb-session
//!
//! The one session loop of the project: every robot (the reference plant
//! of `limb run` and the firmware, a KUKA arm behind FRI, AREBO) and every
//! supervisor (a local script, a Zenoh station) meet the kernel here.
//!
//! ```text
//!   Robot::sense ─▶ Frame (robot's stamp, S frame) ─▶ clock ─▶ kernel time
//!        ▲                                                  │
//!        │                Supervisor::before_step (requests, e-stop)
//!        │                                                  ▼
//!   Robot::actuate ◀── Command ◀──────────────── Kernel::step
//!                                   │
//!                  Observer (session log, timing), Supervisor::after_step
//! ```
//!
//! Modules: [`robot`] (the robot side: frames in, commands out),
//! [`supervisor`] (the operator/supervisor side), [`operator`] (the
//! scripted operator of `limb run`, a [`supervisor::Supervisor`]),
//! [`clock`] (kernel time from the robot's stamps and the session's
//! clock), [`run`] (the loop), [`paced`] (a robot paced by the wall
//! clock; `std` only), [`digest`] (the command hash and the
//! canonical text), [`log`] (the session log in the `plant.md` format;
//! `std` only).
//!
//! # Targets
//! Without its default `std` feature the crate is `no_std` and allocates
//! nothing: the firmware runs this loop on a Cortex-M7.

#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]

pub mod clock;
pub mod command_hash;
pub mod digest;
#[cfg(feature = "serde")]
pub mod kernel_wire;
#[cfg(feature = "std")]
pub mod log;
#[cfg(feature = "mcap")]
pub mod mcap_log;
pub mod operator;
#[cfg(feature = "std")]
pub mod paced;
pub mod robot;
pub mod run;
pub mod supervisor;

pub use operator::{FittedModel, Operator, SessionPlan};
pub use robot::{ArrivalClock, Frame, Robot, Sensed};
pub use run::{run, Observer, Outcome, Step, Unobserved};
pub use supervisor::Supervisor;
