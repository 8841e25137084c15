//! # limb-zenoh
//!
//! Supervisory integration of the limb kernel over Zenoh 1.x: telemetry
//! out, authenticated commands in, a queryable state, a heartbeat watchdog
//! on the supervisor and an emergency stop that never waits behind
//! telemetry.
//!
//! - [`keys`]: the key expressions `limb/<robot-id>/@v2/...`;
//! - [`wire`]: the versioned JSON / CBOR encoding of every message;
//! - [`kernel_wire`]: the wire's own spelling of kernel states, faults,
//!   events, frames and commands (a kernel rename cannot change `@v2`);
//! - [`auth`]: HMAC-SHA256 signatures of commands and heartbeats;
//! - [`link`]: the node's Zenoh side and [`link::Supervision`], its
//!   in-loop half (also usable from another adapter's loop);
//! - [`node`]: a control loop thread stepping a boxed kernel;
//! - [`sensor`]: where frames come from ([`sensor::SensorSource`]);
//! - [`supervisor`]: the supervisor's side;
//! - [`session`]: Zenoh configurations for peers on loopback or a router.
//!
//! The kernel stays pure: this crate owns the clock, threads and sockets,
//! and every remote command goes through `Kernel::request`.

#![forbid(unsafe_code)]

pub mod auth;
pub mod error;
pub mod kernel_wire;
pub mod keys;
pub mod link;
pub mod node;
pub mod sensor;
pub mod session;
pub mod supervisor;
pub mod wire;

pub use error::AdapterError;
