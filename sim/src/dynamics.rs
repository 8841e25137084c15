//! Rigid-body terms of the two-link arm in its generalised coordinates
//! q = (q1, q2) (`plant.md`): q1 upper-arm elevation, q2 elbow flexion,
//! psi = q1 + q2. Each link's mass is spread as its
//! [`crate::params::MassDistribution`] says (plant.md: uniform rods).

use crate::params::ArmParameters;

/// 2-vector.
pub type Vec2 = [f64; 2];
/// 2×2 matrix, row-major.
pub type Mat2 = [[f64; 2]; 2];
/// 3×2 matrix (pose x, z, psi by q1, q2), row-major.
pub type Mat32 = [[f64; 2]; 3];

/// Terms of the equations of motion at one state.
#[derive(Clone, Copy, Debug)]
pub struct ArmTerms {
    /// Mass matrix M(q).
    pub mass: Mat2,
    /// Coriolis and centrifugal C(q, q̇).
    pub coriolis: Vec2,
    /// Gravity g_h(q).
    pub gravity: Vec2,
    /// Grasp pose (x, z, psi) [m, m, rad].
    pub pose: [f64; 3],
    /// Jacobian J = ∂pose/∂q.
    pub jacobian: Mat32,
    /// J̇ q̇.
    pub jacobian_rate: [f64; 3],
}

/// The terms for arm `a` at q, q̇.
pub fn arm_terms(a: &ArmParameters, q: Vec2, qd: Vec2) -> ArmTerms {
    arm_terms_with_rod(a, q, qd, a.forearm_length)
}

/// The terms for arm `a` at q, q̇ whose forearm's mass is spread over
/// `rod` [m] (centre of mass at `centre` rod, inertia m2 rod² / d by the
/// forearm's distribution) while the grasp is at the forearm length
/// (`effects::cuff_offset`); [`arm_terms`] is `rod` = the forearm length.
pub fn arm_terms_with_rod(a: &ArmParameters, q: Vec2, qd: Vec2, rod: f64) -> ArmTerms {
    let (l1, l2, m1, m2, g) = (
        a.upper_arm_length,
        a.forearm_length,
        a.upper_arm_mass,
        a.forearm_mass,
        a.gravity,
    );
    let (d1, d2) = (a.upper_arm_distribution, a.forearm_distribution);
    let (c1, c2) = (l1 * d1.centre, rod * d2.centre);
    let (i1, i2) = (
        m1 * l1 * l1 / d1.inertia_divisor,
        m2 * rod * rod / d2.inertia_divisor,
    );
    let psi = q[0] + q[1];
    let (s1, co1) = (libm::sin(q[0]), libm::cos(q[0]));
    let (sp, cp) = (libm::sin(psi), libm::cos(psi));
    let (s2, co2) = (libm::sin(q[1]), libm::cos(q[1]));
    let m11 = i1 + m1 * c1 * c1 + i2 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * co2);
    let m12 = i2 + m2 * (c2 * c2 + l1 * c2 * co2);
    let m22 = i2 + m2 * c2 * c2;
    let h = m2 * l1 * c2 * s2;
    let psid = qd[0] + qd[1];
    ArmTerms {
        mass: [[m11, m12], [m12, m22]],
        coriolis: [
            -h * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]),
            h * qd[0] * qd[0],
        ],
        gravity: [
            m1 * g * c1 * co1 + m2 * g * (l1 * co1 + c2 * cp),
            m2 * g * c2 * cp,
        ],
        pose: [l1 + l2 - l1 * co1 - l2 * cp, l1 * s1 + l2 * sp, psi],
        jacobian: [
            [l1 * s1 + l2 * sp, l2 * sp],
            [l1 * co1 + l2 * cp, l2 * cp],
            [1.0, 1.0],
        ],
        jacobian_rate: [
            l1 * co1 * qd[0] * qd[0] + l2 * cp * psid * psid,
            -l1 * s1 * qd[0] * qd[0] - l2 * sp * psid * psid,
            0.0,
        ],
    }
}

/// J v for a 3×2 J.
pub fn apply(j: &Mat32, v: Vec2) -> [f64; 3] {
    [
        j[0][0] * v[0] + j[0][1] * v[1],
        j[1][0] * v[0] + j[1][1] * v[1],
        j[2][0] * v[0] + j[2][1] * v[1],
    ]
}

/// Jᵀ f for a 3×2 J.
pub fn apply_transpose(j: &Mat32, f: [f64; 3]) -> Vec2 {
    [
        j[0][0] * f[0] + j[1][0] * f[1] + j[2][0] * f[2],
        j[0][1] * f[0] + j[1][1] * f[1] + j[2][1] * f[2],
    ]
}
