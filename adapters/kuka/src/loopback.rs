//! The whole loop on one machine: the simulated controller
//! ([`crate::sim_controller`]) and the FRI client with the kernel inside
//! ([`crate::udp`] + [`crate::kernel_controller`]) over real UDP sockets on
//! loopback, the client on its own thread. Used by the acceptance tests,
//! the `kuka_loop` latency harness and nothing else.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::time::Duration;

use limb_kernel::{KernelConfig, StateKind};
use limb_sim::operator::SessionPlan;
use limb_sim::PlantParameters;

use crate::kernel_controller::{KernelController, LoopSettings};
use crate::session::SequenceCheck;
use crate::sim_controller::{Pacing, SimController, SimError, SimSettings};
use crate::udp::{ClientError, CycleOutcome, FriClient};

/// The client's receive timeout: a quarter of the kernel's default sensor
/// age limit (20 ms), so a silent link reaches the watchdog in time.
pub const CLIENT_RECEIVE_TIMEOUT: Duration = Duration::from_millis(5);
/// The client's receive timeout against an unpaced controller: there the
/// robot's clock is the plant's, and silence is seen as a gap between time
/// stamps ([`crate::kernel_controller`]); wall-clock stalls of a loaded
/// machine are not link silence.
pub const UNPACED_CLIENT_RECEIVE_TIMEOUT: Duration = Duration::from_millis(500);
/// Largest joint-target change per reply of the loop [rad] (2 rad/s at
/// 1 kHz; the kernel's 0.15 m/s speed limit needs well under 1 rad/s).
pub const MAX_JOINT_STEP: f64 = 0.002;

/// Cycle counts seen by the client.
#[derive(Debug, Clone, Copy, Default)]
pub struct ClientCounts {
    /// Monitoring messages handled.
    pub handled: u64,
    /// Commands sent.
    pub answered: u64,
    /// Datagrams rejected by the decoder (garbage, wrong CRC).
    pub rejected: u64,
    /// Receive timeouts.
    pub timeouts: u64,
    /// Duplicates dropped.
    pub duplicates: u64,
    /// Older (reordered, delayed) datagrams dropped.
    pub stale_datagrams: u64,
    /// Gaps in the monitor's counter (messages handled after a gap).
    pub gaps: u64,
    /// Counter resynchronisations.
    pub resynchronisations: u64,
    /// Cycles with a session fault.
    pub session_faults: u64,
}

impl ClientCounts {
    /// Counts one cycle's outcome.
    pub fn tally(&mut self, outcome: &CycleOutcome) {
        match outcome {
            CycleOutcome::Handled {
                answered,
                fault,
                sequence,
                ..
            } => {
                self.answered += u64::from(*answered);
                self.session_faults += u64::from(fault.is_some());
                match sequence {
                    SequenceCheck::Duplicate => self.duplicates += 1,
                    SequenceCheck::Stale { .. } => self.stale_datagrams += 1,
                    SequenceCheck::Gap { .. } => self.gaps += 1,
                    SequenceCheck::Resynchronised => self.resynchronisations += 1,
                    SequenceCheck::First | SequenceCheck::InOrder => {}
                }
                self.handled += u64::from(sequence.is_handled());
            }
            CycleOutcome::Rejected(_) => self.rejected += 1,
            CycleOutcome::Stale => self.timeouts += 1,
        }
    }
}

/// A failure of the loop's own I/O.
#[derive(Debug, thiserror::Error)]
pub enum LoopbackError {
    /// The simulated controller failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The client failed.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// The client thread panicked (a bug).
    #[error("the FRI client thread panicked")]
    ClientPanicked,
    /// The kernel could not be configured.
    #[error("{0}")]
    Kernel(String),
}

/// The end of a loopback run.
pub struct LoopbackRun {
    /// The simulated controller (plant, stats).
    pub sim: SimController,
    /// The kernel side.
    pub controller: KernelController,
    /// The client's counts.
    pub client: ClientCounts,
}

