//! Where the control loop's sensor frames come from.
//!
//! The loop asks a [`SensorSource`] for the newest frame once per step. Today
//! the only source is [`ScriptedLift`], the deterministic synthetic lift of
//! `limb-verification`; the physical plant (`limb-sim`) or a robot adapter
//! plugs in by implementing the same trait.

use limb_kernel::arm::ArmGeometry;
use limb_kernel::{Kernel, PathSample};
use limb_verification::scenario;

/// A source of sensor frames (frame S, SI units).
pub trait SensorSource: Send {
    /// The newest frame at kernel time `now` [s]. A source with nothing new
    /// returns its last frame: the kernel's watchdog judges its age.
    fn frame(&mut self, now: f64) -> PathSample;
}

/// The synthetic estimation lift of a known arm
/// ([`limb_verification::scenario`]), sampled at the loop's own time: at
/// rest before 2 s and after 26 s of kernel time.
#[derive(Clone, Copy, Debug)]
pub struct ScriptedLift {
    arm: ArmGeometry,
}

impl ScriptedLift {
    /// The lift of `arm`.
    pub fn new(arm: ArmGeometry) -> Self {
        Self { arm }
    }

    /// The scenario's arm (l1 = 0.30 m, l2 = 0.20 m).
    pub fn reference() -> Self {
        Self::new(scenario::arm(0.30, 0.20))
    }

    /// A kernel in Grasp, fed the frame at t = 0; its clock starts at 0 s.
    pub fn kernel_in_grasp(&self) -> Box<Kernel> {
        Box::new(scenario::kernel_in_grasp(&self.arm))
    }

    /// A kernel driven through the whole lift (Validated when the estimate
    /// passes), with the kernel time it reached [s]: a node continues the
    /// clock from there.
    pub fn kernel_after_lift(&self) -> (Box<Kernel>, f64) {
        let (kernel, time) = scenario::kernel_after_lift(&self.arm);
        (Box::new(kernel), time)
    }
}

impl SensorSource for ScriptedLift {
    fn frame(&mut self, now: f64) -> PathSample {
        scenario::lift_frame(&self.arm, now)
    }
}
