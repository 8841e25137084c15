//! Codec tests: golden bytes, never-panic on garbage, round trip per version.

use limb_kuka::messages::*;
use limb_kuka::{
    decode_command, decode_monitoring, encode_command, encode_monitoring, DecodeError, FriVersion,
};
use proptest::prelude::*;
use prost::Message;

fn command_header_only(sequence: u32, reflected: u32) -> FriCommandMessage {
    FriCommandMessage {
        header: MessageHeader {
            message_identifier: COMMAND_MESSAGE_ID,
            sequence_counter: sequence,
            reflected_sequence_counter: reflected,
        },
        command_data: None,
        end_of_message_data: None,
    }
}

/// All three header fields are encoded, even a zero counter.
#[test]
fn golden_header_bytes() {
    let bytes = encode_command(&command_header_only(0, 5), FriVersion::V1_15).unwrap();
    assert_eq!(
        bytes,
        [0x0a, 0x08, 0x08, 0x81, 0x80, 0x0d, 0x10, 0x00, 0x18, 0x05]
    );
}

/// JointValues is encoded unpacked: one key (0x09) per double.
#[test]
fn golden_joint_values_unpacked() {
    let values = JointValues {
        value: vec![1.0, 2.0],
    };
    let mut expected = vec![0x09];
    expected.extend_from_slice(&1.0f64.to_le_bytes());
    expected.push(0x09);
    expected.extend_from_slice(&2.0f64.to_le_bytes());
    assert_eq!(values.encode_to_vec(), expected);
}

/// A packed JointValues (key 0x0a) decodes to the same values.
#[test]
fn joint_values_packed_decodes() {
    let mut packed = vec![0x0a, 16];
    packed.extend_from_slice(&1.0f64.to_le_bytes());
    packed.extend_from_slice(&2.0f64.to_le_bytes());
    let decoded = JointValues::decode(packed.as_slice()).unwrap();
    assert_eq!(decoded.value, vec![1.0, 2.0]);
}

/// CartesianVector is encoded packed.
#[test]
fn golden_cartesian_vector_packed() {
    let vector = CartesianVector { element: vec![1.0] };
    let mut expected = vec![0x0a, 8];
    expected.extend_from_slice(&1.0f64.to_le_bytes());
    assert_eq!(vector.encode_to_vec(), expected);
}

/// 2.7 frames carry the length and CRC; a bad CRC is a typed error.
#[test]
fn v2_7_framing_and_crc() {
    let mut bytes = encode_command(&command_header_only(1, 2), FriVersion::V2_7).unwrap();
    let payload = command_header_only(1, 2).encode_to_vec();
    assert_eq!(&bytes[..4], &(payload.len() as u32).to_le_bytes());
    assert_eq!(&bytes[4..4 + payload.len()], payload.as_slice());
    assert_eq!(
        &bytes[4 + payload.len()..],
        &crc32fast::hash(&payload).to_le_bytes()
    );
    assert!(decode_command(&bytes, FriVersion::V2_7).is_ok());
    let last = bytes.len() - 1;
    bytes[last] ^= 0xff;
    assert!(matches!(
        decode_command(&bytes, FriVersion::V2_7),
        Err(DecodeError::Crc { .. })
    ));
}

/// Missing connection info decodes as IDLE / POOR.
#[test]
fn connection_info_defaults_to_idle_poor() {
    let message = FriMonitoringMessage {
        header: MessageHeader {
            message_identifier: MONITORING_MESSAGE_ID,
            sequence_counter: 3,
            reflected_sequence_counter: 0,
        },
        ..Default::default()
    };
    let bytes = encode_monitoring(&message, FriVersion::V2_5).unwrap();
    let decoded = decode_monitoring(&bytes, FriVersion::V2_5).unwrap();
    let info = decoded.connection_info.unwrap();
    assert_eq!(info.session_state, SessionState::Idle as i32);
    assert_eq!(info.quality, ConnectionQuality::Poor as i32);
}

/// Encoding for 1.x does not emit 2.5+ fields, and 2.7 emits no
/// endOfMessageData.
#[test]
fn version_fields_not_emitted() {
    let mut message = command_header_only(0, 0);
    message.command_data = Some(MessageCommandData {
        cartesian_pose: Some(Transformation {
            name: "tcp".into(),
            element: vec![0.0; 7],
            timestamp: None,
        }),
        ..Default::default()
    });
    message.end_of_message_data = Some(MessageEndOf::default());
    let v1 = encode_command(&message, FriVersion::V1_11).unwrap();
    let decoded = FriCommandMessage::decode(v1.as_slice()).unwrap();
    assert!(decoded.command_data.unwrap().cartesian_pose.is_none());
    assert!(decoded.end_of_message_data.is_some());
    let v27 = encode_command(&message, FriVersion::V2_7).unwrap();
    let decoded = FriCommandMessage::decode(&v27[4..v27.len() - 4]).unwrap();
    assert!(decoded.end_of_message_data.is_none());
}

