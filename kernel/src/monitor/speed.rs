//! End-effector speed monitor (the paper's 2.5 % of maximum, with margin).

use super::{at_most, Limit, Verdict};

/// Grasp-point speed limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedMonitor {
    /// Largest speed [m/s].
    pub max_speed: f64,
}

impl SpeedMonitor {
    /// Verdict on the windowed grasp-point speed [m/s].
    pub fn check(&self, speed: f64) -> Verdict {
        at_most(Limit::Speed, speed, self.max_speed)
    }
}

/// Proof of REQ-MON-003.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-MON-003: for any windowed speed (NaN included) the speed monitor
    /// trips exactly above `max_speed`, naming the speed limit.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_mon_003_speed_monitor_trips_above_the_limit() {
        let m = SpeedMonitor {
            max_speed: SafetyLimits::default().max_speed,
        };
        let speed: f64 = kani::any();
        let verdict = m.check(speed);
        assert_eq!(verdict.is_ok(), speed <= m.max_speed);
        assert!(verdict.is_ok() || verdict.is_err_and(|v| v.limit == Limit::Speed));
        kani::cover!(verdict.is_ok(), "speed monitor: passes");
        kani::cover!(verdict.is_err(), "speed monitor: trips");
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "speed monitor",
                20_000,
                verify_req_mon_003_speed_monitor_trips_above_the_limit,
            );
        }
    }
}
