//! KUKA LBR iiwa / LBR Med FRI client adapter.
//!
//! Theory of operation: the robot controller sends one
//! [`messages::FriMonitoringMessage`] per `sendPeriod`; the client answers
//! with a [`messages::FriCommandMessage`]. This crate holds the wire
//! messages (all FRI versions in one set of structs, the differences being
//! conditions on [`FriVersion`]) and the datagram codec. Wire facts follow
//! `shared/spec/kuka-fri.md`.
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
