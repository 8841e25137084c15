//! Quantized readings: a pose channel that reports the same value for
//! several samples in a row, read as the staircase it is.
//!
//! # Theory of operation
//! A sensor whose resolution is coarser than its noise (an encoder's
//! count, a pose rounded to millimetres) reports a channel (x, z or psi)
//! unchanged while the arm moves through one resolution cell, then steps
//! to the next. Fitted as it is, such a staircase pulls a circle off the
//! path by a fraction of the step, the same way over a whole phase: on
//! `plant.md`'s lift read to 4.3 mm and 0.8° the refined elbow and
//! shoulder came out 2-4 mm off and the estimate was refused
//! (`residual_bias`). With a rounding quantizer, the true value crosses
//! the boundary between two cells, the midpoint of their readings, between
//! the two samples where the reading steps. So each sample of a **run**
//! (the same reading at samples `start..end`, at least [`MIN_RUN`] of
//! them, with a different one on each side) is read as the value
//! interpolated in time between the crossing before the run,
//! ((t₍start−1₎ + t₍start₎)/2, (v₍start−1₎ + v)/2), and the one after it.
//!
//! Left as read: a reading that changes every sample (an unquantized,
//! noisy sensor: the kernel's usual input; on such a path the
//! refinement's input is unchanged, bit for bit), and a non-finite
//! reading (∞ = ∞, but a run of infinities is no quantizer's).
//!
//! **Not known within its cell**, and left out of the fits
//! ([`Dequantizer::pose`] gives `None`), is a sample of a run that cannot
//! be interpolated: one whose neighbours lie on the same side of it (the
//! channel turned within the cell, by an unknown extent), one at either
//! end of the path or longer than [`MAX_RUN`] (an arm at rest that began
//! to move within the cell: on `plant.md`'s lift the grasp's x stays in
//! its resting cell for the first 2 s of the forearm's turn, up to half a
//! step off), or one with a non-finite neighbour. Such a run's reading is
//! true only to half a step, the error the interpolation removes.
//!
//! The recorded path is not changed: the refinement reads each sample
//! through [`Dequantizer::pose`].
//!
//! # Bounds
//! Per channel, a sample outside the run cached for that channel looks at
//! most [`MAX_RUN`] samples back and ahead (comparisons only); within it,
//! one interpolation. A pass that reads a phase in order looks at each
//! sample of a run once per channel.

use crate::geometry::Pose;
use crate::path::PathSample;
use core::ops::Range;

/// Fewest samples of one reading in a row that are read as a quantizer's
/// run (fewer: the reading is left as it is).
pub const MIN_RUN: usize = 2;
/// Longest run that is interpolated [samples]: 2.56 s at the recording
/// rate; a longer one (an arm at rest) is not known within its cell.
pub const MAX_RUN: usize = 256;

/// The channels of a pose: x [m], z [m], psi [rad].
const CHANNELS: usize = 3;

fn channel(pose: &Pose, index: usize) -> f64 {
    match index {
        0 => pose.x,
        1 => pose.z,
        _ => pose.psi,
    }
}

/// How the samples of a run are read.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reading {
    /// As recorded (a run shorter than [`MIN_RUN`]).
    Recorded,
    /// Interpolated between the crossings before and after the run,
    /// (time [s], value).
    Interpolated([(f64, f64); 2]),
    /// Not known within the cell (module doc).
    WithinCell,
}

/// One channel's run of one reading at samples `start..end`, and how its
/// samples are read.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Run {
    start: usize,
    end: usize,
    reading: Reading,
}

