//! FRI wire messages (proto2), one set of structs for every version.
//!
//! Field numbers, types and packing follow `kuka-fri.md`. Fields that only
//! some versions have are present here and cleared by
//! [`FriMonitoringMessage::restrict_to`] / [`FriCommandMessage::restrict_to`],
//! so the per-version differences are conditions on [`FriVersion`], not
//! copies of the structs. `JointValues` is encoded unpacked (as KUKA's
//! encoder does), `CartesianVector` and transformation elements packed;
//! prost decodes both packings.

use crate::version::FriVersion;

/// Identifier of every monitoring message (controller → client).
pub const MONITORING_MESSAGE_ID: u32 = 0x24_5142;
/// Identifier of every command message (client → controller).
pub const COMMAND_MESSAGE_ID: u32 = 0x3_4001;

/// Header of every message; all three fields are required and always encoded.
#[derive(Clone, Copy, PartialEq, Eq, prost::Message)]
pub struct MessageHeader {
    /// Message type identifier.
    #[prost(uint32, required, tag = "1")]
    pub message_identifier: u32,
    /// Sender's own counter, +1 per message, wrapping at 2^32.
    #[prost(uint32, required, tag = "2")]
    pub sequence_counter: u32,
    /// Echo of the counter of the message being answered.
    #[prost(uint32, required, tag = "3")]
    pub reflected_sequence_counter: u32,
}

/// One value per joint (rad, or N m for torques), encoded unpacked.
#[derive(Clone, PartialEq, prost::Message)]
pub struct JointValues {
    /// Values, 7 for an LBR.
    #[prost(double, repeated, packed = "false", tag = "1")]
    pub value: Vec<f64>,
}

/// Up to 6 Cartesian values (N / N m, or mm / rad), encoded packed.
#[derive(Clone, PartialEq, prost::Message)]
pub struct CartesianVector {
    /// Values.
    #[prost(double, repeated, packed = "true", tag = "1")]
    pub element: Vec<f64>,
}

/// A time stamp of the robot controller.
#[derive(Clone, Copy, PartialEq, Eq, prost::Message)]
pub struct TimeStamp {
    /// Seconds.
    #[prost(uint32, required, tag = "1")]
    pub sec: u32,
    /// Nanoseconds.
    #[prost(uint32, required, tag = "2")]
    pub nanosec: u32,
}

/// A named frame: 1.x `Transformation` (12 values, 3×4 row-major [R|t]) or
/// 2.5+ `QuaternionTransformation` (7 values, [tx ty tz mm, qw qx qy qz]);
/// both share field numbers and types.
#[derive(Clone, PartialEq, prost::Message)]
pub struct Transformation {
    /// Frame name (≤ 63 characters).
    #[prost(string, required, tag = "1")]
    pub name: String,
    /// Matrix (1.x) or translation + quaternion (2.5+), packed.
    #[prost(double, repeated, packed = "true", tag = "2")]
    pub element: Vec<f64>,
    /// Time stamp.
    #[prost(message, optional, tag = "3")]
    pub timestamp: Option<TimeStamp>,
}

/// Redundancy of the arm (2.5+).
#[derive(Clone, Copy, PartialEq, prost::Message)]
pub struct RedundancyInformation {
    /// Strategy.
    #[prost(enumeration = "RedundancyStrategy", required, tag = "1")]
    pub strategy: i32,
    /// Value (rad for E1).
    #[prost(double, required, tag = "2")]
    pub value: f64,
}

/// An IO value (1.14+).
#[derive(Clone, PartialEq, prost::Message)]
pub struct FriIoValue {
    /// IO name.
    #[prost(string, required, tag = "1")]
    pub name: String,
    /// IO type.
    #[prost(enumeration = "FriIoType", required, tag = "2")]
    pub r#type: i32,
    /// IO direction.
    #[prost(enumeration = "FriIoDirection", required, tag = "3")]
    pub direction: i32,
    /// Digital value.
    #[prost(uint64, optional, tag = "4")]
    pub digital_value: Option<u64>,
    /// Analog value.
    #[prost(double, optional, tag = "5")]
    pub analog_value: Option<f64>,
}

