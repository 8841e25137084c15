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

/// Proof of REQ-MON-006.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-MON-006: a frame passes exactly when the clock is finite and not
    /// behind the previous reading, every value of the frame is finite, its
    /// time is not behind the previous frame's, and
    /// `0 ≤ now − time ≤ max_age`; a trip names a watchdog limit.
    pub(super) fn check_watchdog_verdict(
        max_age: f64,
        frame: &PathSample,
        now: f64,
        previous: Option<f64>,
        previous_now: Option<f64>,
        verdict: Verdict,
    ) -> Result<(), &'static str> {
        // The age only of a finite clock and stamp: `now − time` of two
        // equal infinities would make a NaN in the check itself (Kani's NaN
        // check found it there, not in the watchdog, which subtracts only
        // after its finiteness test).
        let fresh = now.is_finite()
            && previous_now.is_none_or(|p| now >= p)
            && frame.time.is_finite()
            && frame.pose.is_finite()
            && frame.wrench.is_finite()
            && previous.is_none_or(|p| frame.time >= p)
            && (0.0..=max_age).contains(&(now - frame.time));
        match verdict {
            Ok(()) if fresh => Ok(()),
            Ok(()) => Err("the watchdog passed a faulty frame or clock"),
            Err(_) if fresh => Err("the watchdog tripped on a fresh frame"),
            Err(v) => match v.limit {
                Limit::ClockFault
                | Limit::NonFiniteSensor
                | Limit::SensorTimeReversed
                | Limit::StaleSensor => Ok(()),
                _ => Err("the watchdog named another limit"),
            },
        }
    }

    /// A previous frame time or clock reading: the kernel records only
    /// finite ones (those the watchdog passed).
    fn any_time() -> Option<f64> {
        if kani::any() {
            let time: f64 = kani::any();
            kani::assume(time.is_finite());
            Some(time)
        } else {
            None
        }
    }

    /// REQ-MON-006: for any frame, clock and history the watchdog trips
    /// exactly on a non-finite, stale, future, reversed frame or a bad clock.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_mon_006_watchdog_trips_exactly_on_faults() {
        let max_age = SafetyLimits::default().max_sensor_age;
        let w = Watchdog::new(max_age);
        let now: f64 = kani::any();
        let mut frame = kani::any::<PathSample>();
        if kani::any() {
            // A frame stamped up to 2 max_age before `now`: the nominal and
            // the stale branch under the sampling stand-in too.
            frame.time = now - max_age * 2.0 * (kani::any::<u8>() as f64 / 255.0);
        }
        let (previous, previous_now) = (any_time(), any_time());
        let verdict = w.check(&frame, now, previous, previous_now);
        assert_eq!(
            check_watchdog_verdict(max_age, &frame, now, previous, previous_now, verdict),
            Ok(())
        );
        kani::cover!(verdict.is_ok(), "watchdog: passes");
        let tripped = |limit| verdict.is_err_and(|v| v.limit == limit);
        kani::cover!(tripped(Limit::ClockFault), "watchdog: clock fault");
        kani::cover!(tripped(Limit::NonFiniteSensor), "watchdog: non-finite");
        kani::cover!(tripped(Limit::SensorTimeReversed), "watchdog: reversed");
        kani::cover!(tripped(Limit::StaleSensor), "watchdog: stale");
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "watchdog",
                20_000,
                verify_req_mon_006_watchdog_trips_exactly_on_faults,
            );
        }
    }
}
