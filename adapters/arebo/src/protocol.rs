//! Serial framing of the group's Teensy robots, as AREBO's adapter uses it.
//!
//! # Frames
//! ```text
//! PC → device:  0xAA 0xAA | N | command code | arguments … | chk
//! device → PC:  0xFF 0xFF | N | payload …                  | chk
//! ```
//! N counts the bytes after it, checksum included (payload = N − 1 bytes);
//! chk = (header + header + N + Σ payload) mod 256. 115200 baud 8N1.
//!
//! # AREBO's payloads (our choice; AREBO's firmware is unpublished)
//! Commands (first payload byte), arguments little-endian:
//!
//! | code | command | arguments |
//! |---|---|---|
//! | 0x00 | get version | – |
//! | 0x01 | calibrate (zero encoders) | – |
//! | 0x02 | start stream | – |
//! | 0x03 | stop stream | – |
//! | 0x04 | set control type | u8: 0 off, 1 gravity compensation, 2 torque |
//! | 0x05 | set control target | 3 × f32: τ_d1..τ_d3 [N m] |
//! | 0x06 | set diagnostics | u8: 0 off, 1 on |
//! | 0x07 | reset packet number | – |
//! | 0x80 | heartbeat | – |
//!
//! Device stream frame (N = 54), following the family layout:
//!
//! | offset | field | type |
//! |---|---|---|
//! | 0 | status: bit 0 streaming, bits 4-5 control type | u8 |
//! | 1 | error bits: 0 heartbeat missing, 1 torque sensor fault | u16 |
//! | 3 | packet number | u16 |
//! | 5 | run time [ms] | u32 |
//! | 9 | encoder counts θ1..θ5 | 5 × i32 |
//! | 29 | torque sensors τ_r1..τ_r3 [N m] | 3 × f32 |
//! | 41 | commanded motor torques [N m] | 3 × f32 |
//!
//! Counts are sent as integers rather than the family's float32 so the
//! 217 088 counts per θ1 turn are exact.
//!
//! # Decoding
//! [`Decoder`] is a byte-at-a-time state machine with a fixed buffer: on a
//! wrong header, an impossible length or a wrong checksum it drops one
//! byte and rescans what it holds, so a valid frame embedded in garbage or
//! after a truncated frame is still found. It never panics.

/// Header byte of PC → device frames.
pub const COMMAND_HEADER: u8 = 0xAA;
/// Header byte of device → PC frames.
pub const TELEMETRY_HEADER: u8 = 0xFF;
/// Largest N accepted.
pub const MAX_LENGTH: u8 = 60;
/// N of a device stream frame.
pub const TELEMETRY_LENGTH: u8 = 54;

/// A frame's bytes (header to checksum).
pub type FrameBytes = heapless::Vec<u8, 64>;
/// A frame's payload (N − 1 bytes).
pub type Payload = heapless::Vec<u8, 64>;

fn checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |sum, b| sum.wrapping_add(*b))
}

/// Frames `payload` behind `header`; `None` when it exceeds [`MAX_LENGTH`].
pub fn frame(header: u8, payload: &[u8]) -> Option<FrameBytes> {
    let length = u8::try_from(payload.len() + 1)
        .ok()
        .filter(|n| *n <= MAX_LENGTH)?;
    let mut out = FrameBytes::new();
    out.extend_from_slice(&[header, header, length]).ok()?;
    out.extend_from_slice(payload).ok()?;
    let sum = checksum(&out);
    out.push(sum).ok()?;
    Some(out)
}

/// Counters of what the decoder saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Frames accepted.
    pub frames: u32,
    /// Frames with a wrong checksum.
    pub checksum_errors: u32,
    /// Bytes dropped while searching for a header.
    pub discarded: u32,
}

/// Streaming frame decoder for one header byte.
#[derive(Clone, Debug)]
pub struct Decoder {
    header: u8,
    buffer: heapless::Vec<u8, 64>,
    /// What the decoder has seen so far.
    pub stats: DecoderStats,
}

impl Decoder {
    /// A decoder for frames starting `header header`.
    pub fn new(header: u8) -> Self {
        Self {
            header,
            buffer: heapless::Vec::new(),
            stats: DecoderStats::default(),
        }
    }

    fn drop_front(&mut self) {
        let len = self.buffer.len();
        if len > 0 {
            self.buffer.copy_within(1..len, 0);
            self.buffer.truncate(len - 1);
            self.stats.discarded = self.stats.discarded.saturating_add(1);
        }
    }

