//! The versioned wire encoding (`@v2`, see `PROTOCOL.md`) of every
//! message, in JSON or CBOR.
//!
//! # Format
//! Every payload is one serde value of a type below, encoded as JSON
//! (readable; `application/json`) or CBOR (compact, for rate;
//! `application/cbor`, RFC 8949). The node and its supervisors agree on one
//! [`WireFormat`]; each sample also carries the Zenoh encoding, so a tool
//! can tell them apart. Field names and enum tags are part of the `@v2`
//! contract: a change that old readers would misread gets a new `@vN` key
//! prefix. Lengths are metres, angles radians, forces newtons, torques
//! newton-metres, times seconds (kernel time unless said otherwise).
//!
//! A command is:
//! ```json
//! {"sequence": 17, "command": {"command": "approve_manipulation",
//!   "target": {"shoulder_elevation": 0.6, "elbow_flexion": 0.8}}}
//! ```
//! signed as described in [`crate::auth`]. Unknown fields or commands are
//! refused. Non-finite numbers are encoded as JSON `null` by the kernel side
//! (times of events stamped at a faulty clock); readers treat them as
//! missing.

use limb_kernel::arm::ArmGeometry;
use limb_kernel::config::SafetyLimits;
use limb_kernel::KernelConfig;
use limb_session::kernel_wire::{
    CommandReport, Fault, Frame, Joints, KernelEvent, KernelRefusal, PlanarPoint, State,
};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// Largest payload the kernel side decodes [bytes]; a command is < 300.
pub const MAX_COMMAND_LENGTH: usize = 4096;

/// How payloads are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WireFormat {
    /// JSON text (RFC 8259).
    Json,
    /// CBOR (RFC 8949) via `ciborium`.
    Cbor,
}

/// Why a payload could not be encoded or decoded.
#[derive(Debug, thiserror::Error)]
pub enum WireError {
    /// Longer than [`MAX_COMMAND_LENGTH`].
    #[error("payload of {0} bytes is longer than {MAX_COMMAND_LENGTH}")]
    TooLong(usize),
    /// Not a valid value of the expected type.
    #[error("malformed payload: {0}")]
    Malformed(String),
    /// Bytes left after the value.
    #[error("trailing bytes after the value")]
    Trailing,
    /// The value could not be encoded (a bug, not an input error).
    #[error("cannot encode: {0}")]
    Encode(String),
}

impl WireFormat {
    /// The Zenoh encoding announced with each sample.
    #[cfg(feature = "link")]
    pub fn encoding(self) -> zenoh::bytes::Encoding {
        match self {
            WireFormat::Json => zenoh::bytes::Encoding::APPLICATION_JSON,
            WireFormat::Cbor => zenoh::bytes::Encoding::APPLICATION_CBOR,
        }
    }

    /// Encodes `value`.
    ///
    /// # Errors
    /// [`WireError::Encode`] if serde refuses the value.
    pub fn encode<T: Serialize>(self, value: &T) -> Result<Vec<u8>, WireError> {
        match self {
            WireFormat::Json => {
                serde_json::to_vec(value).map_err(|e| WireError::Encode(e.to_string()))
            }
            WireFormat::Cbor => {
                let mut out = Vec::with_capacity(128);
                ciborium::ser::into_writer(value, &mut out)
                    .map_err(|e| WireError::Encode(e.to_string()))?;
                Ok(out)
            }
        }
    }

    /// Decodes exactly one value from `bytes`. Total: any input gives a
    /// value or an error, never a panic (recursion is bounded by both
    /// decoders: 128 levels for JSON, 256 for CBOR).
    ///
    /// # Errors
    /// [`WireError`] for anything but one well-formed value of `T`.
    pub fn decode<T: DeserializeOwned>(self, bytes: &[u8]) -> Result<T, WireError> {
        match self {
            WireFormat::Json => {
                serde_json::from_slice(bytes).map_err(|e| WireError::Malformed(e.to_string()))
            }
            WireFormat::Cbor => {
                let mut rest = bytes;
                let value = ciborium::de::from_reader(&mut rest)
                    .map_err(|e| WireError::Malformed(e.to_string()))?;
                if rest.is_empty() {
                    Ok(value)
                } else {
                    Err(WireError::Trailing)
                }
            }
        }
    }

