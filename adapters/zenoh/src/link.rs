//! The Zenoh side of a kernel node: subscribers, queryables and the
//! publisher thread, and [`Supervision`], the part that runs inside the
//! control loop.
//!
//! # Theory of operation
//! ```text
//!  cmd/estop ──callback──▶ atomic flag ─────────┐
//!  cmd/request ─callback─▶ verify, decode ─▶ bounded queue (16) ─┐
//!  alive/supervisor ─callback─▶ verify ─▶ atomic time ──────────┐│
//!                                                               ▼▼▼
//!                       session loop (limb_session::run): Supervision's
//!                       before_step (commands, e-stop, liveness) →
//!                       Kernel::step → event, after_step
//!                                                               │
//!   try_send, never blocks the loop: bounded queue (1024), of which
//!   samples take at most half (a loop faster than the publisher thread
//!   loses samples, never acks or events)
//!                                                               ▼
//!       publisher thread: events, acks, link (Block) · status
//!       (alive/kernel) · model/arm · snapshot for the queryables
//!       · samples (Drop), unless [`SampleQos::from_loop`] puts them
//!       from the loop itself
//! ```
//! Zenoh callbacks do constant work and never wait: an emergency stop sets
//! an atomic flag the loop reads at every step, so it reaches the kernel
//! within one control period of its arrival whatever the telemetry queues
//! hold. Every command goes through `Kernel::request`, the same guards as a
//! local request. The loop never blocks on the network: when the outbound
//! queue is full, messages are dropped and counted in [`NodeCounters`].

use crate::auth::CommandKey;
use crate::error::AdapterError;
use crate::inbound::{emergency_stop_sequence, screen, screen_heartbeat};
use crate::keys::Keys;
use crate::wire::{
    Ack, AckOutcome, AckSubject, ArmModel, CommandMessage, EventMessage, KernelStatus, LinkMessage,
    NodeCounters, RefuseReason, SampleMessage, StateSnapshot, StopOrigin, SupervisorCommand,
    WireFormat,
};
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::{
    Command, Kernel, KernelConfig, LimitUpdateRefusal, PathSample, Request, StateKind,
};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicU8, AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TryRecvError, TrySendError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use zenoh::qos::{CongestionControl, Priority};
use zenoh::Wait;

/// Commands waiting for the control loop; more are refused as busy.
pub const COMMAND_QUEUE: usize = 16;
/// Messages waiting for the publisher thread; more are dropped and counted.
pub const OUTBOUND_QUEUE: usize = 1024;
/// Samples among [`OUTBOUND_QUEUE`]; more are dropped and counted, so that
/// telemetry never takes the room of events, acks and link messages (a loop
/// that steps faster than the publisher thread publishes would otherwise
/// fill the queue with samples and lose every ack).
pub const SAMPLE_QUEUE: usize = OUTBOUND_QUEUE / 2;
/// Emergency stops waiting for their ack; more still stop the robot, but
/// their acks are dropped and counted.
pub const ESTOP_QUEUE: usize = 16;

/// What the kernel side does when the supervisor's heartbeat stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnSupervisorLoss {
    /// Keep the current state (the kernel's own monitors still guard).
    Continue,
    /// `Request::Stop`: enter SafeStop.
    Stop,
}

/// The supervisor watchdog: armed by the first valid heartbeat; after that,
/// a silence longer than `timeout` is a loss.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LivenessPolicy {
    /// Longest accepted silence between valid heartbeats, e.g. 150-250 ms
    /// for a 20 Hz heartbeat (3-5 periods).
    pub timeout: Duration,
    /// What to do on a loss.
    pub on_loss: OnSupervisorLoss,
}

/// How `telemetry/sample` is published (always best effort, congestion
/// control Drop: a congested link loses samples, never delays the loop
/// for long).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleQos {
    /// Zenoh express: each sample is sent at once instead of being batched
    /// with others.
    pub express: bool,
    /// Zenoh priority of the samples.
    pub priority: Priority,
    /// Put each sample from the control loop itself instead of handing it
    /// to the publisher thread (one thread wake-up less). A put with
    /// congestion control Drop does not wait for the network; on a full
    /// transmit queue Zenoh waits at most its `wait_before_drop` (1 ms by
    /// default) before dropping.
    pub from_loop: bool,
}

