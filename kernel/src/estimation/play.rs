//! Play in the pitch reading (backlash between the forearm and the robot's
//! psi), read along the upper-arm phase.
//!
//! # Theory of operation
//! Play of width w [rad] between the forearm and the robot's pitch
//! reading makes psi lag the forearm by w/2 in the direction it moves:
//! w/2 below it while it rises, w/2 above while it falls; at a turn the
//! reading stands still until the play is taken up. The forearm phase
//! lifts the forearm (psi rises throughout), so the grasp pitch offset δ
//! measured there absorbs the rising lag. What is left is a step of w at
//! each turn of psi in the upper-arm phase: the elbow points of a falling
//! stretch lie l2 · w off those of a rising one, which a fixed circle
//! reads as a residual bias (1.2-2.1 mm for 0.018-0.031 rad on
//! `plant.md`'s lift, whose psi turns twice at 18-22 s).
//!
//! [`PlayReader`] follows the direction of psi along a phase read in
//! order, with a hysteresis of [`HYSTERESIS`]: it rises until psi falls
//! [`HYSTERESIS`] below the highest reading since it began to rise, then
//! falls until psi rises [`HYSTERESIS`] above the lowest. The refinement
//! reads a sample's psi less a share of w, w a fourth Gauss-Newton
//! parameter of the upper-arm fits (`super::refine`; taken as 0 unless
//! the path shows it above its noise, `refine::PLAY_SIGNIFICANCE`): none
//! while rising, all of it while
//! falling. The samples from a turn (the extremum) up to the one that
//! switches the direction lie in the play's dead band (the forearm turned,
//! the reading has followed by an unknown part of w): their share is
//! interpolated in time between the extremum's and the switching
//! sample's (the forearm turns through the play while the reading stands
//! still; a path without play reads them as recorded, so none is lost). A
//! turn is found by looking ahead at most [`MAX_TURN`] samples; one that
//! is not confirmed within them (an arm at rest) is no turn. A turn within
//! the play (the forearm goes back by less than w + [`HYSTERESIS`]) moves
//! no reading and is not seen.
//!
//! The hysteresis is 10 × the pitch noise of `plant.md` (1 mrad), so that
//! noise at rest does not flip the direction (at 4 mrad it did, on one
//! hold in three), and below the smallest play it is meant to read
//! (15 mrad).
//!
//! # Bounds
//! One comparison per sample read; a sample whose turn is not yet decided
//! looks ahead at most [`MAX_TURN`] samples (comparisons only), which
//! decides every sample up to the one where the look ended. A pass that
//! reads a phase in order looks at each sample at most twice.

use crate::path::PathSample;

/// Fall (or rise) of psi beyond its extremum that switches the reader's
/// direction [rad].
pub const HYSTERESIS: f64 = 0.010;
/// Most samples a turn is looked for ahead of the sample read: 2.56 s at
/// the recording rate.
pub const MAX_TURN: usize = 256;

/// The direction psi moves in, as the reader follows it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Direction {
    /// Rising (or not yet seen to fall): read as recorded.
    #[default]
    Rising,
    /// Falling: read less the play.
    Falling,
}

impl Direction {
    /// The share of the play a reading in this direction is read less.
    fn share(self) -> f64 {
        match self {
            Direction::Rising => 0.0,
            Direction::Falling => 1.0,
        }
    }
}

/// Follows psi's direction along one pass over a phase (module doc). A
/// new reader for each pass; the samples are read in order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlayReader {
    direction: Direction,
    /// The highest psi since rising began, or the lowest since falling
    /// began [rad], and its time [s]; `None` before the first finite
    /// reading.
    extremum: Option<(f64, f64)>,
    /// Samples up to (not including) `.0` are decided: in a turn that
    /// switches at time `.1` [s], or (`None`) in none.
    decided: Option<(usize, Option<f64>)>,
}

