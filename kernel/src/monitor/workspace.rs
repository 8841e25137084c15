//! Workspace monitor: the grasp point inside a box in S, grasp point and
//! elbow never below the table (z = 0) by more than the noise tolerance.

use super::{within, Limit, Verdict, Violation};
use crate::config::Interval;
use crate::geometry::{Point, Pose};

/// Workspace box and table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorkspaceMonitor {
    /// Allowed grasp x [m].
    pub x: Interval,
    /// Allowed grasp z [m].
    pub z: Interval,
    /// Allowed depth below the table [m] (≥ 0).
    pub table_tolerance: f64,
}

impl WorkspaceMonitor {
    /// Verdict on the grasp pose and, when a model gives it, the elbow.
    pub fn check(&self, pose: Pose, elbow: Option<Point>) -> Verdict {
        let floor = -self.table_tolerance;
        if pose.z.is_nan() || pose.z < floor {
            return Err(Violation::new(Limit::GraspBelowTable, pose.z, floor));
        }
        if let Some(elbow) = elbow {
            if elbow.z.is_nan() || elbow.z < floor {
                return Err(Violation::new(Limit::ElbowBelowTable, elbow.z, floor));
            }
        }
        within(Limit::WorkspaceX, pose.x, self.x)?;
        within(Limit::WorkspaceZ, pose.z, self.z)
    }
}
