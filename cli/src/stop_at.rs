//! `limb run --stop-at T`: an emergency stop at T seconds of session time,
//! whatever the state, and what it did to the person's arm.
//!
//! # Theory of operation
//! [`StopAt`] wraps any supervisor (the scripted operator of `limb run`,
//! or whatever supervises an external plant): until T it only passes the
//! session on; on the first step at or after T (counted from the
//! session's first step) it asks the kernel for a stop (`Request::Stop`,
//! as an emergency stop button does) and records
//! the state the kernel was in; from then on it watches every step's frame
//! for [`WINDOW`] and keeps the session running that long, whatever the
//! wrapped supervisor says. Everything is measured from the robot's own
//! frames (grasp pose z and wrench in frame S), never from plant
//! internals, so the same wrapper judges any robot:
//!
//! * `sag_m`: the largest drop of the grasp below its height at the stop
//!   over the window (0 when it never went lower);
//! * `max_force_n`: the largest |(fx, fz)| over the same window;
//! * `category`: the stop category the kernel applied
//!   (`limb_kernel::stop`), `cause` the stop's reason (`emergency_stop`
//!   for this request; a monitor's limit name when a monitor had stopped
//!   the kernel before T).

use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, Kernel, PathSample, Request, StateKind, StopReason};
use limb_session::{SessionPlan, Supervisor};
use serde::Serialize;

/// How long the stop is watched [s] (cli.md: the 2 s after it).
pub const WINDOW: f64 = 2.0;

/// What `--stop-at` reports (cli.md, `limb run --stop-at T`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StopReport {
    /// Session time the stop was asked at [s].
    pub at: f64,
    /// The kernel's state when it was asked (its vocabulary name).
    pub state: String,
    /// The stop's cause: `emergency_stop` for this request, else the
    /// kernel's reason (a monitor by its limit's name).
    pub cause: String,
    /// Largest drop of the grasp below its height at the stop over the
    /// window [m].
    pub sag_m: f64,
    /// Largest |f| over the window [N].
    pub max_force_n: f64,
    /// The stop category the kernel applied (`hold`, `ramp_down`,
    /// `motors_off`).
    pub category: String,
    /// Seconds of the window the session ran (less than [`WINDOW`] when
    /// the robot ended first).
    pub watched_s: f64,
}

/// The stop, once asked.
#[derive(Clone, Copy, Debug)]
struct Stopped {
    at: f64,
    state: StateKind,
    height: Option<f64>,
    lowest: f64,
    max_force: f64,
    last: f64,
    reason: Option<StopReason>,
    ours: bool,
}

/// A supervisor that passes the session to `inner` and asks for an
/// emergency stop at `at` [s] (never when `None`: then it is `inner`).
#[derive(Clone, Debug)]
pub struct StopAt<S> {
    inner: S,
    at: Option<f64>,
    /// Kernel time of the session's first step [s] (a plant's clock may
    /// start anywhere: session time counts from here).
    start: Option<f64>,
    now: f64,
    stopped: Option<Stopped>,
}

impl<S> StopAt<S> {
    /// `inner`, stopped at session time `at` [s] when given.
    pub fn new(inner: S, at: Option<f64>) -> Self {
        Self {
            inner,
            at,
            start: None,
            now: f64::NEG_INFINITY,
            stopped: None,
        }
    }

    /// The report, once the stop was asked.
    pub fn report(&self) -> Option<StopReport> {
        let s = self.stopped?;
        let cause = match s.reason {
            Some(StopReason::Operator) if s.ours => "emergency_stop".to_owned(),
            Some(StopReason::Monitor(v)) => v.limit.name().to_owned(),
            Some(reason) => reason.name().to_owned(),
            None => "none".to_owned(),
        };
        Some(StopReport {
            at: s.at - self.start.unwrap_or(s.at),
            state: s.state.name().to_owned(),
            cause,
            sag_m: s.height.map_or(0.0, |h| (h - s.lowest).max(0.0)),
            max_force_n: s.max_force,
            category: s.reason.map_or("none", |r| r.category().name()).to_owned(),
            watched_s: (s.last - s.at).max(0.0),
        })
    }
}

/// A `--stop-at` time: finite and not negative [s].
///
/// # Errors
/// The value in words.
pub fn parse_time(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err(format!(
            "{text}: not a time in seconds (finite, not negative)"
        )),
    }
}

/// `plan` with a timeout that leaves the stop at `at` its whole window.
pub fn plan(plan: SessionPlan, at: Option<f64>) -> SessionPlan {
    SessionPlan {
        timeout: at.map_or(plan.timeout, |at| plan.timeout.max(at + WINDOW + 0.5)),
        ..plan
    }
}

