//! Speed and force rate over a sliding time window.
//!
//! # Theory of operation
//! Differencing consecutive frames amplifies noise (0.1 mm pose noise at
//! 1 kHz is 0.14 m/s of apparent speed). Instead the rate is the difference
//! between the newest frame and the oldest frame still at least `window`
//! seconds old, divided by their time difference. Frames live in a
//! fixed-capacity queue; when it is full the oldest is dropped, which only
//! shortens the window at very high frame rates (capacity / rate seconds).

use crate::geometry::PoseRate;
use crate::path::PathSample;
use heapless::Deque;

/// Frames kept for the window; at 1 kHz this covers 127 ms.
pub const RATE_WINDOW_CAPACITY: usize = 128;

/// Sliding window of recent frames, at most `N` of them (the kernel's:
/// [`RATE_WINDOW_CAPACITY`]; the proof uses a small `N` so that the full
/// window's branch is reached in a few pushes).
#[derive(Clone, Debug)]
pub struct RateWindow<const N: usize = RATE_WINDOW_CAPACITY> {
    window: f64,
    frames: Deque<PathSample, N>,
}

/// Rates over the window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rates {
    /// Mean pose velocity over the window [m/s, m/s, rad/s].
    pub velocity: PoseRate,
    /// Magnitude of the force vector's rate of change [N/s].
    pub force_rate: f64,
}

impl Rates {
    /// Grasp-point speed [m/s].
    pub fn speed(&self) -> f64 {
        self.velocity.linear_speed()
    }
}

impl<const N: usize> RateWindow<N> {
    /// An empty window of `window` seconds.
    pub fn new(window: f64) -> Self {
        Self {
            window,
            frames: Deque::new(),
        }
    }

    /// Forgets every frame (after a safe stop or reset).
    pub fn clear(&mut self) {
        self.frames.clear();
    }

    /// Adds a finite frame whose time is not before the newest one.
    pub fn push(&mut self, frame: PathSample) {
        if self.frames.is_full() {
            self.frames.pop_front();
        }
        // Capacity was just ensured, so the push cannot fail.
        let _ = self.frames.push_back(frame);
        // Keep exactly one frame at least `window` old at the front.
        while self
            .frames
            .iter()
            .nth(1)
            .is_some_and(|second| frame.time - second.time >= self.window)
        {
            self.frames.pop_front();
        }
    }

    /// Takes the newest frame back out (one the monitors refused: it must
    /// not judge later rates). Frames its push let go of stay gone, so the
    /// window may no longer span: its rates are zero until it does again.
    pub fn retract_newest(&mut self) {
        self.frames.pop_back();
    }

    /// True when the frames span the whole window (the rates are then
    /// measured, not the zero of a window too short).
    pub fn spans(&self) -> bool {
        matches!(
            (self.frames.front(), self.frames.back()),
            (Some(old), Some(new)) if new.time - old.time >= self.window
        )
    }

    /// Velocity and force rate between the oldest and newest frame
    /// ([`rates_between`]); zero until the frames span the whole window
    /// (the first `window` seconds after a start or reset, when a rate
    /// over a shorter span would be mostly noise: 0.5 N of force noise
    /// over 1 ms reads as 700 N/s).
    pub fn rates(&self) -> Rates {
        match (self.frames.front(), self.frames.back()) {
            (Some(old), Some(new)) => rates_between(old, new, self.window),
            _ => Rates::default(),
        }
    }
}