    /// Decodes a command payload, refusing oversized ones first.
    ///
    /// # Errors
    /// [`WireError`] for anything but one well-formed [`CommandMessage`].
    pub fn decode_command(self, bytes: &[u8]) -> Result<CommandMessage, WireError> {
        if bytes.len() > MAX_COMMAND_LENGTH {
            return Err(WireError::TooLong(bytes.len()));
        }
        self.decode(bytes)
    }
}

/// A supervisory command. Each maps to one kernel request except
/// [`SupervisorCommand::UpdateLimits`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    tag = "command",
    rename_all = "snake_case",
    deny_unknown_fields,
    from = "StrictCommand"
)]
pub enum SupervisorCommand {
    /// `Request::StartEstimation`.
    StartEstimation,
    /// `Request::ApproveManipulation(target)`.
    ApproveManipulation {
        /// Target joint angles [rad].
        target: Joints,
    },
    /// `Request::FinishManipulation`.
    FinishManipulation,
    /// `Request::Stop` (an operator stop, authenticated; see also the
    /// unauthenticated emergency stop on `cmd/estop`).
    Stop,
    /// `Request::Reset` after a safe stop.
    Reset,
    /// New safety limits, through `Kernel::update_limits`: accepted only
    /// while the arm is held still and only when `KernelConfig::check`
    /// passes.
    UpdateLimits {
        /// The proposed limits.
        limits: SafetyLimits,
    },
}

/// What a [`SupervisorCommand`] is decoded through: serde does not refuse
/// unknown fields beside the tag of an internally tagged unit variant
/// (`{"command": "stop", "force": true}` would decode as a stop), so every
/// variant is a struct variant here, each refusing unknown fields.
#[derive(Deserialize)]
#[serde(tag = "command", rename_all = "snake_case", deny_unknown_fields)]
enum StrictCommand {
    StartEstimation {},
    ApproveManipulation { target: Joints },
    FinishManipulation {},
    Stop {},
    Reset {},
    UpdateLimits { limits: SafetyLimits },
}

impl From<StrictCommand> for SupervisorCommand {
    fn from(command: StrictCommand) -> Self {
        match command {
            StrictCommand::StartEstimation {} => Self::StartEstimation,
            StrictCommand::ApproveManipulation { target } => Self::ApproveManipulation { target },
            StrictCommand::FinishManipulation {} => Self::FinishManipulation,
            StrictCommand::Stop {} => Self::Stop,
            StrictCommand::Reset {} => Self::Reset,
            StrictCommand::UpdateLimits { limits } => Self::UpdateLimits { limits },
        }
    }
}

/// A signed command on `cmd/request`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CommandMessage {
    /// Strictly increasing per kernel node, across all its supervisors
    /// (replay protection): a command at or below the last decoded, signed
    /// one is refused as `replayed`. Every signed command that decodes uses
    /// up its number, whether the kernel then accepts or refuses it, so a
    /// captured refused command cannot be replayed once the state would
    /// allow it. Supervisors send max(previous + 1, wall clock in µs since
    /// the UNIX epoch), so several supervisors share the sequence.
    pub sequence: u64,
    /// What to do.
    pub command: SupervisorCommand,
}

/// An emergency stop on `cmd/estop`. Any payload stops the robot; this one
/// also lets the ack name the stop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EmergencyStopMessage {
    /// Sender's sequence number, echoed in the ack.
    pub sequence: u64,
}

/// A supervisor heartbeat on `alive/supervisor` (signed). Unknown fields
/// are refused: a heartbeat with one does not count.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Heartbeat {
    /// Strictly increasing per robot, across all its supervisors: the node
    /// accepts a heartbeat only above the last one it accepted. Supervisors
    /// send their wall clock in µs since the UNIX epoch (kept above their
    /// own previous value), so several supervisors and restarts interleave.
    pub sequence: u64,
}

