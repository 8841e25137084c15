//! Single-axis drives (`spec/drive.md`): a drive log against the rigid
//! inverse model tau = M q̈ + offset − f_ext, diagnosed by the same engine
//! as the arm.
//!
//! ```text
//! drive log (log) ─► filter (zero-phase, derivatives) ─► DriveModel (model)
//!     candidates and their physics (effects), linear parameters by
//!     least squares (lsq) ─► engine::select ─► Diagnosis (outcome)
//! ```
//!
//! [`sim`] is a simulated drive under position control with withheld
//! effects, and [`blind`] the blind self-check built on it.

pub mod blind;
pub mod effects;
pub mod filter;
pub mod log;
pub mod lsq;
pub mod model;
pub mod outcome;
pub mod sim;

pub use log::{read, DriveLog, DriveLogError};
pub use model::{DriveModel, DriveModelError, CUTOFF};
pub use outcome::{diagnose, Diagnosed, Diagnosis, DriveError};
