//! UDP FRI client: receive monitoring → session logic → controller → send
//! the command to the datagram's source address.
//!
//! Real-time hygiene (memory locking, SCHED_FIFO) is not applied: both need
//! unsafe FFI and this crate forbids unsafe code; run the process under
//! `chrt -f` on a PREEMPT_RT kernel instead (see README).

use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use crate::codec::{
    decode_monitoring, encode_command, DecodeError, EncodeError, MAX_DATAGRAM_BYTES,
};
use crate::messages::FriMonitoringMessage;
use crate::messages::SessionState;
use crate::session::{
    ClientSession, CommandIntent, Controller, MonitoringView, SequenceCheck, SessionFault,
};
use crate::version::FriVersion;

/// The client's receive timeout: a quarter of the kernel's default sensor
/// age limit (20 ms), so a silent link reaches the watchdog in time.
pub const CLIENT_RECEIVE_TIMEOUT: Duration = Duration::from_millis(5);
/// The client's receive timeout against an unpaced controller: there the
/// robot's clock is the plant's, and silence is seen as a gap between time
/// stamps (the session loop, `limb_session::run`); wall-clock stalls of a loaded
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

/// A failure of the client's own I/O or encoding.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// Socket error.
    #[error("FRI socket: {0}")]
    Io(#[from] std::io::Error),
    /// The reply could not be encoded.
    #[error("FRI encode: {0}")]
    Encode(#[from] EncodeError),
}

/// What one cycle did.
#[derive(Debug, Clone, PartialEq)]
pub enum CycleOutcome {
    /// A monitoring message was handled; `answered` if a command was sent.
    Handled {
        /// Session state of the message.
        state: SessionState,
        /// A command was sent back.
        answered: bool,
        /// A fault of this cycle.
        fault: Option<SessionFault>,
        /// The sequence-counter check (duplicates and stale datagrams are
        /// dropped: not answered, controller not called).
        sequence: SequenceCheck,
    },
    /// A datagram was not a valid monitoring message; nothing sent (the
    /// controller is told the link is stale if it has been silent for a
    /// receive timeout).
    Rejected(DecodeError),
    /// No datagram within the receive timeout; the controller was told
    /// (`on_link_stale` with the time since the last handled message).
    Stale,
}

/// What [`FriClient::receive`] got.
#[derive(Debug, Clone, PartialEq)]
pub enum Receipt {
    /// A monitoring message to handle: answer it with
    /// [`FriClient::answer`].
    Monitoring(MonitoringView),
    /// Nothing to handle; the cycle ended so (a dropped duplicate or stale
    /// datagram, a rejected datagram, no datagram in time).
    Done(CycleOutcome),
}

/// A monitoring message waiting for its answer.
#[derive(Debug, Clone)]
struct Pending {
    message: FriMonitoringMessage,
    source: SocketAddr,
    sequence: SequenceCheck,
}

/// An FRI client bound to one UDP socket.
#[derive(Debug)]
pub struct FriClient {
    socket: UdpSocket,
    version: FriVersion,
    session: ClientSession,
    start: Instant,
    last_receive: Instant,
    receive_timeout: Duration,
    buffer: [u8; MAX_DATAGRAM_BYTES + 1],
    pending: Option<Pending>,
}

impl FriClient {
    /// Binds to `address`; a cycle waits at most `receive_timeout` (must be
    /// non-zero) for a monitoring message. `max_joint_step` in rad per reply.
    ///
    /// # Errors
    /// [`ClientError::Io`] if binding or setting the timeout fails.
    pub fn bind(
        address: SocketAddr,
        version: FriVersion,
        max_joint_step: f64,
        receive_timeout: Duration,
    ) -> Result<Self, ClientError> {
        let socket = UdpSocket::bind(address)?;
        let receive_timeout = receive_timeout.max(Duration::from_micros(1));
        socket.set_read_timeout(Some(receive_timeout))?;
        let now = Instant::now();
        Ok(Self {
            socket,
            version,
            session: ClientSession::new(version, max_joint_step),
            start: now,
            last_receive: now,
            receive_timeout,
            buffer: [0; MAX_DATAGRAM_BYTES + 1],
            pending: None,
        })
    }

    /// The bound local address.
    ///
    /// # Errors
    /// [`ClientError::Io`] from the socket.
    pub fn local_addr(&self) -> Result<SocketAddr, ClientError> {
        Ok(self.socket.local_addr()?)
    }

    /// Runs one receive → decide → send cycle.
    ///
    /// # Errors
    /// [`ClientError`] on socket or encode failure (not on bad datagrams,
    /// which are [`CycleOutcome::Rejected`]).
    pub fn run_cycle(
        &mut self,
        controller: &mut impl Controller,
    ) -> Result<CycleOutcome, ClientError> {
        match self.receive()? {
            Receipt::Monitoring(view) => {
                let intent = controller.on_monitoring(&view, self.received_at());
                self.answer(intent)
            }
            Receipt::Done(outcome) => {
                // A receive that timed out is a receive timeout of silence
                // even when the socket's timer ended it early (it counts in
                // kernel ticks and may wake up to one tick short: seen,
                // the controller not told of a stale link).
                let silent_for = match outcome {
                    CycleOutcome::Stale => Some(
                        self.last_receive
                            .elapsed()
                            .max(self.receive_timeout)
                            .as_secs_f64(),
                    ),
                    _ => self.silence(),
                };
                if let Some(silent_for) = silent_for {
                    controller.on_link_stale(silent_for, self.clock());
                }
                Ok(outcome)
            }
        }
    }

    /// Waits at most the receive timeout for a datagram and checks it.
    ///
    /// # Errors
    /// [`ClientError::Io`] on socket failure.
    pub fn receive(&mut self) -> Result<Receipt, ClientError> {
        let (length, source) = match self.socket.recv_from(&mut self.buffer) {
            Ok(received) => received,
            Err(error)
                if matches!(
                    error.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return Ok(Receipt::Done(CycleOutcome::Stale));
            }
            Err(error) => return Err(error.into()),
        };
        let datagram = self.buffer.get(..length).unwrap_or_default();
        let message = match decode_monitoring(datagram, self.version) {
            Ok(message) => message,
            Err(error) => return Ok(Receipt::Done(CycleOutcome::Rejected(error))),
        };
        let sequence = self.session.accept(&message);
        let view = ClientSession::view(&message);
        if !sequence.is_handled() {
            return Ok(Receipt::Done(CycleOutcome::Handled {
                state: view.session_state,
                answered: false,
                fault: None,
                sequence,
            }));
        }
        self.last_receive = Instant::now();
        self.pending = Some(Pending {
            message,
            source,
            sequence,
        });
        Ok(Receipt::Monitoring(view))
    }

    /// Answers the message [`Self::receive`] returned with `intent` (where
    /// its state allows a command); without one, a [`CycleOutcome::Stale`].
    ///
    /// # Errors
    /// [`ClientError`] on socket or encode failure.
    pub fn answer(&mut self, intent: CommandIntent) -> Result<CycleOutcome, ClientError> {
        let Some(pending) = self.pending.take() else {
            return Ok(CycleOutcome::Stale);
        };
        let reply = self
            .session
            .reply(&pending.message, intent, pending.sequence);
        let answered = reply.command.is_some();
        if let Some(command) = reply.command {
            let bytes = encode_command(&command, self.version)?;
            self.socket.send_to(&bytes, pending.source)?;
        }
        Ok(CycleOutcome::Handled {
            state: ClientSession::view(&pending.message).session_state,
            answered,
            fault: reply.fault,
            sequence: reply.sequence,
        })
    }

    /// The client's clock: seconds since it was bound.
    pub fn clock(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// When the last handled monitoring message arrived, on [`Self::clock`].
    pub fn received_at(&self) -> f64 {
        self.last_receive.duration_since(self.start).as_secs_f64()
    }

    /// How long no monitoring message was handled [s], when that is a
    /// receive timeout or longer (a stream of garbage, duplicates or stale
    /// datagrams does not keep the link alive).
    pub fn silence(&self) -> Option<f64> {
        let silent_for = self.last_receive.elapsed();
        (silent_for >= self.receive_timeout).then_some(silent_for.as_secs_f64())
    }
}
