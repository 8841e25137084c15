//! A fixed-capacity record of what the kernel decided: transitions and
//! refused requests, oldest first.
//!
//! The adapter drains it with [`crate::Kernel::pop_event`]. When it is not
//! drained fast enough the oldest events are dropped and counted, so a loss
//! is visible, never silent.

use crate::lift::LiftEnd;
use crate::state::{Refusal, Request, StateKind};
use crate::stop::{StopCategory, StopReason};
use heapless::Deque;

/// Events kept before the oldest is dropped.
pub const TRACE_CAPACITY: usize = 32;

/// What caused a transition.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Cause {
    /// An operator or supervisor request.
    Request(Request),
    /// The estimate passed validation at the end of the motion.
    ModelValidated,
    /// A stop, with its reason.
    Stop(StopReason),
}

/// One decision of the kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Event {
    /// The state changed.
    Transition {
        /// State left.
        from: StateKind,
        /// State entered.
        to: StateKind,
        /// Why.
        cause: Cause,
    },
    /// A request was refused; the state did not change.
    Refused(Refusal),
    /// The estimation lift ended (Estimate goes on: settling, then the
    /// refinement), and why.
    LiftEnded(LiftEnd),
}

/// An event with the kernel time it happened at [s].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TraceEvent {
    /// Kernel time `now` [s].
    pub time: f64,
    /// What happened.
    pub event: Event,
}

/// The ring of recent events.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    events: Deque<TraceEvent, TRACE_CAPACITY>,
    dropped: u32,
}

impl Trace {
    /// Records `event`, dropping (and counting) the oldest when full.
    pub fn record(&mut self, event: TraceEvent) {
        if self.events.is_full() {
            self.events.pop_front();
            self.dropped = self.dropped.saturating_add(1);
        }
        // Room was just made, so this cannot fail.
        let _ = self.events.push_back(event);
    }

    /// Removes and returns the oldest event.
    pub fn pop(&mut self) -> Option<TraceEvent> {
        self.events.pop_front()
    }

    /// Events dropped because the trace was full (saturating).
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

impl Cause {
    /// The stop category of a transition into SafeStop with this cause (a
    /// stop request is the operator's stop); `None` for a cause that never
    /// stops.
    pub const fn stop_category(&self) -> Option<StopCategory> {
        match self {
            Cause::Stop(reason) => Some(reason.category()),
            Cause::Request(Request::Stop) => Some(StopReason::Operator.category()),
            Cause::Request(_) | Cause::ModelValidated => None,
        }
    }
}
