//! Kernel time from the robot's stamps and the session's clock.
//!
//! # Theory of operation
//! The kernel's watchdog judges a frame by its age, `now − stamp`. The
//! robot's stamp comes from the robot's clock; `now` must come from a clock
//! the robot cannot stop or turn back, the session's (host monotonic time).
//! The two clocks have an unknown offset and drift apart slowly. The
//! offset is taken as the smallest `arrival − stamp` seen so far (the
//! frame that travelled fastest), so
//!
//! `now = arrival − min_k (arrival_k − stamp_k)`,
//!
//! held against rounding so that `now ≥ stamp` and `now` never falls.
//!
//! Then the freshest frame has age 0 and every other frame's age is how
//! much later than the fastest it arrived: a robot clock that stalls or
//! repeats its stamps, or a backlog read after a host stall, ages its
//! frames past the watchdog's limit; a clock that jumps back is a reversed
//! stamp. `now` never decreases (arrivals do not, the minimum only falls).
//! When the session's clock is the robot's own (an unpaced simulation,
//! `arrival = stamp`), `now` is the stamp exactly.

/// The offset between the session's clock and the robot's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AlignedClock {
    /// min(arrival − stamp) over the frames so far [s].
    offset: Option<f64>,
    /// The last kernel time given [s].
    last: Option<f64>,
}

impl AlignedClock {
    /// Kernel time [s] for a frame stamped `stamp` (robot clock) that
    /// arrived at `arrival` (session clock). Computed as
    /// `stamp + ((arrival − stamp) − offset)`, so a frame's age is never
    /// below zero by rounding, and never less than the last kernel time
    /// given (rounding again: the exact value does not decrease). A
    /// non-finite stamp leaves the offset as it was (the watchdog rejects
    /// the frame).
    pub fn frame(&mut self, stamp: f64, arrival: f64) -> f64 {
        let offset = arrival - stamp;
        if offset.is_finite() && self.offset.is_none_or(|o| offset < o) {
            self.offset = Some(offset);
        }
        match self.offset {
            Some(o) if offset.is_finite() => self.monotone(stamp + (offset - o)),
            _ => self.at(arrival),
        }
    }

    /// Kernel time [s] at session-clock reading `at`, no frame arriving
    /// (NaN before the first frame: the watchdog calls that a clock fault).
    pub fn at(&mut self, at: f64) -> f64 {
        match self.offset {
            Some(o) => self.monotone(at - o),
            None => f64::NAN,
        }
    }

    fn monotone(&mut self, now: f64) -> f64 {
        let now = self.last.map_or(now, |last| now.max(last));
        self.last = Some(now);
        now
    }
}

#[cfg(test)]
mod tests {
    use super::AlignedClock;

    #[test]
    fn the_robot_clock_is_kernel_time_when_it_is_the_session_clock() {
        let mut clock = AlignedClock::default();
        for t in [0.0, 0.001, 0.002, 0.1] {
            assert_eq!(clock.frame(t, t).to_bits(), t.to_bits());
        }
    }

    #[test]
    fn a_stalled_robot_clock_ages_its_frames() {
        let mut clock = AlignedClock::default();
        assert_eq!(clock.frame(5.0, 100.0), 5.0);
        // The robot clock stops at 5.001 s while frames keep arriving.
        clock.frame(5.001, 100.001);
        let now = clock.frame(5.001, 100.031);
        assert!((now - 5.001 - 0.030).abs() < 1e-9, "{now}");
    }

    #[test]
    fn the_fastest_frame_sets_the_offset_and_time_never_falls() {
        let mut clock = AlignedClock::default();
        let a = clock.frame(0.0, 10.005);
        let b = clock.frame(0.001, 10.001);
        assert!(b >= a);
        assert!((clock.frame(0.002, 10.002) - 0.002).abs() < 1e-12);
        assert!(clock.frame(f64::NAN, 10.003).is_finite());
    }
}
