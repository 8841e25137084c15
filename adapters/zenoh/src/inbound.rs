//! What an arriving sample becomes: the screens the node's Zenoh callbacks
//! run on `cmd/request`, `cmd/estop` and `alive/supervisor` payloads before
//! anything reaches the control loop. Pure functions of the bytes, so the
//! same code runs under the callbacks, the proptests and the fuzz targets
//! (`fuzz/`).

use crate::auth::CommandKey;
use crate::wire::{
    CommandMessage, EmergencyStopMessage, Heartbeat, RefuseReason, WireFormat, MAX_COMMAND_LENGTH,
};

/// Checks a `cmd/request` sample: signature over `key_expr` and the exact
/// payload bytes, then decoding. Total: any bytes give a command or a
/// refusal (with the sequence number when it could be read).
///
/// # Errors
/// [`RefuseReason::Unauthorised`] or [`RefuseReason::Malformed`].
pub fn screen(
    key: &CommandKey,
    format: WireFormat,
    key_expr: &str,
    payload: &[u8],
    signature: Option<&[u8]>,
) -> Result<CommandMessage, (Option<u64>, RefuseReason)> {
    let decoded = format.decode_command(payload);
    let sequence = decoded.as_ref().ok().map(|m| m.sequence);
    if key.verify(key_expr, payload, signature).is_err() {
        return Err((sequence, RefuseReason::Unauthorised));
    }
    decoded.map_err(|error| {
        (
            None,
            RefuseReason::Malformed {
                detail: error.to_string(),
            },
        )
    })
}

/// The sequence number a `cmd/estop` payload names, when it is a readable
/// [`EmergencyStopMessage`] no longer than [`MAX_COMMAND_LENGTH`]. Any
/// payload stops the robot; this only says which stop the ack names.
pub fn emergency_stop_sequence(format: WireFormat, payload: &[u8]) -> Option<u64> {
    (payload.len() <= MAX_COMMAND_LENGTH)
        .then(|| format.decode::<EmergencyStopMessage>(payload).ok())
        .flatten()
        .map(|m| m.sequence)
}

/// The heartbeat in an `alive/supervisor` sample, when its signature over
/// `key_expr` and the exact payload bytes holds and it decodes; `None`
/// otherwise (the sample keeps nothing alive). Whether it is fresh is the
/// caller's business (its sequence must exceed every one accepted before).
pub fn screen_heartbeat(
    key: &CommandKey,
    format: WireFormat,
    key_expr: &str,
    payload: &[u8],
    signature: Option<&[u8]>,
) -> Option<Heartbeat> {
    key.verify(key_expr, payload, signature).ok()?;
    format.decode::<Heartbeat>(payload).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::SupervisorCommand;
    use proptest::prelude::*;

    fn key() -> CommandKey {
        CommandKey::new(b"fuzzing key, sixteen+ bytes").unwrap()
    }

    const KEY_EXPR: &str = "limb/fuzz/@v2/cmd/request";

    proptest! {
        /// Fuzz: arbitrary bytes, signed or not, never panic; unsigned ones
        /// are always refused as unauthorised; signed ones are refused as
        /// malformed unless they decode to exactly one command.
        #[test]
        fn arbitrary_command_bytes_are_refused(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            for format in [WireFormat::Json, WireFormat::Cbor] {
                let unsigned = screen(&key(), format, KEY_EXPR, &bytes, None);
                prop_assert!(matches!(unsigned, Err((_, RefuseReason::Unauthorised))));
                let signature = key().sign(KEY_EXPR, &bytes);
                match screen(&key(), format, KEY_EXPR, &bytes, Some(&signature)) {
                    Ok(message) => {
                        // Only a well-formed command gets through; it re-encodes.
                        let again = format.encode(&message).unwrap();
                        prop_assert_eq!(format.decode_command(&again).unwrap(), message);
                    }
                    Err((_, reason)) => {
                        prop_assert!(matches!(reason, RefuseReason::Malformed { .. }), "{:?}", reason);
                    }
                }
            }
        }

        /// Fuzz: a valid command with one byte changed is refused (the
        /// signature was over the original bytes).
        #[test]
        fn a_tampered_command_is_unauthorised(index in 0usize..64, flip in 1u8..=255) {
            let message = CommandMessage { sequence: 3, command: SupervisorCommand::Reset };
            for format in [WireFormat::Json, WireFormat::Cbor] {
                let mut bytes = format.encode(&message).unwrap();
                let signature = key().sign(KEY_EXPR, &bytes);
                prop_assert_eq!(screen(&key(), format, KEY_EXPR, &bytes, Some(&signature)), Ok(message));
                let i = index % bytes.len();
                bytes[i] ^= flip;
                let tampered = screen(&key(), format, KEY_EXPR, &bytes, Some(&signature));
                prop_assert!(matches!(tampered, Err((_, RefuseReason::Unauthorised))));
            }
        }
    }
}
