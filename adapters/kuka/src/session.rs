//! Pure FRI client session logic: no I/O, time only as an input.
//!
//! Theory of operation: for each decoded monitoring message,
//! [`ClientSession::on_monitoring`] first checks the monitor's sequence
//! counter ([`SequenceCheck`]): a duplicate or an older (reordered,
//! delayed) datagram is dropped — not answered, not shown to the
//! controller — because a newer one was already handled; a gap or a jump is
//! counted and the message handled (newest data wins). Every other message
//! goes to the [`Controller`] once (in every state, IDLE included, so the
//! control loop runs once per monitoring message). Then the session decides
//! whether to answer (every state but IDLE, every `receiveMultiplier`-th
//! message), stamps the header (own counter from 0 wrapping at 2^32,
//! reflected counter = the monitor's), and fills the per-state contents of
//! `kuka-fri.md`:
//! monitoring states → header only (1.x: echo `commandedJointPosition`);
//! COMMANDING_WAIT → the IPO joint position (wrench mode: plus a zero
//! wrench); COMMANDING_ACTIVE → the controller's intent if quality is GOOD
//! or better and the intent matches the robot's `clientCommandMode`, else
//! hold (joint mode: the last target; wrench mode: zero wrench).
//! Joint targets move at most `max_joint_step` rad per reply from the last
//! one sent, so re-entry into commanding starts from the IPO position without
//! a jump. In wrench mode every reply carries the IPO (else measured) joint
//! position beside `cartesianWrenchFeedForward`. A non-finite intent becomes
//! hold + [`SessionFault::NonFiniteIntent`]; nothing non-finite is ever put on
//! the wire.

use crate::messages::{
    CartesianVector, ClientCommandMode, ConnectionQuality, FriCommandMessage, FriMonitoringMessage,
    JointValues, MessageCommandData, MessageHeader, SessionState, COMMAND_MESSAGE_ID,
};
use crate::version::FriVersion;

/// Joint angles (rad) or torques (N m) of the 7-joint arm.
pub type JointVector = [f64; 7];

/// A Cartesian wrench for `cartesianWrenchFeedForward`: Fx, Fy, Fz [N],
/// then torques A, B, C [N m] (about z, y, x), robot base frame.
pub type CartesianWrench = [f64; 6];

/// Monitor counters older than the last handled one by at most this many
/// are reordered or delayed datagrams (dropped); further back is a
/// counter jump (the controller restarted its counter: resynchronise).
/// 16 datagrams = 16 ms at 1 kHz: far more reordering than a direct
/// Ethernet link shows, and a restarted counter costs at most 16 dropped
/// messages.
pub const REORDER_WINDOW: u32 = 16;

/// What the controller sees of one monitoring message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonitoringView {
    /// The monitor's sequence counter.
    pub sequence_counter: u32,
    /// Session state.
    pub session_state: SessionState,
    /// Connection quality.
    pub quality: ConnectionQuality,
    /// Robot time stamp of the message [s], if present.
    pub timestamp: Option<f64>,
    /// Measured joint position (rad), if present, 7 values and finite.
    pub measured_joint_position: Option<JointVector>,
    /// External joint torques (N m), if present, 7 values and finite.
    pub external_torque: Option<JointVector>,
    /// IPO joint position (rad), if present, 7 values and finite.
    pub ipo_joint_position: Option<JointVector>,
    /// Command mode the robot expects.
    pub client_command_mode: ClientCommandMode,
}

/// What the controller wants sent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CommandIntent {
    /// Keep the last target (or the IPO / measured position); zero wrench.
    Hold,
    /// Absolute joint targets (rad); for `clientCommandMode` POSITION.
    JointPosition(JointVector),
    /// Wrench overlay; for `clientCommandMode` WRENCH.
    Wrench(CartesianWrench),
}

/// The control law behind the adapter; the kernel plugs in here.
pub trait Controller {
    /// Called once for every monitoring message handled (not for dropped
    /// duplicates or stale datagrams), in every session state; `now` in s
    /// (client clock). The intent is used only when a COMMANDING_ACTIVE
    /// reply is due.
    fn on_monitoring(&mut self, view: &MonitoringView, now: f64) -> CommandIntent;
    /// Called when no monitoring message arrived for `silent_for` s.
    fn on_link_stale(&mut self, silent_for: f64, now: f64);
}

/// A fault of one cycle; the reply sent is still safe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SessionFault {
    /// The controller asked for a non-finite target or wrench; held instead.
    #[error("non-finite command intent, holding")]
    NonFiniteIntent,
    /// No finite position to command; header-only reply sent.
    #[error("no finite joint position available to command")]
    NoFinitePosition,
    /// The intent does not match the robot's client command mode; held.
    #[error("command intent does not match the robot's client command mode, holding")]
    ModeMismatch,
}