/// Checksum of `MessageEndOf` (never filled by KUKA's encoder).
#[derive(Clone, Copy, PartialEq, Eq, prost::Message)]
pub struct Checksum {
    /// CRC-32.
    #[prost(int32, optional, tag = "1")]
    pub crc32: Option<i32>,
}

/// End-of-message data (1.x and 2.5 only).
#[derive(Clone, Copy, PartialEq, Eq, prost::Message)]
pub struct MessageEndOf {
    /// Message length in bytes.
    #[prost(int32, optional, tag = "1")]
    pub message_length: Option<i32>,
    /// Checksum.
    #[prost(message, optional, tag = "2")]
    pub message_checksum: Option<Checksum>,
}

/// Connection state as the controller sees it.
#[derive(Clone, Copy, PartialEq, Eq, prost::Message)]
pub struct ConnectionInfo {
    /// Session state.
    #[prost(enumeration = "SessionState", required, tag = "1")]
    pub session_state: i32,
    /// Connection quality.
    #[prost(enumeration = "ConnectionQuality", required, tag = "2")]
    pub quality: i32,
    /// Send period (ms).
    #[prost(uint32, optional, tag = "3")]
    pub send_period: Option<u32>,
    /// Answer every n-th monitoring message.
    #[prost(uint32, optional, tag = "4")]
    pub receive_multiplier: Option<u32>,
}

/// Robot description.
#[derive(Clone, PartialEq, prost::Message)]
pub struct RobotInfo {
    /// Number of joints.
    #[prost(int32, optional, tag = "1")]
    pub number_of_joints: Option<i32>,
    /// Safety state.
    #[prost(enumeration = "SafetyState", optional, tag = "2")]
    pub safety_state: Option<i32>,
    /// Drive state, one per joint.
    #[prost(enumeration = "DriveState", repeated, packed = "false", tag = "5")]
    pub drive_state: Vec<i32>,
    /// Operation mode.
    #[prost(enumeration = "OperationMode", optional, tag = "6")]
    pub operation_mode: Option<i32>,
    /// Control mode.
    #[prost(enumeration = "ControlMode", optional, tag = "7")]
    pub control_mode: Option<i32>,
}

/// Measured data of the robot.
#[derive(Clone, PartialEq, prost::Message)]
pub struct MessageMonitorData {
    /// Measured joint position (rad).
    #[prost(message, optional, tag = "1")]
    pub measured_joint_position: Option<JointValues>,
    /// Measured torque (N m).
    #[prost(message, optional, tag = "2")]
    pub measured_torque: Option<JointValues>,
    /// Commanded joint position (rad), 1.x only.
    #[prost(message, optional, tag = "3")]
    pub commanded_joint_position: Option<JointValues>,
    /// Commanded torque (N m).
    #[prost(message, optional, tag = "4")]
    pub commanded_torque: Option<JointValues>,
    /// External torque (N m).
    #[prost(message, optional, tag = "5")]
    pub external_torque: Option<JointValues>,
    /// External force (N, N m), 2.7 only.
    #[prost(message, optional, tag = "6")]
    pub external_force: Option<CartesianVector>,
    /// IO values read (1.14+).
    #[prost(message, repeated, tag = "8")]
    pub read_io_request: Vec<FriIoValue>,
    /// Measured Cartesian pose (2.5+).
    #[prost(message, optional, tag = "9")]
    pub measured_cartesian_pose: Option<Transformation>,
    /// Measured redundancy (2.5+).
    #[prost(message, optional, tag = "10")]
    pub measured_redundancy_information: Option<RedundancyInformation>,
    /// Time stamp.
    #[prost(message, optional, tag = "15")]
    pub timestamp: Option<TimeStamp>,
}

