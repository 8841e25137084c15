//! The Zenoh side of a kernel node: the session, subscribers, queryables
//! and the publisher thread. Its in-loop half, [`Supervision`], is
//! [`crate::supervision`]; [`Link::open`] makes both.
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
use crate::supervision::{
    stamp, LivenessPolicy, Outbound, Queues, Shared, Supervision, COMMAND_QUEUE, ESTOP_QUEUE,
    OUTBOUND_QUEUE,
};
use crate::wire::{Ack, CommandMessage, RefuseReason, StateSnapshot, WireFormat};
use limb_kernel::KernelConfig;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use zenoh::qos::{CongestionControl, Priority};
use zenoh::Wait;

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
        let shared = Arc::new(Shared::new());
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

        let supervision = Supervision::new(
            Queues {
                shared,
                commands,
                estops,
                outbound: outbound.clone(),
                samples: loop_samples,
            },
            settings.sample_decimation,
            settings.status_period,
            settings.liveness,
        );
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