impl SampleQos {
    /// Batched, priority DataHigh, through the publisher thread: the
    /// default. The README's side-by-side benchmark found no setting with a
    /// lower p99 latency beyond run-to-run noise, and putting from the loop
    /// cost it steps under load.
    pub const BATCHED: Self = Self {
        express: false,
        priority: Priority::DataHigh,
        from_loop: false,
    };
    /// Express, priority DataHigh, put from the loop (one thread hop less;
    /// the loop does Zenoh's work).
    pub const LOW_LATENCY: Self = Self {
        express: true,
        priority: Priority::DataHigh,
        from_loop: true,
    };
}

/// Settings of the Zenoh side of a node.
#[derive(Clone, Debug)]
pub struct LinkSettings {
    /// Robot id, one key chunk (see [`Keys::new`]).
    pub robot_id: String,
    /// Payload encoding of every message.
    pub format: WireFormat,
    /// Shared secret that authorises commands and heartbeats.
    pub command_key: CommandKey,
    /// Publish one sample every this many steps (1 = every step).
    pub sample_decimation: u32,
    /// How samples are published.
    pub sample_qos: SampleQos,
    /// Period of `alive/kernel` status messages [kernel s].
    pub status_period: f64,
    /// Supervisor watchdog.
    pub liveness: LivenessPolicy,
}

/// Nanoseconds since `epoch`, plus one so that 0 can mean "never".
fn stamp(epoch: Instant) -> u64 {
    u64::try_from(epoch.elapsed().as_nanos())
        .unwrap_or(u64::MAX - 1)
        .saturating_add(1)
}

/// What callbacks and the loop share, all lock-free.
#[derive(Debug)]
pub(crate) struct Shared {
    /// Origin of the `stamp` values.
    epoch: Instant,
    /// Arrival stamp of the first pending emergency stop, 0 for none.
    estop_at: AtomicU64,
    /// Emergency-stop acks not queued because [`ESTOP_QUEUE`] was full.
    estop_acks_dropped: AtomicU64,
    /// Arrival stamp of the newest valid heartbeat, 0 for none yet.
    heartbeat_at: AtomicU64,
    /// Sequence of the newest valid heartbeat plus one, 0 for none yet: a
    /// heartbeat counts only when its sequence is above it (replays are
    /// refused).
    heartbeat_sequence: AtomicU64,
    /// Signed heartbeats refused because their sequence was not above the
    /// last accepted one (replays).
    heartbeats_replayed: AtomicU64,
    /// `StateKind as u8` after the last step.
    state: AtomicU8,
    /// Delay from e-stop arrival to the kernel request [ns], 0 for none.
    estop_delay: AtomicU64,
    /// Silence at the last supervisor-loss detection [ns], 0 for none.
    loss_silence: AtomicU64,
    /// The owner asked the session to end.
    end: AtomicBool,
    /// Samples in the outbound queue (at most [`SAMPLE_QUEUE`]).
    queued_samples: AtomicUsize,
}

/// What the loop side of a node can report to its owner.
#[derive(Clone, Debug)]
pub struct LoopView {
    shared: Arc<Shared>,
}

impl LoopView {
    /// The kernel's state after the last step (`None` before the first).
    pub fn state(&self) -> Option<StateKind> {
        match self.shared.state.load(Ordering::Acquire) {
            1 => Some(StateKind::Grasp),
            2 => Some(StateKind::Estimate),
            3 => Some(StateKind::Validated),
            4 => Some(StateKind::Manipulate),
            5 => Some(StateKind::SafeStop),
            _ => None,
        }
    }

    /// Time from the last emergency stop's arrival to its kernel request.
    pub fn last_emergency_stop_delay(&self) -> Option<Duration> {
        nonzero_duration(self.shared.estop_delay.load(Ordering::Acquire))
    }

    /// Heartbeat silence when the last supervisor loss was detected.
    pub fn last_loss_silence(&self) -> Option<Duration> {
        nonzero_duration(self.shared.loss_silence.load(Ordering::Acquire))
    }