fn state_from(raw: u8) -> StateKind {
    [
        StateKind::Grasp,
        StateKind::Estimate,
        StateKind::Validated,
        StateKind::Manipulate,
        StateKind::SafeStop,
    ]
    .into_iter()
    .find(|kind| *kind as u8 == raw)
    .unwrap_or(StateKind::Grasp)
}

/// The `limb run` session on the reference arm (l1 = 0.30 m, l2 = 0.20 m,
/// plant.md defaults) with the default kernel, the kernel's overlay and
/// heading matching `sim`: [`run_loopback`] as the tests and the harness
/// use it.
///
/// # Errors
/// As [`run_loopback`].
pub fn run_reference_session(
    sim: SimSettings,
    max_cycles: u64,
    done: impl FnMut(&SimController, StateKind) -> bool,
) -> Result<LoopbackRun, LoopbackError> {
    let settings = LoopSettings {
        overlay: sim.overlay,
        heading: sim.heading,
        plan: SessionPlan::default(),
    };
    run_loopback(
        sim,
        PlantParameters::new(0.30, 0.20),
        KernelConfig::default(),
        settings,
        max_cycles,
        done,
    )
}

/// Runs the loop until `done(&sim, kernel_state)` (checked after each
/// controller cycle; the kernel state as the client thread last published
/// it) or `max_cycles` controller cycles.
///
/// # Errors
/// [`LoopbackError`] on socket failure or a bad kernel configuration.
pub fn run_loopback(
    sim: SimSettings,
    plant: PlantParameters,
    kernel: KernelConfig,
    settings: LoopSettings,
    max_cycles: u64,
    mut done: impl FnMut(&SimController, StateKind) -> bool,
) -> Result<LoopbackRun, LoopbackError> {
    let loopback = SocketAddr::from(([127, 0, 0, 1], 0));
    let receive_timeout = match sim.pacing {
        Pacing::RealTime => CLIENT_RECEIVE_TIMEOUT,
        Pacing::AsFastAsPossible => UNPACED_CLIENT_RECEIVE_TIMEOUT,
    };
    let mut client = FriClient::bind(loopback, sim.version, MAX_JOINT_STEP, receive_timeout)?;
    let mut controller = KernelController::new(kernel, settings).map_err(LoopbackError::Kernel)?;
    let client_address = client.local_addr()?;
    let mut sim = SimController::bind(loopback, client_address, sim, plant)?;
    let stop = Arc::new(AtomicBool::new(false));
    let client_stop = Arc::clone(&stop);
    let kernel_state = Arc::new(AtomicU8::new(StateKind::Grasp as u8));
    let client_state = Arc::clone(&kernel_state);
    let client_thread = std::thread::spawn(move || {
        let mut counts = ClientCounts::default();
        while !client_stop.load(Ordering::Relaxed) {
            let outcome = client.run_cycle(&mut controller)?;
            if client_stop.load(Ordering::Relaxed) {
                // The wake-up datagram below, or silence after the end.
                break;
            }
            counts.tally(&outcome);
            client_state.store(controller.kernel().state().kind() as u8, Ordering::Relaxed);
        }
        Ok::<_, ClientError>((controller, counts))
    });
    let mut result = Ok(());
    for _ in 0..max_cycles {
        if let Err(error) = sim.run_cycle() {
            result = Err(error);
            break;
        }
        if done(&sim, state_from(kernel_state.load(Ordering::Relaxed))) {
            break;
        }
    }
    stop.store(true, Ordering::Relaxed);
    // Wake the client from its receive (a one-byte datagram it rejects), so
    // the end of the run is not a link silence seen by the kernel.
    let waker = UdpSocket::bind(loopback).and_then(|socket| socket.send_to(&[0], client_address));
    let (controller, client) = client_thread
        .join()
        .map_err(|_| LoopbackError::ClientPanicked)??;
    result?;
    waker.map_err(SimError::Io)?;
    Ok(LoopbackRun {
        sim,
        controller,
        client,
    })
}
