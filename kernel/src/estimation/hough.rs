//! Bounded Hough transform for circles (paper Algorithm 1, redesigned).
//!
//! # Theory of operation
//! The paper votes, for every sample and every 1 mm step of the centre's x
//! along the sample's normal (eq. 18), into a 3-D accumulator over
//! (r, s, t) with 1 mm cells and r ≤ 500 mm: 500 × 1000 × 1000 cells and
//! 1000 votes per sample. Every sample's normal passes through the true
//! centre, so the cell that wins is where the normals of many samples meet.
//!
//! Here each vote is that meeting point computed directly: the intersection
//! of two lines through the centre (a *centre line*):
//!
//! * grasp path (phase 1): the normal of sample i given its measured psi,
//!   eq. 18 (the forearm direction, grasp → elbow), paired with the normal of
//!   sample i + n/2;
//! * elbow path (phase 2, no angle measured): the perpendicular bisectors of
//!   the chords (i, i + n/3) and (i + n/3, i + 2n/3).
//!
//! Each intersection is a candidate circle (centre, radius = mean distance to
//! its samples). Candidates vote into a 1-D radius accumulator with the
//! paper's 1 mm cells up to [`MAX_RADIUS`]; the winner is the cell with the
//! most votes in a window of 2 × [`PEAK_HALF_WIDTH`] + 1 cells, the coarse
//! radius its vote centroid. The fine stage
//! averages the candidates within ±[`FINE_WINDOW`] of the winning radius,
//! then once more within ±[`FINE_WINDOW`] of that average; the centre is the
//! average centre of the same candidates.
//!
//! # Bounds (fixed at compile time)
//! For a phase of n ≤ [`crate::path::PATH_CAPACITY`] samples:
//! * votes: V ≤ n/2 (normals) or ≤ n/3 (chords), at most [`MAX_VOTES`]
//!   = 2 048 (checked at compile time to fit the u16 cells);
//! * work: 3 passes over the votes (vote, coarse-to-fine twice), each vote
//!   ≈ 40 flops and one `sqrt`; plus one scan of the accumulator with a
//!   sliding window (2 × [`BINS`] additions): ≤ 3 × 2 048 × 40 + 1 002 ≈
//!   2.5 × 10⁵ flops in the worst case;
//! * memory: the accumulator, [`ACCUMULATOR_BYTES`] = [`BINS`] × 2 = 1 002
//!   bytes of stack, and
//!   O(1) besides; no copy of the path.
//!
//! # Resolution
//! On noise-free arcs the votes are exact up to rounding, so the result is
//! exact to ≈ 1e-9 m, far inside the 1 mm grid of the paper; with noise the
//! fine stage averages the votes of the peak instead of returning the cell
//! centre, so the result is not quantised to the grid.

use super::circle::{Circle, CircleFitError};
use crate::geometry::Point;
use crate::path::PATH_CAPACITY;

/// Largest radius voted for [m]: the paper's ρ = 500 mm (eq. 17).
pub(super) const MAX_RADIUS: f64 = 0.5;
/// Radius cell width [m]: the paper's 1 mm grid (eq. 16).
pub(super) const CELL: f64 = 1.0e-3;
/// Number of radius cells: 0..=500 mm.
pub(super) const BINS: usize = 501;
/// Half-width of the window the coarse peak is searched with [cells].
pub(super) const PEAK_HALF_WIDTH: usize = 2;
/// Half-width of the fine averaging window about the peak radius [m].
pub(super) const FINE_WINDOW: f64 = 2.0e-3;
/// Most votes one transform casts: n/2 for normals, n ≤
/// [`PATH_CAPACITY`]; chords cast at most n/3.
pub const MAX_VOTES: usize = PATH_CAPACITY / 2;
// Every accumulator cell is a u16: it cannot overflow.
const _: () = assert!(MAX_VOTES <= u16::MAX as usize);
/// The radius accumulator: votes per cell.
type Accumulator = [u16; BINS];
/// Accumulator size [bytes].
pub const ACCUMULATOR_BYTES: usize = core::mem::size_of::<Accumulator>();
/// Smallest sine of the angle between two centre lines that still votes:
/// nearly parallel lines meet far away and carry no information (3°).
const MIN_LINE_SINE: f64 = 0.05;
/// Shortest chord whose bisector votes [m]: shorter chords (a resting arm)
/// give bisectors dominated by noise.
const MIN_CHORD: f64 = 5.0e-3;

