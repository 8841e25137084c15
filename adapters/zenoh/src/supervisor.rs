//! The supervisor side: sends signed commands and the emergency stop,
//! publishes its heartbeat, collects acks and queries the node.
//!
//! Used by the tests, the benchmark and the `limb` tool; a supervisor in
//! another language follows `PROTOCOL.md`.

use crate::auth::CommandKey;
use crate::error::AdapterError;
use crate::keys::Keys;
use crate::supervision::wall_clock_ns;
use crate::wire::{
    Ack, CommandMessage, EmergencyStopMessage, Heartbeat, SupervisorCommand, WireFormat,
};
use serde::de::DeserializeOwned;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use zenoh::qos::{CongestionControl, Priority};
use zenoh::Wait;

/// Acks kept until read; older ones are dropped when full.
const ACK_QUEUE: usize = 256;

/// A supervisor station of one robot, over Zenoh: the remote party that
/// sends commands and e-stops (not `limb_session::Supervisor`, the
/// in-loop role [`crate::supervision::Supervision`] plays in the robot's session).
pub struct SupervisorStation {
    session: zenoh::Session,
    keys: Keys,
    format: WireFormat,
    key: CommandKey,
    request: zenoh::pubsub::Publisher<'static>,
    estop: zenoh::pubsub::Publisher<'static>,
    /// The lowest sequence number the next message may use.
    sequence_floor: u64,
    acks: Receiver<Ack>,
    _ack_subscriber: zenoh::pubsub::Subscriber<()>,
    heartbeat: Option<HeartbeatTask>,
}

struct HeartbeatTask {
    stop: Arc<AtomicBool>,
    thread: JoinHandle<()>,
}

impl SupervisorStation {
    /// Opens a session with `zenoh_config` for robot `robot_id`, signing
    /// with `key`. Sequence numbers follow the wall clock in µs (see
    /// [`next_sequence`]), so a restarted supervisor stays above what the
    /// node last accepted and several supervisors share the node's
    /// sequence.
    ///
    /// # Errors
    /// [`AdapterError`] for a bad robot id or a Zenoh failure.
    pub fn connect(
        zenoh_config: zenoh::Config,
        robot_id: &str,
        format: WireFormat,
        key: CommandKey,
    ) -> Result<Self, AdapterError> {
        let keys = Keys::new(robot_id)?;
        let session = zenoh::open(zenoh_config).wait()?;
        let request = session
            .declare_publisher(keys.request())
            .congestion_control(CongestionControl::Block)
            .priority(Priority::InteractiveHigh)
            .encoding(format.encoding())
            .wait()?;
        let estop = session
            .declare_publisher(keys.emergency_stop())
            .congestion_control(CongestionControl::Block)
            .priority(Priority::RealTime)
            .express(true)
            .encoding(format.encoding())
            .wait()?;
        let (ack_tx, acks) = sync_channel(ACK_QUEUE);
        let ack_subscriber = session
            .declare_subscriber(keys.ack())
            .callback(move |sample| {
                if let Ok(ack) = format.decode::<Ack>(&sample.payload().to_bytes()) {
                    let _ = ack_tx.try_send(ack);
                }
            })
            .wait()?;
        Ok(Self {
            session,
            keys,
            format,
            key,
            request,
            estop,
            sequence_floor: 0,
            acks,
            _ack_subscriber: ack_subscriber,
            heartbeat: None,
        })
    }

    /// The session (to subscribe to telemetry).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    /// The robot's keys.
    pub fn keys(&self) -> &Keys {
        &self.keys
    }

    /// Waits until the node's command and e-stop subscribers are routed.
    ///
    /// # Errors
    /// [`AdapterError::Timeout`] after `timeout`.
    pub fn wait_for_node(&self, timeout: Duration) -> Result<(), AdapterError> {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            let routed = |p: &zenoh::pubsub::Publisher<'static>| {
                p.matching_status().wait().is_ok_and(|s| s.matching())
            };
            if routed(&self.request) && routed(&self.estop) {
                return Ok(());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        Err(AdapterError::Timeout("the node's command subscribers"))
    }

    /// Signs and sends `command`; returns its sequence number.
    ///
    /// # Errors
    /// [`AdapterError`] when it cannot be encoded or sent.
    pub fn send(&mut self, command: SupervisorCommand) -> Result<u64, AdapterError> {
        let sequence = next_sequence(&mut self.sequence_floor);
        let payload = self.format.encode(&CommandMessage { sequence, command })?;
        self.send_raw(&payload, Some(&self.key))?;
        Ok(sequence)
    }

    /// Sends `payload` as is on `cmd/request`, signed with `key` if given
    /// (for tests of what the node refuses).
    ///
    /// # Errors
    /// [`AdapterError::Zenoh`] when it cannot be sent.
    pub fn send_raw(&self, payload: &[u8], key: Option<&CommandKey>) -> Result<(), AdapterError> {
        let put = self.request.put(payload.to_vec());
        let put = match key {
            Some(key) => put.attachment(key.sign(&self.keys.request(), payload).to_vec()),
            None => put,
        };
        put.wait()?;
        Ok(())
    }

