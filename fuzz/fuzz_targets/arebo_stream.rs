//! The AREBO serial stream decoder fed arbitrary bytes, as both the PC's
//! telemetry decoder and the device's command decoder. No silent
//! acceptance: every payload a decoder returns is framed by bytes that
//! arrived (header, header, N, payload, checksum) after the previous
//! frame it returned — a frame found inside a broken one comes out when
//! the broken one's length has arrived, so not necessarily at the last
//! byte — the decoder counts it, and a payload that parses re-encodes to
//! those same bytes (telemetry and commands have one spelling each).
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_arebo::protocol::{frame, Command, Decoder, Telemetry, COMMAND_HEADER, TELEMETRY_HEADER};

fn check(header: u8, data: &[u8]) {
    let mut decoder = Decoder::new(header);
    let mut frames = 0u32;
    // End of the bytes the frames returned so far were taken from.
    let mut used = 0;
    for (i, byte) in data.iter().enumerate() {
        let Some(payload) = decoder.push(*byte) else {
            continue;
        };
        frames += 1;
        let framed = frame(header, &payload).expect("an accepted payload that cannot be framed");
        let start = data[used..=i]
            .windows(framed.len())
            .position(|w| w == framed.as_slice())
            .unwrap_or_else(|| panic!("payload {payload:?} is no frame that arrived"));
        used += start + framed.len();
        let reencoded = if header == TELEMETRY_HEADER {
            Telemetry::parse(&payload).map(|t| t.encode())
        } else {
            Command::parse(&payload).map(|c| c.encode())
        };
        if let Some(reencoded) = reencoded {
            assert_eq!(reencoded, framed, "a parsed payload re-encodes differently");
        }
    }
    assert_eq!(decoder.stats.frames, frames, "frames miscounted");
}

fuzz_target!(|data: &[u8]| {
    check(TELEMETRY_HEADER, data);
    check(COMMAND_HEADER, data);
});
