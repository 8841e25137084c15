//! The arm plant of `plant.md`: the reference plant (`limb-sim`) with the
//! log's arm lengths against a log in the plant.md format.
//!
//! ```text
//! log ─► replay (the commanded set-point) ─► ArmModel (model)
//!     candidates, the arm lengths' own candidate (effects)
//!     ─► engine::select ─► Diagnosis (outcome)
//! ```
//!
//! [`blind`] is the blind self-check: logs of the reference plant with
//! withheld effects, diagnosed without the arm.

pub mod blind;
pub mod curves;
pub mod effects;
pub mod model;
pub mod outcome;
pub mod replay;

pub use limb_sim::ArmBuild;
pub use model::{ArmError, ArmModel, Lengths};
pub use outcome::{diagnose, DiagnoseError, Diagnosed, Diagnosis};
