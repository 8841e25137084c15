//! # limb-firmware
//!
//! The kernel on a Cortex-M7, QEMU's `mps2-an500` board: what the two
//! binaries share.
//!
//! * `session` (`src/bin/session.rs`) runs one whole kernel session against
//!   the reference plant on the target and prints its canonical digest
//!   (the text `limb run --digest` prints on the host), the instructions
//!   of every step per state, and the stack high-water mark.
//! * `panic-never` (`src/bin/panic_never.rs`) links the kernel alone with a
//!   panic handler that calls an undefined symbol: it links only when no
//!   panic path is left in the kernel.
//!
//! Modules: [`count`] (instructions from the SysTick under `-icount`),
//! [`stack`] (painting the stack and reading back its high-water mark).

#![no_std]

pub mod count;
pub mod stack;
