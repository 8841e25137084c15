#![no_std]
#![forbid(unsafe_code)]

pub mod geometry;
pub mod motion;
