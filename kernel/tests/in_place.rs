//! `Kernel::new_in` builds the same kernel as `Kernel::new`, in place.

use core::mem::MaybeUninit;
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request};

fn frame(t: f64) -> PathSample {
    PathSample {
        time: t,
        pose: Pose::new(0.0, 0.0, 0.0),
        wrench: Wrench::new(0.0, 2.0, 0.0),
    }
}

/// The commands and events of a short session, as text (`{:?}` of `f64`
/// round-trips, so equal text is equal bits).
fn run(kernel: &mut Kernel) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..400u32 {
        let t = f64::from(i) * 0.001;
        if i == 100 {
            out.push(format!("{:?}", kernel.request(Request::StartEstimation, t)));
        }
        out.push(format!("{:?}", kernel.step(Some(&frame(t)), t)));
        while let Some(event) = kernel.pop_event() {
            out.push(format!("{event:?}"));
        }
    }
    out
}

#[test]
fn new_in_builds_what_new_builds() {
    let mut slot = Box::new(MaybeUninit::<Kernel>::uninit());
    let in_place = Kernel::new_in(&mut slot, KernelConfig::default()).unwrap();
    let mut moved = Box::new(Kernel::new(KernelConfig::default()).unwrap());
    assert_eq!(run(in_place), run(&mut moved));
}

#[test]
fn new_in_refuses_a_bad_configuration() {
    let mut config = KernelConfig::default();
    config.limits.max_force = f64::NAN;
    let mut slot = Box::new(MaybeUninit::<Kernel>::uninit());
    assert_eq!(
        Kernel::new_in(&mut slot, config).err(),
        Kernel::new(config).err()
    );
    assert!(Kernel::new(config).is_err());
}