impl Run {
    /// The run of channel `c` of `path` that holds sample `index`, whose
    /// reading is `value`.
    fn around(path: &[PathSample], index: usize, c: usize, value: f64) -> Self {
        // A non-finite reading is no quantizer's (∞ == ∞ would make a run
        // whose crossings are ∞ − ∞): read as recorded, alone.
        if !value.is_finite() {
            return Self {
                start: index,
                end: index.saturating_add(1),
                reading: Reading::Recorded,
            };
        }
        let reads = |j: usize| path.get(j).map(|s| channel(&s.pose, c));
        let mut start = index;
        while start > 0 && index - start < MAX_RUN && reads(start - 1) == Some(value) {
            start -= 1;
        }
        let mut end = index.saturating_add(1);
        while end - start <= MAX_RUN && reads(end) == Some(value) {
            end += 1;
        }
        let reading = if end - start < MIN_RUN {
            Reading::Recorded
        } else {
            Self::crossings(path, start..end, c, value)
                .map_or(Reading::WithinCell, Reading::Interpolated)
        };
        Self {
            start,
            end,
            reading,
        }
    }

    /// The crossings before and after the run of channel `c` at samples
    /// `run` reading `value` (finite), (time [s], value); `None` when the
    /// run is longer than [`MAX_RUN`], lies at an end of `path`, turns
    /// within its cell or meets a non-finite number.
    fn crossings(
        path: &[PathSample],
        run: Range<usize>,
        c: usize,
        value: f64,
    ) -> Option<[(f64, f64); 2]> {
        if run.len() > MAX_RUN {
            return None;
        }
        let before = path.get(run.start.checked_sub(1)?)?;
        let after = path.get(run.end)?;
        let (first, last) = (path.get(run.start)?, path.get(run.end.checked_sub(1)?)?);
        let (below, above) = (channel(&before.pose, c), channel(&after.pose, c));
        // Every number finite before any sum (no ∞ − ∞ made; Kani's NaN
        // check found the sums taken first).
        let finite = [below, above, before.time, first.time, last.time, after.time]
            .iter()
            .all(|v| v.is_finite());
        if !finite {
            return None;
        }
        // A step into the run and on out of it, in the same direction.
        let through = (below - value) * (above - value) < 0.0;
        let from = (0.5 * (before.time + first.time), 0.5 * (below + value));
        let to = (0.5 * (last.time + after.time), 0.5 * (value + above));
        (through && to.0 > from.0).then_some([from, to])
    }

    /// The reading of a sample of the run at `time` [s], recorded `value`;
    /// `None` when it is not known within its cell.
    fn read(&self, time: f64, value: f64) -> Option<f64> {
        match self.reading {
            Reading::Recorded => Some(value),
            Reading::Interpolated([(t0, v0), (t1, v1)]) => {
                // t1 > t0, both finite: `along` is finite for a finite time.
                let along = ((time - t0) / (t1 - t0)).clamp(0.0, 1.0);
                Some(if along.is_finite() {
                    v0 + (v1 - v0) * along
                } else {
                    value
                })
            }
            Reading::WithinCell => None,
        }
    }
}

/// Reads a recorded path's poses with quantizer runs interpolated (module
/// doc). Caches one run per channel; holds no path.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dequantizer {
    runs: [Option<Run>; CHANNELS],
    tally: [Tally; CHANNELS],
}

/// What one channel's reads met.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Tally {
    /// Samples read, and those of them in a run of [`MIN_RUN`] or more.
    reads: u32,
    in_runs: u32,
    /// The sum of the steps between the crossings of the interpolated
    /// runs met [m or rad], and their count.
    steps: f64,
    runs: u32,
}

impl Tally {
    /// The mean step when at least half the samples read lay in runs (a
    /// quantized channel: a noisy one written to a file's last digit
    /// repeats a value now and then, which is no resolution); else 0.
    fn resolution(&self) -> f64 {
        if self.runs == 0 || 2 * u64::from(self.in_runs) < u64::from(self.reads) {
            0.0
        } else {
            self.steps / f64::from(self.runs)
        }
    }
}

impl Dequantizer {
    /// A reader with nothing cached.
    pub fn new() -> Self {
        Self::default()
    }