/// Why a command was refused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum RefuseReason {
    /// Not a well-formed command; nothing changed.
    Malformed {
        /// The decoder's message.
        detail: String,
    },
    /// Missing or wrong signature; nothing changed.
    Unauthorised,
    /// The sequence number was not above the last accepted one.
    Replayed {
        /// The last accepted sequence number.
        last_accepted: u64,
    },
    /// The command queue of the control loop was full; nothing changed.
    Busy,
    /// The kernel refused the request (its own transition guards).
    Kernel {
        /// The kernel's refusal.
        refusal: KernelRefusal,
    },
    /// The proposed limits failed `KernelConfig::check`.
    InvalidLimits {
        /// The first unusable group (a `ConfigError` fault).
        error: Fault,
    },
    /// Limits change only in Grasp, Validated or SafeStop.
    LimitsNotAllowedInState {
        /// The state the kernel was in.
        state: State,
    },
}

/// The result of a command.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum AckOutcome {
    /// Carried out; the kernel is now in `state`.
    Accepted {
        /// The state after the command.
        state: State,
    },
    /// Refused; the state did not change.
    Refused {
        /// Why.
        #[serde(flatten)]
        reason: RefuseReason,
    },
}

/// Which command an ack answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AckSubject {
    /// A request on `cmd/request` (sequence `None` if it did not decode).
    Request,
    /// An emergency stop on `cmd/estop`.
    EmergencyStop,
}

/// An acknowledgement on `ack/command`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ack {
    /// What was acknowledged.
    pub subject: AckSubject,
    /// The command's sequence number, when it could be read.
    pub sequence: Option<u64>,
    /// Accepted or refused.
    pub outcome: AckOutcome,
}

impl Ack {
    /// A refusal of a request with `sequence` (when it could be read).
    pub fn refused(sequence: Option<u64>, reason: RefuseReason) -> Self {
        Self {
            subject: AckSubject::Request,
            sequence,
            outcome: AckOutcome::Refused { reason },
        }
    }
}

/// A kernel trace event on `telemetry/event`, numbered so a reader sees
/// loss or reordering.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EventMessage {
    /// 0, 1, 2, … per node.
    pub sequence: u64,
    /// Events the kernel dropped before the adapter drained them (total).
    pub kernel_dropped: u32,
    /// The event.
    pub event: KernelEvent,
    /// Who asked for the stop, when the event is a transition into
    /// SafeStop that this node's supervision requested (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<StopOrigin>,
}

/// Which of the node's supervisory paths stopped the kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopOrigin {
    /// An emergency stop on `cmd/estop` (unsigned, express).
    EmergencyStop,
    /// A signed `stop` command on `cmd/request`.
    Command,
    /// The supervisor watchdog: heartbeats stopped (policy `stop`).
    SupervisorLost,
}

/// One control step on `telemetry/sample` (decimated).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleMessage {
    /// Control step number.
    pub step: u64,
    /// Kernel time of the step [s].
    pub time: f64,
    /// Node wall clock at publication [ns since the UNIX epoch], for
    /// latency measurements.
    pub sent_at_ns: u64,
    /// The sensor frame.
    pub frame: Frame,
    /// The kernel's command.
    pub command: CommandReport,
}

/// A change of the supervisor link on `telemetry/link`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "link", rename_all = "snake_case")]
pub enum LinkMessage {
    /// No valid heartbeat for longer than the timeout.
    SupervisorLost {
        /// Kernel time of detection [s].
        time: f64,
        /// Silence at detection [s].
        silence: f64,
        /// Whether the policy stopped the kernel.
        stopped: bool,
    },
    /// Heartbeats resumed.
    SupervisorBack {
        /// Kernel time [s].
        time: f64,
    },
}

