//! Driving the plant from a controller's commands, one control period at a
//! time (shared by `limb run` and the simulated KUKA FRI controller).

use crate::plant::{Plant, Truth};
use crate::sensing::{Measurement, STEP};
use limb_kernel::motion::SetPoint;

/// A plant the kernel can close the loop on.
pub trait ClosedLoopPlant {
    /// Plant time [s].
    fn time(&self) -> f64;
    /// What a robot measures now: time stamp, grasp pose, lateral y and
    /// wrench (frame S); the kernel gets all but y.
    fn measure(&mut self) -> Measurement;
    /// Advances the plant by `duration` seconds with the robot's impedance
    /// following `set_point` (held when the kernel gives none).
    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64);
    /// The person's ground truth now, as a log records it.
    fn truth(&self) -> Truth;
}

impl<P: ClosedLoopPlant + ?Sized> ClosedLoopPlant for &mut P {
    fn time(&self) -> f64 {
        (**self).time()
    }

    fn measure(&mut self) -> Measurement {
        (**self).measure()
    }

    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64) {
        (**self).advance(set_point, duration);
    }

    fn truth(&self) -> Truth {
        (**self).truth()
    }
}

impl ClosedLoopPlant for Plant {
    fn time(&self) -> f64 {
        Plant::time(self)
    }

    fn measure(&mut self) -> Measurement {
        Plant::measure(self)
    }

    fn advance(&mut self, set_point: Option<&SetPoint>, duration: f64) {
        advance(self, set_point, duration);
    }

    fn truth(&self) -> Truth {
        Plant::truth(self)
    }
}

/// Advances `plant` by `duration` seconds (rounded to whole
/// [`STEP`]s) with the robot's impedance following `set_point`, or holding
/// its current set-point pose still when there is none.
pub fn advance(plant: &mut Plant, set_point: Option<&SetPoint>, duration: f64) {
    if let Some(set_point) = set_point {
        plant.set(*set_point);
    } else {
        let held = plant.set_point().pose;
        plant.set(SetPoint::hold(held));
    }
    let end = plant.time() + duration - STEP / 2.0;
    while plant.time() < end {
        plant.step();
    }
}