    /// The pose of `path[index]` with each channel's quantizer run
    /// interpolated; `None` when a channel is not known within its cell
    /// (module doc) or `index` is not in `path`. The same `path` on every
    /// call (the cache belongs to it).
    pub fn pose(&mut self, path: &[PathSample], index: usize) -> Option<Pose> {
        let sample = path.get(index)?;
        let mut read = [sample.pose.x, sample.pose.z, sample.pose.psi];
        let channels = read
            .iter_mut()
            .zip(self.runs.iter_mut().zip(&mut self.tally));
        for (c, (value, (cached, tally))) in channels.enumerate() {
            let run = match cached {
                Some(run) if (run.start..run.end).contains(&index) => *run,
                _ => {
                    let run = Run::around(path, index, c, *value);
                    if let Reading::Interpolated([(_, v0), (_, v1)]) = run.reading {
                        tally.steps += libm::fabs(v1 - v0);
                        tally.runs = tally.runs.saturating_add(1);
                    }
                    *cached.insert(run)
                }
            };
            tally.reads = tally.reads.saturating_add(1);
            if run.end - run.start >= MIN_RUN {
                tally.in_runs = tally.in_runs.saturating_add(1);
            }
            *value = run.read(sample.time, *value)?;
        }
        let [x, z, psi] = read;
        Some(Pose::new(x, z, psi))
    }

    /// The resolution the reads met, per channel (x [m], z [m], psi
    /// [rad]): the mean step between the crossings of the interpolated
    /// runs (a quantizer's step) of a channel with at least half its reads
    /// in runs; 0 for any other channel.
    pub fn resolution(&self) -> Pose {
        let [x, z, psi] = self.tally.map(|tally| tally.resolution());
        Pose::new(x, z, psi)
    }
}

