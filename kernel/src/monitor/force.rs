//! Interaction force monitor: magnitude, torque and rate of change.

use super::{at_most, Limit, Verdict};
use crate::geometry::Wrench;

/// Force, torque and force-rate limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceMonitor {
    /// Largest |(fx, fz)| [N].
    pub max_force: f64,
    /// Largest |ty| [N m].
    pub max_torque: f64,
    /// Largest force rate [N/s].
    pub max_force_rate: f64,
}

impl ForceMonitor {
    /// Verdict on the measured wrench and force rate [N/s].
    pub fn check(&self, wrench: Wrench, force_rate: f64) -> Verdict {
        at_most(
            Limit::ForceMagnitude,
            wrench.force_magnitude(),
            self.max_force,
        )?;
        at_most(Limit::Torque, libm::fabs(wrench.ty), self.max_torque)?;
        at_most(Limit::ForceRate, force_rate, self.max_force_rate)
    }
}

/// Proofs of REQ-MON-001 and REQ-MON-002 (the force-rate bound).
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    use crate::monitor::Limit;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    fn monitor() -> ForceMonitor {
        let l = SafetyLimits::default();
        ForceMonitor {
            max_force: l.max_force,
            max_torque: l.max_torque,
            max_force_rate: l.max_force_rate,
        }
    }

    /// REQ-MON-001, REQ-MON-002: what the verdict must be, decided without
    /// a square root: a NaN anywhere, a force component, the torque or the
    /// rate beyond its limit trips (naming a crossed limit); a force whose
    /// components sum within the limit, with torque and rate within, passes.
    /// The exact circle |(fx, fz)| = max_force is the proptest's
    /// ([`tests`]): the proofs stub `hypot`.
    pub(super) fn check_force_verdict(
        m: &ForceMonitor,
        wrench: Wrench,
        rate: f64,
        verdict: Verdict,
    ) -> Result<(), &'static str> {
        let (fx, fz, ty) = (
            libm::fabs(wrench.fx),
            libm::fabs(wrench.fz),
            libm::fabs(wrench.ty),
        );
        let clearly_beyond = !(fx <= m.max_force
            && fz <= m.max_force
            && ty <= m.max_torque
            && rate <= m.max_force_rate);
        let clearly_within =
            fx + fz <= m.max_force && ty <= m.max_torque && rate <= m.max_force_rate;
        match verdict {
            Ok(()) if clearly_beyond => Err("a wrench or rate beyond a limit passed"),
            Err(_) if clearly_within => Err("a wrench and rate within every limit tripped"),
            Err(v) => match v.limit {
                Limit::ForceMagnitude if v.value <= m.max_force => {
                    Err("force trip below the force limit")
                }
                Limit::Torque if ty <= m.max_torque => Err("torque trip within the torque limit"),
                Limit::ForceRate if rate <= m.max_force_rate => {
                    Err("rate trip within the rate limit")
                }
                Limit::ForceMagnitude | Limit::Torque | Limit::ForceRate => Ok(()),
                _ => Err("the force monitor named another limit"),
            },
            Ok(()) => Ok(()),
        }
    }

    /// REQ-MON-001, REQ-MON-002: for any wrench and force rate (NaN and
    /// infinities included) the force monitor trips beyond its limits,
    /// passes within them and names the limit it tripped on.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    pub(super) fn verify_req_mon_001_force_monitor_trips_beyond_limits() {
        let m = monitor();
        let wrench = kani::any::<Wrench>();
        let rate: f64 = kani::any();
        let verdict = m.check(wrench, rate);
        assert_eq!(check_force_verdict(&m, wrench, rate, verdict), Ok(()));
        kani::cover!(verdict.is_ok(), "force monitor: passes");
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::ForceMagnitude),
            "force monitor: force trips"
        );
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::Torque),
            "force monitor: torque trips"
        );
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::ForceRate),
            "force monitor: rate trips"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "force monitor",
                20_000,
                verify_req_mon_001_force_monitor_trips_beyond_limits,
            );
        }

        proptest! {
            /// REQ-MON-001, REQ-MON-002: with the real `hypot` the monitor
            /// meets the proofs' check and trips exactly outside the force
            /// circle, the torque and the rate limit.
            #[test]
            fn req_mon_001_force_monitor_trips_exactly_outside_the_circle(
                fx in -60.0..60.0f64, fz in -60.0..60.0f64, ty in -10.0..10.0f64,
                rate in 0.0..400.0f64,
            ) {
                let m = monitor();
                let wrench = Wrench::new(fx, fz, ty);
                let verdict = m.check(wrench, rate);
                prop_assert_eq!(check_force_verdict(&m, wrench, rate, verdict), Ok(()));
                let beyond = !(libm::hypot(fx, fz) <= m.max_force
                    && ty.abs() <= m.max_torque
                    && rate <= m.max_force_rate);
                prop_assert_eq!(verdict.is_err(), beyond);
            }
        }
    }
}
