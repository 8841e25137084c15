//! # limb-plant
//!
//! The client of `limb-plant/1` (`../shared/spec/external-plant.md`): any
//! simulator that speaks the protocol — the MuJoCo musculoskeletal arm of
//! `plants/myoarm`, a test script — is the robot and arm of a kernel
//! session, in lockstep over a child process's stdin/stdout or TCP.
//!
//! ```text
//!  plant ──line──▶ transport::Link (reader thread, 64 KiB limit, timeout)
//!                        │ bytes
//!                        ▼
//!                  wire::decode_* (strict: fields, finiteness, truth names)
//!                        │ PlantFrame
//!                        ▼
//!                  robot::PlantRobot ──Frame──▶ limb_session::run ──▶ Kernel::step
//!                        ▲                                               │
//!  plant ◀──line── wire::encode_command ◀──────── Command ◀──────────────┘
//! ```
//!
//! Modules: [`transport`] (the byte stream and its timeout), [`wire`] (the
//! messages), [`robot`] (the session's robot), [`error`] (the faults, each
//! with a stable code). Decisions where the spec is silent are listed in
//! [`wire`] and in this crate's README.

#![forbid(unsafe_code)]

pub mod error;
pub mod robot;
pub mod transport;
pub mod wire;

pub use error::{Fault, PlantError};
pub use robot::{Ending, PlantRobot};
pub use transport::Endpoint;
