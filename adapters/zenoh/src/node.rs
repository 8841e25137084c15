//! A kernel node: the control loop thread stepping a boxed kernel at a
//! fixed period from a [`SensorSource`], supervised over a [`Link`].
//!
//! The node owns time: kernel time is `origin + (Instant::now() − epoch)`
//! [s], monotonic. The loop sleeps to absolute deadlines; a step that
//! starts more than one period late is counted as an overrun and the
//! schedule restarts from now (no burst of catch-up steps).

use crate::error::AdapterError;
use crate::link::{Link, LinkSettings, LoopView, Supervision};
use crate::sensor::SensorSource;
use limb_kernel::Kernel;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Stack of the control-loop thread [bytes]: the kernel itself is boxed,
/// but the estimator's end-of-motion step needs more than Rust's 2 MB
/// default in debug builds.
const LOOP_STACK: usize = 16 * 1024 * 1024;

/// Settings of a node's control loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopSettings {
    /// Control period, e.g. 1 ms for 1 kHz.
    pub period: Duration,
    /// Kernel time at the first step [s] (0 for a new kernel, the time a
    /// replayed or pre-driven kernel reached otherwise).
    pub origin: f64,
}

/// A running node: control loop plus Zenoh link. Dropping it without
/// [`Node::shutdown`] stops the loop too (without waiting for it).
pub struct Node {
    /// `Some` until shutdown.
    link: Option<Link>,
    view: LoopView,
    stop: Arc<AtomicBool>,
    /// `Some` until shutdown.
    control_loop: Option<JoinHandle<Box<Kernel>>>,
}

impl Node {
    /// Opens the link and starts the control loop on `kernel`.
    ///
    /// # Errors
    /// [`AdapterError`] for a bad setting, a Zenoh failure, or a thread
    /// that could not start.
    pub fn spawn(
        zenoh_config: zenoh::Config,
        link_settings: &LinkSettings,
        loop_settings: LoopSettings,
        kernel: Box<Kernel>,
        source: Box<dyn SensorSource>,
    ) -> Result<Self, AdapterError> {
        if loop_settings.period.is_zero() || !loop_settings.origin.is_finite() {
            return Err(AdapterError::Setting(
                "the control period must be positive and the origin finite",
            ));
        }
        let (link, supervision) = Link::open(zenoh_config, link_settings, *kernel.config())?;
        let view = supervision.view();
        let stop = Arc::new(AtomicBool::new(false));
        let control_loop = std::thread::Builder::new()
            .name("limb-control".into())
            .stack_size(LOOP_STACK)
            .spawn({
                let stop = Arc::clone(&stop);
                move || run(kernel, source, supervision, loop_settings, &stop)
            })?;
        Ok(Self {
            link: Some(link),
            view,
            stop,
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

    /// Stops the loop, closes the link and returns the kernel.
    ///
    /// # Errors
    /// [`AdapterError::LoopPanicked`] if the loop thread panicked (a bug), or a
    /// Zenoh failure while closing.
    pub fn shutdown(mut self) -> Result<Box<Kernel>, AdapterError> {
        self.stop.store(true, Ordering::Release);
        let kernel = self
            .control_loop
            .take()
            .ok_or(AdapterError::LoopPanicked)?
            .join()
            .map_err(|_| AdapterError::LoopPanicked)?;
        if let Some(link) = self.link.take() {
            link.close()?;
        }
        Ok(kernel)
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
    }
}

fn run(
    mut kernel: Box<Kernel>,
    mut source: Box<dyn SensorSource>,
    mut supervision: Supervision,
    settings: LoopSettings,
    stop: &AtomicBool,
) -> Box<Kernel> {
    let epoch = supervision.epoch();
    let mut deadline = Instant::now();
    while !stop.load(Ordering::Acquire) {
        let now = settings.origin + epoch.elapsed().as_secs_f64();
        supervision.before_step(&mut kernel, now);
        let frame = source.frame(now);
        let command = kernel.step(&frame, now);
        supervision.after_step(&mut kernel, &frame, &command, now);
        deadline += settings.period;
        let current = Instant::now();
        if let Some(wait) = deadline.checked_duration_since(current) {
            std::thread::sleep(wait);
        } else if current.duration_since(deadline) > settings.period {
            supervision.record_overrun();
            deadline = current;
        }
    }
    kernel
}