    /// Feeds one byte; returns a payload when it completes a valid frame.
    pub fn push(&mut self, byte: u8) -> Option<Payload> {
        if self.buffer.push(byte).is_err() {
            // Cannot happen (the buffer never holds a full frame plus a
            // byte), but stay total: restart the search.
            self.drop_front();
            let _ = self.buffer.push(byte);
        }
        loop {
            let len = self.buffer.len();
            let bad_header = (len >= 1 && self.buffer[0] != self.header)
                || (len >= 2 && self.buffer[1] != self.header);
            let bad_length = len >= 3 && (self.buffer[2] == 0 || self.buffer[2] > MAX_LENGTH);
            if bad_header || bad_length {
                self.drop_front();
                continue;
            }
            if len < 3 {
                return None;
            }
            let total = 3 + usize::from(self.buffer[2]);
            if len < total {
                return None;
            }
            if checksum(&self.buffer[..total - 1]) != self.buffer[total - 1] {
                self.stats.checksum_errors = self.stats.checksum_errors.saturating_add(1);
                self.drop_front();
                continue;
            }
            let payload = Payload::from_slice(&self.buffer[3..total - 1]).ok();
            self.buffer.copy_within(total..len, 0);
            self.buffer.truncate(len - total);
            self.stats.frames = self.stats.frames.saturating_add(1);
            return payload;
        }
    }
}

/// How the firmware drives the motors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControlType {
    /// Motors off (the safe state).
    Off = 0,
    /// Gravity compensation only (τ_c = 0).
    GravityCompensation = 1,
    /// Torque control toward the target τ_d.
    Torque = 2,
}

impl ControlType {
    /// The type of a code (0-2); `None` for any other.
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Self::Off),
            1 => Some(Self::GravityCompensation),
            2 => Some(Self::Torque),
            _ => None,
        }
    }
}

/// A PC → device command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// 0x00.
    GetVersion,
    /// 0x01: zero the encoders.
    Calibrate,
    /// 0x02.
    StartStream,
    /// 0x03.
    StopStream,
    /// 0x04.
    SetControlType(ControlType),
    /// 0x05: desired interaction torques τ_d [N m].
    SetControlTarget([f32; 3]),
    /// 0x06.
    SetDiagnostics(bool),
    /// 0x07.
    ResetPacketNumber,
    /// 0x80: the PC is alive; the device stops assisting after ~1 s
    /// without one.
    Heartbeat,
}

impl Command {
    /// The framed bytes.
    pub fn encode(&self) -> FrameBytes {
        let mut payload = heapless::Vec::<u8, 16>::new();
        let (code, args): (u8, &[u8]) = match self {
            Command::GetVersion => (0x00, &[]),
            Command::Calibrate => (0x01, &[]),
            Command::StartStream => (0x02, &[]),
            Command::StopStream => (0x03, &[]),
            Command::SetControlType(kind) => (0x04, &[*kind as u8]),
            Command::SetControlTarget(_) => (0x05, &[]),
            Command::SetDiagnostics(on) => (0x06, if *on { &[1] } else { &[0] }),
            Command::ResetPacketNumber => (0x07, &[]),
            Command::Heartbeat => (0x80, &[]),
        };
        // Capacity 16 holds the longest command (13 bytes).
        let _ = payload.push(code);
        let _ = payload.extend_from_slice(args);
        if let Command::SetControlTarget(torques) = self {
            for t in torques {
                let _ = payload.extend_from_slice(&t.to_le_bytes());
            }
        }
        frame(COMMAND_HEADER, &payload).unwrap_or_default()
    }

    /// Parses a command payload; `None` for unknown codes, bad lengths or
    /// arguments outside their codes (each command has one spelling: what
    /// is accepted re-encodes to the same bytes).
    pub fn parse(payload: &[u8]) -> Option<Self> {
        let (&code, args) = payload.split_first()?;
        let command = match (code, args) {
            (0x00, []) => Command::GetVersion,
            (0x01, []) => Command::Calibrate,
            (0x02, []) => Command::StartStream,
            (0x03, []) => Command::StopStream,
            (0x04, [kind]) => Command::SetControlType(ControlType::from_code(*kind)?),
            (0x05, a) if a.len() == 12 => {
                Command::SetControlTarget([f32_at(a, 0)?, f32_at(a, 4)?, f32_at(a, 8)?])
            }
            (0x06, [0]) => Command::SetDiagnostics(false),
            (0x06, [1]) => Command::SetDiagnostics(true),
            (0x07, []) => Command::ResetPacketNumber,
            (0x80, []) => Command::Heartbeat,
            _ => return None,
        };
        Some(command)
    }
}