/// Proof of REQ-EST-007's reader: total, and never further from a
/// recorded reading than half the step next to it.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// Samples of the harness's path: a run of two with a reading on each
    /// side.
    const SAMPLES: usize = 4;

    /// REQ-EST-007: `read`, what [`Dequantizer::pose`] gave for
    /// `path[index]`, is `None` only for a sample with a neighbour of the
    /// same reading in some channel (a run: an unquantized sample is never
    /// left out) or beyond the path; otherwise each channel is the
    /// recorded reading when that is not finite, and else a finite number
    /// within half the largest step from it to any finite reading of the
    /// channel in the path (an interpolation lies between the midpoints
    /// to the readings before and after its run), to rounding.
    pub(super) fn check_read(
        path: &[PathSample],
        index: usize,
        read: Option<Pose>,
    ) -> Result<(), &'static str> {
        let Some(sample) = path.get(index) else {
            return if read.is_none() {
                Ok(())
            } else {
                Err("a sample beyond the path was read")
            };
        };
        let neighbours = |c: usize| {
            let value = channel(&sample.pose, c);
            let at = |j: Option<usize>| {
                j.and_then(|j| path.get(j))
                    .is_some_and(|s| channel(&s.pose, c) == value)
            };
            at(index.checked_sub(1)) || at(index.checked_add(1))
        };
        let Some(read) = read else {
            return if (0..CHANNELS).any(neighbours) {
                Ok(())
            } else {
                Err("a sample outside any run was left out")
            };
        };
        for c in 0..CHANNELS {
            let (value, got) = (channel(&sample.pose, c), channel(&read, c));
            if !value.is_finite() {
                if got.to_bits() != value.to_bits() {
                    return Err("a non-finite reading was changed");
                }
                continue;
            }
            let step = path
                .iter()
                .map(|s| channel(&s.pose, c))
                .filter(|v| v.is_finite())
                .fold(0.0f64, |step, v| step.max(libm::fabs(v - value)));
            let slack = 4.0 * f64::EPSILON * (libm::fabs(value) + step);
            if !(got.is_finite() && libm::fabs(got - value) <= 0.5 * step + slack) {
                return Err("a reading moved further than half a step");
            }
        }
        Ok(())
    }

    /// A channel's reading: one of three cells of a 4 mm quantizer (so
    /// that runs, steps and turns occur), or NaN or an infinity. Any other
    /// finite reading is the proptest's below: with any `f64` the proof
    /// did not finish in 618 s.
    fn any_reading() -> f64 {
        match kani::any::<u8>() % 6 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            cell => 0.004 * f64::from(cell - 3),
        }
    }

    /// REQ-EST-007: for any path of up to [`SAMPLES`] samples 10 ms apart
    /// whose psi readings are quantized, NaN or infinite, and any index, the reader returns without a panic and
    /// its reading meets [`check_read`]. x and z change every sample (read
    /// as recorded): the three channels share one code path, `channel(c)`,
    /// and one symbolic channel keeps the proof within 10 min (three did
    /// not finish in 619 s). Unwind 7: the crossings' finiteness check goes
    /// over six numbers, the run's scans and the check's folds over at
    /// most the path.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(7))]
    pub(super) fn verify_req_est_007_the_reader_is_total_and_within_half_a_step() {
        let mut path = [PathSample::default(); SAMPLES];
        for (i, sample) in path.iter_mut().enumerate() {
            sample.time = 0.01 * i as f64;
            let s = i as f64;
            sample.pose = Pose::new(1e-3 * s, -1e-3 * s, any_reading());
        }
        let len = usize::from(kani::any::<u8>()) % (SAMPLES + 1);
        let index = usize::from(kani::any::<u8>()) % (SAMPLES + 1);
        let path = &path[..len];
        let read = Dequantizer::new().pose(path, index);
        assert_eq!(check_read(path, index, read), Ok(()));
        let moved = read.zip(path.get(index)).is_some_and(|(r, s)| r != s.pose);
        kani::cover!(moved, "reader: a reading interpolated");
        kani::cover!(read.is_none() && index < len, "reader: a sample left out");
        kani::cover!(
            read.zip(path.get(index)).is_some_and(|(r, s)| r == s.pose),
            "reader: a reading as recorded"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "dequantizer",
                20_000,
                verify_req_est_007_the_reader_is_total_and_within_half_a_step,
            );
        }

        proptest! {
            /// REQ-EST-007: over a quantized ramp with noise before the
            /// quantizer (so that readings chatter at the cell
            /// boundaries), glitches and non-finite readings, every read
            /// of every sample meets [`check_read`], with one reader read
            /// in order, as the refinement's passes read.
            #[test]
            fn req_est_007_every_read_is_within_half_a_step(
                rate in -0.01f64..0.01,
                step in 0.0005f64..0.01,
                noise in proptest::collection::vec(-0.002f64..0.002, 60),
                spoiled in proptest::collection::vec((0usize..60, 0usize..3, prop_oneof![Just(f64::NAN), Just(f64::INFINITY), -1.0f64..1.0]), 0..4),
            ) {
                let mut path: heapless::Vec<PathSample, 60> = (0..60)
                    .map(|i| {
                        let t = 0.01 * i as f64;
                        let q = |v: f64| libm::round(v / step) * step;
                        let v = rate * i as f64 + noise[i] * step;
                        PathSample {
                            time: t,
                            pose: Pose::new(q(v), q(0.5 * v), q(-v)),
                            ..PathSample::default()
                        }
                    })
                    .collect();
                for (i, c, value) in spoiled {
                    let pose = &mut path[i].pose;
                    match c {
                        0 => pose.x = value,
                        1 => pose.z = value,
                        _ => pose.psi = value,
                    }
                }
                let mut reader = Dequantizer::new();
                for index in 0..=path.len() {
                    let read = reader.pose(&path, index);
                    prop_assert_eq!(check_read(&path, index, read), Ok(()));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path_of(values: impl Fn(f64) -> Pose, samples: usize) -> heapless::Vec<PathSample, 512> {
        (0..samples)
            .map(|i| {
                let time = i as f64 * 0.01;
                PathSample {
                    time,
                    pose: values(time),
                    ..PathSample::default()
                }
            })
            .collect()
    }

    fn round(value: f64, step: f64) -> f64 {
        libm::round(value / step) * step
    }

    /// REQ-EST-007: a path whose readings change every sample is read as
    /// recorded, and has no resolution.
    #[test]
    fn req_est_007_an_unquantized_path_is_read_as_recorded() {
        let path = path_of(
            |t| Pose::new(0.1 * t, 0.05 * libm::sin(t), 0.3 * t * t),
            200,
        );
        let mut reader = Dequantizer::new();
        for (index, sample) in path.iter().enumerate() {
            assert_eq!(reader.pose(&path, index), Some(sample.pose));
        }
        assert_eq!(reader.pose(&path, path.len()), None);
        assert_eq!(reader.resolution(), Pose::new(0.0, 0.0, 0.0));
    }

    /// REQ-EST-007: ramps read to a step (4 mm, 1 mm, 0.014 rad) are read
    /// back within a tenth of it (half a step as recorded), and the steps
    /// are the resolution.
    #[test]
    fn req_est_007_a_staircase_is_read_within_a_tenth_of_its_step() {
        // A ramp read to 4 mm (x), a slower one to 1 mm (z), psi to 0.014 rad.
        let truth = |t: f64| Pose::new(0.03 * t, 0.004 * t, 0.2 * t);
        let (step, fine, angle) = (0.004, 0.001, 0.014);
        let path = path_of(
            |t| {
                let p = truth(t);
                Pose::new(round(p.x, step), round(p.z, fine), round(p.psi, angle))
            },
            300,
        );
        let mut reader = Dequantizer::new();
        let mut worst = [0.0f64; 3];
        let mut raw = 0.0f64;
        // Away from the ends, where runs have no crossing on one side.
        for index in 30..270 {
            let read = reader.pose(&path, index).expect("in the path");
            let true_pose = truth(path[index].time);
            worst[0] = worst[0].max((read.x - true_pose.x).abs() / step);
            worst[1] = worst[1].max((read.z - true_pose.z).abs() / fine);
            worst[2] = worst[2].max((read.psi - true_pose.psi).abs() / angle);
            raw = raw.max((path[index].pose.x - true_pose.x).abs() / step);
        }
        assert!(raw > 0.45, "the staircase is off by half a step: {raw}");
        for (channel, error) in worst.iter().enumerate() {
            assert!(*error < 0.1, "channel {channel}: {error} of a step");
        }
        let resolution = reader.resolution();
        let steps = [
            (resolution.x, step),
            (resolution.z, fine),
            (resolution.psi, angle),
        ];
        for (seen, step) in steps {
            assert!((seen - step).abs() < 1e-9, "{seen} for a step of {step}");
        }
    }

    /// REQ-EST-007: a run the channel turns in, one at rest longer than
    /// `MAX_RUN` and one at the path's end are not known within their cell.
    #[test]
    fn req_est_007_a_turn_within_a_cell_a_rest_and_the_ends_are_not_known() {
        // x rises and turns back inside one 4 mm cell (samples 118-182);
        // psi rests for longer than MAX_RUN, then rises in 0.1 rad steps (a
        // run of 10 samples), the last one at the path's end.
        let path = path_of(
            |t| {
                let x = round(0.02 * (1.0 - (t - 1.5).powi(2)), 0.004);
                Pose::new(x, 0.001 * t, round((t - 3.0).max(0.0), 0.1))
            },
            MAX_RUN + 155,
        );
        let mut reader = Dequantizer::new();
        let unknown: heapless::Vec<usize, 512> = (0..path.len())
            .filter(|&index| reader.pose(&path, index).is_none())
            .collect();
        // The turn's run, then the rest (0..=300, psi), and the last run.
        assert!(unknown.iter().any(|i| (118..182).contains(i)));
        assert!((119..181).all(|i| unknown.contains(&i)));
        assert!((0..=300).all(|i| unknown.contains(&i)));
        assert!(!unknown.contains(&310));
        assert!(unknown.contains(&(path.len() - 1)));
    }
}
