//! Deterministic sensor streams for driving the kernel through a session.
//!
//! The synthetic estimation lift is pure kinematics of a known arm in frame
//! S (shoulder at (l1 + l2, 0), grasp at the origin at t = 0): rest for
//! 2 s, the forearm turns about the resting elbow to psi = 1.45 rad
//! (2-14 s), then the upper arm rises to q1 = 1.2 rad while psi rises by
//! 0.2 rad (14-26 s), then rest. Every phase uses minimum-jerk timing, so
//! the grasp point stays below 0.07 m/s, inside the default speed limit.
//! Frames are 10 ms apart and run past the kernel's estimation (the lift
//! ends by its arcs, ≈ 20 s in; the refinement then takes ≈ 6 s at this
//! frame rate).

use limb_kernel::arm::{ArmGeometry, JointAngles};
use limb_kernel::geometry::{Point, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, StateKind};

/// Frame period of the scenarios [s].
pub const FRAME_PERIOD: f64 = 0.01;
/// Frames of the synthetic lift (at rest after 26 s) are given for this
/// long [s]: longer than the kernel's estimation, whose refinement runs a
/// slice per step (at this 100 Hz frame rate it takes ≈ 6 s after the
/// lift has ended and the arm has settled).
pub const LIFT_DURATION: f64 = 45.0;
/// A constant, plausible interaction wrench [N, N, N m].
pub const LIFT_WRENCH: Wrench = Wrench::new(-10.0, -5.0, 1.0);

/// The arm of the scenario: l1, l2 [m], shoulder at (l1 + l2, 0).
pub fn arm(upper_arm_length: f64, forearm_length: f64) -> ArmGeometry {
    let shoulder = Point::new(upper_arm_length + forearm_length, 0.0);
    // The scenario's lengths are positive constants or drawn from positive
    // ranges; a failure here is a bug in the test itself.
    ArmGeometry::new(upper_arm_length, forearm_length, shoulder).expect("scenario arm")
}

fn minimum_jerk(tau: f64) -> f64 {
    let tau = tau.clamp(0.0, 1.0);
    tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)
}

/// Joint angles of the synthetic lift at time `t` [s].
pub fn lift_angles(t: f64) -> JointAngles {
    let forearm = minimum_jerk((t - 2.0) / 12.0);
    let upper = minimum_jerk((t - 14.0) / 12.0);
    let q1 = 1.2 * upper;
    let psi = 1.45 * forearm + 0.2 * upper;
    JointAngles {
        shoulder_elevation: q1,
        elbow_flexion: psi - q1,
    }
}

/// The sensor frame of the synthetic lift of `arm` at time `t`.
pub fn lift_frame(arm: &ArmGeometry, t: f64) -> PathSample {
    PathSample {
        time: t,
        pose: arm.forward(lift_angles(t)),
        wrench: LIFT_WRENCH,
    }
}

/// A kernel with the default configuration, fed one resting frame at t = 0.
pub fn kernel_in_grasp(arm: &ArmGeometry) -> Kernel {
    let mut kernel = Kernel::new(KernelConfig::default()).expect("default config is valid");
    kernel.step(Some(&lift_frame(arm, 0.0)), 0.0);
    kernel
}

/// Drives a fresh kernel through the whole synthetic lift; returns it (in
/// Validated when estimation and validation succeed) and the time reached.
pub fn kernel_after_lift(arm: &ArmGeometry) -> (Kernel, f64) {
    let mut kernel = kernel_in_grasp(arm);
    let _ = kernel.request(Request::StartEstimation, 0.0);
    let mut t = 0.0;
    let mut i = 0u32;
    while kernel.state().kind() == StateKind::Estimate && t < LIFT_DURATION {
        i += 1;
        t = f64::from(i) * FRAME_PERIOD;
        kernel.step(Some(&lift_frame(arm, t)), t);
    }
    (kernel, t)
}

/// A manipulation target inside the default joint limits.
pub const TARGET: JointAngles = JointAngles {
    shoulder_elevation: 0.6,
    elbow_flexion: 0.8,
};
