//! The grasp path recorded during the estimation motion.
//!
//! The kernel records at most one sample per [`PATH_SAMPLE_PERIOD`] into a
//! fixed-capacity buffer, so estimator work and memory are bounded at compile
//! time whatever rate the adapter steps the kernel at.

use crate::geometry::{Pose, Wrench};

/// Capacity of the grasp-path buffer [samples]. The estimation motion of
/// `plant.md` lasts about 29.3 s; at 100 Hz that is 2 930 samples, so 4 096
/// leaves room for longer lifts (up to 40.9 s).
pub const PATH_CAPACITY: usize = 4096;

/// Minimum time between two recorded samples [s] (100 Hz, the paper's rate).
pub const PATH_SAMPLE_PERIOD: f64 = 0.01;

/// One measured sample of the grasp path, frame S.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PathSample {
    /// Time stamp of the measurement [s].
    pub time: f64,
    /// Measured grasp pose [m, m, rad].
    pub pose: Pose,
    /// Measured external wrench at the grasp (robot's estimate f_ext) [N, N, N m].
    pub wrench: Wrench,
}

/// The recorded grasp path.
pub type GraspPath = heapless::Vec<PathSample, PATH_CAPACITY>;

/// True when a sample stamped `time` [s] is due for recording after `last`:
/// at least [`PATH_SAMPLE_PERIOD`] later (to within 1 ppm, so a 100 Hz log
/// with rounded time stamps keeps every row), or the first.
pub fn is_due(last: Option<&PathSample>, time: f64) -> bool {
    last.is_none_or(|last| time - last.time >= PATH_SAMPLE_PERIOD * (1.0 - 1e-6))
}
