//! The plant as the robot of a `limb-session` session: `limb run`, the
//! firmware and `limb zenoh node` close the kernel's loop on it.
//!
//! Unpaced: the plant's clock is the session's (a frame arrives at the
//! plant time it was measured), and each command advances the plant by one
//! control period. The caller builds the plant (parameters, effects) and
//! wraps it here. The session log gets the plant's ground truth as its
//! own columns (`q1,q2,elbow_x,elbow_z,shoulder_x,shoulder_z`).

use crate::closed_loop::ClosedLoopPlant;
use crate::sensing::Measurement;
use core::convert::Infallible;
use limb_kernel::motion::SetPoint;
use limb_kernel::{Command, PathSample, StopCategory};
use limb_session::{Frame, Robot, Sensed};

/// A closed-loop plant driven by the kernel at a fixed rate.
#[derive(Clone, Debug)]
pub struct ReferenceRobot<P> {
    plant: P,
    period: f64,
    timeout: f64,
    last: Option<Measurement>,
}

impl<P: ClosedLoopPlant> ReferenceRobot<P> {
    /// `plant` stepped by a kernel at `rate` [Hz] until plant time
    /// `timeout` [s].
    pub fn new(plant: P, rate: f64, timeout: f64) -> Self {
        Self {
            plant,
            period: 1.0 / rate,
            timeout,
            last: None,
        }
    }

    /// The plant.
    pub fn plant(&self) -> &P {
        &self.plant
    }

    /// The last measurement sensed (`None` before the first).
    pub fn measurement(&self) -> Option<&Measurement> {
        self.last.as_ref()
    }
}

impl<P: ClosedLoopPlant> Robot for ReferenceRobot<P> {
    type Error = Infallible;

    fn sense(&mut self) -> Result<Sensed, Infallible> {
        let arrival = self.plant.time();
        if arrival >= self.timeout || arrival.is_nan() {
            return Ok(Sensed::Ended);
        }
        let m = self.plant.measure();
        self.last = Some(m);
        Ok(Sensed::Frame(Frame {
            sample: PathSample {
                time: m.time,
                pose: m.pose,
                wrench: m.wrench,
            },
            lateral: Some(m.lateral),
            arrival,
            following: true,
        }))
    }

    /// Follows the command's set-point (held when it has none). A
    /// motors-off stop leaves the robot limp: its set-point follows the
    /// measured pose, so the spring carries nothing and only the damping
    /// of the drives' short-circuited windings acts (plant.md's robot has
    /// no brakes).
    fn actuate(&mut self, command: &Command) -> Result<(), Infallible> {
        if command.stop == Some(StopCategory::MotorsOff) {
            let limp = self.last.map(|m| SetPoint::hold(m.pose));
            self.plant.advance(limp.as_ref(), self.period);
        } else {
            self.plant.advance(command.set_point.as_ref(), self.period);
        }
        Ok(())
    }
}

#[cfg(feature = "std")]
impl<P: ClosedLoopPlant> limb_session::log::Logged for ReferenceRobot<P> {
    fn columns(&self) -> Vec<&str> {
        crate::log::TRUTH_COLUMNS.to_vec()
    }

    fn values(&self, out: &mut Vec<Option<f64>>) {
        out.extend(crate::log::truth_values(Some(&self.plant.truth())));
    }
}