/// Velocity and force rate from frame `old` to frame `new`; zero unless
/// they are at least `window` [s] apart. Differences that overflow
/// (frames near `f64::MAX` apart, which no sensor gives) read as
/// infinitely fast, so that the monitors stop; no NaN is made (∞ / ∞).
pub(crate) fn rates_between(old: &PathSample, new: &PathSample, window: f64) -> Rates {
    let dt = new.time - old.time;
    // A NaN span (a NaN time) spans nothing either.
    let spans = dt >= window;
    if !spans {
        return Rates::default();
    }
    let moved = [
        new.pose.x - old.pose.x,
        new.pose.z - old.pose.z,
        new.pose.psi - old.pose.psi,
        libm::hypot(new.wrench.fx - old.wrench.fx, new.wrench.fz - old.wrench.fz),
    ];
    if !(dt.is_finite() && moved.iter().all(|d| d.is_finite())) {
        return Rates {
            velocity: PoseRate::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
            force_rate: f64::INFINITY,
        };
    }
    Rates {
        velocity: PoseRate::new(moved[0] / dt, moved[1] / dt, moved[2] / dt),
        force_rate: moved[3] / dt,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Pose, Wrench};

    /// REQ-MON-002, REQ-MON-003: frames whose differences overflow (times,
    /// poses and forces near f64::MAX apart: ∞ / ∞) read as infinitely
    /// fast, never NaN, so that the speed and force-rate monitors stop.
    #[test]
    fn req_mon_002_overflowing_differences_read_as_infinitely_fast() {
        let mut window: RateWindow = RateWindow::new(0.05);
        for (time, value) in [(-f64::MAX, -f64::MAX), (f64::MAX, f64::MAX)] {
            window.push(PathSample {
                time,
                pose: Pose::new(value, value, value),
                wrench: Wrench::new(value, value, 0.0),
            });
        }
        let rates = window.rates();
        assert_eq!(rates.speed(), f64::INFINITY, "{rates:?}");
        assert_eq!(rates.force_rate, f64::INFINITY, "{rates:?}");
        assert_eq!(rates.velocity.psi, f64::INFINITY, "{rates:?}");
    }

    /// A grasp moving at a constant velocity, read every 10 ms through a
    /// 50 ms window: each rate is the velocity itself, not a difference.
    #[test]
    fn the_rates_of_a_uniform_motion_are_its_velocity() {
        let mut window: RateWindow = RateWindow::new(0.05);
        for k in 0..=12 {
            let t = f64::from(k) * 0.01;
            window.push(PathSample {
                time: t,
                pose: Pose::new(0.1 * t, -0.2 * t, 0.5 * t),
                wrench: Wrench::new(3.0 * t, -4.0 * t, 0.0),
            });
        }
        let rates = window.rates();
        let expected = [0.1, -0.2, 0.5, 5.0];
        let got = [
            rates.velocity.x,
            rates.velocity.z,
            rates.velocity.psi,
            rates.force_rate,
        ];
        for (g, e) in got.iter().zip(expected) {
            assert!((g - e).abs() < 1e-9, "{got:?} != {expected:?}");
        }
    }
}

/// Proof of the rate window behind REQ-MON-002 and REQ-MON-003.
#[cfg(any(test, kani))]
pub(crate) mod verification {
    use super::*;
    use crate::config::SafetyLimits;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// The proof's window capacity: the push logic does not depend on it,
    /// and with 3 the full window's branch is reached in 4 pushes.
    const CAPACITY: usize = 3;

    /// Frames pushed by the harness: one more than [`CAPACITY`], so that
    /// the window can be full and drop a frame for room, and enough to
    /// drop one from the front by age and to span or not span the window.
    const PUSHES: usize = CAPACITY + 1;