/// How a monitor's sequence counter relates to the last handled one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SequenceCheck {
    /// The first message of the session.
    First,
    /// The next counter.
    InOrder,
    /// `missed` counters were skipped (lost datagrams); handled.
    Gap {
        /// Number of counters skipped.
        missed: u32,
    },
    /// The same counter again; dropped.
    Duplicate,
    /// An older counter (reordered or delayed); dropped.
    Stale {
        /// How far behind the last handled counter.
        behind: u32,
    },
    /// More than [`REORDER_WINDOW`] behind: a restarted counter; handled.
    Resynchronised,
}

impl SequenceCheck {
    /// Classifies `counter` given the last handled counter (wrapping).
    pub fn classify(last: Option<u32>, counter: u32) -> Self {
        let Some(last) = last else {
            return Self::First;
        };
        let ahead = counter.wrapping_sub(last);
        let behind = last.wrapping_sub(counter);
        match ahead {
            0 => Self::Duplicate,
            1 => Self::InOrder,
            _ if behind <= REORDER_WINDOW => Self::Stale { behind },
            _ if ahead <= u32::MAX / 2 => Self::Gap { missed: ahead - 1 },
            _ => Self::Resynchronised,
        }
    }

    /// True when the message is handled (not dropped).
    pub fn is_handled(self) -> bool {
        !matches!(self, Self::Duplicate | Self::Stale { .. })
    }
}

/// The outcome of one monitoring message.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionReply {
    /// The command to send back, if any.
    pub command: Option<FriCommandMessage>,
    /// A fault of this cycle, if any.
    pub fault: Option<SessionFault>,
    /// The sequence-counter check of the message.
    pub sequence: SequenceCheck,
}

/// Client session state across messages.
#[derive(Debug, Clone)]
pub struct ClientSession {
    version: FriVersion,
    max_joint_step: f64,
    own_counter: u32,
    messages_since_reply: u32,
    last_target: Option<JointVector>,
    last_monitor_counter: Option<u32>,
}

fn finite_joints(values: Option<&JointValues>) -> Option<JointVector> {
    let values = values?;
    let array: JointVector = values.value.as_slice().try_into().ok()?;
    array.iter().all(|value| value.is_finite()).then_some(array)
}

/// Joint position and wrench of one reply.
type Contents = (
    Option<JointVector>,
    Option<CartesianWrench>,
    Option<SessionFault>,
);

impl ClientSession {
    /// A new session; `max_joint_step` is the largest target change per
    /// reply (rad), taken as its absolute value.
    pub fn new(version: FriVersion, max_joint_step: f64) -> Self {
        Self {
            version,
            max_joint_step: max_joint_step.abs(),
            own_counter: 0,
            messages_since_reply: 0,
            last_target: None,
            last_monitor_counter: None,
        }
    }

    /// The controller's view of `message`.
    pub fn view(message: &FriMonitoringMessage) -> MonitoringView {
        let info = message.connection_info.unwrap_or_default();
        let ipo = message.ipo_data.as_ref();
        let monitor = message.monitor_data.as_ref();
        MonitoringView {
            sequence_counter: message.header.sequence_counter,
            session_state: SessionState::try_from(info.session_state).unwrap_or(SessionState::Idle),
            quality: ConnectionQuality::try_from(info.quality).unwrap_or(ConnectionQuality::Poor),
            timestamp: monitor
                .and_then(|data| data.timestamp)
                .map(|stamp| f64::from(stamp.sec) + f64::from(stamp.nanosec) * 1e-9),
            measured_joint_position: finite_joints(
                monitor.and_then(|data| data.measured_joint_position.as_ref()),
            ),
            external_torque: finite_joints(monitor.and_then(|data| data.external_torque.as_ref())),
            ipo_joint_position: finite_joints(ipo.and_then(|ipo| ipo.joint_position.as_ref())),
            client_command_mode: ipo
                .and_then(|ipo| ipo.client_command_mode)
                .and_then(|raw| ClientCommandMode::try_from(raw).ok())
                .unwrap_or(ClientCommandMode::NoCommand),
        }
    }

    /// Handles one monitoring message received at `now` (s): [`Self::accept`],
    /// the controller, [`Self::reply`].
    pub fn on_monitoring(
        &mut self,
        message: &FriMonitoringMessage,
        controller: &mut impl Controller,
        now: f64,
    ) -> SessionReply {
        let sequence = self.accept(message);
        if !sequence.is_handled() {
            return SessionReply {
                command: None,
                fault: None,
                sequence,
            };
        }
        let intent = controller.on_monitoring(&Self::view(message), now);
        self.reply(message, intent, sequence)
    }

    /// Checks the sequence counter of `message` and, when it is handled
    /// (not a duplicate or a stale datagram), records it.
    pub fn accept(&mut self, message: &FriMonitoringMessage) -> SequenceCheck {
        let sequence =
            SequenceCheck::classify(self.last_monitor_counter, message.header.sequence_counter);
        if sequence.is_handled() {
            self.last_monitor_counter = Some(message.header.sequence_counter);
        }
        sequence
    }

