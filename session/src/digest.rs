//! A session in text that compares exactly.
//!
//! [`EventLine`] and [`Digest`] print a session in one
//! canonical text (times and lengths with Rust's shortest round-trip `f64`
//! form, i.e. exact), which the host (`limb run --digest`) and the firmware
//! both print for comparison.

use crate::operator::Described;
use crate::run::Outcome;
use core::fmt;
use limb_kernel::trace::TraceEvent;

/// One event in the canonical text: `event TIME WHAT`.
#[derive(Clone, Copy, Debug)]
pub struct EventLine<'a>(pub &'a TraceEvent);

impl fmt::Display for EventLine<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "event {:?} {}", self.0.time, Described(self.0))
    }
}

/// The outcome in the canonical text (after the [`EventLine`]s): the model
/// exactly, the step counts, the final state and the command hash, one
/// item a line.
#[derive(Clone, Copy, Debug)]
pub struct Digest<'a>(pub &'a Outcome);

impl fmt::Display for Digest<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let o = self.0;
        match &o.model {
            Some(m) => writeln!(
                f,
                "model l1 {:?} l2 {:?} shoulder {:?} {:?} elbow {:?} {:?}",
                m.upper_arm_length,
                m.forearm_length,
                m.shoulder.x,
                m.shoulder.z,
                m.elbow.x,
                m.elbow.z
            )?,
            None => writeln!(f, "model none")?,
        }
        writeln!(
            f,
            "steps {} saturated {} final {} completed {}",
            o.steps, o.saturated_commands, o.final_state, o.completed
        )?;
        write!(f, "command-hash {:016x}", o.command_hash)
    }
}