    /// Sends `command` and waits for its ack.
    ///
    /// # Errors
    /// [`AdapterError::Timeout`] when no ack arrives within `timeout`.
    pub fn request(
        &mut self,
        command: SupervisorCommand,
        timeout: Duration,
    ) -> Result<Ack, AdapterError> {
        let sequence = self.send(command)?;
        self.wait_ack(|ack| ack.sequence == Some(sequence), timeout)
    }

    /// Waits for the first ack that satisfies `matches`, discarding others.
    ///
    /// # Errors
    /// [`AdapterError::Timeout`] after `timeout`.
    pub fn wait_ack(
        &self,
        matches: impl Fn(&Ack) -> bool,
        timeout: Duration,
    ) -> Result<Ack, AdapterError> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.acks.recv_timeout(left) {
                Ok(ack) if matches(&ack) => return Ok(ack),
                Ok(_) => {}
                Err(_) => return Err(AdapterError::Timeout("an ack")),
            }
        }
    }

    /// Sends an emergency stop: unsigned, express, priority RealTime.
    ///
    /// # Errors
    /// [`AdapterError`] when it cannot be sent.
    pub fn emergency_stop(&mut self) -> Result<u64, AdapterError> {
        let sequence = next_sequence(&mut self.sequence_floor);
        let payload = self.format.encode(&EmergencyStopMessage { sequence })?;
        self.estop.put(payload).wait()?;
        Ok(sequence)
    }

    /// Starts publishing signed heartbeats every `period` (e.g. 50 ms);
    /// replaces a running heartbeat.
    ///
    /// # Errors
    /// [`AdapterError`] when the publisher or thread cannot start.
    pub fn start_heartbeat(&mut self, period: Duration) -> Result<(), AdapterError> {
        self.stop_heartbeat();
        let key_expr = self.keys.supervisor_alive();
        let publisher = self
            .session
            .declare_publisher(key_expr.clone())
            .congestion_control(CongestionControl::Drop)
            .priority(Priority::InteractiveHigh)
            .encoding(self.format.encoding())
            .wait()?;
        let stop = Arc::new(AtomicBool::new(false));
        let (format, key) = (self.format, self.key.clone());
        let thread = std::thread::Builder::new()
            .name("limb-supervisor-heartbeat".into())
            .spawn({
                let stop = Arc::clone(&stop);
                move || {
                    let mut next = 0;
                    while !stop.load(Ordering::Acquire) {
                        let sequence = next_sequence(&mut next);
                        if let Ok(payload) = format.encode(&Heartbeat { sequence }) {
                            let signature = key.sign(&key_expr, &payload).to_vec();
                            let _ = publisher.put(payload).attachment(signature).wait();
                        }
                        std::thread::sleep(period);
                    }
                }
            })?;
        self.heartbeat = Some(HeartbeatTask { stop, thread });
        Ok(())
    }

    /// Stops the heartbeat while keeping the session: what a hung
    /// supervisor looks like to the node.
    pub fn stop_heartbeat(&mut self) {
        if let Some(task) = self.heartbeat.take() {
            task.stop.store(true, Ordering::Release);
            let _ = task.thread.join();
        }
    }

    /// Queries `key` (e.g. `keys().state()`) and decodes the first answer.
    ///
    /// # Errors
    /// [`AdapterError::Timeout`] when nothing usable answers in `timeout`.
    pub fn query<T: DeserializeOwned>(
        &self,
        key: &str,
        timeout: Duration,
    ) -> Result<T, AdapterError> {
        let replies = self.session.get(key).timeout(timeout).wait()?;
        while let Ok(reply) = replies.recv() {
            if let Ok(sample) = reply.result() {
                return Ok(self.format.decode(&sample.payload().to_bytes())?);
            }
        }
        Err(AdapterError::Timeout("a query answer"))
    }

    /// Stops the heartbeat and closes the session (dropping the supervisor
    /// stops the heartbeat too).
    ///
    /// # Errors
    /// [`AdapterError::Zenoh`] on a close failure.
    pub fn close(mut self) -> Result<(), AdapterError> {
        self.stop_heartbeat();
        self.session.close().wait()?;
        Ok(())
    }
}

/// The next sequence number of a command or heartbeat: the wall clock in
/// µs since the UNIX epoch, or `next` when that is higher (a clock step
/// back, or two sends in one µs); advances `next` past it.
///
/// The node accepts only numbers above the last it accepted from any
/// supervisor; numbers taken from one shared clock interleave, so
/// supervisors started at different times can take turns. Their clocks
/// must agree to better than the time between their commands.
pub fn next_sequence(next: &mut u64) -> u64 {
    let sequence = (wall_clock_ns() / 1000).max(*next);
    *next = sequence.saturating_add(1);
    sequence
}

impl Drop for SupervisorStation {
    fn drop(&mut self) {
        self.stop_heartbeat();
    }
}
