//! Verification of the limb kernel.
//!
//! * [`checks`]: the checking functions, each a safety property of one
//!   step or one request, shared by the proptest properties
//!   (`tests/properties.rs`) and the Kani harnesses.
//! * [`scenario`]: deterministic sensor streams (a synthetic estimation
//!   lift of a known arm) that drive the kernel into every state, for the
//!   properties, the transition-table test and the benchmarks.

pub mod checks;
pub mod explore;
#[cfg(not(kani))]
pub mod kani_stand_in;
pub mod proofs;
pub mod scenario;
