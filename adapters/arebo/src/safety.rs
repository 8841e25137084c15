//! Safety verdicts for AREBO.
//!
//! The kernel's [`limb_kernel::monitor::Violation`] carries a
//! [`limb_kernel::monitor::Limit`], a closed enum of the planar kernel's
//! limits (it has shoulder elevation and elbow flexion but no abduction,
//! and the kernel may not be edited from here). AREBO therefore wraps it:
//! [`AreboLimit::Kernel`] reuses the kernel's codes for the kinds both
//! share (stale sensor, non-finite sensor, force, torque) and adds the 3-D
//! shoulder's flexion and abduction limits. Codes stay stable: kernel codes
//! as they are, AREBO's own from 100.

use crate::human::ShoulderAngles;
use crate::protocol::{
    status_control, ControlType, ERROR_HEARTBEAT, ERROR_TORQUE_SENSOR, STATUS_KNOWN,
};
use limb_kernel::config::Interval;
use limb_kernel::monitor::Limit;
use nalgebra::Vector3;

/// Which limit an AREBO verdict crossed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AreboLimit {
    /// A limit the kernel also has (same code).
    Kernel(Limit),
    /// Shoulder flexion/extension φ1 outside its range [rad].
    Flexion,
    /// Shoulder abduction/adduction φ2 outside its range [rad].
    Abduction,
    /// The device reports the host's heartbeat missing: it has stopped
    /// applying the torque target (value: the error bits).
    DeviceHeartbeatMissing,
    /// The device reports a torque sensor fault (value: the error bits).
    TorqueSensorFault,
    /// The device reports an error bit this host does not know, or a
    /// reserved status bit (value: the error bits, or the status byte).
    UnknownDeviceError,
    /// The device runs another control type than the host set (value: the
    /// reported code, 3 = undefined; bound: the expected code).
    ControlType,
}

impl AreboLimit {
    /// Stable numeric code (kernel codes below 100).
    pub fn code(self) -> u16 {
        match self {
            AreboLimit::Kernel(limit) => limit.code(),
            AreboLimit::Flexion => 100,
            AreboLimit::Abduction => 101,
            AreboLimit::DeviceHeartbeatMissing => 102,
            AreboLimit::TorqueSensorFault => 103,
            AreboLimit::UnknownDeviceError => 104,
            AreboLimit::ControlType => 105,
        }
    }

    /// Stable snake_case name (the kernel's for the kernel's limits,
    /// `limb_kernel::vocabulary`).
    pub const fn name(self) -> &'static str {
        match self {
            AreboLimit::Kernel(limit) => limit.name(),
            AreboLimit::Flexion => "flexion",
            AreboLimit::Abduction => "abduction",
            AreboLimit::DeviceHeartbeatMissing => "device_heartbeat_missing",
            AreboLimit::TorqueSensorFault => "torque_sensor_fault",
            AreboLimit::UnknownDeviceError => "unknown_device_error",
            AreboLimit::ControlType => "control_type",
        }
    }
}

impl core::fmt::Display for AreboViolation {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} (code {}) {} beyond {}",
            self.limit.name(),
            self.limit.code(),
            self.value,
            self.bound
        )
    }
}

/// A crossed limit with the measured value and the bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreboViolation {
    /// Which limit.
    pub limit: AreboLimit,
    /// Measured value (NaN for non-finite input).
    pub value: f64,
    /// The bound crossed.
    pub bound: f64,
}

/// A verdict.
pub type AreboVerdict = Result<(), AreboViolation>;

/// Limits of the AREBO safety check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafetyLimits {
    /// Allowed φ1 [rad] (default −20°..120°: flexion task 0-90° plus margin).
    pub flexion: Interval,
    /// Allowed φ2 [rad] (default ±50°: the weight support clamps at ±45°).
    pub abduction: Interval,
    /// Largest interaction force magnitude [N] (default 60 N: the SJM load
    /// cell ranges 100 N; the paper's zero-torque median is 5.88 N).
    pub max_force: f64,
    /// Largest |torque sensor reading| per actuated joint [N m] (sensor
    /// ranges 40, 20, 20 N m, paper Table 2).
    pub max_torque: [f64; 3],
    /// Oldest acceptable sensor frame [s] (default 0.05 s: ten 200 Hz
    /// periods).
    pub stale_after: f64,
}

