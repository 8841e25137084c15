//! The Zenoh `cmd/request` handler's screen (signature, then decoding;
//! JSON and CBOR) on arbitrary payloads, signed genuinely, for another key
//! expression, tampered or not at all. No silent acceptance: only a
//! genuinely signed payload is ever accepted, an accepted command is in
//! canonical form, and the same payload with one bit flipped is refused as
//! unauthorised.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_fuzz::{assert_wire_canonical, command_key, pick, zenoh_sample, Signing};
use limb_zenoh::inbound::screen;
use limb_zenoh::wire::RefuseReason;

const KEY_EXPR: &str = "limb/fuzz/@v2/cmd/request";

fuzz_target!(|data: &[u8]| {
    let key = command_key();
    let Some(sample) = zenoh_sample(data, &key, KEY_EXPR) else {
        return;
    };
    let signature = sample.signature.as_deref();
    match screen(&key, sample.format, KEY_EXPR, sample.payload, signature) {
        Ok(message) => {
            assert_eq!(
                sample.signing,
                Signing::Genuine,
                "accepted without a genuine signature"
            );
            assert_wire_canonical(sample.format, &message);
            let mut tampered = sample.payload.to_vec();
            let bit = pick(sample.payload, tampered.len() * 8);
            tampered[bit / 8] ^= 1 << (bit % 8);
            let refused = screen(&key, sample.format, KEY_EXPR, &tampered, signature);
            assert!(
                matches!(refused, Err((_, RefuseReason::Unauthorised))),
                "a tampered command was not refused as unauthorised: {refused:?}"
            );
        }
        Err((_, RefuseReason::Unauthorised)) => {
            assert_ne!(
                sample.signing,
                Signing::Genuine,
                "a genuine signature refused"
            );
        }
        Err((sequence, RefuseReason::Malformed { .. })) => {
            assert_eq!(
                sample.signing,
                Signing::Genuine,
                "malformed reported before the signature"
            );
            assert_eq!(sequence, None, "a malformed command named a sequence");
        }
        Err((_, reason)) => panic!("the screen refused with {reason:?}"),
    }
});
