//! Sensor watchdog: non-finite, stale, reversed or future-stamped data.

use super::{at_most, Limit, Verdict, Violation};
use crate::path::PathSample;

/// Checks one sensor frame against the clock and the previous frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Watchdog {
    max_age: f64,
}

impl Watchdog {
    /// A watchdog accepting frames at most `max_age` seconds old.
    pub const fn new(max_age: f64) -> Self {
        Self { max_age }
    }

    /// Verdict on `frame` at time `now` [s], given the previous accepted
    /// frame time `previous` and the previous clock reading `previous_now`.
    /// A frame is fresh when `0 ≤ now − frame.time ≤ max_age`.
    pub fn check(
        &self,
        frame: &PathSample,
        now: f64,
        previous: Option<f64>,
        previous_now: Option<f64>,
    ) -> Verdict {
        if !now.is_finite() || previous_now.is_some_and(|p| now < p) {
            return Err(Violation::new(
                Limit::ClockFault,
                now,
                previous_now.unwrap_or(f64::NAN),
            ));
        }
        let finite = frame.time.is_finite() && frame.pose.is_finite() && frame.wrench.is_finite();
        if !finite {
            return Err(Violation::new(Limit::NonFiniteSensor, f64::NAN, f64::NAN));
        }
        if let Some(previous) = previous {
            if frame.time < previous {
                return Err(Violation::new(
                    Limit::SensorTimeReversed,
                    frame.time,
                    previous,
                ));
            }
        }
        let age = now - frame.time;
        if age < 0.0 {
            return Err(Violation::new(Limit::StaleSensor, age, 0.0));
        }
        at_most(Limit::StaleSensor, age, self.max_age)
    }
}
