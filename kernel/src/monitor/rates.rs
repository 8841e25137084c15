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

/// Sliding window of recent frames.
#[derive(Clone, Debug)]
pub struct RateWindow {
    window: f64,
    frames: Deque<PathSample, RATE_WINDOW_CAPACITY>,
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

impl RateWindow {
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

    /// Velocity and force rate between the oldest and newest frame; zero
    /// until the frames span the whole window (the first `window` seconds
    /// after a start or reset, when a rate over a shorter span would be
    /// mostly noise: 0.5 N of force noise over 1 ms reads as 700 N/s).
    pub fn rates(&self) -> Rates {
        match (self.frames.front(), self.frames.back()) {
            (Some(old), Some(new)) if new.time - old.time >= self.window => {
                let dt = new.time - old.time;
                Rates {
                    velocity: PoseRate::new(
                        (new.pose.x - old.pose.x) / dt,
                        (new.pose.z - old.pose.z) / dt,
                        (new.pose.psi - old.pose.psi) / dt,
                    ),
                    force_rate: libm::hypot(
                        new.wrench.fx - old.wrench.fx,
                        new.wrench.fz - old.wrench.fz,
                    ) / dt,
                }
            }
            _ => Rates::default(),
        }
    }
}
