//! The table: two unilateral constraints, q1 ≥ 0 (elbow on the table) and
//! psi = q1 + q2 ≥ 0 (forearm not below it), rows A = [[1, 0], [1, 1]].
//!
//! # Theory of operation (`plant.md`)
//! A constraint may be active only when its coordinate is at its bound
//! (within [`AT_BOUND`]) and not separating (velocity toward the table or
//! zero). Among the active sets {}, {q1}, {psi}, {q1, psi}, in that order,
//! the first whose KKT solution has non-negative constraint forces and does
//! not accelerate an at-bound inactive coordinate into the table is taken.

use crate::dynamics::{Mat2, Vec2};

/// Distance to a bound that counts as "at the bound" [rad].
pub const AT_BOUND: f64 = 1e-12;

/// Which constraints are active.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ActiveSet {
    /// q1 ≥ 0 is active.
    pub elbow: bool,
    /// psi ≥ 0 is active.
    pub forearm: bool,
}

/// The candidate sets, in the order plant.md prescribes.
pub const CANDIDATES: [ActiveSet; 4] = [
    ActiveSet {
        elbow: false,
        forearm: false,
    },
    ActiveSet {
        elbow: true,
        forearm: false,
    },
    ActiveSet {
        elbow: false,
        forearm: true,
    },
    ActiveSet {
        elbow: true,
        forearm: true,
    },
];

/// Which constraints are at their bound and not separating, for q, q̇.
pub fn at_bound(q: Vec2, qd: Vec2) -> ActiveSet {
    let psi = q[0] + q[1];
    let psid = qd[0] + qd[1];
    ActiveSet {
        elbow: q[0] <= AT_BOUND && qd[0] <= 0.0,
        forearm: psi <= AT_BOUND && psid <= 0.0,
    }
}

/// Puts the active coordinates exactly onto their bounds with zero velocity.
pub fn project(set: ActiveSet, q: &mut Vec2, qd: &mut Vec2) {
    if set.elbow {
        q[0] = 0.0;
        qd[0] = 0.0;
    }
    if set.forearm {
        q[1] = -q[0];
        qd[1] = -qd[0];
    }
}

/// Solves `mass · q̈ = rhs + Aᵀ λ` with the rows of `set` held at zero
/// acceleration; returns q̈ and λ (elbow, forearm; zero when inactive), or
/// `None` for a singular system.
pub fn solve(set: ActiveSet, mass: &Mat2, rhs: Vec2) -> Option<(Vec2, Vec2)> {
    let [[m11, m12], [m21, m22]] = *mass;
    match (set.elbow, set.forearm) {
        (false, false) => {
            let det = m11 * m22 - m12 * m21;
            (libm::fabs(det) > 0.0).then(|| {
                (
                    [
                        (m22 * rhs[0] - m12 * rhs[1]) / det,
                        (m11 * rhs[1] - m21 * rhs[0]) / det,
                    ],
                    [0.0, 0.0],
                )
            })
        }
        (true, false) => {
            // q̈1 = 0: row 2 gives q̈2, row 1 the force.
            (libm::fabs(m22) > 0.0).then(|| {
                let a2 = rhs[1] / m22;
                ([0.0, a2], [m12 * a2 - rhs[0], 0.0])
            })
        }
        (false, true) => {
            // q̈2 = −q̈1, λ acts on both rows.
            let k = m11 - m12 - m21 + m22;
            (libm::fabs(k) > 0.0).then(|| {
                let a = (rhs[0] - rhs[1]) / k;
                ([a, -a], [0.0, (m21 - m22) * a - rhs[1]])
            })
        }
        (true, true) => Some(([0.0, 0.0], [rhs[1] - rhs[0], -rhs[1]])),
    }
}

/// True when the solution respects the rules: active forces non-negative,
/// at-bound inactive coordinates not accelerated into the table.
pub fn admissible(set: ActiveSet, bound: ActiveSet, qdd: Vec2, lambda: Vec2) -> bool {
    let forces_ok = (!set.elbow || lambda[0] >= 0.0) && (!set.forearm || lambda[1] >= 0.0);
    let elbow_ok = set.elbow || !bound.elbow || qdd[0] >= 0.0;
    let forearm_ok = set.forearm || !bound.forearm || qdd[0] + qdd[1] >= 0.0;
    forces_ok && elbow_ok && forearm_ok
}

/// After integration: any coordinate that crossed its bound goes back onto
/// it with non-negative velocity, q1 first, then psi.
pub fn clamp(q: &mut Vec2, qd: &mut Vec2) {
    if q[0] < 0.0 {
        q[0] = 0.0;
        qd[0] = libm::fmax(qd[0], 0.0);
    }
    if q[0] + q[1] < 0.0 {
        q[1] = -q[0];
        let psid = libm::fmax(qd[0] + qd[1], 0.0);
        qd[1] = psid - qd[0];
    }
}