/// The validated arm model on `model/arm`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmModel {
    /// Upper-arm length l1 [m].
    pub upper_arm_length: f64,
    /// Forearm length l2 [m].
    pub forearm_length: f64,
    /// Shoulder position, frame S [m].
    pub shoulder: PlanarPoint,
}

impl From<&ArmGeometry> for ArmModel {
    fn from(arm: &ArmGeometry) -> Self {
        Self {
            upper_arm_length: arm.upper_arm_length(),
            forearm_length: arm.forearm_length(),
            shoulder: arm.shoulder().into(),
        }
    }
}

/// Counters of the node.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NodeCounters {
    /// Control steps run.
    pub steps: u64,
    /// Steps that started later than one period after their deadline.
    pub overruns: u64,
    /// Samples not published because the outbound queue was full.
    pub samples_dropped: u64,
    /// Reliable messages not published because the outbound queue was full.
    pub reliable_dropped: u64,
    /// Kernel trace events lost before being drained.
    pub kernel_events_dropped: u32,
    /// Signed heartbeats refused because their sequence was not above the
    /// last accepted one (replays, or a supervisor whose clock is behind).
    pub heartbeats_replayed: u64,
    /// Emergency stops applied whose ack was dropped (more than
    /// [`crate::supervision::ESTOP_QUEUE`] in one control period).
    pub estop_acks_dropped: u64,
}

/// The kernel side's status on `alive/kernel`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KernelStatus {
    /// Kernel time [s].
    pub time: f64,
    /// The kernel's state.
    pub state: State,
    /// Whether a valid supervisor heartbeat is current.
    pub supervisor_present: bool,
    /// Counters.
    pub counters: NodeCounters,
}