    /// The reply to an accepted `message` (its `sequence` check) carrying
    /// `intent` where the state allows.
    pub fn reply(
        &mut self,
        message: &FriMonitoringMessage,
        intent: CommandIntent,
        sequence: SequenceCheck,
    ) -> SessionReply {
        let silent = |sequence| SessionReply {
            command: None,
            fault: None,
            sequence,
        };
        let view = Self::view(message);
        if view.session_state == SessionState::Idle {
            self.last_target = None;
            self.messages_since_reply = 0;
            return silent(sequence);
        }
        if view.session_state < SessionState::CommandingWait {
            self.last_target = None;
        }
        let multiplier = message
            .connection_info
            .and_then(|info| info.receive_multiplier)
            .unwrap_or(1)
            .max(1);
        self.messages_since_reply += 1;
        if self.messages_since_reply < multiplier {
            return silent(sequence);
        }
        self.messages_since_reply = 0;
        let wrench_mode = view.client_command_mode == ClientCommandMode::Wrench;
        let (joint_position, wrench, fault) = match view.session_state {
            SessionState::Idle => (None, None, None),
            SessionState::MonitoringWait | SessionState::MonitoringReady => {
                let echo = self.version.is_v1().then(|| {
                    finite_joints(
                        message
                            .monitor_data
                            .as_ref()
                            .and_then(|data| data.commanded_joint_position.as_ref()),
                    )
                });
                (echo.flatten(), None, None)
            }
            SessionState::CommandingWait => {
                let sync = view.ipo_joint_position.or(view.measured_joint_position);
                self.last_target = sync;
                (
                    sync,
                    wrench_mode.then_some([0.0; 6]),
                    sync.is_none().then_some(SessionFault::NoFinitePosition),
                )
            }
            SessionState::CommandingActive if wrench_mode => Self::wrench_contents(&view, intent),
            SessionState::CommandingActive => self.joint_contents(&view, intent),
        };
        let header = MessageHeader {
            message_identifier: COMMAND_MESSAGE_ID,
            sequence_counter: self.own_counter,
            reflected_sequence_counter: message.header.sequence_counter,
        };
        self.own_counter = self.own_counter.wrapping_add(1);
        let command_data =
            (joint_position.is_some() || wrench.is_some()).then(|| MessageCommandData {
                joint_position: joint_position.map(|values| JointValues {
                    value: values.to_vec(),
                }),
                cartesian_wrench_feed_forward: wrench.map(|values| CartesianVector {
                    element: values.to_vec(),
                }),
                ..Default::default()
            });
        let mut command = FriCommandMessage {
            header,
            command_data,
            end_of_message_data: None,
        };
        command.restrict_to(self.version);
        SessionReply {
            command: Some(command),
            fault,
            sequence,
        }
    }

    /// Wrench mode, COMMANDING_ACTIVE: the IPO (else measured) joint
    /// position and the intent's wrench, or zero when holding.
    fn wrench_contents(view: &MonitoringView, intent: CommandIntent) -> Contents {
        let position = view.ipo_joint_position.or(view.measured_joint_position);
        let Some(position) = position else {
            return (None, None, Some(SessionFault::NoFinitePosition));
        };
        let (wrench, fault) = match intent {
            _ if view.quality < ConnectionQuality::Good => ([0.0; 6], None),
            CommandIntent::Hold => ([0.0; 6], None),
            CommandIntent::Wrench(wrench) if wrench.iter().all(|v| v.is_finite()) => (wrench, None),
            CommandIntent::Wrench(_) => ([0.0; 6], Some(SessionFault::NonFiniteIntent)),
            CommandIntent::JointPosition(_) => ([0.0; 6], Some(SessionFault::ModeMismatch)),
        };
        (Some(position), Some(wrench), fault)
    }

    /// Joint-position mode, COMMANDING_ACTIVE: the intent's target, rate
    /// limited from the last one sent, or the hold position.
    fn joint_contents(&mut self, view: &MonitoringView, intent: CommandIntent) -> Contents {
        let hold = self
            .last_target
            .or(view.ipo_joint_position)
            .or(view.measured_joint_position);
        let Some(hold) = hold else {
            return (None, None, Some(SessionFault::NoFinitePosition));
        };
        let (wanted, fault) = match intent {
            _ if view.quality < ConnectionQuality::Good => (hold, None),
            CommandIntent::Hold => (hold, None),
            CommandIntent::JointPosition(target) if target.iter().all(|v| v.is_finite()) => {
                (target, None)
            }
            CommandIntent::JointPosition(_) => (hold, Some(SessionFault::NonFiniteIntent)),
            CommandIntent::Wrench(_) => (hold, Some(SessionFault::ModeMismatch)),
        };
        let step = self.max_joint_step;
        let mut limited = hold;
        for (out, (from, to)) in limited.iter_mut().zip(hold.iter().zip(wanted.iter())) {
            *out = from + (to - from).clamp(-step, step);
        }
        self.last_target = Some(limited);
        (Some(limited), None, fault)
    }
}
