//! Pure FRI client session logic: no I/O, time only as an input.
//!
//! Theory of operation: for each decoded monitoring message,
//! [`ClientSession::on_monitoring`] decides whether to answer (every state
//! but IDLE, every `receiveMultiplier`-th message), stamps the header (own
//! counter from 0 wrapping at 2^32, reflected counter = the monitor's), and
//! fills the per-state contents of `kuka-fri.md`:
//! monitoring states → header only (1.x: echo `commandedJointPosition`);
//! COMMANDING_WAIT → the IPO joint position; COMMANDING_ACTIVE → the
//! controller's target if quality is GOOD or better, else the hold position.
//! Targets move at most `max_joint_step` rad per reply from the last one
//! sent, so re-entry into commanding starts from the IPO position without a
//! jump. A non-finite intent becomes hold + [`SessionFault::NonFiniteIntent`];
//! nothing non-finite is ever put on the wire.
//!
//! Joint-position command mode only for now; wrench and torque modes are
//! left to do.

use crate::messages::{
    ClientCommandMode, ConnectionQuality, FriCommandMessage, FriMonitoringMessage, JointValues,
    MessageCommandData, MessageHeader, SessionState, COMMAND_MESSAGE_ID,
};
use crate::version::FriVersion;

/// Joint angles of the 7-joint arm (rad).
pub type JointVector = [f64; 7];

/// What the controller sees of one monitoring message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonitoringView {
    /// Session state.
    pub session_state: SessionState,
    /// Connection quality.
    pub quality: ConnectionQuality,
    /// Measured joint position (rad), if present, 7 values and finite.
    pub measured_joint_position: Option<JointVector>,
    /// IPO joint position (rad), if present, 7 values and finite.
    pub ipo_joint_position: Option<JointVector>,
    /// Command mode the robot expects.
    pub client_command_mode: ClientCommandMode,
}

/// What the controller wants sent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CommandIntent {
    /// Keep the last target (or the IPO / measured position).
    Hold,
    /// Absolute joint targets (rad).
    JointPosition(JointVector),
}

/// The control law behind the adapter; the kernel plugs in here.
pub trait Controller {
    /// Called for every monitoring message that is answered; `now` in s.
    fn on_monitoring(&mut self, view: &MonitoringView, now: f64) -> CommandIntent;
    /// Called when no monitoring message arrived for `silent_for` s.
    fn on_link_stale(&mut self, silent_for: f64, now: f64);
}

/// A fault of one cycle; the reply sent is still safe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SessionFault {
    /// The controller asked for a non-finite target; held instead.
    #[error("non-finite command intent, holding")]
    NonFiniteIntent,
    /// No finite position to command; header-only reply sent.
    #[error("no finite joint position available to command")]
    NoFinitePosition,
}

/// The outcome of one monitoring message.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionReply {
    /// The command to send back, if any.
    pub command: Option<FriCommandMessage>,
    /// A fault of this cycle, if any.
    pub fault: Option<SessionFault>,
}

/// Client session state across messages.
#[derive(Debug, Clone)]
pub struct ClientSession {
    version: FriVersion,
    max_joint_step: f64,
    own_counter: u32,
    messages_since_reply: u32,
    last_target: Option<JointVector>,
}

fn finite_joints(values: Option<&JointValues>) -> Option<JointVector> {
    let values = values?;
    let array: JointVector = values.value.as_slice().try_into().ok()?;
    array.iter().all(|value| value.is_finite()).then_some(array)
}

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
        }
    }

    /// The controller's view of `message`.
    pub fn view(message: &FriMonitoringMessage) -> MonitoringView {
        let info = message.connection_info.unwrap_or_default();
        let ipo = message.ipo_data.as_ref();
        MonitoringView {
            session_state: SessionState::try_from(info.session_state).unwrap_or(SessionState::Idle),
            quality: ConnectionQuality::try_from(info.quality).unwrap_or(ConnectionQuality::Poor),
            measured_joint_position: finite_joints(
                message
                    .monitor_data
                    .as_ref()
                    .and_then(|data| data.measured_joint_position.as_ref()),
            ),
            ipo_joint_position: finite_joints(ipo.and_then(|ipo| ipo.joint_position.as_ref())),
            client_command_mode: ipo
                .and_then(|ipo| ipo.client_command_mode)
                .and_then(|raw| ClientCommandMode::try_from(raw).ok())
                .unwrap_or(ClientCommandMode::NoCommand),
        }
    }

    /// Handles one monitoring message received at `now` (s).
    pub fn on_monitoring(
        &mut self,
        message: &FriMonitoringMessage,
        controller: &mut impl Controller,
        now: f64,
    ) -> SessionReply {
        let view = Self::view(message);
        if view.session_state == SessionState::Idle {
            self.last_target = None;
            return SessionReply {
                command: None,
                fault: None,
            };
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
            return SessionReply {
                command: None,
                fault: None,
            };
        }
        self.messages_since_reply = 0;
        let hold = self
            .last_target
            .or(view.ipo_joint_position)
            .or(view.measured_joint_position);
        let (joint_position, fault) = match view.session_state {
            SessionState::Idle => (None, None),
            SessionState::MonitoringWait | SessionState::MonitoringReady => {
                let echo = self.version.is_v1().then(|| {
                    finite_joints(
                        message
                            .monitor_data
                            .as_ref()
                            .and_then(|data| data.commanded_joint_position.as_ref()),
                    )
                });
                (echo.flatten(), None)
            }
            SessionState::CommandingWait => {
                let sync = view.ipo_joint_position.or(view.measured_joint_position);
                self.last_target = sync;
                (
                    sync,
                    sync.is_none().then_some(SessionFault::NoFinitePosition),
                )
            }
            SessionState::CommandingActive => self.commanding_target(&view, hold, controller, now),
        };
        let header = MessageHeader {
            message_identifier: COMMAND_MESSAGE_ID,
            sequence_counter: self.own_counter,
            reflected_sequence_counter: message.header.sequence_counter,
        };
        self.own_counter = self.own_counter.wrapping_add(1);
        let mut command = FriCommandMessage {
            header,
            command_data: joint_position.map(|values| MessageCommandData {
                joint_position: Some(JointValues {
                    value: values.to_vec(),
                }),
                ..Default::default()
            }),
            end_of_message_data: None,
        };
        command.restrict_to(self.version);
        SessionReply {
            command: Some(command),
            fault,
        }
    }

    fn commanding_target(
        &mut self,
        view: &MonitoringView,
        hold: Option<JointVector>,
        controller: &mut impl Controller,
        now: f64,
    ) -> (Option<JointVector>, Option<SessionFault>) {
        let Some(hold) = hold else {
            return (None, Some(SessionFault::NoFinitePosition));
        };
        let intent = controller.on_monitoring(view, now);
        let (wanted, fault) = match intent {
            _ if view.quality < ConnectionQuality::Good => (hold, None),
            CommandIntent::Hold => (hold, None),
            CommandIntent::JointPosition(target) if target.iter().all(|v| v.is_finite()) => {
                (target, None)
            }
            CommandIntent::JointPosition(_) => (hold, Some(SessionFault::NonFiniteIntent)),
        };
        let step = self.max_joint_step;
        let mut limited = hold;
        for (out, (from, to)) in limited.iter_mut().zip(hold.iter().zip(wanted.iter())) {
            *out = from + (to - from).clamp(-step, step);
        }
        self.last_target = Some(limited);
        (Some(limited), fault)
    }
}
