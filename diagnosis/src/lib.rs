//! # limb-diagnosis: where the sim-to-real gap lies, which unmodelled
//! effect causes it, and how far it shrinks once that effect is added
//!
//! Data flow:
//!
//! ```text
//! real log ──► Model (arm: the reference plant with the log's arm lengths)
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
//! verdict::diagnose (the `limb diagnose` answer) · selfcheck (blind check)
//! ```
//!
//! [`drive`] is the second plant: one actuated axis against its rigid
//! inverse model (`spec/drive.md`).
//!
//! [`model`] is the only thing a plant provides; [`engine`], [`optimize`],
//! [`holdout`], [`residual`] and [`locate`] know nothing of arms.

#![forbid(unsafe_code)]

pub mod arm;
pub mod drive;
pub mod engine;
pub mod holdout;
pub mod locate;
pub mod model;
pub mod optimize;
pub mod report;
pub mod residual;
pub mod selfcheck;
pub mod verdict;

pub use engine::{select, Options, Problem, Progress, Selection};
pub use holdout::HoldOut;
pub use model::{Applied, Candidate, Data, Model, ModelError, Series};
