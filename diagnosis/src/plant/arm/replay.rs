//! The commanded set-point of a log, replayed at every integration step:
//! what drives the sim is what was commanded, whatever the motion (the
//! plant.md lift, a `limb run --log` session, a KUKA session).
//!
//! # Theory of operation
//! The log gives the set-point pose x_d (`xd, zd, psid`, frame S) at its
//! rows, not its velocity or acceleration. Between rows the pose is a
//! cubic Hermite curve; the velocity and acceleration at each row are
//! the centred first and second differences limited by the monotonised
//! central limiter (second order where the motion is smooth, zero at a
//! jump — a held pose that changes in one period, as a kernel's hold
//! does), each interpolated linearly between rows. Before the first row
//! the first pose is held; a row without a command holds the pose before
//! it (what the plant does when a controller sends none).

use super::ArmError;
use limb_kernel::geometry::{Pose, PoseRate};
use limb_kernel::motion::SetPoint;
use limb_sim::log::Record;
use limb_sim::STEP;

/// One row of the commanded motion: time [s], pose, limited velocity and
/// acceleration (x, z, psi).
#[derive(Clone, Copy, Debug)]
struct Knot {
    time: f64,
    pose: [f64; 3],
    velocity: [f64; 3],
    acceleration: [f64; 3],
}

/// The set-point at every integration step up to the log's last row.
#[derive(Clone, Debug)]
pub struct Replay {
    knots: Vec<Knot>,
}

/// The argument of smallest magnitude when all share a sign, else 0.
fn minmod(values: &[f64]) -> f64 {
    let positive = values.iter().all(|v| *v > 0.0);
    let negative = values.iter().all(|v| *v < 0.0);
    let smallest = values
        .iter()
        .copied()
        .map(f64::abs)
        .fold(f64::INFINITY, f64::min);
    if positive {
        smallest
    } else if negative {
        -smallest
    } else {
        0.0
    }
}

impl Replay {
    /// The commanded motion of `records` (times already checked to be
    /// strictly increasing and finite).
    ///
    /// # Errors
    /// [`ArmError::NoCommand`] when the first row has no commanded pose:
    /// nothing says where the robot was sent.
    pub fn new(records: &[Record]) -> Result<Self, ArmError> {
        let first = records.first().ok_or(ArmError::Empty)?;
        let mut held = first.command.ok_or(ArmError::NoCommand {
            column: "xd",
            time: first.time,
        })?;
        let poses: Vec<(f64, [f64; 3])> = records
            .iter()
            .map(|r| {
                held = r.command.unwrap_or(held);
                (r.time, [held.x, held.z, held.psi])
            })
            .collect();
        // Slope of segment i (rows i → i + 1), per channel.
        let slope = |i: usize, c: usize| {
            let (a, b) = (poses[i], poses[i + 1]);
            (b.1[c] - a.1[c]) / (b.0 - a.0)
        };
        let n = poses.len();
        let velocity = |k: usize, c: usize| -> f64 {
            if k == 0 || k + 1 >= n {
                return 0.0;
            }
            let (before, after) = (slope(k - 1, c), slope(k, c));
            let central =
                (poses[k + 1].1[c] - poses[k - 1].1[c]) / (poses[k + 1].0 - poses[k - 1].0);
            minmod(&[central, 2.0 * before, 2.0 * after])
        };
        // Second difference at row k.
        let second = |k: usize, c: usize| -> f64 {
            if k == 0 || k + 1 >= n {
                return 0.0;
            }
            2.0 * (slope(k, c) - slope(k - 1, c)) / (poses[k + 1].0 - poses[k - 1].0)
        };
        let knots = (0..n)
            .map(|k| {
                let mut knot = Knot {
                    time: poses[k].0,
                    pose: poses[k].1,
                    velocity: [0.0; 3],
                    acceleration: [0.0; 3],
                };
                for c in 0..3 {
                    knot.velocity[c] = velocity(k, c);
                    let around = [
                        second(k, c),
                        2.0 * second(k.saturating_sub(1), c),
                        2.0 * second((k + 1).min(n - 1), c),
                    ];
                    knot.acceleration[c] = minmod(&around);
                }
                knot
            })
            .collect();
        Ok(Self { knots })
    }

    /// Rows of the replay.
    pub fn rows(&self) -> usize {
        self.knots.len()
    }

