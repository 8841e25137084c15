//! `shoulder_height`: the shoulder stands above the elbow resting on the
//! table. A seated person's shoulder is higher than the table their arm
//! rests on, so at rest the upper arm slopes down from the shoulder to the
//! elbow, and the elbow is flexed by as much to keep the forearm on the
//! table; plant.md's dummy lies straight and flat, the shoulder at the
//! elbow's height. (Where the elbow's axis lies above or below the grasp,
//! the forearm's joint line is off the cuff: that is `cuff_offset`'s
//! `across`.)
//!
//! # Model
//! With `height` h the upper arm rests at the elevation r = −asin(h / l1)
//! (below the horizontal) and the arm starts at q = (r, −r): elbow on the
//! table, forearm flat (psi = 0), the grasp at frame S's origin, the
//! shoulder at (l2 + l1 cos r, h). The table holds the elbow at its rest
//! height: q1 ≥ r (plant.md's q1 ≥ 0, counted from r); psi ≥ 0 as in
//! plant.md. Gravity, inertia and the Jacobian are plant.md's at the true
//! angles; the grasp is displaced by the shoulder's shift from (L, 0),
//! l1 (cos r − 1) in x and h in z. `shoulder_rhythm`'s displacement
//! counts from the rest posture (it grows with q1 − r), so the grasp still
//! starts at the origin.
//!
//! # Unlike `shoulder_rhythm` and `shoulder_drift`
//! Both move the shoulder during the motion (with the elevation, or
//! yielding to the robot's force) from where plant.md puts it; this puts
//! it elsewhere from the start and moves nothing.
//!
//! # Magnitudes
//! 0-0.25 m allowed, below l1 (the plant refuses a shoulder the upper arm
//! cannot reach down from). Typical 3-10 cm: a table at elbow height,
//! seated upright (the upper arm near vertical) it is most of l1, leaning
//! forward onto the table a few centimetres; the MyoArm subjects
//! (`plants/myoarm`) rest with the shoulder 4.4 cm above the elbow's axis
//! (subject m50).

use super::Parameter;

/// Parameters: height [m].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "height",
    "m",
    0.0,
    0.25,
    "shoulder centre's height above the elbow's at rest",
)];

/// Shoulder above the elbow at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShoulderHeight {
    /// Height of the shoulder centre above the elbow's at rest [m].
    pub height: f64,
}

/// The rest posture of one arm under a raised shoulder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rest {
    /// Joint angles at rest (q1, q2) [rad]: (r, −r).
    pub q: [f64; 2],
    /// The shoulder's shift (x, z) [m] from plant.md's (L, 0).
    pub shift: [f64; 2],
}

impl ShoulderHeight {
    /// The rest posture of an upper arm of `l1` [m]; `None` when the
    /// height is not below `l1`.
    pub fn rest(&self, l1: f64) -> Option<Rest> {
        (self.height < l1).then(|| {
            let r = -libm::asin(self.height / l1);
            Rest {
                q: [r, -r],
                shift: [l1 * (libm::cos(r) - 1.0), self.height],
            }
        })
    }
}