impl Default for SafetyLimits {
    fn default() -> Self {
        Self {
            flexion: Interval::new((-20f64).to_radians(), 120f64.to_radians()),
            abduction: Interval::new((-50f64).to_radians(), 50f64.to_radians()),
            max_force: 60.0,
            max_torque: [40.0, 20.0, 20.0],
            stale_after: 0.05,
        }
    }
}

impl SafetyLimits {
    /// The defaults without the link's own freshness bound: for a session
    /// whose kernel judges the frames' age (`limb-session`, AREBO as a
    /// robot). On the device's own clock (a lock-stepped simulation) the
    /// host's time says nothing of a frame's age; a device that falls
    /// silent ends the session at its duration.
    pub fn judged_by_kernel() -> Self {
        Self {
            stale_after: f64::INFINITY,
            ..Self::default()
        }
    }
}

fn at_most(limit: AreboLimit, value: f64, bound: f64) -> AreboVerdict {
    if value <= bound {
        Ok(())
    } else {
        Err(AreboViolation {
            limit,
            value,
            bound,
        })
    }
}

fn within(limit: AreboLimit, value: f64, range: Interval) -> AreboVerdict {
    if value < range.low {
        Err(AreboViolation {
            limit,
            value,
            bound: range.low,
        })
    } else if range.contains(value) {
        Ok(())
    } else {
        Err(AreboViolation {
            limit,
            value,
            bound: range.high,
        })
    }
}

/// Age check: the newest frame, stamped `frame_time` [s], at `now` [s].
/// No frame at all, a non-finite time or a frame from the future count as
/// stale.
pub fn check_fresh(frame_time: Option<f64>, now: f64, limits: &SafetyLimits) -> AreboVerdict {
    let stale = AreboLimit::Kernel(Limit::StaleSensor);
    let Some(time) = frame_time else {
        return Err(AreboViolation {
            limit: stale,
            value: f64::INFINITY,
            bound: limits.stale_after,
        });
    };
    let age = now - time;
    if age < 0.0 {
        return Err(AreboViolation {
            limit: stale,
            value: age,
            bound: 0.0,
        });
    }
    at_most(stale, age, limits.stale_after)
}

/// Checks a frame's device status and error bits against the control type
/// the host set: every error bit stops (a known one by name, any other as
/// [`AreboLimit::UnknownDeviceError`]), so does a reserved status bit or a
/// control type other than `expected`.
pub fn check_device(status: u8, error: u16, expected: ControlType) -> AreboVerdict {
    let device = |limit, value: u16, bound: f64| AreboViolation {
        limit,
        value: f64::from(value),
        bound,
    };
    if error & ERROR_HEARTBEAT != 0 {
        return Err(device(AreboLimit::DeviceHeartbeatMissing, error, 0.0));
    }
    if error & ERROR_TORQUE_SENSOR != 0 {
        return Err(device(AreboLimit::TorqueSensorFault, error, 0.0));
    }
    if error != 0 {
        return Err(device(AreboLimit::UnknownDeviceError, error, 0.0));
    }
    if status & !STATUS_KNOWN != 0 {
        return Err(device(
            AreboLimit::UnknownDeviceError,
            u16::from(status),
            0.0,
        ));
    }
    match status_control(status) {
        Some(control) if control == expected => Ok(()),
        reported => Err(device(
            AreboLimit::ControlType,
            reported.map_or(3, |c| c as u16),
            f64::from(expected as u8),
        )),
    }
}