impl PlayReader {
    /// A reader at the start of a pass: rising (the forearm phase before
    /// it lifts the forearm).
    pub fn new() -> Self {
        Self::default()
    }

    /// The share of the play `path[index]`'s psi is read less (read after
    /// the earlier samples the pass reads, in order: the refinement passes
    /// over isolated outliers): 0 while psi rises, 1 while it falls, and
    /// within a turn's dead band the share interpolated in time from the
    /// extremum (the old direction's) to the sample that switches (the
    /// new one's); `None` beyond the path. A non-finite psi keeps the
    /// direction (and is left out by the fits, which take finite points
    /// only).
    pub fn read(&mut self, path: &[PathSample], index: usize) -> Option<f64> {
        let sample = path.get(index)?;
        let psi = sample.pose.psi;
        if !psi.is_finite() {
            return Some(self.direction.share());
        }
        let (extremum, _) = *self.extremum.get_or_insert((psi, sample.time));
        if self.beyond(psi, extremum) {
            self.extremum = Some((psi, sample.time));
        } else if self.switches(psi, extremum) {
            self.direction = match self.direction {
                Direction::Rising => Direction::Falling,
                Direction::Falling => Direction::Rising,
            };
            self.extremum = Some((psi, sample.time));
        }
        let switch = match self.decided {
            Some((until, switch)) if index < until => switch,
            _ => {
                let decided = self.look_ahead(path, index);
                self.decided = Some(decided);
                decided.1
            }
        };
        let from = self.direction.share();
        Some(match (switch, self.extremum) {
            (Some(switch), Some((_, turned))) => {
                let along = (sample.time - turned) / (switch - turned);
                // Times not increasing or not finite: half the play.
                let along = if along.is_finite() {
                    along.clamp(0.0, 1.0)
                } else {
                    0.5
                };
                from + (1.0 - 2.0 * from) * along
            }
            _ => from,
        })
    }

    /// True when `psi` goes past the extremum in the direction of motion.
    fn beyond(&self, psi: f64, extremum: f64) -> bool {
        match self.direction {
            Direction::Rising => psi > extremum,
            Direction::Falling => psi < extremum,
        }
    }

    /// True when `psi` lies [`HYSTERESIS`] back from the extremum.
    fn switches(&self, psi: f64, extremum: f64) -> bool {
        match self.direction {
            Direction::Rising => psi < extremum - HYSTERESIS,
            Direction::Falling => psi > extremum + HYSTERESIS,
        }
    }

    /// Whether the samples from `index` on lie in a turn: the first later
    /// sample (within [`MAX_TURN`]) that goes past the current extremum
    /// says no, the first that switches the direction says yes; neither
    /// (the path or the look ends) says no; a non-finite reading is passed
    /// over. Returns the first sample not decided by the look, and the
    /// switching sample's time when it is a turn.
    fn look_ahead(&self, path: &[PathSample], index: usize) -> (usize, Option<f64>) {
        let Some((extremum, _)) = self.extremum else {
            return (index.saturating_add(1), None);
        };
        let first = index.saturating_add(1);
        let end = first.saturating_add(MAX_TURN).min(path.len());
        for (j, sample) in path.iter().enumerate().take(end).skip(first) {
            let psi = sample.pose.psi;
            // A non-finite reading decides nothing (−∞ would "switch").
            if !psi.is_finite() {
                continue;
            }
            if self.beyond(psi, extremum) {
                return (j, None);
            }
            if self.switches(psi, extremum) {
                return (j, Some(sample.time));
            }
        }
        (end.max(first), None)
    }
}

/// Proof of REQ-EST-009's reader: total, a share of the play in [0, 1],
/// and some of it only after psi went back by more than the hysteresis.
#[cfg(any(test, kani))]
mod verification {
    use super::*;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// Samples of the harness's path.
    const SAMPLES: usize = 3;

