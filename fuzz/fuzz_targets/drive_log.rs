//! The drive-log reader (`limb_diagnosis::plant::drive::log::parse`) on arbitrary
//! text. No silent acceptance: an accepted log has at least `MIN_SAMPLES`
//! rows, strictly increasing times, only finite values and equally long
//! columns, and writing it back out reads back to the same log.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_diagnosis::plant::drive::log::{parse, to_csv, MIN_SAMPLES};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(log) = parse(&text) else {
        return;
    };
    assert!(log.len() >= MIN_SAMPLES, "a short log was accepted");
    assert!(
        log.t.windows(2).all(|w| w[0] < w[1]),
        "times do not increase"
    );
    let optional = log.q_load.iter().chain(&log.f_ext);
    let columns = [&log.t, &log.reference, &log.q, &log.tau]
        .into_iter()
        .chain(optional);
    for column in columns {
        assert_eq!(column.len(), log.len(), "columns of different lengths");
        assert!(
            column.iter().all(|v| v.is_finite()),
            "a non-finite value was accepted"
        );
    }
    let written = to_csv(&log);
    let again = parse(&written).expect("the reader refused the writer's text");
    assert_eq!(again, log, "written and read back differently");
});
