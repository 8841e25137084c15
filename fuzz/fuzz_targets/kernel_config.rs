//! The kernel configuration as it arrives from outside (the Zenoh wire's
//! `KernelConfig`, JSON or CBOR, as the `config` queryable spells it),
//! decoded and checked by `KernelConfig::check`. No silent acceptance: a
//! configuration the check accepts has only finite numbers and non-empty
//! intervals (an independent walk of its JSON form), is in canonical form,
//! builds a kernel, and that kernel's commands pass the command checks
//! while it holds a resting frame and runs its estimation motion.
//! Input: a format byte (bit 0: CBOR), then the payload.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_fuzz::assert_wire_canonical;
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request};
use limb_verification::checks::{checked_step, SessionOracle};
use limb_zenoh::wire::WireFormat;
use serde_json::Value;

/// Every number finite (serde_json writes a non-finite one as null) and
/// every `{low, high}` interval non-empty.
fn sane(value: &Value) -> bool {
    match value {
        Value::Null => false,
        Value::Object(fields) => {
            let ordered = match (fields.get("low"), fields.get("high")) {
                (Some(low), Some(high)) => low.as_f64() <= high.as_f64(),
                _ => true,
            };
            ordered && fields.values().all(sane)
        }
        Value::Array(items) => items.iter().all(sane),
        _ => true,
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, payload)) = data.split_first() else {
        return;
    };
    let format = if mode & 1 == 1 {
        WireFormat::Cbor
    } else {
        WireFormat::Json
    };
    let Ok(config) = format.decode::<KernelConfig>(payload) else {
        return;
    };
    if config.check().is_err() {
        return;
    }
    let tree = serde_json::to_value(config).expect("a config serialises");
    assert!(sane(&tree), "an insane configuration was accepted: {tree}");
    assert_wire_canonical(format, &config);
    let mut slot = Box::new_uninit();
    let kernel = Kernel::new_in(&mut slot, config).expect("an accepted config builds no kernel");
    let mut oracle = SessionOracle::default();
    let mut frame = PathSample {
        time: 0.0,
        pose: Pose::new(0.3, 0.2, 0.0),
        wrench: Wrench::new(0.0, 0.0, 0.0),
    };
    let period = config.limits.max_sensor_age / 2.0;
    for i in 0..40u32 {
        let now = f64::from(i) * period;
        frame.time = now;
        let command = checked_step(kernel, &mut oracle, &frame, now)
            .unwrap_or_else(|property| panic!("{property} at step {i}"));
        // Follow the set-point, as an ideal robot would.
        if let Some(set_point) = command.set_point {
            frame.pose = set_point.pose;
        }
        if i == 1 {
            let _ = kernel.request(Request::StartEstimation, now);
        }
    }
});
