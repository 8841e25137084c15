//! The Zenoh `cmd/estop` handler's reading of arbitrary payloads (JSON and
//! CBOR). Any payload stops the robot; the handler only reads which stop
//! its ack names. No silent acceptance: a sequence is read only from a
//! payload within the command length that decodes as exactly one
//! emergency-stop message, and that message is in canonical form.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_fuzz::assert_wire_canonical;
use limb_zenoh::inbound::emergency_stop_sequence;
use limb_zenoh::wire::{EmergencyStopMessage, WireFormat, MAX_COMMAND_LENGTH};

fuzz_target!(|data: &[u8]| {
    for format in [WireFormat::Json, WireFormat::Cbor] {
        if let Some(sequence) = emergency_stop_sequence(format, data) {
            assert!(
                data.len() <= MAX_COMMAND_LENGTH,
                "an oversized e-stop was read"
            );
            assert_wire_canonical(format, &EmergencyStopMessage { sequence });
            let decoded: EmergencyStopMessage = format
                .decode(data)
                .expect("a sequence read from a payload that does not decode");
            assert_eq!(decoded.sequence, sequence, "the ack names another stop");
        }
    }
});
