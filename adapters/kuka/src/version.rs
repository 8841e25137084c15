//! FRI protocol versions and which wire features each one has.

use core::fmt;
use core::str::FromStr;

/// The FRI client SDK version the robot controller speaks. A client of one
/// version cannot talk to a controller of another (`kuka-fri.md`, Versions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FriVersion {
    /// FRI 1.11 (Sunrise 1.11).
    V1_11,
    /// FRI 1.14: adds IO requests.
    V1_14,
    /// FRI 1.15.
    V1_15,
    /// FRI 1.16.
    V1_16,
    /// FRI 2.5: Cartesian pose, redundancy, quaternion transformations.
    V2_5,
    /// FRI 2.7: external force, length + CRC-32 framing, no endOfMessageData.
    V2_7,
}

impl FriVersion {
    /// Every supported version, oldest first.
    pub const ALL: [FriVersion; 6] = [
        FriVersion::V1_11,
        FriVersion::V1_14,
        FriVersion::V1_15,
        FriVersion::V1_16,
        FriVersion::V2_5,
        FriVersion::V2_7,
    ];

    /// True for the 1.x family.
    pub fn is_v1(self) -> bool {
        matches!(self, Self::V1_11 | Self::V1_14 | Self::V1_15 | Self::V1_16)
    }
    /// `commandedJointPosition` in monitor data exists (1.x only).
    pub fn has_commanded_joint_position(self) -> bool {
        self.is_v1()
    }
    /// IO read/write requests exist (1.14+).
    pub fn has_io(self) -> bool {
        self != Self::V1_11
    }
    /// Cartesian pose and redundancy fields exist (2.5+).
    pub fn has_cartesian_pose(self) -> bool {
        !self.is_v1()
    }
    /// `externalForce` in monitor data exists (2.7 only).
    pub fn has_external_force(self) -> bool {
        self == Self::V2_7
    }
    /// `endOfMessageData` exists (1.x and 2.5 only).
    pub fn has_end_of_message(self) -> bool {
        self != Self::V2_7
    }
    /// Datagrams are framed as `[u32 LE length][payload][u32 LE CRC-32]` (2.7).
    pub fn is_framed(self) -> bool {
        self == Self::V2_7
    }
}

impl fmt::Display for FriVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Self::V1_11 => "1.11",
            Self::V1_14 => "1.14",
            Self::V1_15 => "1.15",
            Self::V1_16 => "1.16",
            Self::V2_5 => "2.5",
            Self::V2_7 => "2.7",
        };
        f.write_str(text)
    }
}

/// A version string that names no supported FRI version.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unsupported FRI version {0:?} (expected 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7)")]
pub struct UnknownVersion(pub String);

impl FromStr for FriVersion {
    type Err = UnknownVersion;
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|version| version.to_string() == text.trim())
            .ok_or_else(|| UnknownVersion(text.to_string()))
    }
}
