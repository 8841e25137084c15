//! Encoding and decoding of FRI datagrams for one [`FriVersion`].
//!
//! 1.x and 2.5 datagrams are the bare protobuf; 2.7 datagrams are framed as
//! `[u32 LE payload length][payload][u32 LE CRC-32 (zlib polynomial)]`.
//! Decoding never panics: every malformed input is a [`DecodeError`].

use prost::Message;

use crate::messages::{
    ConnectionInfo, ConnectionQuality, FriCommandMessage, FriMonitoringMessage, SessionState,
};
use crate::version::FriVersion;

/// Largest datagram either side sends or accepts (bytes).
pub const MAX_DATAGRAM_BYTES: usize = 1500;
/// Length prefix plus CRC suffix of a 2.7 frame (bytes).
const FRAME_OVERHEAD_BYTES: usize = 8;

/// Why a datagram could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// Datagram longer than [`MAX_DATAGRAM_BYTES`].
    #[error("datagram of {0} bytes exceeds 1500")]
    TooLong(usize),
    /// 2.7 frame shorter than its length prefix and CRC, or length mismatch.
    #[error("2.7 frame length mismatch: prefix says {declared} bytes, datagram carries {actual}")]
    FrameLength {
        /// Payload length in the prefix (bytes).
        declared: usize,
        /// Payload bytes present.
        actual: usize,
    },
    /// 2.7 frame whose CRC does not match its payload.
    #[error("2.7 frame CRC mismatch: frame says {declared:#010x}, payload has {computed:#010x}")]
    Crc {
        /// CRC carried by the frame.
        declared: u32,
        /// CRC computed over the payload.
        computed: u32,
    },
    /// Not valid protobuf for the message.
    #[error("malformed protobuf: {0}")]
    Protobuf(String),
    /// The header carries an identifier of another message type.
    #[error("message identifier {found:#x}, expected {expected:#x}")]
    WrongIdentifier {
        /// Identifier found.
        found: u32,
        /// Identifier expected.
        expected: u32,
    },
}

/// Why a message could not be encoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    /// The encoded datagram would exceed [`MAX_DATAGRAM_BYTES`].
    #[error("encoded datagram of {0} bytes exceeds 1500")]
    TooLong(usize),
}

/// Encodes a monitoring message for `version`; fields the version lacks are
/// not emitted.
///
/// # Errors
/// [`EncodeError::TooLong`] past 1500 bytes.
pub fn encode_monitoring(
    message: &FriMonitoringMessage,
    version: FriVersion,
) -> Result<Vec<u8>, EncodeError> {
    let mut restricted = message.clone();
    restricted.restrict_to(version);
    frame(restricted.encode_to_vec(), version)
}

/// Encodes a command message for `version`; fields the version lacks are not
/// emitted.
///
/// # Errors
/// [`EncodeError::TooLong`] past 1500 bytes.
pub fn encode_command(
    message: &FriCommandMessage,
    version: FriVersion,
) -> Result<Vec<u8>, EncodeError> {
    let mut restricted = message.clone();
    restricted.restrict_to(version);
    frame(restricted.encode_to_vec(), version)
}

/// Decodes a monitoring datagram. Connection info defaults to IDLE / POOR
/// when absent, as KUKA's decoder does; fields `version` lacks are dropped.
///
/// # Errors
/// Any [`DecodeError`].
pub fn decode_monitoring(
    datagram: &[u8],
    version: FriVersion,
) -> Result<FriMonitoringMessage, DecodeError> {
    let payload = unframe(datagram, version)?;
    let mut message = FriMonitoringMessage {
        connection_info: Some(ConnectionInfo {
            session_state: SessionState::Idle as i32,
            quality: ConnectionQuality::Poor as i32,
            send_period: None,
            receive_multiplier: None,
        }),
        ..FriMonitoringMessage::default()
    };
    message
        .merge(payload)
        .map_err(|error| DecodeError::Protobuf(error.to_string()))?;
    check_identifier(
        message.header.message_identifier,
        crate::messages::MONITORING_MESSAGE_ID,
    )?;
    message.restrict_to(version);
    Ok(message)
}

/// Decodes a command datagram; fields `version` lacks are dropped.
///
/// # Errors
/// Any [`DecodeError`].
pub fn decode_command(
    datagram: &[u8],
    version: FriVersion,
) -> Result<FriCommandMessage, DecodeError> {
    let payload = unframe(datagram, version)?;
    let mut message = FriCommandMessage::decode(payload)
        .map_err(|error| DecodeError::Protobuf(error.to_string()))?;
    check_identifier(
        message.header.message_identifier,
        crate::messages::COMMAND_MESSAGE_ID,
    )?;
    message.restrict_to(version);
    Ok(message)
}

fn check_identifier(found: u32, expected: u32) -> Result<(), DecodeError> {
    if found == expected {
        Ok(())
    } else {
        Err(DecodeError::WrongIdentifier { found, expected })
    }
}

fn frame(payload: Vec<u8>, version: FriVersion) -> Result<Vec<u8>, EncodeError> {
    let datagram = if version.is_framed() {
        let length =
            u32::try_from(payload.len()).map_err(|_| EncodeError::TooLong(payload.len()))?;
        let mut framed = Vec::with_capacity(payload.len() + FRAME_OVERHEAD_BYTES);
        framed.extend_from_slice(&length.to_le_bytes());
        framed.extend_from_slice(&payload);
        framed.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        framed
    } else {
        payload
    };
    if datagram.len() > MAX_DATAGRAM_BYTES {
        return Err(EncodeError::TooLong(datagram.len()));
    }
    Ok(datagram)
}

fn unframe(datagram: &[u8], version: FriVersion) -> Result<&[u8], DecodeError> {
    if datagram.len() > MAX_DATAGRAM_BYTES {
        return Err(DecodeError::TooLong(datagram.len()));
    }
    if !version.is_framed() {
        return Ok(datagram);
    }
    let actual = datagram.len().saturating_sub(FRAME_OVERHEAD_BYTES);
    let (prefix, rest) = datagram
        .split_first_chunk::<4>()
        .ok_or(DecodeError::FrameLength {
            declared: 0,
            actual,
        })?;
    let declared = u32::from_le_bytes(*prefix) as usize;
    let (payload, suffix) = rest
        .split_last_chunk::<4>()
        .ok_or(DecodeError::FrameLength { declared, actual })?;
    if payload.len() != declared {
        return Err(DecodeError::FrameLength { declared, actual });
    }
    let computed = crc32fast::hash(payload);
    let declared_crc = u32::from_le_bytes(*suffix);
    if computed != declared_crc {
        return Err(DecodeError::Crc {
            declared: declared_crc,
            computed,
        });
    }
    Ok(payload)
}