    /// REQ-EST-009: `reads[i]`, what one reader gave reading `path` in
    /// order (`i` up to one beyond it), is `None` exactly beyond the path;
    /// within it a share in [0, 1], above 0 only where a finite reading at
    /// or before the sample lies more than [`HYSTERESIS`] above a later
    /// finite one (psi went back, or is about to: a turn). So a psi that
    /// never falls back is read as recorded.
    pub(super) fn check_reads(
        path: &[PathSample],
        reads: &[Option<f64>],
    ) -> Result<(), &'static str> {
        let psi = |i: usize| path.get(i).map(|s| s.pose.psi).filter(|p| p.is_finite());
        for (i, read) in reads.iter().enumerate() {
            let Some(share) = *read else {
                return if i < path.len() {
                    Err("a sample of the path was not read")
                } else {
                    Ok(())
                };
            };
            if i >= path.len() {
                return Err("a sample beyond the path was read");
            }
            if !(0.0..=1.0).contains(&share) {
                return Err("a share outside [0, 1]");
            }
            let falls_back = (0..=i).any(|k| {
                (k + 1..path.len())
                    .any(|j| psi(j).zip(psi(k)).is_some_and(|(j, k)| j < k - HYSTERESIS))
            });
            if share > 0.0 && !falls_back {
                return Err("a share of the play without psi going back");
            }
        }
        Ok(())
    }

    /// A psi reading: NaN, an infinity or one of five levels 6 mrad apart
    /// (so that falls of less and more than [`HYSTERESIS`], turns and
    /// switches occur). Any other finite reading is the proptest's below:
    /// with any `f64` the proof did not finish in 609 s (7.6 GiB).
    fn any_reading() -> f64 {
        match kani::any::<u8>() % 8 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            level => 0.006 * f64::from(level - 3),
        }
    }

    /// REQ-EST-009: for any path of up to [`SAMPLES`] samples 10 ms apart
    /// whose psi readings are such levels, NaN or infinite, one reader
    /// reading it in order and one sample beyond it returns without a
    /// panic and its reads meet [`check_reads`]. Unwind 5: the reads go
    /// over at most 4 indices, the look ahead and the check's scans over
    /// at most the path.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(5))]
    pub(super) fn verify_req_est_009_the_play_reader_is_total() {
        let mut path = [PathSample::default(); SAMPLES];
        for (i, sample) in path.iter_mut().enumerate() {
            sample.time = 0.01 * i as f64;
            sample.pose.psi = any_reading();
        }
        let len = usize::from(kani::any::<u8>()) % (SAMPLES + 1);
        let path = &path[..len];
        let mut reader = PlayReader::new();
        let mut reads = [None; SAMPLES + 1];
        for (index, read) in reads.iter_mut().enumerate().take(len + 1) {
            *read = reader.read(path, index);
        }
        let reads = &reads[..=len];
        assert!(check_reads(path, reads).is_ok());
        kani::cover!(
            reads.iter().any(|r| r.is_some_and(|s| s > 0.0 && s < 1.0)),
            "play: a turn read between its directions"
        );
        kani::cover!(reads.contains(&Some(1.0)), "play: a sample read falling");
        kani::cover!(
            len == SAMPLES && reads[..len].iter().all(|r| *r == Some(0.0)),
            "play: a path read as recorded"
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::geometry::Pose;

        fn path(psi: &[f64]) -> heapless::Vec<PathSample, 64> {
            psi.iter()
                .enumerate()
                .map(|(i, &psi)| PathSample {
                    time: i as f64 * 0.01,
                    pose: Pose::new(0.0, 0.0, psi),
                    ..PathSample::default()
                })
                .collect()
        }

        fn read_all(psi: &[f64]) -> heapless::Vec<Option<f64>, 64> {
            let path = path(psi);
            let mut reader = PlayReader::new();
            (0..path.len()).map(|i| reader.read(&path, i)).collect()
        }

        /// REQ-EST-009: a rise, a turn whose reading stands still (the dead
        /// band) and falls, and a turn back up: the dead band from the
        /// extremum to the switching sample is read with the share
        /// interpolated in time, the falling stretch with all of it, and a
        /// second turn the same way back.
        #[test]
        fn req_est_009_a_turn_is_read_between_its_extremum_and_its_switch() {
            let psi = [
                0.0, 0.01, 0.02, 0.03, 0.03, 0.03, 0.025, 0.015, 0.005, -0.005, -0.005, 0.002,
                0.010, 0.020,
            ];
            let expected = [
                0.0,
                0.0,
                0.0,
                0.0, // the extremum (0.03 s): the turn begins
                0.25,
                0.5,
                0.75, // 0.025
                1.0,  // 0.015 (0.07 s): 15 mrad below the highest, switched
                1.0,
                1.0, // -0.005 (0.09 s): the lowest, and psi turns again
                2.0 / 3.0,
                1.0 / 3.0,
                0.0, // 0.010 (0.12 s): 15 mrad above the lowest
                0.0,
            ];
            let read = read_all(&psi);
            assert_eq!(read.len(), expected.len());
            for (i, (read, expected)) in read.iter().zip(expected).enumerate() {
                let read = read.expect("read");
                assert!(
                    (read - expected).abs() < 1e-9,
                    "sample {i}: {read} for {expected}"
                );
            }
        }

        /// REQ-EST-009: noise below the hysteresis never flips the direction,
        /// and a pause whose end the look cannot reach is no turn.
        #[test]
        fn req_est_009_noise_and_rest_are_no_turn() {
            let mut psi = [0.0; 40];
            for (i, p) in psi.iter_mut().enumerate() {
                *p = 0.5 + 0.004 * if i % 2 == 0 { 1.0 } else { -1.0 };
            }
            assert!(read_all(&psi).iter().all(|d| *d == Some(0.0)));
        }

        /// A non-finite reading keeps the direction and decides nothing; a
        /// read beyond the path is `None`.
        #[test]
        fn non_finite_readings_and_indices_beyond_the_path() {
            let psi = [0.0, f64::NAN, 0.02, f64::INFINITY, -0.02, -0.03];
            let path = path(&psi);
            let mut reader = PlayReader::new();
            let read: heapless::Vec<_, 8> =
                (0..path.len()).map(|i| reader.read(&path, i)).collect();
            assert_eq!(read[1], Some(0.0));
            assert_eq!(read[3], Some(0.0));
            assert_eq!(read[4], Some(1.0));
            assert_eq!(read[5], Some(1.0));
            assert_eq!(reader.read(&path, 6), None);
        }

        #[test]
        fn harness_under_the_stand_in() {
            kani::check(
                "play reader",
                20_000,
                verify_req_est_009_the_play_reader_is_total,
            );
        }

        proptest::proptest! {
            /// REQ-EST-009: over a noisy psi that rises, turns and falls at
            /// random (with non-finite readings sprinkled in), one reader
            /// read in order, as the refinement's passes read, meets
            /// [`check_reads`].
            #[test]
            fn req_est_009_every_read_meets_the_check(
                steps in proptest::collection::vec(-0.02f64..0.02, 60),
                spoiled in proptest::collection::vec((0usize..60, proptest::prop_oneof![proptest::strategy::Just(f64::NAN), proptest::strategy::Just(f64::INFINITY), proptest::strategy::Just(f64::NEG_INFINITY)]), 0..4),
            ) {
                let mut level = 0.0;
                let mut psi = [0.0; 60];
                for (p, step) in psi.iter_mut().zip(&steps) {
                    level += step;
                    *p = level;
                }
                for (i, value) in spoiled {
                    psi[i] = value;
                }
                let path = path(&psi);
                let mut reader = PlayReader::new();
                let reads: heapless::Vec<_, 61> = (0..=path.len()).map(|i| reader.read(&path, i)).collect();
                proptest::prop_assert_eq!(check_reads(&path, &reads), Ok(()));
            }
        }
    }
}
