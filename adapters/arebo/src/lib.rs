//! # limb-arebo
//!
//! Adapter for AREBO (Mathavan Jeyabalan et al., *Robotics* 2023, 12, 149),
//! a 6-DoF self-aligning end-effector robot whose three actuated joints
//! θ1..θ3 place a spherical joint (θ4..θ6) at the person's upper arm.
//!
//! The limb kernel is planar (sagittal frame S); AREBO's arm model is 3-D,
//! so its geometry lives here, in `no_std`, heap-free, panic-free modules
//! the kernel could host later:
//!
//! ```text
//! encoder counts ─▶ encoder ─▶ kinematics (FK, IK, Jacobian)
//!                                   │ endpoint p_r (frame R0)
//!     calibration (plane ─▶ ψx, sphere ─▶ origin, l) ─▶ ValidatedArmModel
//!                                   │
//!                    human (φ1, φ2, J_h, τ_h) ─▶ control (τ_g, torque PD,
//!                                   unassisted / weight support, adaptive α)
//!                                   │           safety (typed verdicts)
//!                    supervisor (one frame → τ_d or a latched safe stop)
//!                    protocol (framing, streaming decoder)
//!                    sagittal (the kernel's frame S in R0)
//! ```
//! With `std`: [`link`] (the serial session), [`recording`] (calibration
//! over a session) and [`robot`] (AREBO as the robot of a `limb-session`
//! session: the kernel's Grasp → Estimate → Validated → Manipulate loop).
//!
//! Frames: R0 is the robot base (z up, gravity −z); H0 is the human base
//! frame, R0 rotated about x_R0 by ψx and translated to the shoulder centre;
//! S is the kernel's sagittal frame ([`sagittal`]).
//! All quantities SI (m, rad, N, N m, s) unless a name says otherwise.
//!
//! With the `sim` feature the crate also carries the simulations: `sim`,
//! the shoulder joint model (SJM) used to reproduce the paper's
//! experiments, `held_arm`, the kernel's reference arm held at the wrist,
//! and `device`, a simulated AREBO moving either on a pseudo-terminal.

#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]

pub mod calibration;
pub mod control;
#[cfg(feature = "sim")]
pub mod device;
pub mod encoder;
#[cfg(feature = "sim")]
pub mod held_arm;
pub mod human;
pub mod kinematics;
#[cfg(feature = "std")]
pub mod link;
pub mod protocol;
#[cfg(feature = "std")]
pub mod recording;
#[cfg(feature = "std")]
pub mod robot;
pub mod safety;
pub mod sagittal;
#[cfg(feature = "sim")]
pub mod sim;
pub mod supervisor;
