//! The plant.md log reader (`limb_sim::log::parse`) on arbitrary text. No
//! silent acceptance: an accepted log has rows and strictly increasing
//! times, and writing it back out reads back to the same records and the
//! same text (so every value is finite: the reader refuses the `NaN` and
//! `inf` the writer would print).
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_sim::log::{parse, to_csv};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(records) = parse(&text) else {
        return;
    };
    assert!(!records.is_empty(), "a log without rows was accepted");
    assert!(
        records.windows(2).all(|w| w[0].time < w[1].time),
        "times do not increase"
    );
    let written = to_csv(&records);
    let again = parse(&written).expect("the reader refused the writer's text");
    assert_eq!(again, records, "written and read back differently");
    assert_eq!(to_csv(&again), written, "the writer's text is not stable");
});