/// The answer of the `state` queryable.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StateSnapshot {
    /// Status at the last state change or heartbeat.
    pub status: KernelStatus,
    /// The validated model, in Validated and Manipulate.
    pub arm: Option<ArmModel>,
    /// The kernel's configuration.
    pub config: KernelConfig,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn approve() -> CommandMessage {
        CommandMessage {
            sequence: 7,
            command: SupervisorCommand::ApproveManipulation {
                target: Joints {
                    shoulder_elevation: 0.6,
                    elbow_flexion: 0.8,
                },
            },
        }
    }

    /// PROTOCOL.md: unknown fields are refused as malformed, at every
    /// level of a command and in a heartbeat (the foreign supervisor's
    /// cases: a stop with `force`, a start or finish with an extra field,
    /// an approval with a `speed` beside its target, a limit update with
    /// an unknown limit, a heartbeat naming its `supervisor`).
    #[test]
    fn unknown_fields_are_refused_everywhere() {
        let limits = serde_json::to_value(SafetyLimits::default()).unwrap();
        let mut extra_limit = limits.clone();
        extra_limit["max_speed_typo"] = serde_json::json!(1.0);
        let mut extra_interval = limits.clone();
        extra_interval["elbow_flexion"]["mid"] = serde_json::json!(0.0);
        let bad = [
            serde_json::json!({"sequence": 1, "command": {"command": "stop", "force": true}}),
            serde_json::json!({"sequence": 1, "command": {"command": "start_estimation", "now": 1}}),
            serde_json::json!({"sequence": 1, "command": {"command": "finish_manipulation", "force": true}}),
            serde_json::json!({"sequence": 1, "command": {"command": "reset", "x": 0}}),
            serde_json::json!({"sequence": 1, "command": {"command": "approve_manipulation",
                "target": {"shoulder_elevation": 0.6, "elbow_flexion": 0.8}, "speed": 9.9}}),
            serde_json::json!({"sequence": 1, "command": {"command": "approve_manipulation",
                "target": {"shoulder_elevation": 0.6, "elbow_flexion": 0.8, "speed": 9.9}}}),
            serde_json::json!({"sequence": 1, "command": {"command": "update_limits", "limits": extra_limit}}),
            serde_json::json!({"sequence": 1, "command": {"command": "update_limits", "limits": extra_interval}}),
            serde_json::json!({"sequence": 1, "command": {"command": "stop"}, "priority": 1}),
        ];
        for format in [WireFormat::Json, WireFormat::Cbor] {
            for message in &bad {
                let bytes = format.encode(message).unwrap();
                assert!(
                    matches!(format.decode_command(&bytes), Err(WireError::Malformed(_))),
                    "{format:?} accepted {message}"
                );
            }
            let beat = format
                .encode(&serde_json::json!({"sequence": 5, "supervisor": "me"}))
                .unwrap();
            assert!(format.decode::<Heartbeat>(&beat).is_err(), "{format:?}");
            let good = format.encode(&serde_json::json!({"sequence": 5})).unwrap();
            assert_eq!(
                format.decode::<Heartbeat>(&good).unwrap(),
                Heartbeat { sequence: 5 }
            );
            let ok = serde_json::json!({"sequence": 1, "command": {"command": "update_limits", "limits": limits}});
            assert!(format.decode_command(&format.encode(&ok).unwrap()).is_ok());
        }
    }

    #[test]
    fn commands_round_trip_in_both_formats() {
        let limits = CommandMessage {
            sequence: 8,
            command: SupervisorCommand::UpdateLimits {
                limits: SafetyLimits::default(),
            },
        };
        for format in [WireFormat::Json, WireFormat::Cbor] {
            for message in [approve(), limits] {
                let bytes = format.encode(&message).unwrap();
                assert_eq!(format.decode_command(&bytes).unwrap(), message);
            }
        }
    }

    #[test]
    fn the_documented_json_form_decodes() {
        let text = br#"{"sequence": 7, "command": {"command": "approve_manipulation",
            "target": {"shoulder_elevation": 0.6, "elbow_flexion": 0.8}}}"#;
        assert_eq!(WireFormat::Json.decode_command(text).unwrap(), approve());
    }

    /// Found by the `zenoh_command` fuzz target: serde_json's default
    /// float parser may land one unit in the last place off the nearest
    /// double for a long mantissa, so the command acted on was not the
    /// number sent, and its own encoding read back as another one. Numbers
    /// are now read correctly rounded (`float_roundtrip`).
    #[test]
    fn json_numbers_are_read_correctly_rounded() {
        let sent = br#"{"sequence":1000000000,"command":{"command":"approve_manipulation","target":{"shoulder_elevation":25000000000000000000000000000000000000001295154896,"elbow_flexion":1.8}}}"#;
        let json = WireFormat::Json;
        let message = json.decode_command(sent).unwrap();
        let SupervisorCommand::ApproveManipulation { target } = message.command else {
            panic!("not an approval: {message:?}");
        };
        // The nearest double to the decimal sent (Rust's own parser is
        // correctly rounded).
        let nearest: f64 = "25000000000000000000000000000000000000001295154896"
            .parse()
            .unwrap();
        assert_eq!(target.shoulder_elevation.to_bits(), nearest.to_bits());
        let again = json.encode(&message).unwrap();
        assert_eq!(json.decode_command(&again).unwrap(), message);
    }

    #[test]
    fn unknown_commands_fields_and_trailing_bytes_are_refused() {
        let json = WireFormat::Json;
        for bad in [
            &br#"{"sequence": 1, "command": {"command": "self_destruct"}}"#[..],
            br#"{"sequence": 1, "command": {"command": "stop"}, "extra": 1}"#,
            br#"{"sequence": -1, "command": {"command": "stop"}}"#,
            br#"{"sequence": 1, "command": {"command": "stop"}} x"#,
            b"",
        ] {
            assert!(json.decode_command(bad).is_err());
        }
        let mut cbor = WireFormat::Cbor.encode(&approve()).unwrap();
        cbor.push(0);
        assert!(matches!(
            WireFormat::Cbor.decode_command(&cbor),
            Err(WireError::Trailing)
        ));
        let long = vec![b' '; MAX_COMMAND_LENGTH + 1];
        assert!(matches!(
            json.decode_command(&long),
            Err(WireError::TooLong(_))
        ));
    }
}