fn finite() -> impl Strategy<Value = f64> {
    -1.0e6..1.0e6f64
}

fn joints() -> impl Strategy<Value = Option<JointValues>> {
    proptest::option::of(
        proptest::collection::vec(finite(), 0..8).prop_map(|value| JointValues { value }),
    )
}

fn transformation() -> impl Strategy<Value = Transformation> {
    (
        "[a-z]{0,10}",
        proptest::collection::vec(finite(), 0..13),
        proptest::option::of((any::<u32>(), any::<u32>())),
    )
        .prop_map(|(name, element, stamp)| Transformation {
            name,
            element,
            timestamp: stamp.map(|(sec, nanosec)| TimeStamp { sec, nanosec }),
        })
}

fn header() -> impl Strategy<Value = (u32, u32)> {
    (any::<u32>(), any::<u32>())
}

fn monitoring() -> impl Strategy<Value = FriMonitoringMessage> {
    (
        header(),
        (
            0..5i32,
            0..4i32,
            proptest::option::of(1..100u32),
            proptest::option::of(1..10u32),
        ),
        (joints(), joints(), joints(), joints(), joints()),
        proptest::option::of(transformation()),
        (
            joints(),
            proptest::option::of(0..5i32),
            proptest::option::of(0.0..1.0f64),
        ),
        proptest::collection::vec(transformation(), 0..3),
        proptest::option::of((
            proptest::option::of(0..8i32),
            proptest::collection::vec(0..3i32, 0..8),
        )),
    )
        .prop_map(
            |(
                (seq, refl),
                (state, quality, period, multiplier),
                (m, t, c, ct, et),
                pose,
                (ipo, mode, tracking),
                requested,
                robot,
            )| {
                FriMonitoringMessage {
                    header: MessageHeader {
                        message_identifier: MONITORING_MESSAGE_ID,
                        sequence_counter: seq,
                        reflected_sequence_counter: refl,
                    },
                    robot_info: robot.map(|(joints, drive_state)| RobotInfo {
                        number_of_joints: joints,
                        drive_state,
                        ..Default::default()
                    }),
                    monitor_data: Some(MessageMonitorData {
                        measured_joint_position: m,
                        measured_torque: t,
                        commanded_joint_position: c,
                        commanded_torque: ct,
                        external_torque: et.clone(),
                        external_force: et.map(|v| CartesianVector { element: v.value }),
                        measured_cartesian_pose: pose,
                        timestamp: Some(TimeStamp {
                            sec: seq,
                            nanosec: refl,
                        }),
                        ..Default::default()
                    }),
                    connection_info: Some(ConnectionInfo {
                        session_state: state,
                        quality,
                        send_period: period,
                        receive_multiplier: multiplier,
                    }),
                    ipo_data: Some(MessageIpoData {
                        joint_position: ipo,
                        client_command_mode: mode,
                        tracking_performance: tracking,
                        ..Default::default()
                    }),
                    requested_transformations: requested,
                    end_of_message_data: Some(MessageEndOf::default()),
                }
            },
        )
}

fn command() -> impl Strategy<Value = FriCommandMessage> {
    (
        header(),
        joints(),
        joints(),
        proptest::option::of(proptest::collection::vec(finite(), 0..7)),
        proptest::option::of(transformation()),
    )
        .prop_map(
            |((seq, refl), position, torque, wrench, pose)| FriCommandMessage {
                header: MessageHeader {
                    message_identifier: COMMAND_MESSAGE_ID,
                    sequence_counter: seq,
                    reflected_sequence_counter: refl,
                },
                command_data: Some(MessageCommandData {
                    joint_position: position,
                    joint_torque: torque,
                    cartesian_wrench_feed_forward: wrench
                        .map(|element| CartesianVector { element }),
                    cartesian_pose: pose,
                    ..Default::default()
                }),
                end_of_message_data: None,
            },
        )
}

proptest! {
    /// Any bytes into every decoder of every version: Ok or Err, no panic.
    #[test]
    fn garbage_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..1600)) {
        for version in FriVersion::ALL {
            let _ = decode_monitoring(&bytes, version);
            let _ = decode_command(&bytes, version);
        }
    }

    /// encode → decode is the identity on a version-valid monitoring message.
    #[test]
    fn monitoring_round_trip(message in monitoring()) {
        for version in FriVersion::ALL {
            let mut expected = message.clone();
            expected.restrict_to(version);
            let bytes = encode_monitoring(&message, version).unwrap();
            prop_assert_eq!(decode_monitoring(&bytes, version).unwrap(), expected);
        }
    }

    /// encode → decode is the identity on a version-valid command message.
    #[test]
    fn command_round_trip(message in command()) {
        for version in FriVersion::ALL {
            let mut expected = message.clone();
            expected.restrict_to(version);
            let bytes = encode_command(&message, version).unwrap();
            prop_assert_eq!(decode_command(&bytes, version).unwrap(), expected);
        }
    }
}