/// Checks one frame's derived quantities: shoulder angles, interaction
/// force [N, frame R0] and torque sensor readings [N m].
pub fn check_frame(
    phi: ShoulderAngles,
    force: &Vector3<f64>,
    torques: &Vector3<f64>,
    limits: &SafetyLimits,
) -> AreboVerdict {
    let finite = force.iter().chain(torques.iter()).all(|v| v.is_finite())
        && phi.flexion.is_finite()
        && phi.abduction.is_finite();
    if !finite {
        return Err(AreboViolation {
            limit: AreboLimit::Kernel(Limit::NonFiniteSensor),
            value: f64::NAN,
            bound: 0.0,
        });
    }
    within(AreboLimit::Flexion, phi.flexion, limits.flexion)?;
    within(AreboLimit::Abduction, phi.abduction, limits.abduction)?;
    at_most(
        AreboLimit::Kernel(Limit::ForceMagnitude),
        force.norm(),
        limits.max_force,
    )?;
    for (torque, bound) in torques.iter().zip(limits.max_torque) {
        at_most(
            AreboLimit::Kernel(Limit::Torque),
            libm::fabs(*torque),
            bound,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Finding 7 of issue 18: every error bit and every status bit reaches
    /// the verdict.
    #[test]
    fn every_device_error_and_status_bit_is_a_verdict() {
        use crate::protocol::status_byte;
        let torque = status_byte(true, ControlType::Torque);
        assert_eq!(check_device(torque, 0, ControlType::Torque), Ok(()));
        let limit = |status, error| {
            check_device(status, error, ControlType::Torque)
                .unwrap_err()
                .limit
        };
        assert_eq!(
            limit(torque, ERROR_HEARTBEAT),
            AreboLimit::DeviceHeartbeatMissing
        );
        assert_eq!(
            limit(torque, ERROR_TORQUE_SENSOR),
            AreboLimit::TorqueSensorFault
        );
        for bit in 2..16 {
            assert_eq!(limit(torque, 1 << bit), AreboLimit::UnknownDeviceError);
        }
        for bit in [1, 2, 3, 6, 7] {
            assert_eq!(
                limit(torque | (1 << bit), 0),
                AreboLimit::UnknownDeviceError
            );
        }
        for other in [ControlType::Off, ControlType::GravityCompensation] {
            assert_eq!(limit(status_byte(true, other), 0), AreboLimit::ControlType);
        }
        assert_eq!(limit(0b0011_0001, 0), AreboLimit::ControlType);
        let codes = [102, 103, 104, 105];
        for (limit, code) in [
            AreboLimit::DeviceHeartbeatMissing,
            AreboLimit::TorqueSensorFault,
            AreboLimit::UnknownDeviceError,
            AreboLimit::ControlType,
        ]
        .into_iter()
        .zip(codes)
        {
            assert_eq!(limit.code(), code);
        }
    }

    #[test]
    fn verdicts_name_the_limit() {
        let limits = SafetyLimits::default();
        assert!(check_fresh(Some(1.0), 1.01, &limits).is_ok());
        let stale = check_fresh(Some(1.0), 1.2, &limits).unwrap_err();
        assert_eq!(stale.limit.code(), Limit::StaleSensor.code());
        assert!(check_fresh(None, 0.0, &limits).is_err());
        let phi = ShoulderAngles {
            flexion: 0.5,
            abduction: 1.2,
        };
        let zero = Vector3::zeros();
        assert_eq!(
            check_frame(phi, &zero, &zero, &limits).unwrap_err().limit,
            AreboLimit::Abduction
        );
        let phi = ShoulderAngles {
            flexion: 0.5,
            abduction: 0.0,
        };
        let push = Vector3::new(0.0, 70.0, 0.0);
        assert_eq!(
            check_frame(phi, &push, &zero, &limits).unwrap_err().limit,
            AreboLimit::Kernel(Limit::ForceMagnitude)
        );
        let nan = Vector3::new(f64::NAN, 0.0, 0.0);
        assert_eq!(
            check_frame(phi, &zero, &nan, &limits).unwrap_err().limit,
            AreboLimit::Kernel(Limit::NonFiniteSensor)
        );
    }
}
