//! Driving the plant from a controller's commands, one control period at a
//! time (shared by `limb run` and the simulated KUKA FRI controller).

use crate::plant::{Plant, STEP};
use limb_kernel::motion::SetPoint;

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