/// A line through a circle's centre: a point on it and a unit direction.
#[derive(Clone, Copy)]
struct CentreLine {
    point: Point,
    direction: Point,
}

fn intersect(a: CentreLine, b: CentreLine) -> Option<Point> {
    let det = a.direction.x * b.direction.z - a.direction.z * b.direction.x;
    // Also rejects NaN.
    if libm::fabs(det) < MIN_LINE_SINE || det.is_nan() {
        return None;
    }
    let (dx, dz) = (b.point.x - a.point.x, b.point.z - a.point.z);
    let s = (dx * b.direction.z - dz * b.direction.x) / det;
    let centre = Point::new(a.point.x + s * a.direction.x, a.point.z + s * a.direction.z);
    centre.is_finite().then_some(centre)
}

fn bisector(p: Point, q: Point) -> Option<CentreLine> {
    let length = p.distance(q);
    if length < MIN_CHORD || length.is_nan() {
        return None;
    }
    Some(CentreLine {
        point: Point::new(0.5 * (p.x + q.x), 0.5 * (p.z + q.z)),
        direction: Point::new(-(q.z - p.z) / length, (q.x - p.x) / length),
    })
}

/// A candidate circle from one vote.
#[derive(Clone, Copy)]
struct Candidate {
    centre: Point,
    radius: f64,
}

/// Circle through samples that each carry their normal (phase 1):
/// `sample(i)` gives the point p and forearm elevation psi of the i-th of
/// `count` samples, and the centre lies on the line through p along
/// (cos psi, −sin psi) (eq. 18 in frame S).
///
/// # Errors
/// Fewer than three or more than [`PATH_CAPACITY`] samples, no peak (no two usable normals), non-finite
/// result.
pub fn hough_circle_normals<F>(count: usize, sample: F) -> Result<Circle, CircleFitError>
where
    F: Fn(usize) -> Option<(Point, f64)>,
{
    if count < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    if count > PATH_CAPACITY {
        return Err(CircleFitError::TooManyPoints);
    }
    let half = count / 2;
    let line = |i: usize| {
        sample(i).map(|(point, psi)| {
            let line = CentreLine {
                point,
                direction: Point::new(libm::cos(psi), -libm::sin(psi)),
            };
            (point, line)
        })
    };
    let candidates = (0..count - half).map(move |i| {
        let (p, a) = line(i)?;
        let (q, b) = line(i + half)?;
        let centre = intersect(a, b)?;
        Some(Candidate {
            centre,
            radius: 0.5 * (centre.distance(p) + centre.distance(q)),
        })
    });
    vote(candidates)
}

/// Circle through points without normals (phase 2): votes are the
/// circumcentres of the triples (i, i + n/3, i + 2n/3) of the `count`
/// points given by `point(i)`.
///
/// # Errors
/// Fewer than three or more than [`PATH_CAPACITY`] points, no peak, non-finite result.
pub fn hough_circle_chords<F>(count: usize, point: F) -> Result<Circle, CircleFitError>
where
    F: Fn(usize) -> Option<Point>,
{
    if count < 3 {
        return Err(CircleFitError::TooFewPoints);
    }
    if count > PATH_CAPACITY {
        return Err(CircleFitError::TooManyPoints);
    }
    let third = count / 3;
    let point = &point;
    let candidates = (0..count - 2 * third).map(move |i| {
        let (p, q, s) = (point(i)?, point(i + third)?, point(i + 2 * third)?);
        let centre = intersect(bisector(p, q)?, bisector(q, s)?)?;
        Some(Candidate {
            centre,
            radius: (centre.distance(p) + centre.distance(q) + centre.distance(s)) / 3.0,
        })
    });
    vote(candidates)
}

