//! The faults the simulated device can be told to show, switched while it
//! runs (from a test or a CLI thread).

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

/// Faults the simulated device can be told to show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum DeviceFault {
    /// Normal streaming.
    None = 0,
    /// Garbage, a truncated frame and a frame with a wrong checksum before
    /// every valid frame.
    Garbage = 1,
    /// Stops sending (the firmware hangs).
    Stall = 2,
    /// Closes the port (USB unplugged).
    Unplug = 3,
    /// Behaves as if the host's heartbeats stopped arriving: reports
    /// [`crate::protocol::ERROR_HEARTBEAT`] and stops applying the torque
    /// target.
    HeartbeatLost = 4,
    /// Keeps streaming, its run time stopped (a hung firmware clock).
    FrozenClock = 5,
}

/// Shared switch for [`DeviceFault`].
#[derive(Clone, Debug, Default)]
pub struct FaultSwitch(Arc<AtomicU8>);

impl FaultSwitch {
    /// Sets the fault.
    pub fn set(&self, fault: DeviceFault) {
        self.0.store(fault as u8, Ordering::SeqCst);
    }

    /// The fault set last.
    pub(super) fn get(&self) -> DeviceFault {
        match self.0.load(Ordering::SeqCst) {
            1 => DeviceFault::Garbage,
            2 => DeviceFault::Stall,
            3 => DeviceFault::Unplug,
            4 => DeviceFault::HeartbeatLost,
            5 => DeviceFault::FrozenClock,
            _ => DeviceFault::None,
        }
    }
}
