//! # limb-kernel
//!
//! A deterministic, `no_std`, heap-free, panic-free control kernel for a
//! robot that holds a passive person's wrist, learns the arm, and only then
//! moves it.
//!
//! Data flow of one [`Kernel::step`] (all frame S, SI units):
//!
//! ```text
//! sensor frame ─▶ monitor::watchdog ─▶ monitor::rates ─▶ monitor::{force, speed,
//!   (adapter)                                              workspace, joint_limits}
//!                                                                 │ violation → SafeStop
//!                                                                 ▼
//!        state (Grasp │ Estimate │ Validated │ Manipulate │ SafeStop) ─▶ set-point
//!          Estimate: sample ─▶ path + estimation::online (O(1)) ─▶ provisional arm
//!                      ─▶ joint envelope ─▶ monitor::joint_limits + lift (shaped, ended)
//!                    held: estimation::refine (≤ SAMPLES_PER_STEP per step)
//!                      ─▶ validate ─▶ ValidatedArm                (motion)
//!                                                                 ▼
//!                                         impedance (saturated) ─▶ Command
//! ```
//!
//! Modules: [`geometry`] (frame S quantities), [`arm`] (two-link kinematics),
//! [`motion`] (minimum-jerk set-points, the estimation motion), [`lift`]
//! (the estimation lift shaped and ended by the provisional model), [`path`]
//! (the recorded grasp path), [`estimation`] (circle fits, Hough, the
//! online estimator and its bounded refinement),
//! [`validate`] (the only maker of [`validate::ValidatedArm`]), [`state`]
//! (typed states and transitions), [`monitor`], [`impedance`], [`command`],
//! [`trace`], [`config`], and [`kernel`] (the runtime wrapper).

#![no_std]
#![forbid(unsafe_code)]
// Panics are bugs (Tock's rule): no unwrap, expect or panic outside tests.
// Indexing stays allowed: it is used only on fixed-size arrays and nalgebra
// vectors with indices bounded by their length, and the panic-freedom
// properties and harnesses (REQ-PANIC-001, REQ-EST-001) exercise it.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod arm;
pub mod command;
pub mod config;
pub mod estimation;
pub mod geometry;
pub mod impedance;
pub mod kernel;
pub mod lift;
pub mod monitor;
pub mod motion;
pub mod path;
pub mod state;
pub mod trace;
pub mod validate;

pub use command::{Command, CommandMode};
pub use config::KernelConfig;
pub use kernel::Kernel;
pub use path::PathSample;
pub use state::{
    LimitUpdateRefusal, Refusal, RefusalReason, Request, State, StateKind, StopReason,
};
