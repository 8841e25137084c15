//! The estimation motion starts at the Grasp hold pose: the set-point is
//! continuous at Grasp → Estimate, whatever the latest measurement's noise
//! (found by the KUKA soak: a 0.1 mm, 1 mrad step in one 1 ms period made
//! the joint-position robot's force jump by 10-25 N and the force-rate
//! monitor stop the session as the estimation began).

use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, StateKind};

fn frame(time: f64, pose: Pose) -> PathSample {
    PathSample {
        time,
        pose,
        wrench: Wrench::ZERO,
    }
}

/// REQ-SM-008: the first Estimate set-point continues from the last Grasp
/// hold although the latest measurement is off it by noise.
#[test]
fn req_sm_008_the_estimation_set_point_continues_from_the_hold() {
    let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
    let first = Pose::new(0.0, 0.0, 0.0);
    let hold = kernel.step(Some(&frame(0.0, first)), 0.0);
    assert_eq!(hold.set_point.map(|s| s.pose), Some(first));
    // The latest measurement is off the hold by noise; the hold averages
    // it in (REQ-SM-009), by half its deviation.
    let noisy = Pose::new(2e-4, -1.5e-4, 1e-3);
    let held = kernel
        .step(Some(&frame(0.001, noisy)), 0.001)
        .set_point
        .expect("a hold")
        .pose;
    assert_ne!(held, noisy);
    assert_eq!(
        kernel.request(Request::StartEstimation, 0.001),
        Ok(StateKind::Estimate)
    );
    let first = kernel.step(Some(&frame(0.002, noisy)), 0.002);
    assert_eq!(first.state, StateKind::Estimate);
    let start = first.set_point.expect("a set-point").pose;
    let step = [start.x - held.x, start.z - held.z, start.psi - held.psi];
    assert!(
        step.iter().all(|d| d.abs() < 1e-5),
        "the set-point stepped by {step:?} at Grasp → Estimate"
    );
}
