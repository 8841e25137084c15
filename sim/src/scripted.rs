//! The scripted estimation run of `plant.md`: the robot follows the
//! estimation motion (kernel's [`EstimationMotion`], paper eq. 3) from the
//! grasp pose, a row is logged every [`LOG_EVERY`] steps (100 Hz) before
//! that step's integration, until the lift and its hold are over.

use crate::plant::{Plant, Truth};
use crate::sensing::{Measurement, STEP};
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use limb_kernel::geometry::Pose;
use limb_kernel::motion::{EstimationMotion, EstimationMotionParameters, SetPoint};

/// Integration steps per log row (20 × 0.5 ms = 10 ms).
pub const LOG_EVERY: u64 = 20;

/// One logged row: the set-point, the measurement and the truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Equilibrium set-point x_d at this instant.
    pub set_point: SetPoint,
    /// What the robot measured.
    pub measurement: Measurement,
    /// The dummy's ground truth.
    pub truth: Truth,
}

/// Runs the estimation motion on `plant` from its current state and
/// returns the log.
///
/// # Errors
/// When the motion cannot be planned (non-finite parameters).
pub fn estimation_run(plant: &mut Plant) -> Result<Vec<Row>, String> {
    let motion = EstimationMotion::new(Pose::default(), &EstimationMotionParameters::default())
        .map_err(|e| format!("estimation motion: {e:?}"))?;
    let steps = libm::round(motion.total_duration() / STEP) as u64;
    let mut rows = Vec::with_capacity((steps / LOG_EVERY + 1) as usize);
    for k in 0..=steps {
        let t = k as f64 * STEP;
        plant.set(motion.at(t));
        if k % LOG_EVERY == 0 {
            rows.push(Row {
                set_point: plant.set_point(),
                measurement: plant.measure(),
                truth: plant.truth(),
            });
        }
        plant.step();
    }
    Ok(rows)
}