    /// Ends the session the supervision runs in (after its current step).
    pub fn end_session(&self) {
        self.shared.end.store(true, Ordering::Release);
    }
}

fn nonzero_duration(nanos: u64) -> Option<Duration> {
    (nanos != 0).then(|| Duration::from_nanos(nanos))
}

/// Work for the publisher thread.
enum Outbound {
    Event(EventMessage),
    Sample(SampleMessage),
    Link(LinkMessage),
    Ack(Ack),
    Status(KernelStatus, Option<ArmModel>),
    Close,
}

/// The in-loop half of a node: the supervisor side of a `limb-session`
/// session ([`limb_session::Supervisor`]) — in the node's own session
/// ([`crate::node::Node`]) or in any robot's (`limb kuka run --zenoh`).
/// Supervisory commands wait in their queue while the robot does not follow
/// commands; the emergency stop and the supervisor watchdog act at every
/// step.
pub struct Supervision {
    shared: Arc<Shared>,
    commands: Receiver<CommandMessage>,
    /// The sample publisher when samples are put from the loop
    /// ([`SampleQos::from_loop`]).
    samples: Option<(WireFormat, zenoh::pubsub::Publisher<'static>)>,
    /// Sequences of the emergency stops that arrived (`None`: unreadable
    /// payload), in arrival order.
    estops: Receiver<Option<u64>>,
    outbound: SyncSender<Outbound>,
    sample_decimation: u64,
    status_period: f64,
    liveness: LivenessPolicy,
    last_sequence: Option<u64>,
    event_sequence: u64,
    counters: NodeCounters,
    last_state: Option<StateKind>,
    next_status: f64,
    supervisor_lost: bool,
    /// Deadline overruns of a paced loop, counted by its pacer.
    overruns: Option<Arc<AtomicU64>>,
    /// Who asked for each stop this supervision made that the kernel has
    /// not yet reported (a stop moves the kernel into SafeStop: one
    /// transition event each, drained after the step).
    stop_origins: VecDeque<StopOrigin>,
}

impl limb_session::Supervisor for Supervision {
    /// Applies pending commands (while the robot follows), then a pending
    /// emergency stop, then the supervisor watchdog, at kernel time `now`
    /// [s]. Bounded: at most [`COMMAND_QUEUE`] commands.
    fn before_step(&mut self, kernel: &mut Kernel, now: f64, following: bool) {
        for _ in 0..COMMAND_QUEUE {
            if !following {
                break;
            }
            match self.commands.try_recv() {
                Ok(message) => self.apply(kernel, message, now),
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => break,
            }
        }
        let arrived = self.shared.estop_at.swap(0, Ordering::AcqRel);
        if arrived != 0 {
            let state = self.stop(kernel, now, StopOrigin::EmergencyStop);
            let delay = stamp(self.shared.epoch).saturating_sub(arrived).max(1);
            self.shared.estop_delay.store(delay, Ordering::Release);
            // One kernel request, one ack per e-stop that arrived: every
            // sender learns that its stop was applied.
            for _ in 0..ESTOP_QUEUE {
                let Ok(sequence) = self.estops.try_recv() else {
                    break;
                };
                self.ack(Ack {
                    subject: AckSubject::EmergencyStop,
                    sequence,
                    outcome: outcome(state),
                });
            }
        }
        self.watch_supervisor(kernel, now);
    }