/// Interpolator data of the robot.
#[derive(Clone, PartialEq, prost::Message)]
pub struct MessageIpoData {
    /// IPO joint position (rad), only while a joint overlay commands.
    #[prost(message, optional, tag = "1")]
    pub joint_position: Option<JointValues>,
    /// IPO Cartesian pose (2.5+).
    #[prost(message, optional, tag = "2")]
    pub cartesian_pose: Option<Transformation>,
    /// IPO redundancy (2.5+).
    #[prost(message, optional, tag = "3")]
    pub redundancy_information: Option<RedundancyInformation>,
    /// Command mode of the client.
    #[prost(enumeration = "ClientCommandMode", optional, tag = "10")]
    pub client_command_mode: Option<i32>,
    /// Overlay type.
    #[prost(enumeration = "OverlayType", optional, tag = "11")]
    pub overlay_type: Option<i32>,
    /// Tracking performance, 0..1.
    #[prost(double, optional, tag = "12")]
    pub tracking_performance: Option<f64>,
}

/// Command data of the client.
#[derive(Clone, PartialEq, prost::Message)]
pub struct MessageCommandData {
    /// Absolute joint position targets (rad).
    #[prost(message, optional, tag = "1")]
    pub joint_position: Option<JointValues>,
    /// Cartesian wrench feed-forward: Fx Fy Fz (N), A B C (N m).
    #[prost(message, optional, tag = "2")]
    pub cartesian_wrench_feed_forward: Option<CartesianVector>,
    /// Joint torques (N m).
    #[prost(message, optional, tag = "3")]
    pub joint_torque: Option<JointValues>,
    /// Commanded transformations (≤ 5).
    #[prost(message, repeated, tag = "4")]
    pub commanded_transformations: Vec<Transformation>,
    /// IO values written (1.14+).
    #[prost(message, repeated, tag = "5")]
    pub write_io_request: Vec<FriIoValue>,
    /// Cartesian pose target (2.5+).
    #[prost(message, optional, tag = "6")]
    pub cartesian_pose: Option<Transformation>,
    /// Redundancy target (2.5+).
    #[prost(message, optional, tag = "7")]
    pub redundancy_information: Option<RedundancyInformation>,
}

/// Controller → client, every `sendPeriod` ms.
#[derive(Clone, PartialEq, prost::Message)]
pub struct FriMonitoringMessage {
    /// Header (required).
    #[prost(message, required, tag = "1")]
    pub header: MessageHeader,
    /// Robot info.
    #[prost(message, optional, tag = "2")]
    pub robot_info: Option<RobotInfo>,
    /// Monitor data.
    #[prost(message, optional, tag = "3")]
    pub monitor_data: Option<MessageMonitorData>,
    /// Connection info.
    #[prost(message, optional, tag = "4")]
    pub connection_info: Option<ConnectionInfo>,
    /// IPO data.
    #[prost(message, optional, tag = "5")]
    pub ipo_data: Option<MessageIpoData>,
    /// Requested transformations (≤ 5).
    #[prost(message, repeated, tag = "6")]
    pub requested_transformations: Vec<Transformation>,
    /// End of message (1.x and 2.5 only).
    #[prost(message, optional, tag = "15")]
    pub end_of_message_data: Option<MessageEndOf>,
}

/// Client → controller, every `receiveMultiplier`-th monitoring message.
#[derive(Clone, PartialEq, prost::Message)]
pub struct FriCommandMessage {
    /// Header (required).
    #[prost(message, required, tag = "1")]
    pub header: MessageHeader,
    /// Command data.
    #[prost(message, optional, tag = "2")]
    pub command_data: Option<MessageCommandData>,
    /// End of message (1.x and 2.5 only).
    #[prost(message, optional, tag = "15")]
    pub end_of_message_data: Option<MessageEndOf>,
}

/// FRI session state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
#[allow(clippy::upper_case_acronyms)]
pub enum SessionState {
    /// No session.
    Idle = 0,
    /// Monitoring, quality not yet sufficient.
    MonitoringWait = 1,
    /// Monitoring, ready to command.
    MonitoringReady = 2,
    /// Commanding requested, client must sync on the IPO position.
    CommandingWait = 3,
    /// Client commands.
    CommandingActive = 4,
}

