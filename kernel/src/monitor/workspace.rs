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

/// Proof of REQ-MON-004.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    fn monitor() -> WorkspaceMonitor {
        let l = SafetyLimits::default();
        WorkspaceMonitor {
            x: l.workspace_x,
            z: l.workspace_z,
            table_tolerance: l.table_tolerance,
        }
    }

    /// REQ-MON-004: the verdict trips exactly when the grasp point or the
    /// elbow (when given) is more than the tolerance below the table or the
    /// grasp point is outside the box, NaN included.
    pub(super) fn check_workspace_verdict(
        m: &WorkspaceMonitor,
        pose: Pose,
        elbow: Option<Point>,
        verdict: Verdict,
    ) -> Result<(), &'static str> {
        let floor = -m.table_tolerance;
        let inside = pose.z >= floor
            && elbow.is_none_or(|e| e.z >= floor)
            && m.x.contains(pose.x)
            && m.z.contains(pose.z);
        match (verdict, inside) {
            (Ok(()), true) | (Err(_), false) => Ok(()),
            (Ok(()), false) => Err("a pose outside the workspace passed"),
            (Err(_), true) => Err("a pose inside the workspace tripped"),
        }
    }

    /// REQ-MON-004: for any grasp pose and any (or no) elbow the workspace
    /// monitor trips exactly outside the workspace and above the table.
    #[cfg_attr(kani, kani::proof)]
    pub(super) fn verify_req_mon_004_workspace_monitor_trips_beyond_limits() {
        let m = monitor();
        let pose = kani::any::<Pose>();
        let elbow = if kani::any() {
            Some(Point::new(kani::any(), kani::any()))
        } else {
            None
        };
        let verdict = m.check(pose, elbow);
        assert_eq!(check_workspace_verdict(&m, pose, elbow, verdict), Ok(()));
        kani::cover!(verdict.is_ok(), "workspace monitor: passes");
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::ElbowBelowTable),
            "workspace monitor: elbow below the table"
        );
        kani::cover!(
            verdict.is_err_and(|v| v.limit == Limit::WorkspaceX),
            "workspace monitor: outside the box"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "workspace monitor",
                20_000,
                verify_req_mon_004_workspace_monitor_trips_beyond_limits,
            );
        }
    }
}
