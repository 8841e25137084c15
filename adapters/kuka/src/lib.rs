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
//! [`grasp_frame`] (robot base ↔ frame S), [`robot`] (the arm as the
//! robot of a `limb-session` session: monitoring in as kernel frames,
//! commands out); robot side for tests and
//! measurements — [`sim_controller`] (simulated FRI controller driving the
//! reference plant), [`faults`] (seeded fault schedules), [`loopback`]
//! (both on loopback UDP); the `sim` feature brings the simulated
//! controller and the loopback (and `limb-sim`), the client needs neither.
#![forbid(unsafe_code)]

pub mod codec;
pub mod faults;
pub mod grasp_frame;
pub mod kinematics;
#[cfg(feature = "sim")]
pub mod loopback;
pub mod messages;
pub mod robot;
pub mod session;
#[cfg(feature = "sim")]
pub mod sim_controller;
pub mod udp;
pub mod vectors;
pub mod version;

pub use codec::{
    decode_command, decode_monitoring, encode_command, encode_monitoring, DecodeError, EncodeError,
};
pub use version::FriVersion;
