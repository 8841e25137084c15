#![no_std]
#![forbid(unsafe_code)]

pub mod arm;
pub mod estimation;
pub mod geometry;
pub mod motion;
pub mod path;
pub mod validate;
