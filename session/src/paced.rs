//! A robot paced by the session's wall clock: a simulated plant run in real
//! time (`limb zenoh node`), where no robot sets the rhythm.
//!
//! Before each [`Robot::sense`] the pacer sleeps to the next absolute
//! deadline (one period after the last). A turn that starts more than one
//! period late is an overrun: counted, and the schedule restarts from now
//! (no burst of catch-up steps). The robot's frames are unchanged: a
//! simulated plant's clock stays the session's.

use crate::robot::{Robot, Sensed};
use limb_kernel::Command;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// `R` sensed once per period.
#[derive(Debug)]
pub struct Paced<R> {
    robot: R,
    period: Duration,
    deadline: Option<Instant>,
    overruns: Arc<AtomicU64>,
}

impl<R> Paced<R> {
    /// `robot` sensed once every `period`.
    pub fn new(robot: R, period: Duration) -> Self {
        Self {
            robot,
            period,
            deadline: None,
            overruns: Arc::new(AtomicU64::new(0)),
        }
    }

    /// The overrun count, shared (a supervisor may publish it).
    pub fn overruns(&self) -> Arc<AtomicU64> {
        Arc::clone(&self.overruns)
    }

    /// The robot.
    pub fn robot(&self) -> &R {
        &self.robot
    }
}

impl<R: Robot> Robot for Paced<R> {
    type Error = R::Error;

    fn sense(&mut self) -> Result<Sensed, R::Error> {
        let now = Instant::now();
        match self.deadline {
            None => self.deadline = Some(now),
            Some(last) => {
                let deadline = last + self.period;
                if let Some(wait) = deadline.checked_duration_since(now) {
                    std::thread::sleep(wait);
                    self.deadline = Some(deadline);
                } else if now.duration_since(deadline) > self.period {
                    self.overruns.fetch_add(1, Ordering::Relaxed);
                    self.deadline = Some(now);
                } else {
                    self.deadline = Some(deadline);
                }
            }
        }
        self.robot.sense()
    }

    fn actuate(&mut self, command: &Command) -> Result<(), R::Error> {
        self.robot.actuate(command)
    }
}

impl<R: crate::log::Logged> crate::log::Logged for Paced<R> {
    fn columns(&self) -> Vec<&str> {
        self.robot.columns()
    }

    fn values(&self, out: &mut Vec<Option<f64>>) {
        self.robot.values(out);
    }
}