    /// Publishes the step's sample (decimated) and, on a state change or
    /// every status period, the status and arm model.
    fn after_step(&mut self, kernel: &Kernel, frame: &PathSample, command: &Command, now: f64) {
        let step = self.counters.steps;
        self.counters.steps += 1;
        if step % self.sample_decimation == 0 {
            let message = SampleMessage {
                step,
                time: now,
                sent_at_ns: wall_clock_ns(),
                frame: (*frame).into(),
                command: (*command).into(),
            };
            let sent = match &self.samples {
                Some((format, publisher)) => format
                    .encode(&message)
                    .is_ok_and(|bytes| publisher.put(bytes).wait().is_ok()),
                None => self.queue_sample(message),
            };
            if !sent {
                self.counters.samples_dropped += 1;
            }
        }
        let state = kernel.state().kind();
        self.shared.state.store(state as u8, Ordering::Release);
        if self.last_state != Some(state) || now >= self.next_status {
            self.last_state = Some(state);
            self.next_status = now + self.status_period;
            self.counters.kernel_events_dropped = kernel.dropped_events();
            self.counters.heartbeats_replayed =
                self.shared.heartbeats_replayed.load(Ordering::Acquire);
            self.counters.estop_acks_dropped =
                self.shared.estop_acks_dropped.load(Ordering::Acquire);
            if let Some(overruns) = &self.overruns {
                self.counters.overruns = overruns.load(Ordering::Relaxed);
            }
            let status = KernelStatus {
                time: now,
                state: state.into(),
                supervisor_present: self.supervisor_present(),
                counters: self.counters,
            };
            let arm = kernel.state().arm().map(|a| ArmModel::from(a.geometry()));
            self.send_reliable(Outbound::Status(status, arm));
        }
    }

    /// Publishes each trace event as it is drained, a stop this
    /// supervision asked for with its origin.
    fn event(&mut self, kernel: &Kernel, event: &TraceEvent) {
        let requested_stop = matches!(
            event.event,
            Event::Transition {
                cause: Cause::Request(Request::Stop),
                ..
            }
        );
        let message = EventMessage {
            sequence: self.event_sequence,
            kernel_dropped: kernel.dropped_events(),
            event: (*event).into(),
            origin: requested_stop
                .then(|| self.stop_origins.pop_front())
                .flatten(),
        };
        self.event_sequence += 1;
        self.send_reliable(Outbound::Event(message));
    }

    /// The session ends when the owner asks ([`LoopView::end_session`]).
    fn finished(&self, _: StateKind, _: bool) -> bool {
        self.shared.end.load(Ordering::Acquire)
    }
}

impl Supervision {
    /// `Request::Stop` on behalf of `origin`; a stop that moves the kernel
    /// (not already in SafeStop) is remembered for its event.
    fn stop(
        &mut self,
        kernel: &mut Kernel,
        now: f64,
        origin: StopOrigin,
    ) -> Result<StateKind, limb_kernel::Refusal> {
        let moving = kernel.state().kind() != StateKind::SafeStop;
        let result = kernel.request(Request::Stop, now);
        if moving && result.is_ok() {
            self.stop_origins.push_back(origin);
        }
        result
    }

    /// Hands `message` to the publisher thread unless [`SAMPLE_QUEUE`]
    /// samples are already waiting or the queue is full; true when queued.
    fn queue_sample(&mut self, message: SampleMessage) -> bool {
        let queued = &self.shared.queued_samples;
        // Counted before sending: the publisher thread uncounts it on receipt.
        if queued.fetch_add(1, Ordering::AcqRel) < SAMPLE_QUEUE
            && self.outbound.try_send(Outbound::Sample(message)).is_ok()
        {
            return true;
        }
        queued.fetch_sub(1, Ordering::AcqRel);
        false
    }

    /// Reads the loop's deadline overruns (for the status message) from
    /// `counter`, which its pacer counts.
    pub fn count_overruns(&mut self, counter: Arc<AtomicU64>) {
        self.overruns = Some(counter);
    }

    /// What the supervision counted so far (the status message's
    /// counters).
    pub fn counters(&self) -> NodeCounters {
        self.counters
    }

    /// The shared view for the loop's owner.
    pub fn view(&self) -> LoopView {
        LoopView {
            shared: Arc::clone(&self.shared),
        }
    }

    /// The instant stamps and the loop clock are measured from.
    pub fn epoch(&self) -> Instant {
        self.shared.epoch
    }

