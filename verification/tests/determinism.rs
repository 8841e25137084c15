//! REQ-DET-001: the kernel is deterministic: the same frames, clock and
//! requests give bit-identical commands and events.

use limb_kernel::{Kernel, KernelConfig, PathSample, Request};
use limb_verification::scenario::{arm, lift_frame, FRAME_PERIOD, TARGET};

fn session() -> Vec<String> {
    let arm = arm(0.28, 0.19);
    let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
    let mut out = Vec::new();
    let mut record = |kernel: &mut Kernel, text: String| {
        out.push(text);
        while let Some(event) = kernel.pop_event() {
            out.push(format!("{event:?}"));
        }
    };
    for i in 0..3200u32 {
        let t = f64::from(i) * FRAME_PERIOD;
        if i == 1 {
            let r = kernel.request(Request::StartEstimation, t);
            record(&mut kernel, format!("{r:?}"));
        }
        if i == 3000 {
            let r = kernel.request(Request::ApproveManipulation(TARGET), t);
            record(&mut kernel, format!("{r:?}"));
        }
        let frame: PathSample = lift_frame(&arm, t.min(29.5));
        let command = kernel.step(&PathSample { time: t, ..frame }, t);
        // Debug formatting of f64 round-trips exactly, so equal text means
        // bit-identical numbers.
        record(&mut kernel, format!("{command:?}"));
    }
    out
}

/// REQ-DET-001: two runs of the same session are identical.
#[test]
fn req_det_001_same_inputs_give_identical_outputs() {
    let first = session();
    assert!(
        first.iter().any(|line| line.contains("Manipulate")),
        "the session must reach Manipulate"
    );
    assert_eq!(first, session());
}
