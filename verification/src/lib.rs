//! Verification of the limb kernel.
//!
//! * [`checks`]: the session-level checking functions, each a safety
//!   property of one step or one request, for the proptest properties
//!   (`tests/properties.rs`) and the state-space explorer; a command's own
//!   invariants are the kernel's `Command::check`, which the Kani harnesses
//!   beside the kernel's modules assert too (in its square-root-free part).
//! * [`explore`]: the abstract state-space exploration.
//! * [`scenario`]: deterministic sensor streams (a synthetic estimation
//!   lift of a known arm) that drive the kernel into every state, for the
//!   properties, the transition-table test and the benchmarks.
//!
//! The Kani harnesses live beside the code they prove, in the kernel's
//! `mod verification` blocks; the sampling stand-in that runs them under
//! `cargo test` is the `limb-kani-stand-in` crate (`stand-in/`).

pub mod checks;
pub mod explore;
pub mod scenario;
