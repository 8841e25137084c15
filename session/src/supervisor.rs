//! The operator or supervisor side of a session: who asks the kernel to
//! start, approve, finish or stop, and who is told what happened.
//!
//! Implemented by the scripted [`crate::operator::Operator`] (`limb run`,
//! the firmware, an unsupervised robot session) and by the Zenoh link
//! (`limb-zenoh`, a remote supervisor station). Every request goes through
//! `Kernel::request`, the kernel's guards.

use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, Kernel, PathSample, StateKind};

/// The side that makes requests of the kernel.
pub trait Supervisor {
    /// Before the step at kernel time `now` [s]: the supervisor's requests
    /// (through `Kernel::request`), bounded in number. `following`: the
    /// robot follows commands now ([`crate::robot::Frame::following`]).
    fn before_step(&mut self, kernel: &mut Kernel, now: f64, following: bool);
    /// After the step: its frame and command.
    fn after_step(&mut self, _kernel: &Kernel, _frame: &PathSample, _command: &Command, _now: f64) {
    }
    /// Each transition, refusal or event the kernel recorded, in order.
    fn event(&mut self, _kernel: &Kernel, _event: &TraceEvent) {}
    /// True when the session is over for the supervisor, given the state
    /// after the step and whether a manipulation was finished
    /// (Manipulate → Validated) in this session.
    fn finished(&self, state: StateKind, completed: bool) -> bool;
}