/// Accumulator cell of a radius, `None` outside 0..=MAX_RADIUS or non-finite.
fn cell(radius: f64) -> Option<usize> {
    if !(0.0..=MAX_RADIUS).contains(&radius) {
        return None;
    }
    // In range and finite, so the cast neither saturates nor wraps.
    let index = libm::round(radius / CELL) as usize;
    (index < BINS).then_some(index)
}

/// Mean centre and radius of the candidates whose radius is within
/// `window` of `radius`.
fn window_mean<I>(candidates: I, radius: f64, window: f64) -> Option<Candidate>
where
    I: Iterator<Item = Option<Candidate>>,
{
    let (n, sx, sz, sr) = candidates
        .flatten()
        .filter(|c| libm::fabs(c.radius - radius) <= window)
        .fold((0usize, 0.0, 0.0, 0.0), |(n, sx, sz, sr), c| {
            (n + 1, sx + c.centre.x, sz + c.centre.z, sr + c.radius)
        });
    (n > 0).then(|| {
        let n = n as f64;
        Candidate {
            centre: Point::new(sx / n, sz / n),
            radius: sr / n,
        }
    })
}

fn vote<I>(candidates: I) -> Result<Circle, CircleFitError>
where
    I: Iterator<Item = Option<Candidate>> + Clone,
{
    let mut accumulator: Accumulator = [0; BINS];
    for index in candidates.clone().flatten().filter_map(|c| cell(c.radius)) {
        if let Some(slot) = accumulator.get_mut(index) {
            *slot = slot.checked_add(1).ok_or(CircleFitError::TooManyPoints)?;
        }
    }
    // Sliding-window peak: votes in cells start..start + window; the coarse
    // radius is the centroid of the winning window.
    let window = 2 * PEAK_HALF_WIDTH + 1;
    let (best_start, best) = accumulator
        .windows(window)
        .enumerate()
        .map(|(start, cells)| (start, cells.iter().map(|&c| u32::from(c)).sum::<u32>()))
        .fold((0usize, 0u32), |best, current| {
            if current.1 > best.1 {
                current
            } else {
                best
            }
        });
    if best == 0 {
        return Err(CircleFitError::Degenerate);
    }
    let moment: u32 = accumulator
        .iter()
        .skip(best_start)
        .take(window)
        .zip(0u32..)
        .map(|(&c, offset)| offset * u32::from(c))
        .sum();
    let coarse = (best_start as f64 + f64::from(moment) / f64::from(best)) * CELL;
    let first =
        window_mean(candidates.clone(), coarse, FINE_WINDOW).ok_or(CircleFitError::Degenerate)?;
    let fine =
        window_mean(candidates, first.radius, FINE_WINDOW).ok_or(CircleFitError::Degenerate)?;
    let circle = Circle {
        centre: fine.centre,
        radius: fine.radius,
    };
    if circle.is_valid() {
        Ok(circle)
    } else {
        Err(CircleFitError::NonFinite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Centre lines at exactly the smallest sine still meet; a hair below
    /// it they cast no vote.
    #[test]
    fn lines_at_exactly_the_smallest_sine_meet() {
        let horizontal = CentreLine {
            point: Point::new(0.0, 0.0),
            direction: Point::new(1.0, 0.0),
        };
        let at = |sine: f64| CentreLine {
            point: Point::new(0.0, 1.0),
            direction: Point::new(libm::sqrt(1.0 - sine * sine), sine),
        };
        assert!(intersect(horizontal, at(MIN_LINE_SINE)).is_some());
        assert!(intersect(horizontal, at(MIN_LINE_SINE * (1.0 - 1e-9))).is_none());
    }
}
