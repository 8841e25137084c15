//! Safety monitors: small pure checks with configured limits and a typed
//! verdict.
//!
//! # Theory of operation
//! Each monitor looks at one kind of hazard and returns `Ok(())` or a
//! [`Violation`] naming the [`Limit`] crossed, the measured value and the
//! bound, so the excess is known. The kernel runs the monitors that apply
//! to its state on every step, before it computes a command, and any
//! violation commands a safe stop within that same step.
//!
//! | monitor | states | needs |
//! |---|---|---|
//! | [`watchdog`] | all but SafeStop | the frame and `now` |
//! | [`force`] | all but SafeStop | the frame and the rate window |
//! | [`speed`] | Estimate, Manipulate | the rate window |
//! | [`workspace`] | all but SafeStop (elbow with a model) | the frame |
//! | [`joint_limits`] | Estimate (the provisional model's joint envelope), Validated, Manipulate | the provisional or validated model |
//!
//! [`set::MonitorSet`] holds them all, built once from the safety limits.

pub mod force;
pub mod joint_limits;
pub mod rates;
pub mod set;
pub mod speed;
pub mod watchdog;
pub mod workspace;

/// Which limit a violation crossed. Codes are stable (they appear in logs
/// and on the wire).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u16)]
pub enum Limit {
    /// A sensor value is NaN or infinite.
    NonFiniteSensor = 1,
    /// The clock `now` is NaN, infinite or went backwards.
    ClockFault = 2,
    /// The sensor time stamp went backwards.
    SensorTimeReversed = 3,
    /// The newest frame is older than allowed (or stamped in the future).
    StaleSensor = 4,
    /// Interaction force magnitude [N].
    ForceMagnitude = 10,
    /// Interaction torque magnitude [N m].
    Torque = 11,
    /// Rate of change of the force [N/s].
    ForceRate = 12,
    /// Grasp-point speed [m/s].
    Speed = 20,
    /// Grasp point below the table [m].
    GraspBelowTable = 30,
    /// Elbow below the table [m].
    ElbowBelowTable = 31,
    /// Grasp point outside the workspace box in x [m].
    WorkspaceX = 32,
    /// Grasp point outside the workspace box in z [m].
    WorkspaceZ = 33,
    /// Shoulder elevation q1 outside its range [rad].
    ShoulderElevation = 40,
    /// Elbow flexion q2 outside its range (below: hyperextension) [rad].
    ElbowFlexion = 41,
    /// The measured pose does not fit the validated model [m].
    ModelMismatch = 42,
}

impl Limit {
    /// Stable numeric code.
    pub fn code(self) -> u16 {
        self as u16
    }
}

/// A limit crossed, with the measured value and the bound it crossed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Violation {
    /// Which limit.
    pub limit: Limit,
    /// The measured value (NaN for a non-finite input).
    pub value: f64,
    /// The bound it crossed.
    pub bound: f64,
}

impl Violation {
    /// A violation of `limit`: `value` against `bound`.
    pub const fn new(limit: Limit, value: f64, bound: f64) -> Self {
        Self {
            limit,
            value,
            bound,
        }
    }

    /// By how much the bound was crossed (absolute, in the limit's unit;
    /// NaN when the value was not finite).
    pub fn excess(&self) -> f64 {
        libm::fabs(self.value - self.bound)
    }
}

/// A monitor's verdict.
pub type Verdict = Result<(), Violation>;

/// `Ok` when `value <= bound`, else a violation. NaN violates.
pub(crate) fn at_most(limit: Limit, value: f64, bound: f64) -> Verdict {
    if value <= bound {
        Ok(())
    } else {
        Err(Violation::new(limit, value, bound))
    }
}

