//! The in-loop half of a kernel node, [`Supervision`]: the
//! `limb_session::Supervisor` a session's loop calls every step (commands
//! and the emergency stop into `Kernel::request`, the supervisor watchdog,
//! telemetry out), fed by the lock-free state and bounded queues the
//! network side ([`crate::link`]) fills. Nothing here touches the network
//! but a sample put from the loop ([`crate::link::SampleQos::from_loop`]):
//! the loop never blocks on it.

use crate::wire::{
    Ack, AckOutcome, AckSubject, ArmModel, CommandMessage, EventMessage, KernelStatus, LinkMessage,
    NodeCounters, RefuseReason, SampleMessage, StopOrigin, SupervisorCommand, WireFormat,
};
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::{Command, Kernel, LimitUpdateRefusal, PathSample, Request, StateKind};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicU8, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
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

/// Nanoseconds since `epoch`, plus one so that 0 can mean "never".
pub(crate) fn stamp(epoch: Instant) -> u64 {
    u64::try_from(epoch.elapsed().as_nanos())
        .unwrap_or(u64::MAX - 1)
        .saturating_add(1)
}

/// What callbacks and the loop share, all lock-free.
#[derive(Debug)]
pub(crate) struct Shared {
    /// Origin of the `stamp` values.
    pub(crate) epoch: Instant,
    /// Arrival stamp of the first pending emergency stop, 0 for none.
    pub(crate) estop_at: AtomicU64,
    /// Emergency-stop acks not queued because [`ESTOP_QUEUE`] was full.
    pub(crate) estop_acks_dropped: AtomicU64,
    /// Arrival stamp of the newest valid heartbeat, 0 for none yet.
    pub(crate) heartbeat_at: AtomicU64,
    /// Sequence of the newest valid heartbeat plus one, 0 for none yet: a
    /// heartbeat counts only when its sequence is above it (replays are
    /// refused).
    pub(crate) heartbeat_sequence: AtomicU64,
    /// Signed heartbeats refused because their sequence was not above the
    /// last accepted one (replays).
    pub(crate) heartbeats_replayed: AtomicU64,
    /// `StateKind as u8` after the last step.
    pub(crate) state: AtomicU8,
    /// Delay from e-stop arrival to the kernel request [ns], 0 for none.
    pub(crate) estop_delay: AtomicU64,
    /// Silence at the last supervisor-loss detection [ns], 0 for none.
    pub(crate) loss_silence: AtomicU64,
    /// The owner asked the session to end.
    pub(crate) end: AtomicBool,
    /// Samples in the outbound queue (at most [`SAMPLE_QUEUE`]).
    pub(crate) queued_samples: AtomicUsize,
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
pub(crate) enum Outbound {
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

impl Shared {
    /// Nothing arrived yet; stamps count from now.
    pub(crate) fn new() -> Self {
        Self {
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
        }
    }
}

/// Where the in-loop half's inputs come from and its outputs go: the
/// queues the network side's callbacks fill and its publisher thread
/// drains.
pub(crate) struct Queues {
    /// What callbacks and the loop share.
    pub(crate) shared: Arc<Shared>,
    /// Verified commands, in arrival order.
    pub(crate) commands: Receiver<CommandMessage>,
    /// Sequences of the emergency stops that arrived.
    pub(crate) estops: Receiver<Option<u64>>,
    /// To the publisher thread.
    pub(crate) outbound: SyncSender<Outbound>,
    /// The sample publisher when samples are put from the loop.
    pub(crate) samples: Option<(WireFormat, zenoh::pubsub::Publisher<'static>)>,
}

impl Supervision {
    /// The in-loop half on `queues`: a sample every `sample_decimation`
    /// steps (≥ 1), a status every `status_period` [kernel s], the
    /// supervisor watched by `liveness`.
    pub(crate) fn new(
        queues: Queues,
        sample_decimation: u32,
        status_period: f64,
        liveness: LivenessPolicy,
    ) -> Self {
        Self {
            shared: queues.shared,
            commands: queues.commands,
            samples: queues.samples,
            estops: queues.estops,
            outbound: queues.outbound,
            sample_decimation: u64::from(sample_decimation),
            status_period,
            liveness,
            last_sequence: None,
            event_sequence: 0,
            counters: NodeCounters::default(),
            last_state: None,
            next_status: f64::NEG_INFINITY,
            supervisor_lost: false,
            overruns: None,
            stop_origins: VecDeque::new(),
        }
    }

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
