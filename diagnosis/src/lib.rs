//! # limb-diagnosis: where the sim-to-real gap lies, which unmodelled
//! effect causes it, and how far it shrinks once that effect is added
//!
//! Data flow:
//!
//! ```text
//! real log ──► Model (plant::arm: the reference plant with the log's arm
//!                │ lengths; plant::drive: one axis's rigid inverse model)
//!                │ predict(effects) → signals at every sample
//!                ▼
//! holdout ─► Problem { fit samples, held-out samples }
//!                ▼
//! engine::select ─► nominal residual ─► locate (signals, time, band)
//!                 ─► every candidate: optimize on fit samples,
//!                    score on held-out samples (information criterion)
//!                 ─► rank; forward selection while an effect earns its
//!                    parameters; gap before/after on held-out data
//!                ▼
//! plant::*::outcome::diagnose (the answer) · plant::*::blind (blind check)
//!                ▼
//! report (the HTML page of either plant)
//! ```
//!
//! [`plant`] holds the plants, one folder each with the same file roles:
//! [`plant::arm`] (`plant.md`) and [`plant::drive`] (one actuated axis
//! against its rigid inverse model, `spec/drive.md`).
//!
//! [`model`] is the only thing a plant provides; [`engine`], [`optimize`],
//! [`holdout`], [`residual`], [`locate`] and [`report`] know nothing of
//! arms or drives.

#![forbid(unsafe_code)]

pub mod engine;
pub mod holdout;
pub mod locate;
pub mod model;
pub mod optimize;
pub mod plant;
pub mod report;
pub mod residual;

pub use engine::{select, Options, Problem, Progress, Selection};
pub use holdout::HoldOut;
pub use model::{Applied, Candidate, Data, Model, ModelError, Series};