/// FRI connection quality.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum ConnectionQuality {
    /// Poor.
    Poor = 0,
    /// Fair.
    Fair = 1,
    /// Good (needed to command).
    Good = 2,
    /// Excellent.
    Excellent = 3,
}

/// Safety state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum SafetyState {
    /// Normal operation.
    NormalOperation = 0,
    /// Stop 0.
    SafetyStopLevel0 = 1,
    /// Stop 1.
    SafetyStopLevel1 = 2,
    /// Stop 2.
    SafetyStopLevel2 = 3,
}

/// Operation mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum OperationMode {
    /// Manual reduced velocity.
    T1 = 0,
    /// Manual high velocity.
    T2 = 1,
    /// Automatic.
    Automatic = 2,
}

/// Drive state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum DriveState {
    /// Off.
    Off = 0,
    /// Transitioning.
    Transitioning = 1,
    /// Active.
    Active = 2,
}

/// Robot-side control mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum ControlMode {
    /// Position control.
    Position = 0,
    /// Cartesian impedance.
    CartesianImpedance = 1,
    /// Joint impedance.
    JointImpedance = 2,
    /// No control.
    NoControl = 3,
}

/// Client command mode (`POSITION` is named `JOINT_POSITION` in 2.x).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum ClientCommandMode {
    /// No command.
    NoCommand = 0,
    /// Joint position.
    JointPosition = 1,
    /// Cartesian wrench.
    Wrench = 2,
    /// Joint torque.
    Torque = 3,
    /// Cartesian pose (2.5+).
    CartesianPose = 4,
}

/// Overlay type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum OverlayType {
    /// None.
    NoOverlay = 0,
    /// Joint overlay.
    Joint = 1,
    /// Cartesian overlay.
    Cartesian = 2,
}

/// Redundancy strategy (2.5+).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum RedundancyStrategy {
    /// Elbow angle E1.
    E1 = 0,
    /// None.
    None = 4,
}

/// IO type (1.14+).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum FriIoType {
    /// Boolean.
    Boolean = 0,
    /// Digital.
    Digital = 1,
    /// Analog.
    Analog = 2,
}

/// IO direction (1.14+).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
pub enum FriIoDirection {
    /// Input.
    Input = 0,
    /// Output.
    Output = 1,
}

impl FriMonitoringMessage {
    /// Clears every field `version` does not have (as that version's decoder
    /// would skip them as unknown fields).
    pub fn restrict_to(&mut self, version: FriVersion) {
        if let Some(data) = self.monitor_data.as_mut() {
            if !version.has_commanded_joint_position() {
                data.commanded_joint_position = None;
            }
            if !version.has_external_force() {
                data.external_force = None;
            }
            if !version.has_io() {
                data.read_io_request.clear();
            }
            if !version.has_cartesian_pose() {
                data.measured_cartesian_pose = None;
                data.measured_redundancy_information = None;
            }
        }
        if let Some(ipo) = self.ipo_data.as_mut() {
            if !version.has_cartesian_pose() {
                ipo.cartesian_pose = None;
                ipo.redundancy_information = None;
                if ipo.client_command_mode == Some(ClientCommandMode::CartesianPose as i32) {
                    ipo.client_command_mode = None;
                }
            }
        }
        if !version.has_end_of_message() {
            self.end_of_message_data = None;
        }
    }
}

impl FriCommandMessage {
    /// Clears every field `version` does not have.
    pub fn restrict_to(&mut self, version: FriVersion) {
        if let Some(data) = self.command_data.as_mut() {
            if !version.has_io() {
                data.write_io_request.clear();
            }
            if !version.has_cartesian_pose() {
                data.cartesian_pose = None;
                data.redundancy_information = None;
            }
        }
        if !version.has_end_of_message() {
            self.end_of_message_data = None;
        }
    }
}
