//! `grasp_slip`: at time `at` [s] the grasp slides once along the forearm by
//! `shift` [m] (positive: away from the elbow). From then on the forearm
//! length l2 (elbow to grasp) is l2 + shift and the shoulder sits at
//! l1 + l2 + shift in frame S, as in the shared reference logs; the rod's
//! mass is unchanged.

use super::Parameter;

/// Parameters: shift [m], at [s].
pub const PARAMETERS: [Parameter; 2] = [
    Parameter::new(
        "shift",
        "m",
        -0.05,
        0.05,
        "slide of the grasp along the forearm",
    ),
    Parameter::new("at", "s", 0.0, 60.0, "time of the slide"),
];

/// One slide of the grasp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GraspSlip {
    /// Slide [m].
    pub shift: f64,
    /// Time [s].
    pub at: f64,
}