    fn apply(&mut self, kernel: &mut Kernel, message: CommandMessage, now: f64) {
        if let Some(last) = self.last_sequence.filter(|last| message.sequence <= *last) {
            return self.refuse(
                Some(message.sequence),
                RefuseReason::Replayed {
                    last_accepted: last,
                },
            );
        }
        self.last_sequence = Some(message.sequence);
        let request = match message.command {
            SupervisorCommand::StartEstimation => Request::StartEstimation,
            SupervisorCommand::ApproveManipulation { target } => {
                Request::ApproveManipulation(target.into())
            }
            SupervisorCommand::FinishManipulation => Request::FinishManipulation,
            SupervisorCommand::Stop => Request::Stop,
            SupervisorCommand::Reset => Request::Reset,
            SupervisorCommand::UpdateLimits { limits } => {
                let outcome = match kernel.update_limits(limits) {
                    Ok(()) => AckOutcome::Accepted {
                        state: kernel.state().kind().into(),
                    },
                    Err(LimitUpdateRefusal::Invalid(error)) => AckOutcome::Refused {
                        reason: RefuseReason::InvalidLimits {
                            error: error.into(),
                        },
                    },
                    Err(LimitUpdateRefusal::NotAllowedInState(state)) => AckOutcome::Refused {
                        reason: RefuseReason::LimitsNotAllowedInState {
                            state: state.into(),
                        },
                    },
                };
                self.ack(Ack {
                    subject: AckSubject::Request,
                    sequence: Some(message.sequence),
                    outcome,
                });
                return;
            }
        };
        let result = match request {
            Request::Stop => self.stop(kernel, now, StopOrigin::Command),
            other => kernel.request(other, now),
        };
        self.ack(Ack {
            subject: AckSubject::Request,
            sequence: Some(message.sequence),
            outcome: outcome(result),
        });
    }

    fn watch_supervisor(&mut self, kernel: &mut Kernel, now: f64) {
        let last = self.shared.heartbeat_at.load(Ordering::Acquire);
        if last == 0 {
            return;
        }
        let silence = stamp(self.shared.epoch).saturating_sub(last);
        let lost = Duration::from_nanos(silence) > self.liveness.timeout;
        if lost && !self.supervisor_lost {
            self.supervisor_lost = true;
            self.shared
                .loss_silence
                .store(silence.max(1), Ordering::Release);
            let stopped = self.liveness.on_loss == OnSupervisorLoss::Stop
                && self.stop(kernel, now, StopOrigin::SupervisorLost).is_ok();
            tracing::warn!(silence_ns = silence, stopped, "supervisor lost");
            self.send_reliable(Outbound::Link(LinkMessage::SupervisorLost {
                time: now,
                silence: Duration::from_nanos(silence).as_secs_f64(),
                stopped,
            }));
        } else if !lost && self.supervisor_lost {
            self.supervisor_lost = false;
            self.send_reliable(Outbound::Link(LinkMessage::SupervisorBack { time: now }));
        }
    }

    fn supervisor_present(&self) -> bool {
        self.shared.heartbeat_at.load(Ordering::Acquire) != 0 && !self.supervisor_lost
    }

    fn refuse(&mut self, sequence: Option<u64>, reason: RefuseReason) {
        tracing::warn!(?sequence, ?reason, "command refused");
        self.ack(Ack::refused(sequence, reason));
    }

    fn ack(&mut self, ack: Ack) {
        self.send_reliable(Outbound::Ack(ack));
    }

    fn send_reliable(&mut self, message: Outbound) {
        if self.outbound.try_send(message).is_err() {
            self.counters.reliable_dropped += 1;
        }
    }
}

fn outcome(result: Result<StateKind, limb_kernel::Refusal>) -> AckOutcome {
    match result {
        Ok(state) => AckOutcome::Accepted {
            state: state.into(),
        },
        Err(refusal) => AckOutcome::Refused {
            reason: RefuseReason::Kernel {
                refusal: refusal.into(),
            },
        },
    }
}

/// Wall clock [ns since the UNIX epoch] (0 if the clock is before 1970).
pub fn wall_clock_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}

/// The Zenoh half of a node: session, subscribers, queryables and the
/// publisher thread. Dropping it without [`Link::close`] leaves the
/// publisher thread to end when the session does.
pub struct Link {
    session: zenoh::Session,
    outbound: SyncSender<Outbound>,
    publisher: Option<JoinHandle<()>>,
    _subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    _queryables: Vec<zenoh::query::Queryable<()>>,
}

