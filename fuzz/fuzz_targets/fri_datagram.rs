//! FRI monitoring (controller → client) and command (client → controller)
//! datagrams of every version, 2.7 framing included: decoding never
//! panics, and what it accepts is canonical and, framed, tamper-evident
//! ([`limb_fuzz::assert_fri_canonical`]).
//! Input: a selector byte (version: selector mod 6; command message when
//! selector / 6 is odd), then the datagram.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_fuzz::{assert_fri_canonical, fri_version};
use limb_kuka::{decode_command, decode_monitoring, encode_command, encode_monitoring};

fuzz_target!(|data: &[u8]| {
    let Some((&selector, datagram)) = data.split_first() else {
        return;
    };
    let version = fri_version(selector);
    if (selector / 6) % 2 == 1 {
        if let Ok(message) = decode_command(datagram, version) {
            assert_fri_canonical(datagram, &message, version, encode_command, decode_command);
        }
    } else if let Ok(message) = decode_monitoring(datagram, version) {
        assert_fri_canonical(
            datagram,
            &message,
            version,
            encode_monitoring,
            decode_monitoring,
        );
    }
});
