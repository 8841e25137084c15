//! A kernel node: a `limb-session` session on its own thread, any robot
//! on the robot side, the Zenoh link's [`Supervision`] on the supervisor
//! side.
//!
//! The robot sets the rhythm (an FRI client answers each monitoring
//! message); a simulated plant with no rhythm of its own is paced at a
//! fixed period ([`limb_session::paced::Paced`]: absolute deadlines, an
//! overrun restarts the schedule and is counted in the status).

use crate::error::AdapterError;
use crate::link::{Link, LinkSettings};
use crate::supervision::{LoopView, Supervision};
use limb_kernel::Kernel;
use limb_session::paced::Paced;
use limb_session::{Observer, Outcome, Robot, Unobserved};
use std::thread::JoinHandle;
use std::time::Duration;

/// Stack of the session thread [bytes]: the kernel itself is boxed, but
/// the estimator's end-of-motion step needs more than Rust's 2 MB default
/// in debug builds.
const LOOP_STACK: usize = 16 * 1024 * 1024;

/// The session thread's result: the kernel, how the session ended (or the
/// robot's failure, in words) and the observer.
type Ended<O> = (Box<Kernel>, Result<Outcome, String>, O);

/// A running node: session thread plus Zenoh link, and what observes the
/// session (a session log). Dropping it without [`Node::shutdown`] ends
/// the session too (without waiting for it).
pub struct Node<O = Unobserved> {
    /// `Some` until shutdown.
    link: Option<Link>,
    view: LoopView,
    /// `Some` until shutdown.
    control_loop: Option<JoinHandle<Ended<O>>>,
}

impl Node {
    /// Opens the link and runs a session of `kernel` on `robot`, paced at
    /// `period` when given (a robot without a rhythm of its own).
    ///
    /// # Errors
    /// [`AdapterError`] for a bad setting, a Zenoh failure, or a thread
    /// that could not start.
    pub fn spawn<R>(
        zenoh_config: zenoh::Config,
        link_settings: &LinkSettings,
        period: Option<Duration>,
        kernel: Box<Kernel>,
        robot: R,
    ) -> Result<Self, AdapterError>
    where
        R: Robot + Send + 'static,
        R::Error: core::fmt::Debug,
    {
        Self::spawn_observed(
            zenoh_config,
            link_settings,
            period,
            kernel,
            robot,
            Unobserved,
        )
    }
}

impl<O: Send + 'static> Node<O> {
    /// [`Node::spawn`], the session shown to `observer` (e.g. a
    /// `limb_session::log::SessionLog`), returned by [`Node::finish`].
    ///
    /// # Errors
    /// As [`Node::spawn`].
    pub fn spawn_observed<R>(
        zenoh_config: zenoh::Config,
        link_settings: &LinkSettings,
        period: Option<Duration>,
        mut kernel: Box<Kernel>,
        robot: R,
        mut observer: O,
    ) -> Result<Self, AdapterError>
    where
        R: Robot + Send + 'static,
        R::Error: core::fmt::Debug,
        O: Observer<R> + Observer<Paced<R>>,
    {
        if period.is_some_and(|p| p.is_zero()) {
            return Err(AdapterError::Setting("the control period must be positive"));
        }
        let (link, mut supervision) = Link::open(zenoh_config, link_settings, *kernel.config())?;
        let view = supervision.view();
        let control_loop = std::thread::Builder::new()
            .name("limb-control".into())
            .stack_size(LOOP_STACK)
            .spawn(move || {
                let outcome = match period {
                    Some(period) => {
                        let mut paced = Paced::new(robot, period);
                        supervision.count_overruns(paced.overruns());
                        run(&mut kernel, &mut paced, &mut supervision, &mut observer)
                    }
                    None => {
                        let mut robot = robot;
                        run(&mut kernel, &mut robot, &mut supervision, &mut observer)
                    }
                };
                (kernel, outcome, observer)
            })?;
        Ok(Self {
            link: Some(link),
            view,
            control_loop: Some(control_loop),
        })
    }

    /// What the loop reports (state, e-stop delay, supervisor loss).
    pub fn view(&self) -> &LoopView {
        &self.view
    }

    /// The node's Zenoh session (`None` only during shutdown).
    pub fn session(&self) -> Option<&zenoh::Session> {
        self.link.as_ref().map(Link::session)
    }

    /// Ends the session, closes the link and returns the kernel.
    ///
    /// # Errors
    /// As [`Node::finish`].
    pub fn shutdown(self) -> Result<Box<Kernel>, AdapterError> {
        self.finish().map(|(kernel, _)| kernel)
    }

    /// Ends the session, closes the link and returns the kernel and the
    /// observer.
    ///
    /// # Errors
    /// [`AdapterError::LoopPanicked`] if the loop thread panicked (a bug),
    /// [`AdapterError::Robot`] if the robot's I/O failed, or a Zenoh
    /// failure while closing.
    pub fn finish(self) -> Result<(Box<Kernel>, O), AdapterError> {
        self.end().map(|(kernel, _, observer)| (kernel, observer))
    }

    /// [`Node::finish`], with how the session ended (its step count, the
    /// soak's reference for the session log's rows).
    ///
    /// # Errors
    /// As [`Node::finish`].
    pub fn end(mut self) -> Result<(Box<Kernel>, Outcome, O), AdapterError> {
        self.view.end_session();
        let (kernel, outcome, observer) = self
            .control_loop
            .take()
            .ok_or(AdapterError::LoopPanicked)?
            .join()
            .map_err(|_| AdapterError::LoopPanicked)?;
        if let Some(link) = self.link.take() {
            link.close()?;
        }
        let outcome = outcome.map_err(AdapterError::Robot)?;
        Ok((kernel, outcome, observer))
    }
}

impl<O> Drop for Node<O> {
    fn drop(&mut self) {
        self.view.end_session();
    }
}

fn run<R, O>(
    kernel: &mut Kernel,
    robot: &mut R,
    supervision: &mut Supervision,
    observer: &mut O,
) -> Result<Outcome, String>
where
    R: Robot,
    R::Error: core::fmt::Debug,
    O: Observer<R>,
{
    limb_session::run(kernel, robot, supervision, observer).map_err(|e| format!("{e:?}"))
}