impl<S: Supervisor> Supervisor for StopAt<S> {
    fn before_step(&mut self, kernel: &mut Kernel, now: f64, following: bool) {
        self.now = now;
        let start = *self.start.get_or_insert(now);
        if let (Some(at), None) = (self.at, self.stopped) {
            if now - start >= at {
                let state = kernel.state().kind();
                let ours = state != StateKind::SafeStop;
                // A stop is never refused (REQ-SM-004); in SafeStop it
                // leaves the first stop latched.
                let _ = kernel.request(Request::Stop, now);
                self.stopped = Some(Stopped {
                    at: now,
                    state,
                    height: None,
                    lowest: f64::INFINITY,
                    max_force: 0.0,
                    last: now,
                    reason: kernel.stopped().map(|s| s.reason()),
                    ours,
                });
                return;
            }
        }
        self.inner.before_step(kernel, now, following);
    }

    fn after_step(&mut self, kernel: &Kernel, frame: &PathSample, command: &Command, now: f64) {
        if let Some(s) = self.stopped.as_mut() {
            if now <= s.at + WINDOW {
                let z = frame.pose.z;
                s.height.get_or_insert(z);
                if z.is_finite() {
                    s.lowest = s.lowest.min(z);
                }
                let force = frame.wrench.fx.hypot(frame.wrench.fz);
                if force.is_finite() {
                    s.max_force = s.max_force.max(force);
                }
                s.last = s.last.max(now);
            }
        }
        self.inner.after_step(kernel, frame, command, now);
    }

    fn event(&mut self, kernel: &Kernel, event: &TraceEvent) {
        self.inner.event(kernel, event);
    }

    fn finished(&self, state: StateKind, completed: bool) -> bool {
        match (self.at, self.stopped) {
            (None, _) => self.inner.finished(state, completed),
            (Some(_), None) => false,
            (Some(_), Some(s)) => self.now >= s.at + WINDOW,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use limb_kernel::geometry::{Pose, Wrench};
    use limb_kernel::KernelConfig;

    struct Never;

    impl Supervisor for Never {
        fn before_step(&mut self, _: &mut Kernel, _: f64, _: bool) {}
        fn finished(&self, _: StateKind, _: bool) -> bool {
            true
        }
    }

    fn frame(t: f64, z: f64, fz: f64) -> PathSample {
        PathSample {
            time: t,
            pose: Pose::new(0.0, z, 0.0),
            wrench: Wrench::new(0.0, fz, 0.0),
        }
    }

    /// The stop is asked at the first step at or after T, the session runs
    /// on for the window, and sag and force are the frames' over it.
    #[test]
    fn the_stop_is_asked_at_t_and_measured_over_the_window() {
        let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
        let mut stop = StopAt::new(Never, Some(0.5));
        let command = kernel.step(Some(&frame(0.0, 0.0, 0.0)), 0.0);
        for (k, z, fz) in [
            (0, 0.01, 3.0),
            (100, 0.01, 3.0),
            (499, 0.01, 3.0),
            (500, 0.01, 3.0),
        ] {
            let now = f64::from(k) * 1e-3;
            stop.before_step(&mut kernel, now, true);
            stop.after_step(&kernel, &frame(now, z, fz), &command, now);
            assert!(!stop.finished(kernel.state().kind(), false));
        }
        assert_eq!(kernel.state().kind(), StateKind::SafeStop);
        for (t, z, fz) in [(1.0, 0.007, -6.0), (2.4, 0.009, 2.0), (2.6, 0.0, 50.0)] {
            stop.before_step(&mut kernel, t, true);
            stop.after_step(&kernel, &frame(t, z, fz), &command, t);
        }
        assert!(stop.finished(StateKind::SafeStop, false));
        let report = stop.report().unwrap();
        assert_eq!(report.at, 0.5);
        assert_eq!(report.state, "grasp");
        assert_eq!(report.cause, "emergency_stop");
        assert_eq!(report.category, "hold");
        assert!((report.sag_m - 0.003).abs() < 1e-12, "{report:?}");
        assert_eq!(report.max_force_n, 6.0);
    }

    /// T counts from the session's first step, not from kernel time 0 (a
    /// plant whose clock starts at 1000.5 s).
    #[test]
    fn the_stop_time_is_session_time() {
        let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
        let mut stop = StopAt::new(Never, Some(0.5));
        let command = kernel.step(Some(&frame(1000.5, 0.0, 0.0)), 1000.5);
        for now in [1000.5, 1000.9, 1001.0] {
            stop.before_step(&mut kernel, now, true);
            stop.after_step(&kernel, &frame(now, 0.01, 0.0), &command, now);
            assert_eq!(stop.report().is_some(), now >= 1001.0, "{now}");
        }
        assert_eq!(stop.report().unwrap().at, 0.5);
    }

    /// Without a stop time the wrapper is the supervisor it wraps.
    #[test]
    fn without_a_time_it_is_the_inner_supervisor() {
        let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
        let mut stop = StopAt::new(Never, None);
        stop.before_step(&mut kernel, 100.0, true);
        assert_eq!(kernel.state().kind(), StateKind::Grasp);
        assert!(stop.finished(StateKind::Grasp, false));
        assert!(stop.report().is_none());
    }
}
