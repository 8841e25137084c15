//! The robot side of a session: frames in, commands out.
//!
//! An adapter implements [`Robot`] by translating its wire into kernel
//! types and back, nothing more: the reference plant (`limb-sim`), the
//! KUKA FRI client (`limb-kuka`), the AREBO link (`limb-arebo`). The loop
//! ([`crate::run`]) owns the kernel, the clock and the order of things.

use limb_kernel::{Command, PathSample};

/// One frame the robot measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// What the kernel sees: the robot's own time stamp as the robot gave
    /// it (robot clock, seconds since the robot's first frame, never
    /// adjusted), the grasp pose and the external wrench in frame S.
    pub sample: PathSample,
    /// Lateral position y of the grasp in frame S [m], when the robot
    /// measures it: logged, and given to the kernel (which reads it for the
    /// tilt of the arm's plane, REQ-EST-011; 0 when not measured).
    pub lateral: Option<f64>,
    /// When the frame arrived, on the session's clock [s] (host monotonic
    /// time; a simulation's own time when it is not paced).
    pub arrival: f64,
    /// The robot follows the commands now (KUKA: COMMANDING_ACTIVE with
    /// quality GOOD or better). While it does not, the loop stops any
    /// motion and the scripted operator makes no request.
    pub following: bool,
}

/// Which clock a robot's frames arrive on (the session's clock, against
/// which the kernel's watchdog ages the robot's stamps).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrivalClock {
    /// The host's monotonic clock: a real robot (or a simulated one in
    /// real time). A robot clock that stalls, repeats or lags, or a
    /// backlog the host reads late, ages its frames.
    Host,
    /// The robot's own stamps: a simulated robot whose clock is the
    /// simulation's and runs at whatever speed the machine allows. Only
    /// what the stamps themselves show (a jump back, a gap) is seen.
    Robot,
}

/// What one [`Robot::sense`] gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sensed {
    /// A new frame.
    Frame(Frame),
    /// No frame arrived within the robot's receive timeout; the session
    /// clock reads this [s]. The kernel's watchdog judges the silence.
    Silent(f64),
    /// The robot's session is over (its time budget spent).
    Ended,
}

/// A robot the kernel closes its loop on.
pub trait Robot {
    /// A failure of the robot's own I/O.
    type Error;
    /// Waits for the robot's next frame (the robot paces the loop).
    ///
    /// # Errors
    /// The robot's I/O failure; the session ends with it.
    fn sense(&mut self) -> Result<Sensed, Self::Error>;
    /// Carries out `command`, the kernel's answer to the frame last sensed.
    ///
    /// # Errors
    /// The robot's I/O failure; the session ends with it.
    fn actuate(&mut self, command: &Command) -> Result<(), Self::Error>;
}
