//! The synthetic estimation lift of a known arm
//! (`limb_verification::scenario`) as the robot of a node's session: at
//! rest before 2 s and after 26 s of kernel time. Like a simulated plant,
//! its clock advances one step per frame (a loaded machine slows it down
//! instead of opening gaps between its stamps). Test support only: a real
//! node runs a robot.

// Each test crate (and the bench example) uses its own subset.
#![allow(dead_code)]

use core::convert::Infallible;
use limb_kernel::arm::ArmGeometry;
use limb_kernel::{Command, Kernel, PathSample};
use limb_session::{Frame, Robot, Sensed};
use limb_verification::scenario;
use std::time::Duration;

/// The lift of an arm, from kernel time `origin`.
#[derive(Clone, Copy, Debug)]
pub struct Lift {
    arm: ArmGeometry,
    origin: f64,
    step: f64,
    frames: u32,
}

impl Lift {
    /// The scenario's arm (l1 = 0.30 m, l2 = 0.20 m), from time 0.
    pub fn reference() -> Self {
        Self {
            arm: scenario::arm(0.30, 0.20),
            origin: 0.0,
            step: 0.002,
            frames: 0,
        }
    }

    /// The lift advancing `period` per frame (2 ms by default).
    pub fn stepping(self, period: Duration) -> Self {
        Self {
            step: period.as_secs_f64(),
            ..self
        }
    }

    /// A kernel in Grasp, fed the frame at t = 0; its clock starts at 0 s.
    pub fn kernel_in_grasp(&self) -> Box<Kernel> {
        Box::new(scenario::kernel_in_grasp(&self.arm))
    }

    /// A kernel driven through the whole lift (Validated), and this lift
    /// continuing from the kernel time it reached.
    pub fn kernel_after_lift(self) -> (Box<Kernel>, Self) {
        let (kernel, time) = scenario::kernel_after_lift(&self.arm);
        (
            Box::new(kernel),
            Self {
                origin: time,
                ..self
            },
        )
    }

    /// Kernel time at the lift's start [s].
    pub fn origin(&self) -> f64 {
        self.origin
    }

    /// The frame at kernel time `now` [s].
    pub fn frame(&self, now: f64) -> PathSample {
        scenario::lift_frame(&self.arm, now)
    }
}

impl Robot for Lift {
    type Error = Infallible;

    fn sense(&mut self) -> Result<Sensed, Infallible> {
        let now = self.origin + f64::from(self.frames) * self.step;
        self.frames = self.frames.saturating_add(1);
        Ok(Sensed::Frame(Frame {
            sample: self.frame(now),
            lateral: None,
            arrival: now,
            following: true,
        }))
    }

    fn actuate(&mut self, _: &Command) -> Result<(), Infallible> {
        Ok(())
    }
}