    /// REQ-MON-002, REQ-MON-003: after any push the window holds at most
    /// its capacity and at most one frame at least `window` older than the
    /// newest (the front).
    pub(super) fn check_window<const N: usize>(window: &RateWindow<N>) -> Result<(), &'static str> {
        let Some(back) = window.frames.back() else {
            return Ok(());
        };
        if window.frames.len() > N {
            return Err("the window outgrew its capacity");
        }
        if window
            .frames
            .iter()
            .nth(1)
            .is_some_and(|second| back.time - second.time >= window.window)
        {
            return Err("more than one frame is a whole window old");
        }
        Ok(())
    }

    /// REQ-MON-002, REQ-MON-003: the rates are zero until the frames span
    /// the window, and never NaN (an overflowing difference reads as
    /// infinitely fast).
    pub(super) fn check_rates<const N: usize>(window: &RateWindow<N>) -> Result<(), &'static str> {
        rates_contract(window.spans(), &window.rates())
    }

    /// REQ-MON-002, the contract of [`rates_between`] and so of
    /// [`RateWindow::rates`]: zero unless the window `spans`, never NaN.
    /// Asserted of the real rates by
    /// [`verify_req_mon_002_rates_are_zero_until_the_window_spans`] (via
    /// [`check_rates`]) and assumed by [`stub::rates_between`], which the
    /// whole-kernel harnesses put in their place.
    pub(crate) fn rates_contract(spans: bool, rates: &Rates) -> Result<(), &'static str> {
        let values = [
            rates.velocity.x,
            rates.velocity.z,
            rates.velocity.psi,
            rates.force_rate,
        ];
        if values.iter().any(|v| v.is_nan()) {
            return Err("a rate is NaN");
        }
        if !spans && *rates != Rates::default() {
            return Err("a rate over less than the window");
        }
        Ok(())
    }

    /// Kani stubs of the window, each any value its proved contract
    /// allows.
    #[cfg(kani)]
    pub(crate) mod stub {
        use super::*;

        /// Stub of [`rates_between`] by [`rates_contract`]: any rates,
        /// none NaN, zero unless the frames are a window apart (the
        /// divisions of symbolic differences are the rates' own harness's,
        /// proved there for finite frames in time order: the only frames
        /// the kernel pushes into its window).
        pub(crate) fn rates_between(old: &PathSample, new: &PathSample, window: f64) -> Rates {
            let rates = Rates {
                velocity: kani::any(),
                force_rate: kani::any(),
            };
            kani::assume(rates_contract(new.time - old.time >= window, &rates).is_ok());
            rates
        }
    }

    /// A frame at `time` [s] with any pose and wrench under the
    /// stand-in; under Kani the pose and wrench are zero: the window's
    /// bookkeeping reads only times ([`verify_req_mon_002_rates_are_zero_until_the_window_spans`]
    /// covers the values).
    fn frame_at(time: f64) -> PathSample {
        #[cfg(kani)]
        let frame = PathSample {
            time,
            pose: crate::geometry::Pose::new(0.0, 0.0, 0.0),
            wrench: crate::geometry::Wrench::ZERO,
        };
        #[cfg(not(kani))]
        let frame = PathSample {
            time,
            ..kani::any::<PathSample>()
        };
        frame
    }

    /// REQ-MON-002, REQ-MON-003: pushing frames in time order (what the
    /// kernel pushes) keeps the window's invariants for any finite times,
    /// in a window of [`CAPACITY`] frames (the kernel's has
    /// [`RATE_WINDOW_CAPACITY`]; the code is the same for any capacity).
    /// The bookkeeping reads only the frames' times, so the pose and
    /// wrench are fixed here (CBMC's solver spent its 600 s on the
    /// arithmetic of 28 free `f64`s, none of which the bookkeeping reads);
    /// the rates' arithmetic is the next harness's. Unwind 5: the harness
    /// pushes 4 frames and `push` pops at most the 3 older ones.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(5))]
    pub(super) fn verify_req_mon_002_rate_window_spans_its_window() {
        let mut window = RateWindow::<CAPACITY>::new(SafetyLimits::default().rate_window);
        let mut last = f64::NEG_INFINITY;
        let mut dropped_for_room = false;
        let mut spanned = false;
        for _ in 0..PUSHES {
            let time = if kani::any::<u8>() < 64 {
                kani::any()
            } else {
                // Steps of 1 to 51 ms: both sides of the 50 ms window
                // under the sampling stand-in too.
                last.max(0.0) + f64::from(1 + kani::any::<u8>() % 51) * 1e-3
            };
            kani::assume(time.is_finite() && time > last);
            let full = window.frames.is_full();
            window.push(frame_at(time));
            dropped_for_room |= full;
            spanned |= window.spans();
            last = time;
            assert_eq!(check_window(&window), Ok(()));
        }
        kani::cover!(spanned, "rate window: spans the window");
        kani::cover!(!spanned, "rate window: not yet");
        kani::cover!(dropped_for_room, "rate window: full, dropped the oldest");
        kani::cover!(
            window.frames.len() < CAPACITY,
            "rate window: dropped by age"
        );
    }

    /// REQ-MON-002, REQ-MON-003: for any two finite frames in time order
    /// (what the kernel pushes; a window's rates read only its front and
    /// back, and not the torque ty, which is 0 here), the rates are zero until the frames span the window and
    /// never NaN. Unwind 5: the loops over the four differences and the
    /// four rates.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(5))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    pub(super) fn verify_req_mon_002_rates_are_zero_until_the_window_spans() {
        let mut window = RateWindow::<2>::new(SafetyLimits::default().rate_window);
        // Any finite frames (the kernel pushes only finite ones): a
        // non-finite draw reads as 0, which keeps every finite frame in
        // the domain and spares the stand-in's draws.
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let any_finite_frame = |time: f64| PathSample {
            time,
            pose: crate::geometry::Pose::new(
                finite(kani::any()),
                finite(kani::any()),
                finite(kani::any()),
            ),
            wrench: crate::geometry::Wrench::new(finite(kani::any()), finite(kani::any()), 0.0),
        };
        let first = any_finite_frame(kani::any());
        // Any time, or (so that the stand-in's draws are mostly in order)
        // 1 to 100 ms after the first.
        let time = if kani::any() {
            kani::any()
        } else {
            first.time + f64::from(1 + kani::any::<u8>() % 100) * 1e-3
        };
        let second = any_finite_frame(time);
        kani::assume(first.time.is_finite() && second.time.is_finite() && second.time > first.time);
        window.push(first);
        window.push(second);
        assert_eq!(check_rates(&window), Ok(()));
        let spans = window.spans();
        kani::cover!(spans, "rates: over the window");
        kani::cover!(!spans, "rates: zero, not yet");
        kani::cover!(
            spans && window.rates().speed() == f64::INFINITY,
            "rates: an overflowing difference reads as infinitely fast"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "rate window",
                5_000,
                verify_req_mon_002_rate_window_spans_its_window,
            );
            kani::check(
                "rates",
                5_000,
                verify_req_mon_002_rates_are_zero_until_the_window_spans,
            );
        }
    }
}
