//! Every monitor of the kernel, built once from the safety limits: when
//! the kernel is made and when its limits are replaced, never per step.

use super::force::ForceMonitor;
use super::joint_limits::JointLimitMonitor;
use super::speed::SpeedMonitor;
use super::watchdog::Watchdog;
use super::workspace::WorkspaceMonitor;
use crate::config::SafetyLimits;

/// The monitors of one set of safety limits.
///
/// # Invariants
/// Each monitor's bounds are the limits' own values, unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonitorSet {
    /// Sensor age, clock and time stamps.
    pub watchdog: Watchdog,
    /// Force, torque and force rate.
    pub force: ForceMonitor,
    /// Grasp-point speed.
    pub speed: SpeedMonitor,
    /// Workspace box and table.
    pub workspace: WorkspaceMonitor,
    /// The person's joint ranges and the model's fit.
    pub joint_limits: JointLimitMonitor,
}

impl MonitorSet {
    /// The monitors of `limits`.
    pub fn from_limits(limits: &SafetyLimits) -> Self {
        Self {
            watchdog: Watchdog::new(limits.max_sensor_age),
            force: ForceMonitor {
                max_force: limits.max_force,
                max_torque: limits.max_torque,
                max_force_rate: limits.max_force_rate,
            },
            speed: SpeedMonitor {
                max_speed: limits.max_speed,
            },
            workspace: WorkspaceMonitor {
                x: limits.workspace_x,
                z: limits.workspace_z,
                table_tolerance: limits.table_tolerance,
            },
            joint_limits: JointLimitMonitor::from_limits(limits),
        }
    }
}