impl Link {
    /// Opens a Zenoh session with `zenoh_config` and declares everything
    /// for a kernel configured with `config`; returns the link and the
    /// loop's half.
    ///
    /// # Errors
    /// [`AdapterError`] for a bad setting or a Zenoh failure.
    pub fn open(
        zenoh_config: zenoh::Config,
        settings: &LinkSettings,
        config: KernelConfig,
    ) -> Result<(Self, Supervision), AdapterError> {
        if settings.sample_decimation == 0 {
            return Err(AdapterError::Setting(
                "sample decimation must be at least 1",
            ));
        }
        if !(settings.status_period.is_finite() && settings.status_period > 0.0) {
            return Err(AdapterError::Setting("status period must be positive"));
        }
        let keys = Keys::new(&settings.robot_id)?;
        let format = settings.format;
        let session = zenoh::open(zenoh_config).wait()?;
        let shared = Arc::new(Shared {
            epoch: Instant::now(),
            estop_at: AtomicU64::new(0),
            estop_acks_dropped: AtomicU64::new(0),
            heartbeat_at: AtomicU64::new(0),
            heartbeat_sequence: AtomicU64::new(0),
            heartbeats_replayed: AtomicU64::new(0),
            state: AtomicU8::new(0),
            estop_delay: AtomicU64::new(0),
            loss_silence: AtomicU64::new(0),
            end: AtomicBool::new(false),
            queued_samples: AtomicUsize::new(0),
        });
        let (outbound, outbound_rx) = sync_channel(OUTBOUND_QUEUE);
        let (commands_tx, commands) = sync_channel(COMMAND_QUEUE);
        let (estops_tx, estops) = sync_channel(ESTOP_QUEUE);
        let snapshot = Arc::new(Mutex::new(None::<StateSnapshot>));

        let qos = settings.sample_qos;
        let sample_publisher = session
            .declare_publisher(keys.sample())
            .congestion_control(CongestionControl::Drop)
            .priority(qos.priority)
            .express(qos.express)
            .encoding(format.encoding())
            .wait()?;
        let (thread_samples, loop_samples) = if qos.from_loop {
            (None, Some((format, sample_publisher)))
        } else {
            (Some(sample_publisher), None)
        };
        let publishers = Publishers::declare(&session, &keys, format, thread_samples)?;
        let publisher = std::thread::Builder::new()
            .name("limb-zenoh-publish".into())
            .spawn({
                let (snapshot, shared) = (Arc::clone(&snapshot), Arc::clone(&shared));
                move || publishers.run(&outbound_rx, &snapshot, &shared.queued_samples, config)
            })?;

        let subscribers = vec![
            declare_estop(&session, &keys, format, &shared, estops_tx)?,
            declare_requests(&session, &keys, settings, commands_tx, outbound.clone())?,
            declare_heartbeat(&session, &keys, settings, &shared)?,
        ];
        let queryables = [
            (keys.state(), Answer::State),
            (keys.config(), Answer::Config),
            (keys.arm(), Answer::Arm),
        ]
        .into_iter()
        .map(|(key, answer)| declare_queryable(&session, key, answer, format, &snapshot))
        .collect::<Result<Vec<_>, _>>()?;

        let supervision = Supervision {
            shared,
            commands,
            samples: loop_samples,
            estops,
            outbound: outbound.clone(),
            sample_decimation: u64::from(settings.sample_decimation),
            status_period: settings.status_period,
            liveness: settings.liveness,
            last_sequence: None,
            event_sequence: 0,
            counters: NodeCounters::default(),
            last_state: None,
            next_status: f64::NEG_INFINITY,
            supervisor_lost: false,
            overruns: None,
            stop_origins: VecDeque::new(),
        };
        let link = Self {
            session,
            outbound,
            publisher: Some(publisher),
            _subscribers: subscribers,
            _queryables: queryables,
        };
        Ok((link, supervision))
    }

    /// The session (to declare more, or to inspect).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    /// Flushes what is queued, stops the publisher thread and closes the
    /// session.
    ///
    /// # Errors
    /// A Zenoh failure while closing.
    pub fn close(mut self) -> Result<(), AdapterError> {
        // Blocks only while the queue is full; the publisher thread drains it.
        let _ = self.outbound.send(Outbound::Close);
        if let Some(handle) = self.publisher.take() {
            let _ = handle.join();
        }
        self.session.close().wait()?;
        Ok(())
    }
}

