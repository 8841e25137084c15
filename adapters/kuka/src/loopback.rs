//! The whole loop on one machine: the simulated controller
//! ([`crate::sim_controller`]) and the FRI client with the kernel inside
//! ([`crate::udp`] + [`crate::robot`] in a `limb-session` session) over real UDP sockets on
//! loopback, the client on its own thread. Used by the acceptance tests,
//! the `kuka_loop` latency harness and nothing else.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;

use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, Kernel, KernelConfig, StateKind};
use limb_session::operator::describe;
use limb_session::{Frame, Observer, Operator, Outcome, SessionPlan, Supervisor, Unobserved};
use limb_sim::PlantParameters;

use crate::robot::{ArrivalClock, FriRobot};
use crate::sim_controller::{Pacing, SimController, SimError, SimSettings};
use crate::udp::{
    ClientError, FriClient, CLIENT_RECEIVE_TIMEOUT, MAX_JOINT_STEP, UNPACED_CLIENT_RECEIVE_TIMEOUT,
};

/// Stack of the session thread [bytes]: the kernel is boxed, but the
/// estimator's concluding step needs more than Rust's 2 MB default in
/// debug builds.
const SESSION_STACK: usize = 16 * 1024 * 1024;
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
    #[error("kernel configuration: {0}")]
    Kernel(limb_kernel::config::ConfigError),
}

/// The end of a loopback run.
pub struct LoopbackRun<S> {
    /// The simulated controller (plant, stats).
    pub sim: SimController,
    /// The kernel at the end.
    pub kernel: Box<Kernel>,
    /// The robot side of the session (its counts).
    pub robot: FriRobot,
    /// The session's supervisor.
    pub supervisor: S,
    /// How the session ended.
    pub outcome: Outcome,
    /// Every kernel event, in order.
    pub events: Vec<TraceEvent>,
    /// The last command.
    pub last_command: Option<Command>,
}

impl<S> LoopbackRun<S> {
    /// True when the kernel stopped with an event whose words contain
    /// `cause`.
    pub fn stopped_because(&self, cause: &str) -> bool {
        self.events.iter().any(|event| {
            let what = describe(event);
            what.contains("→ SafeStop") && what.contains(cause)
        })
    }
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

/// What the client thread records of the session as it runs.
struct Recorder {
    state: Arc<AtomicU8>,
    events: Vec<TraceEvent>,
    last_command: Option<Command>,
}

impl Observer<FriRobot> for Recorder {
    fn after_step(&mut self, _: &FriRobot, _: &Frame, _: StateKind, command: &Command) {
        self.state.store(command.state as u8, Ordering::Relaxed);
        self.last_command = Some(*command);
    }

    fn event(&mut self, event: &TraceEvent) {
        self.events.push(*event);
    }
}

/// The `limb run` session on the reference arm (l1 = 0.30 m, l2 = 0.20 m,
/// plant.md defaults) with the default kernel and the scripted operator,
/// the kernel's overlay and heading matching `sim`: [`run_loopback`] as
/// the tests and the harness use it.
///
/// # Errors
/// As [`run_loopback`].
pub fn run_reference_session(
    sim: SimSettings,
    max_cycles: u64,
    done: impl FnMut(&SimController, StateKind) -> bool,
) -> Result<LoopbackRun<Operator>, LoopbackError> {
    run_loopback(
        sim,
        PlantParameters::new(0.30, 0.20),
        KernelConfig::default(),
        Operator::continuing(SessionPlan::default()),
        max_cycles,
        done,
    )
}

/// Runs the loop until `done(&sim, kernel_state)` (checked after each
/// controller cycle; the kernel state as the client thread last published
/// it) or `max_cycles` controller cycles: the simulated controller on this
/// thread, the session ([`limb_session::run`] on an [`FriRobot`] under
/// `supervisor`, overlay and heading as `sim`'s) on its own.
///
/// # Errors
/// [`LoopbackError`] on socket failure or a bad kernel configuration.
pub fn run_loopback<S: Supervisor + Send + 'static>(
    sim: SimSettings,
    plant: PlantParameters,
    kernel: KernelConfig,
    supervisor: S,
    max_cycles: u64,
    done: impl FnMut(&SimController, StateKind) -> bool,
) -> Result<LoopbackRun<S>, LoopbackError> {
    run_loopback_observed(sim, plant, kernel, supervisor, Unobserved, max_cycles, done)
        .map(|(run, _)| run)
}

/// [`run_loopback`], the session also shown to `observer` (e.g. a
/// `limb_session::log::SessionLog`), which is returned with the run.
///
/// # Errors
/// As [`run_loopback`].
pub fn run_loopback_observed<S, O>(
    sim: SimSettings,
    plant: PlantParameters,
    kernel: KernelConfig,
    mut supervisor: S,
    mut observer: O,
    max_cycles: u64,
    mut done: impl FnMut(&SimController, StateKind) -> bool,
) -> Result<(LoopbackRun<S>, O), LoopbackError>
where
    S: Supervisor + Send + 'static,
    O: Observer<FriRobot> + Send + 'static,
{
    let loopback = SocketAddr::from(([127, 0, 0, 1], 0));
    let (receive_timeout, clock) = match sim.pacing {
        Pacing::RealTime => (CLIENT_RECEIVE_TIMEOUT, ArrivalClock::Host),
        Pacing::AsFastAsPossible => (UNPACED_CLIENT_RECEIVE_TIMEOUT, ArrivalClock::Robot),
    };
    let client = FriClient::bind(loopback, sim.version, MAX_JOINT_STEP, receive_timeout)?;
    let mut kernel = Box::new(Kernel::new(kernel).map_err(LoopbackError::Kernel)?);
    let client_address = client.local_addr()?;
    let stop = Arc::new(AtomicBool::new(false));
    let mut robot = FriRobot::new(client, sim.overlay, sim.heading, None);
    robot.stop_when(Arc::clone(&stop));
    robot.arrival_clock(clock);
    let mut sim = SimController::bind(loopback, client_address, sim, plant)?;
    let kernel_state = Arc::new(AtomicU8::new(StateKind::Grasp as u8));
    let mut recorder = Recorder {
        state: Arc::clone(&kernel_state),
        events: Vec::new(),
        last_command: None,
    };
    let client_thread = std::thread::Builder::new()
        .name("limb-fri-session".into())
        .stack_size(SESSION_STACK)
        .spawn(move || {
            let mut observers = (&mut recorder, &mut observer);
            let outcome =
                limb_session::run(&mut kernel, &mut robot, &mut supervisor, &mut observers)?;
            Ok::<_, ClientError>((kernel, robot, supervisor, outcome, recorder, observer))
        })
        .map_err(|error| LoopbackError::Client(ClientError::Io(error)))?;
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
    let (kernel, robot, supervisor, outcome, recorder, observer) = client_thread
        .join()
        .map_err(|_| LoopbackError::ClientPanicked)??;
    result?;
    waker.map_err(SimError::Io)?;
    let run = LoopbackRun {
        sim,
        kernel,
        robot,
        supervisor,
        outcome,
        events: recorder.events,
        last_command: recorder.last_command,
    };
    Ok((run, observer))
}