fn bytes_at<const N: usize>(bytes: &[u8], at: usize) -> Option<[u8; N]> {
    bytes.get(at..at + N)?.try_into().ok()
}

fn f32_at(bytes: &[u8], at: usize) -> Option<f32> {
    bytes_at(bytes, at).map(f32::from_le_bytes)
}

/// Error bit: the PC's heartbeat is missing (the device has stopped
/// applying the torque target).
pub const ERROR_HEARTBEAT: u16 = 1;
/// Error bit: a torque sensor did not answer.
pub const ERROR_TORQUE_SENSOR: u16 = 2;
/// Status bit: the device is streaming.
pub const STATUS_STREAMING: u8 = 1;
/// Status bits 4-5: the control type the device is running.
pub const STATUS_CONTROL_SHIFT: u8 = 4;
/// Mask of the status bits with a meaning; the others are reserved (0).
pub const STATUS_KNOWN: u8 = STATUS_STREAMING | (0b11 << STATUS_CONTROL_SHIFT);

/// The status byte of a device streaming (or not) in `control`.
pub fn status_byte(streaming: bool, control: ControlType) -> u8 {
    u8::from(streaming) | ((control as u8) << STATUS_CONTROL_SHIFT)
}

/// The control type in a status byte; `None` for the undefined code 3.
pub fn status_control(status: u8) -> Option<ControlType> {
    ControlType::from_code((status >> STATUS_CONTROL_SHIFT) & 0b11)
}

/// One device stream frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Telemetry {
    /// Status byte (bit 0 streaming, bits 4-5 control type).
    pub status: u8,
    /// Error bits ([`ERROR_HEARTBEAT`], [`ERROR_TORQUE_SENSOR`]).
    pub error: u16,
    /// Packet number (wraps).
    pub packet: u16,
    /// Firmware run time [ms].
    pub run_time_ms: u32,
    /// Encoder counts θ1..θ5.
    pub counts: [i32; 5],
    /// Torque sensor readings τ_r [N m].
    pub torques: [f32; 3],
    /// Motor torques commanded [N m].
    pub commanded: [f32; 3],
}

impl Telemetry {
    /// The framed bytes.
    pub fn encode(&self) -> FrameBytes {
        let mut payload = Payload::new();
        // 53 bytes fit the 64-byte buffer.
        let _ = payload.push(self.status);
        let _ = payload.extend_from_slice(&self.error.to_le_bytes());
        let _ = payload.extend_from_slice(&self.packet.to_le_bytes());
        let _ = payload.extend_from_slice(&self.run_time_ms.to_le_bytes());
        for c in self.counts {
            let _ = payload.extend_from_slice(&c.to_le_bytes());
        }
        for t in self.torques.iter().chain(self.commanded.iter()) {
            let _ = payload.extend_from_slice(&t.to_le_bytes());
        }
        frame(TELEMETRY_HEADER, &payload).unwrap_or_default()
    }