/// `Ok` when `value` lies in `range`, else a violation against the crossed
/// bound. NaN violates.
pub(crate) fn within(limit: Limit, value: f64, range: crate::config::Interval) -> Verdict {
    if value < range.low {
        Err(Violation::new(limit, value, range.low))
    } else if range.contains(value) {
        Ok(())
    } else {
        Err(Violation::new(limit, value, range.high))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Interval;

    #[test]
    fn codes_are_stable() {
        let table = [
            (Limit::NonFiniteSensor, 1),
            (Limit::ClockFault, 2),
            (Limit::SensorTimeReversed, 3),
            (Limit::StaleSensor, 4),
            (Limit::ForceMagnitude, 10),
            (Limit::Torque, 11),
            (Limit::ForceRate, 12),
            (Limit::Speed, 20),
            (Limit::GraspBelowTable, 30),
            (Limit::ElbowBelowTable, 31),
            (Limit::WorkspaceX, 32),
            (Limit::WorkspaceZ, 33),
            (Limit::ShoulderElevation, 40),
            (Limit::ElbowFlexion, 41),
            (Limit::ModelMismatch, 42),
        ];
        for (limit, code) in table {
            assert_eq!(limit.code(), code, "{limit:?}");
        }
    }

    #[test]
    fn excess_is_the_distance_past_the_bound() {
        assert_eq!(Violation::new(Limit::Speed, 0.25, 0.15).excess(), 0.1);
        assert_eq!(
            Violation::new(Limit::GraspBelowTable, -0.007, -0.005).excess(),
            0.002
        );
    }

    #[test]
    fn bounds_themselves_are_inside() {
        let range = Interval::new(-1.0, 2.0);
        assert_eq!(within(Limit::ElbowFlexion, -1.0, range), Ok(()));
        assert_eq!(within(Limit::ElbowFlexion, 2.0, range), Ok(()));
        assert_eq!(
            within(Limit::ElbowFlexion, -1.5, range),
            Err(Violation::new(Limit::ElbowFlexion, -1.5, -1.0))
        );
        assert_eq!(
            within(Limit::ElbowFlexion, 2.5, range),
            Err(Violation::new(Limit::ElbowFlexion, 2.5, 2.0))
        );
        assert!(within(Limit::ElbowFlexion, f64::NAN, range).is_err());
        assert_eq!(at_most(Limit::Speed, 0.15, 0.15), Ok(()));
        assert!(at_most(Limit::Speed, f64::NAN, 0.15).is_err());
    }
}

/// Proofs of the comparison every monitor verdict goes through.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::Interval;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// REQ-MON-007: [`at_most`] passes exactly the values at or below the
    /// bound (NaN violates) and a violation records the value and bound.
    pub(super) fn check_at_most(
        value: f64,
        bound: f64,
        verdict: Verdict,
    ) -> Result<(), &'static str> {
        match verdict {
            Ok(()) if value <= bound => Ok(()),
            Ok(()) => Err("at_most passed a value beyond the bound or NaN"),
            Err(_) if value <= bound => Err("at_most tripped within the bound"),
            Err(v)
                if v.limit == Limit::Speed
                    && v.bound.to_bits() == bound.to_bits()
                    && v.value.to_bits() == value.to_bits() =>
            {
                Ok(())
            }
            Err(_) => Err("at_most's violation misreports the limit, value or bound"),
        }
    }

    /// REQ-MON-005: [`within`] passes exactly the values of the closed
    /// interval (NaN violates) and names the crossed bound.
    pub(super) fn check_within(
        value: f64,
        range: Interval,
        verdict: Verdict,
    ) -> Result<(), &'static str> {
        let inside = range.low <= value && value <= range.high;
        let below = value < range.low;
        match verdict {
            Ok(()) if inside => Ok(()),
            Ok(()) => Err("within passed a value outside the range or NaN"),
            Err(_) if inside => Err("within tripped inside the range"),
            Err(v) if v.value.to_bits() != value.to_bits() => Err("within misreports the value"),
            Err(v) if below && v.bound.to_bits() != range.low.to_bits() => {
                Err("within names the high bound for a value below the range")
            }
            Err(v) if !below && v.bound.to_bits() != range.high.to_bits() => {
                Err("within names the low bound for a value not below the range")
            }
            Err(_) => Ok(()),
        }
    }

    /// REQ-MON-007: the upper-bound comparison of every monitor, for any
    /// value and bound (NaN and infinities included).
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_mon_007_at_most_is_a_closed_upper_bound() {
        let (value, bound): (f64, f64) = (kani::any(), kani::any());
        let verdict = at_most(Limit::Speed, value, bound);
        assert_eq!(check_at_most(value, bound, verdict), Ok(()));
        kani::cover!(verdict.is_ok(), "at_most: passes");
        kani::cover!(
            verdict.is_err() && !value.is_nan(),
            "at_most: trips on a number"
        );
        kani::cover!(value.is_nan(), "at_most: NaN");
    }

    /// REQ-MON-005: the range comparison of the joint-limit and workspace
    /// monitors, for any value and any range.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_mon_005_within_is_the_closed_interval() {
        let value: f64 = kani::any();
        let range = Interval::new(kani::any(), kani::any());
        let verdict = within(Limit::ElbowFlexion, value, range);
        assert_eq!(check_within(value, range, verdict), Ok(()));
        kani::cover!(verdict.is_ok(), "within: passes");
        kani::cover!(value < range.low, "within: below");
        kani::cover!(value > range.high, "within: above");
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "at_most",
                20_000,
                verify_req_mon_007_at_most_is_a_closed_upper_bound,
            );
            kani::check(
                "within",
                20_000,
                verify_req_mon_005_within_is_the_closed_interval,
            );
        }

        proptest! {
            /// REQ-MON-005, REQ-MON-007: the comparisons meet the proofs'
            /// checks on sampled values and ranges.
            #[test]
            fn comparisons_meet_their_checks(value in -10.0..10.0f64, low in -10.0..10.0f64,
                                             width in 0.0..10.0f64) {
                let range = Interval::new(low, low + width);
                prop_assert_eq!(check_within(value, range, within(Limit::ElbowFlexion, value, range)), Ok(()));
                prop_assert_eq!(check_at_most(value, low, at_most(Limit::Speed, value, low)), Ok(()));
            }
        }
    }
}
