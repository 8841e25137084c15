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
//!          Estimate: sample ─▶ estimation::tilt (in the arm's plane)
//!                      ─▶ path + estimation::online (O(1)) ─▶ provisional arm
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
//! [`stop`] (stop categories and the set-point's move at a stop),
//! [`trace`], [`config`], [`linear`] (small linear systems, no panic
//! path), and [`kernel`] (the runtime wrapper).
//!
//! # Verification beside the code
//! Each module that carries a safety requirement ends in a
//! `#[cfg(any(test, kani))] mod verification`: Kani proof harnesses named
//! `verify_req_<id>_…` for the requirement they prove, the checking
//! functions they assert, and (under `cargo test`) the proptest properties
//! that call the same checking functions plus a run of every harness
//! through the sampling stand-in (`limb-kani-stand-in`). `cargo kani` from
//! the workspace root proves them; `kani_stubs` states the contracts of the
//! libm functions the proofs replace. Every harness that runs a loop says
//! which loop its `kani::unwind` bound covers; a harness without one runs
//! none. Harnesses start from states built directly (`kani_inputs`), never
//! from a whole session.

#![no_std]
#![forbid(unsafe_code)]
// The public API is the public modules and the root's re-exports; an item
// marked `pub` that no user can reach is a mistake (Tock's rule).
#![deny(unreachable_pub)]
// Panics are bugs (Tock's rule): no unwrap, expect or panic outside tests.
// Indexing stays allowed: it is used only on fixed-size arrays and nalgebra
// vectors with indices bounded by their length, and the panic-freedom
// properties and harnesses (REQ-PANIC-001, REQ-EST-001) exercise it.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
// Kani's `stub` attribute expands recursively, once per stub: a first
// lift step's harness has thirteen (its libm functions, the step's proved
// contracts, the estimation's later parts), past the default limit of 128.
#![cfg_attr(kani, recursion_limit = "256")]

// Kani's library under `cargo kani` (the crate is no_std, so it is not in
// the prelude by itself).
#[cfg(kani)]
extern crate kani;

pub mod arm;
pub mod command;
pub mod config;
pub mod estimation;
pub mod geometry;
pub mod impedance;
#[cfg(any(test, kani))]
mod kani_inputs;
#[cfg(any(test, kani))]
mod kani_stubs;
mod kernel;
pub mod lift;
mod linear;
pub mod monitor;
pub mod motion;
pub mod path;
pub mod state;
pub mod stop;
pub mod trace;
pub mod validate;
pub mod vocabulary;

pub use command::{Command, CommandMode};
pub use config::KernelConfig;
pub use kernel::Kernel;
pub use path::PathSample;
pub use state::{LimitUpdateRefusal, Refusal, RefusalReason, Request, State, StateKind};
pub use stop::{StopCategory, StopReason};
