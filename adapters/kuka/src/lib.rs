//! KUKA LBR iiwa / LBR Med FRI client adapter.
//!
//! Theory of operation: the robot controller sends one
//! [`messages::FriMonitoringMessage`] per `sendPeriod`; the client answers
//! with a [`messages::FriCommandMessage`]. Wire facts follow
//! `shared/spec/kuka-fri.md`.
//!
//! Modules: wire — [`version`], [`messages`] (all FRI versions in one set
//! of structs), [`codec`], [`vectors`]; client — [`session`] (pure session
//! logic), [`udp`] (the socket loop), [`kinematics`] (iiwa 7 R800),
//! [`grasp_frame`] (robot base ↔ frame S), [`kernel_controller`] (the
//! kernel's `step` once per monitoring message); robot side for tests and
//! measurements — [`sim_controller`] (simulated FRI controller driving the
//! reference plant), [`faults`] (seeded fault schedules), [`loopback`]
//! (both on loopback UDP).
#![forbid(unsafe_code)]

pub mod codec;
pub mod faults;
pub mod grasp_frame;
pub mod kernel_controller;
pub mod kinematics;
pub mod loopback;
pub mod messages;
pub mod session;
pub mod sim_controller;
pub mod udp;
pub mod vectors;
pub mod version;

pub use codec::{
    decode_command, decode_monitoring, encode_command, encode_monitoring, DecodeError, EncodeError,
};
pub use version::FriVersion;
