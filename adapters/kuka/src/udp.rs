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
use crate::messages::SessionState;
use crate::session::{ClientSession, Controller, SequenceCheck, SessionFault};
use crate::version::FriVersion;

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
        let (length, source) = match self.socket.recv_from(&mut self.buffer) {
            Ok(received) => received,
            Err(error)
                if matches!(
                    error.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                self.tell_if_stale(controller, Instant::now());
                return Ok(CycleOutcome::Stale);
            }
            Err(error) => return Err(error.into()),
        };
        let datagram = self.buffer.get(..length).unwrap_or_default();
        let message = match decode_monitoring(datagram, self.version) {
            Ok(message) => message,
            Err(error) => {
                self.tell_if_stale(controller, Instant::now());
                return Ok(CycleOutcome::Rejected(error));
            }
        };
        let now = Instant::now();
        let reply = self.session.on_monitoring(
            &message,
            controller,
            now.duration_since(self.start).as_secs_f64(),
        );
        if reply.sequence.is_handled() {
            self.last_receive = now;
        } else {
            self.tell_if_stale(controller, now);
        }
        let state = ClientSession::view(&message).session_state;
        let answered = reply.command.is_some();
        if let Some(command) = reply.command {
            let bytes = encode_command(&command, self.version)?;
            self.socket.send_to(&bytes, source)?;
        }
        Ok(CycleOutcome::Handled {
            state,
            answered,
            fault: reply.fault,
            sequence: reply.sequence,
        })
    }

    /// Tells the controller the link is stale when no monitoring message
    /// was handled for a receive timeout or longer (a stream of garbage,
    /// duplicates or stale datagrams does not keep the link alive).
    fn tell_if_stale(&self, controller: &mut impl Controller, now: Instant) {
        let silent_for = now.duration_since(self.last_receive);
        if silent_for >= self.receive_timeout {
            controller.on_link_stale(
                silent_for.as_secs_f64(),
                now.duration_since(self.start).as_secs_f64(),
            );
        }
    }
}