    /// Parses a stream payload; `None` unless it is exactly 53 bytes.
    pub fn parse(payload: &[u8]) -> Option<Self> {
        if payload.len() != usize::from(TELEMETRY_LENGTH) - 1 {
            return None;
        }
        let mut counts = [0i32; 5];
        for (i, c) in counts.iter_mut().enumerate() {
            *c = i32::from_le_bytes(bytes_at(payload, 9 + 4 * i)?);
        }
        let mut torques = [0f32; 3];
        let mut commanded = [0f32; 3];
        for i in 0..3 {
            torques[i] = f32_at(payload, 29 + 4 * i)?;
            commanded[i] = f32_at(payload, 41 + 4 * i)?;
        }
        Some(Self {
            status: payload[0],
            error: u16::from_le_bytes(bytes_at(payload, 1)?),
            packet: u16::from_le_bytes(bytes_at(payload, 3)?),
            run_time_ms: u32::from_le_bytes(bytes_at(payload, 5)?),
            counts,
            torques,
            commanded,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn telemetry() -> impl Strategy<Value = Telemetry> {
        (
            any::<u8>(),
            any::<u16>(),
            any::<u16>(),
            any::<u32>(),
            proptest::array::uniform5(any::<i32>()),
            proptest::array::uniform3(-40f32..40.0),
        )
            .prop_map(
                |(status, error, packet, run_time_ms, counts, torques)| Telemetry {
                    status,
                    error,
                    packet,
                    run_time_ms,
                    counts,
                    torques,
                    commanded: torques,
                },
            )
    }

    fn decode_all(decoder: &mut Decoder, bytes: &[u8]) -> std::vec::Vec<Telemetry> {
        bytes
            .iter()
            .filter_map(|b| decoder.push(*b))
            .filter_map(|p| Telemetry::parse(&p))
            .collect()
    }

    proptest! {
        /// Arbitrary byte streams never panic the decoder.
        #[test]
        fn decoder_is_total(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
            let mut decoder = Decoder::new(TELEMETRY_HEADER);
            for b in bytes {
                if let Some(p) = decoder.push(b) {
                    let _ = Telemetry::parse(&p);
                    let _ = Command::parse(&p);
                }
            }
        }

        /// Valid frames between garbage, after a truncated frame and next
        /// to a frame with a wrong checksum are all recovered, in order.
        #[test]
        fn frames_survive_garbage(
            frames in proptest::collection::vec(telemetry(), 1..6),
            garbage in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..40), 6),
            cut in 1usize..53,
        ) {
            let mut stream = std::vec::Vec::new();
            for (i, t) in frames.iter().enumerate() {
                stream.extend_from_slice(&garbage[i]);
                // A truncated frame and a corrupted one before every frame.
                stream.extend_from_slice(&t.encode()[..cut]);
                let mut corrupt = t.encode();
                corrupt[20] ^= 0x5A;
                stream.extend_from_slice(&corrupt);
                stream.extend_from_slice(&t.encode());
            }
            let mut decoder = Decoder::new(TELEMETRY_HEADER);
            let decoded = decode_all(&mut decoder, &stream);
            // Every valid frame appears, in order (garbage may by chance
            // form extra valid frames, but they cannot displace these).
            let mut expected = frames.iter().peekable();
            for d in &decoded {
                if expected.peek().is_some_and(|e| *e == d) {
                    expected.next();
                }
            }
            prop_assert!(expected.next().is_none(), "decoded {} of {}", decoded.len(), frames.len());
        }

        /// Commands round-trip through framing and decoding.
        #[test]
        fn commands_round_trip(t in proptest::array::uniform3(-20f32..20.0), kind in 0u8..3, on in any::<bool>()) {
            let commands = [
                Command::GetVersion, Command::Calibrate, Command::StartStream, Command::StopStream,
                Command::SetControlType(ControlType::from_code(kind).unwrap()), Command::SetControlTarget(t),
                Command::SetDiagnostics(on), Command::ResetPacketNumber, Command::Heartbeat,
            ];
            let mut decoder = Decoder::new(COMMAND_HEADER);
            for c in commands {
                let payload = c.encode().iter().filter_map(|b| decoder.push(*b)).next().unwrap();
                prop_assert_eq!(Command::parse(&payload), Some(c));
            }
        }
    }

    /// Found by the `arebo_stream` fuzz target: set-diagnostics took any
    /// nonzero argument as "on", so `aa aa 03 06 a3 00` was accepted as the
    /// command whose only spelling is `aa aa 03 06 01 5e`.
    #[test]
    fn set_diagnostics_takes_only_0_or_1() {
        let mut decoder = Decoder::new(COMMAND_HEADER);
        let payloads: std::vec::Vec<Payload> = [0xAA, 0xAA, 0x03, 0x06, 0xA3, 0x00]
            .iter()
            .filter_map(|b| decoder.push(*b))
            .collect();
        assert_eq!(payloads.len(), 1, "the frame itself is well formed");
        assert_eq!(Command::parse(&payloads[0]), None);
        for on in [false, true] {
            let framed = Command::SetDiagnostics(on).encode();
            assert_eq!(
                Command::parse(&framed[3..framed.len() - 1]),
                Some(Command::SetDiagnostics(on))
            );
        }
    }

    #[test]
    fn checksum_follows_the_family_convention() {
        let bytes = Command::Heartbeat.encode();
        assert_eq!(
            &bytes[..],
            &[0xAA, 0xAA, 0x02, 0x80, (0xAAu32 + 0xAA + 0x02 + 0x80) as u8]
        );
        assert_eq!(Telemetry::parse(&[0; 53]).map(|t| t.packet), Some(0));
        let mut decoder = Decoder::new(TELEMETRY_HEADER);
        let mut wrong = Telemetry::parse(&[0; 53]).unwrap().encode();
        let last = wrong.len() - 1;
        wrong[last] ^= 1;
        assert!(wrong.iter().all(|b| decoder.push(*b).is_none()));
        assert_eq!(decoder.stats.checksum_errors, 1);
    }
}
