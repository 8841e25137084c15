//! Example datagrams for each session state: test vectors for `protoc`,
//! for other FRI implementations and for `limb kuka vectors`.
//!
//! Contents follow `kuka-fri.md`'s "what to send in each session state"
//! table for a joint-position client: monitoring states get a header-only
//! reply (1.x: echo of `commandedJointPosition`), COMMANDING_WAIT the IPO
//! joint position, COMMANDING_ACTIVE an absolute joint target.

use crate::messages::{
    ClientCommandMode, ConnectionInfo, ConnectionQuality, FriCommandMessage, FriMonitoringMessage,
    JointValues, MessageCommandData, MessageHeader, MessageIpoData, MessageMonitorData,
    SessionState, COMMAND_MESSAGE_ID, MONITORING_MESSAGE_ID,
};
use crate::version::FriVersion;

/// Every session state, in the order a session walks them.
pub const SESSION_STATES: [SessionState; 5] = [
    SessionState::Idle,
    SessionState::MonitoringWait,
    SessionState::MonitoringReady,
    SessionState::CommandingWait,
    SessionState::CommandingActive,
];

/// Example joint position of the vectors (rad).
const EXAMPLE_JOINT_POSITION: [f64; 7] = [0.0, 0.5, 0.0, -1.2, 0.0, 0.9, 0.0];
/// Joint step of the example COMMANDING_ACTIVE target (rad).
const EXAMPLE_TARGET_STEP: f64 = 0.001;

fn joint_values(values: [f64; 7]) -> Option<JointValues> {
    Some(JointValues {
        value: values.to_vec(),
    })
}

/// An example monitoring message in `state` (sequence counter = state index).
pub fn example_monitoring(state: SessionState, version: FriVersion) -> FriMonitoringMessage {
    let commanding = state >= SessionState::CommandingWait;
    let mut message = FriMonitoringMessage {
        header: MessageHeader {
            message_identifier: MONITORING_MESSAGE_ID,
            sequence_counter: state as u32,
            reflected_sequence_counter: 0,
        },
        connection_info: Some(ConnectionInfo {
            session_state: state as i32,
            quality: if state == SessionState::Idle {
                ConnectionQuality::Poor as i32
            } else {
                ConnectionQuality::Excellent as i32
            },
            send_period: Some(1),
            receive_multiplier: Some(1),
        }),
        monitor_data: Some(MessageMonitorData {
            measured_joint_position: joint_values(EXAMPLE_JOINT_POSITION),
            measured_torque: joint_values([0.0; 7]),
            commanded_joint_position: joint_values(EXAMPLE_JOINT_POSITION),
            external_torque: joint_values([0.0; 7]),
            ..Default::default()
        }),
        ipo_data: Some(MessageIpoData {
            joint_position: commanding.then(|| JointValues {
                value: EXAMPLE_JOINT_POSITION.to_vec(),
            }),
            client_command_mode: Some(ClientCommandMode::JointPosition as i32),
            ..Default::default()
        }),
        ..Default::default()
    };
    message.restrict_to(version);
    message
}

/// The example reply to [`example_monitoring`] in `state`; `None` in IDLE,
/// where the client sends nothing.
pub fn example_command(state: SessionState, version: FriVersion) -> Option<FriCommandMessage> {
    let joint_position = match state {
        SessionState::Idle => return None,
        SessionState::MonitoringWait | SessionState::MonitoringReady => {
            version.is_v1().then_some(EXAMPLE_JOINT_POSITION)
        }
        SessionState::CommandingWait => Some(EXAMPLE_JOINT_POSITION),
        SessionState::CommandingActive => {
            Some(EXAMPLE_JOINT_POSITION.map(|angle| angle + EXAMPLE_TARGET_STEP))
        }
    };
    let mut message = FriCommandMessage {
        header: MessageHeader {
            message_identifier: COMMAND_MESSAGE_ID,
            sequence_counter: state as u32 - 1,
            reflected_sequence_counter: state as u32,
        },
        command_data: joint_position.map(|values| MessageCommandData {
            joint_position: joint_values(values),
            ..Default::default()
        }),
        end_of_message_data: None,
    };
    message.restrict_to(version);
    Some(message)
}
