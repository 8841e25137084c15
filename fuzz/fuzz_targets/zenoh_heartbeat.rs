//! The Zenoh `alive/supervisor` handler's screen (signature, then decoding;
//! JSON and CBOR) on arbitrary payloads. No silent acceptance: only a
//! genuinely signed payload keeps the node alive, and what it accepts is
//! in canonical form.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_fuzz::{assert_wire_canonical, command_key, zenoh_sample, Signing};
use limb_zenoh::inbound::screen_heartbeat;

const KEY_EXPR: &str = "limb/fuzz/@v2/alive/supervisor";

fuzz_target!(|data: &[u8]| {
    let key = command_key();
    let Some(sample) = zenoh_sample(data, &key, KEY_EXPR) else {
        return;
    };
    let signature = sample.signature.as_deref();
    if let Some(heartbeat) =
        screen_heartbeat(&key, sample.format, KEY_EXPR, sample.payload, signature)
    {
        assert_eq!(
            sample.signing,
            Signing::Genuine,
            "a heartbeat accepted without a genuine signature"
        );
        assert_wire_canonical(sample.format, &heartbeat);
    }
});
