//! # limb-zenoh
//!
//! Supervisory integration of the limb kernel over Zenoh 1.x: telemetry
//! out, authenticated commands in, a queryable state, a heartbeat watchdog
//! on the supervisor and an emergency stop that never waits behind
//! telemetry.
//!
//! - [`keys`]: the key expressions `limb/<robot-id>/@v2/...`;
//! - [`wire`]: the versioned JSON / CBOR encoding of every message;
//! - `limb_session::kernel_wire` (not here: `limb run --json` and the
//!   CLI's reports spell kernel values with it too): the wire's own
//!   spelling of kernel states, faults, events, frames and commands (a
//!   kernel rename cannot change `@v2`);
//! - [`auth`]: HMAC-SHA256 signatures of commands and heartbeats;
//! - [`inbound`]: the screens every arriving command, e-stop and
//!   heartbeat payload passes (signature, then decoding);
//! - [`link`]: the node's Zenoh side (session, subscribers, queryables,
//!   the publisher thread);
//! - [`supervision`]: [`supervision::Supervision`], the node's in-loop
//!   half (also usable from another adapter's loop);
//! - [`node`]: a `limb-session` session of any robot on its own thread,
//!   supervised over the link;
//! - [`supervisor`]: the supervisor's side;
//! - [`session`]: Zenoh configurations for peers on loopback or a router.
//!
//! Feature `link` (default) brings Zenoh and the modules that use it
//! (`link`, `node`, `session`, `supervisor`); without it the crate is the
//! wire format, the signatures and the screens (what `fuzz/` builds).
//!
//! The kernel stays pure and the loop is `limb-session`'s: this crate owns
//! the Zenoh side, and every remote command goes through `Kernel::request`.

#![forbid(unsafe_code)]

pub mod auth;
pub mod error;
pub mod inbound;
pub mod keys;
#[cfg(feature = "link")]
pub mod link;
#[cfg(feature = "link")]
pub mod node;
#[cfg(feature = "link")]
pub mod session;
#[cfg(feature = "link")]
pub mod supervision;
#[cfg(feature = "link")]
pub mod supervisor;
pub mod wire;

pub use error::AdapterError;
/// The Zenoh crate this adapter is built on (its `Config` is part of the API).
#[cfg(feature = "link")]
pub use zenoh;