    /// The set-point at integration step `step` (time `step` · [`STEP`]),
    /// given the row `row` at or before it (so a pass over the steps costs
    /// no search).
    pub fn at(&self, step: usize, row: usize) -> SetPoint {
        let time = step as f64 * STEP;
        let Some(a) = self.knots.get(row) else {
            return SetPoint::default();
        };
        let pose = |p: [f64; 3]| Pose {
            x: p[0],
            z: p[1],
            psi: p[2],
        };
        let rate = |p: [f64; 3]| PoseRate {
            x: p[0],
            z: p[1],
            psi: p[2],
        };
        let Some(b) = self.knots.get(row + 1).filter(|_| time > a.time) else {
            return SetPoint {
                pose: pose(a.pose),
                velocity: rate(if time < a.time { [0.0; 3] } else { a.velocity }),
                acceleration: rate(if time < a.time {
                    [0.0; 3]
                } else {
                    a.acceleration
                }),
            };
        };
        let h = b.time - a.time;
        let s = ((time - a.time) / h).clamp(0.0, 1.0);
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) = (
            2.0 * s3 - 3.0 * s2 + 1.0,
            s3 - 2.0 * s2 + s,
            -2.0 * s3 + 3.0 * s2,
            s3 - s2,
        );
        let mut p = [0.0; 3];
        let mut v = [0.0; 3];
        let mut acc = [0.0; 3];
        for c in 0..3 {
            p[c] = h00 * a.pose[c]
                + h10 * h * a.velocity[c]
                + h01 * b.pose[c]
                + h11 * h * b.velocity[c];
            v[c] = a.velocity[c] + s * (b.velocity[c] - a.velocity[c]);
            acc[c] = a.acceleration[c] + s * (b.acceleration[c] - a.acceleration[c]);
        }
        SetPoint {
            pose: pose(p),
            velocity: rate(v),
            acceleration: rate(acc),
        }
    }

    /// The row whose time is the last at or before step `step`, starting
    /// the search at `from`.
    pub fn row_at(&self, step: usize, from: usize) -> usize {
        let time = step as f64 * STEP + STEP * 1e-6;
        let mut row = from;
        while self.knots.get(row + 1).is_some_and(|k| k.time <= time) {
            row += 1;
        }
        row
    }

    /// The set-point at every integration step from 0 to `last`.
    pub fn set_points(&self, last: usize) -> Vec<SetPoint> {
        let mut row = 0;
        (0..=last)
            .map(|step| {
                row = self.row_at(step, row);
                self.at(step, row)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::{minmod, Replay};
    use limb_kernel::geometry::Pose;
    use limb_kernel::motion::{EstimationMotion, EstimationMotionParameters};
    use limb_sim::log::Record;
    use limb_sim::STEP;

    /// The plant.md lift logged at 100 Hz with six decimals, as the shared
    /// logs are, replays within a micrometre, 1 mm/s and 0.1 m/s².
    #[test]
    fn the_lift_logged_at_100_hz_replays_at_every_step() {
        let motion =
            EstimationMotion::new(Pose::default(), &EstimationMotionParameters::default()).unwrap();
        let round = |v: f64| (v * 1e6).round() / 1e6;
        let records: Vec<Record> = (0..3000)
            .map(|k| {
                let t = k as f64 * 0.01;
                let p = motion.at(t).pose;
                Record {
                    time: t,
                    command: Some(Pose {
                        x: round(p.x),
                        z: round(p.z),
                        psi: round(p.psi),
                    }),
                    pose: p,
                    lateral: None,
                    wrench: Default::default(),
                    truth: None,
                }
            })
            .collect();
        let replay = Replay::new(&records).unwrap();
        let (mut row, mut worst) = (0, [0.0f64; 3]);
        for step in 0..59_980 {
            row = replay.row_at(step, row);
            let (a, b) = (replay.at(step, row), motion.at(step as f64 * STEP));
            let e = [
                (a.pose.x - b.pose.x)
                    .abs()
                    .max((a.pose.z - b.pose.z).abs())
                    .max((a.pose.psi - b.pose.psi).abs()),
                (a.velocity.x - b.velocity.x)
                    .abs()
                    .max((a.velocity.z - b.velocity.z).abs())
                    .max((a.velocity.psi - b.velocity.psi).abs()),
                (a.acceleration.x - b.acceleration.x)
                    .abs()
                    .max((a.acceleration.z - b.acceleration.z).abs())
                    .max((a.acceleration.psi - b.acceleration.psi).abs()),
            ];
            for (w, e) in worst.iter_mut().zip(e) {
                *w = w.max(e);
            }
        }
        eprintln!("worst pose, velocity, acceleration error: {worst:?}");
        assert!(
            worst[0] < 1e-6 && worst[1] < 1e-3 && worst[2] < 0.1,
            "{worst:?}"
        );
    }

    #[test]
    fn minmod_is_zero_across_a_sign_change_and_smallest_otherwise() {
        assert_eq!(minmod(&[1.0, -2.0]), 0.0);
        assert_eq!(minmod(&[3.0, 2.0, 4.0]), 2.0);
        assert_eq!(minmod(&[-3.0, -2.0]), -2.0);
    }
}