/// The publishers the publisher thread owns.
struct Publishers {
    format: WireFormat,
    event: zenoh::pubsub::Publisher<'static>,
    /// `None` when the loop puts the samples itself.
    sample: Option<zenoh::pubsub::Publisher<'static>>,
    link: zenoh::pubsub::Publisher<'static>,
    ack: zenoh::pubsub::Publisher<'static>,
    status: zenoh::pubsub::Publisher<'static>,
    arm: zenoh::pubsub::Publisher<'static>,
}

impl Publishers {
    fn declare(
        session: &zenoh::Session,
        keys: &Keys,
        format: WireFormat,
        sample: Option<zenoh::pubsub::Publisher<'static>>,
    ) -> Result<Self, AdapterError> {
        let declare = |key: String, congestion: CongestionControl, priority: Priority| {
            session
                .declare_publisher(key)
                .congestion_control(congestion)
                .priority(priority)
                .encoding(format.encoding())
                .wait()
        };
        use CongestionControl::{Block, Drop};
        Ok(Self {
            format,
            event: declare(keys.event(), Block, Priority::InteractiveHigh)?,
            sample,
            link: declare(keys.link(), Block, Priority::InteractiveHigh)?,
            ack: declare(keys.ack(), Block, Priority::InteractiveHigh)?,
            status: declare(keys.kernel_alive(), Drop, Priority::Data)?,
            arm: declare(keys.arm(), Block, Priority::Data)?,
        })
    }

    /// Publishes what `queue` brings until [`Outbound::Close`], uncounting
    /// each sample from `queued_samples`.
    fn run(
        self,
        queue: &Receiver<Outbound>,
        snapshot: &Mutex<Option<StateSnapshot>>,
        queued_samples: &AtomicUsize,
        config: KernelConfig,
    ) {
        let mut published_arm = None;
        while let Ok(message) = queue.recv() {
            let result = match message {
                Outbound::Close => return,
                Outbound::Event(m) => self.put(&self.event, &m),
                Outbound::Sample(m) => {
                    queued_samples.fetch_sub(1, Ordering::AcqRel);
                    match &self.sample {
                        Some(publisher) => self.put(publisher, &m),
                        None => Ok(()),
                    }
                }
                Outbound::Link(m) => self.put(&self.link, &m),
                Outbound::Ack(m) => self.put(&self.ack, &m),
                Outbound::Status(status, arm) => {
                    if let Ok(mut guard) = snapshot.lock() {
                        *guard = Some(StateSnapshot {
                            status,
                            arm,
                            config,
                        });
                    }
                    let arm_result = match arm {
                        Some(model) if published_arm != Some(model) => {
                            published_arm = Some(model);
                            self.put(&self.arm, &model)
                        }
                        _ => Ok(()),
                    };
                    arm_result.and(self.put(&self.status, &status))
                }
            };
            if let Err(error) = result {
                tracing::warn!(%error, "telemetry not published");
            }
        }
    }

    fn put<T: serde::Serialize>(
        &self,
        publisher: &zenoh::pubsub::Publisher<'static>,
        value: &T,
    ) -> Result<(), AdapterError> {
        let bytes = self.format.encode(value)?;
        publisher.put(bytes).wait()?;
        Ok(())
    }
}

fn declare_estop(
    session: &zenoh::Session,
    keys: &Keys,
    format: WireFormat,
    shared: &Arc<Shared>,
    estops: SyncSender<Option<u64>>,
) -> Result<zenoh::pubsub::Subscriber<()>, AdapterError> {
    let shared = Arc::clone(shared);
    Ok(session
        .declare_subscriber(keys.emergency_stop())
        .callback(move |sample| {
            // Any payload stops; a readable one names the stop in its ack.
            let sequence = emergency_stop_sequence(format, &sample.payload().to_bytes());
            // Queue the ack first, then raise the flag: the loop that sees
            // the flag also finds the ack.
            if estops.try_send(sequence).is_err() {
                shared.estop_acks_dropped.fetch_add(1, Ordering::AcqRel);
            }
            // Keep the first arrival's stamp when several are pending.
            let _ = shared.estop_at.compare_exchange(
                0,
                stamp(shared.epoch),
                Ordering::AcqRel,
                Ordering::Acquire,
            );
        })
        .wait()?)
}

fn declare_requests(
    session: &zenoh::Session,
    keys: &Keys,
    settings: &LinkSettings,
    commands: SyncSender<CommandMessage>,
    outbound: SyncSender<Outbound>,
) -> Result<zenoh::pubsub::Subscriber<()>, AdapterError> {
    let key = settings.command_key.clone();
    let format = settings.format;
    let key_expr = keys.request();
    let refuse = move |sequence, reason: RefuseReason| {
        tracing::warn!(?sequence, ?reason, "command refused");
        // A full queue already drops telemetry; the sender's ack times out.
        let _ = outbound.try_send(Outbound::Ack(Ack::refused(sequence, reason)));
    };
    Ok(session
        .declare_subscriber(key_expr.clone())
        .callback(move |sample| {
            let payload = sample.payload().to_bytes();
            let attachment = sample.attachment().map(|a| a.to_bytes());
            match screen(&key, format, &key_expr, &payload, attachment.as_deref()) {
                Err((sequence, reason)) => refuse(sequence, reason),
                Ok(message) => {
                    if let Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) =
                        commands.try_send(message)
                    {
                        refuse(Some(message.sequence), RefuseReason::Busy);
                    }
                }
            }
        })
        .wait()?)
}

fn declare_heartbeat(
    session: &zenoh::Session,
    keys: &Keys,
    settings: &LinkSettings,
    shared: &Arc<Shared>,
) -> Result<zenoh::pubsub::Subscriber<()>, AdapterError> {
    let key = settings.command_key.clone();
    let format = settings.format;
    let key_expr = keys.supervisor_alive();
    let shared = Arc::clone(shared);
    Ok(session
        .declare_subscriber(key_expr.clone())
        .callback(move |sample| {
            let payload = sample.payload().to_bytes();
            let attachment = sample.attachment().map(|a| a.to_bytes());
            let Some(heartbeat) =
                screen_heartbeat(&key, format, &key_expr, &payload, attachment.as_deref())
            else {
                return;
            };
            // Fresh only when its sequence is above every one accepted
            // before: a captured heartbeat replayed later keeps nothing alive.
            let marker = heartbeat.sequence.saturating_add(1);
            let previous = shared
                .heartbeat_sequence
                .fetch_max(marker, Ordering::AcqRel);
            if marker > previous {
                shared
                    .heartbeat_at
                    .store(stamp(shared.epoch), Ordering::Release);
            } else {
                shared.heartbeats_replayed.fetch_add(1, Ordering::AcqRel);
                tracing::warn!(sequence = heartbeat.sequence, "replayed heartbeat refused");
            }
        })
        .wait()?)
}

/// What a queryable answers with.
#[derive(Clone, Copy, Debug)]
enum Answer {
    State,
    Config,
    Arm,
}

fn declare_queryable(
    session: &zenoh::Session,
    key: String,
    answer: Answer,
    format: WireFormat,
    snapshot: &Arc<Mutex<Option<StateSnapshot>>>,
) -> Result<zenoh::query::Queryable<()>, AdapterError> {
    let snapshot = Arc::clone(snapshot);
    Ok(session
        .declare_queryable(key)
        .callback(move |query| {
            let current = snapshot.lock().ok().and_then(|guard| *guard);
            let encoded = match (current, answer) {
                (None, _) => Err("no state yet"),
                (Some(s), Answer::State) => format.encode(&s).map_err(|_| "encoding failed"),
                (Some(s), Answer::Config) => {
                    format.encode(&s.config).map_err(|_| "encoding failed")
                }
                (Some(s), Answer::Arm) => match s.arm {
                    Some(arm) => format.encode(&arm).map_err(|_| "encoding failed"),
                    None => Err("no validated arm model"),
                },
            };
            let reply = match encoded {
                Ok(bytes) => query
                    .reply(query.key_expr().clone(), bytes)
                    .encoding(format.encoding())
                    .wait(),
                Err(reason) => query.reply_err(reason).wait(),
            };
            if let Err(error) = reply {
                tracing::warn!(%error, "query not answered");
            }
        })
        .wait()?)
}
