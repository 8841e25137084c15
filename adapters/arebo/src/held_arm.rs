//! The kernel's reference arm with its wrist in AREBO's cuff: the person
//! the simulated device moves when the limb kernel runs a session on it.
//!
//! # Theory of operation
//! The arm is `plant.md`'s passive two-link arm (upper arm, forearm) lying
//! on its table, in the sagittal frame S ([`SagittalFrame`], placed in R0
//! by the device's setup): `limb_sim`'s rigid-body terms and table
//! contact, the shoulder fixed at (l1 + l2, 0). The cuff holds the wrist
//! (`plant.md`'s grasp point) through AREBO's spherical joint, so the
//! robot pushes the wrist with a force and no moment: the generalised
//! force is Jᵀ (fx, fz, 0) of the cuff force in S. The robot's moving
//! links are lumped at the cuff as `plant.md`'s robot inertia Λ (2 kg in
//! x and z, none about y: the spherical joint turns freely), added to the
//! arm's mass matrix as Jᵀ Λ J. Semi-implicit Euler at `plant.md`'s
//! 0.5 ms, contact by `plant.md`'s active-set rule (`limb_sim::contact`).
//! The cuff's roll axis z_R5 lies along the forearm, elbow → hand.

use crate::sagittal::SagittalFrame;
use limb_sim::contact::{self, CANDIDATES};
use limb_sim::dynamics::{apply_transpose, arm_terms, Vec2};
use limb_sim::ArmParameters;
use nalgebra::Vector3;

/// Integration step [s] (`plant.md`).
pub const STEP: f64 = limb_sim::sensing::STEP;
/// The robot's inertia lumped at the cuff, x and z [kg] (`plant.md`'s Λ).
pub const CUFF_INERTIA: f64 = 2.0;

/// Frame S's origin in R0 for [`HeldArm::reference`] [m]: AREBO's base
/// beside the arm, 0.35 m lateral of its plane, 0.25 m above the table and
/// 0.25 m from the wrist toward the shoulder (the wrist's lift and the
/// manipulation target stay 0.4-0.6 m from the base, clear of the
/// kinematic singularities).
pub const REFERENCE_ORIGIN: [f64; 3] = [-0.25, 0.35, -0.25];
/// Frame S's heading in R0 for [`HeldArm::reference`]: x_S = x_R0 [rad].
pub const REFERENCE_HEADING: f64 = 0.0;

/// The reference arm held at the wrist.
#[derive(Clone, Copy, Debug)]
pub struct HeldArm {
    arm: ArmParameters,
    frame: SagittalFrame,
    q: Vec2,
    qd: Vec2,
}

impl HeldArm {
    /// `arm` at rest on its table (q = 0), frame S placed by `frame`.
    pub fn new(arm: ArmParameters, frame: SagittalFrame) -> Self {
        Self {
            arm,
            frame,
            q: [0.0; 2],
            qd: [0.0; 2],
        }
    }

    /// `plant.md`'s default arm (l1 0.30 m, l2 0.20 m) placed at
    /// [`REFERENCE_ORIGIN`], [`REFERENCE_HEADING`].
    pub fn reference() -> Self {
        let origin = Vector3::from(REFERENCE_ORIGIN);
        let frame = SagittalFrame::new(origin, REFERENCE_HEADING);
        Self::new(ArmParameters::new(0.30, 0.20), frame)
    }

    /// Joint angles (shoulder elevation q1, elbow flexion q2) [rad].
    pub fn joints(&self) -> Vec2 {
        self.q
    }

    /// Grasp pose (x, z, ψ) in S.
    pub fn pose(&self) -> [f64; 3] {
        arm_terms(&self.arm, self.q, self.qd).pose
    }

    /// The wrist (cuff centre) in R0 [m].
    pub fn cuff(&self) -> Vector3<f64> {
        let [x, z, _] = self.pose();
        self.frame.origin + self.frame.from_s(&Vector3::new(x, 0.0, z))
    }

    /// The forearm axis, elbow → hand, in R0 (unit).
    pub fn forearm(&self) -> Vector3<f64> {
        let psi = self.pose()[2];
        self.frame
            .from_s(&Vector3::new(-libm::cos(psi), 0.0, libm::sin(psi)))
    }

    /// Advances `duration` [s] with the robot pushing the wrist with
    /// `force` [N, frame R0].
    pub fn advance(&mut self, force: &Vector3<f64>, duration: f64) {
        let f = self.frame.in_s(force);
        let steps = libm::round(duration / STEP).max(0.0) as usize;
        for _ in 0..steps {
            self.step([f.x, f.z, 0.0]);
        }
    }

    /// One [`STEP`] under the wrist force `f` (x, z, 0) in S.
    fn step(&mut self, f: [f64; 3]) {
        let bound = contact::at_bound(self.q, self.qd);
        let mut next = None;
        for set in CANDIDATES {
            if (set.elbow && !bound.elbow) || (set.forearm && !bound.forearm) {
                continue;
            }
            let (mut q, mut qd) = (self.q, self.qd);
            contact::project(set, &mut q, &mut qd);
            let t = arm_terms(&self.arm, q, qd);
            let mut mass = t.mass;
            for (row, mass_row) in mass.iter_mut().enumerate() {
                for (col, m) in mass_row.iter_mut().enumerate() {
                    // Λ in x and z (rows 0, 1 of J).
                    for k in 0..2 {
                        *m += t.jacobian[k][row] * CUFF_INERTIA * t.jacobian[k][col];
                    }
                }
            }
            // The cuff's inertia is accelerated with the wrist: −Λ J̇ q̇.
            let inertial = [
                f[0] - CUFF_INERTIA * t.jacobian_rate[0],
                f[1] - CUFF_INERTIA * t.jacobian_rate[1],
                0.0,
            ];
            let jf = apply_transpose(&t.jacobian, inertial);
            let rhs = [
                jf[0] - t.coriolis[0] - t.gravity[0],
                jf[1] - t.coriolis[1] - t.gravity[1],
            ];
            let Some((qdd, lambda)) = contact::solve(set, &mass, rhs) else {
                continue;
            };
            let admissible = contact::admissible(set, bound, qdd, lambda);
            next = Some((q, qd, qdd));
            if admissible {
                break;
            }
        }
        let Some((mut q, mut qd, qdd)) = next else {
            return;
        };
        for i in 0..2 {
            qd[i] += qdd[i] * STEP;
            q[i] += qd[i] * STEP;
        }
        contact::clamp(&mut q, &mut qd);
        self.q = q;
        self.qd = qd;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arm() -> HeldArm {
        let frame = SagittalFrame::new(Vector3::new(0.3, -0.2, -0.25), 0.4);
        HeldArm::new(ArmParameters::new(0.30, 0.20), frame)
    }

    #[test]
    fn unheld_it_rests_on_the_table() {
        let mut held = arm();
        let start = held.cuff();
        held.advance(&Vector3::zeros(), 1.0);
        assert_eq!(held.joints(), [0.0, 0.0]);
        assert!((held.cuff() - start).norm() < 1e-12);
        // The forearm lies along −x_S (elbow → hand, toward the wrist).
        let x = Vector3::new(libm::cos(0.4), libm::sin(0.4), 0.0);
        assert!((held.forearm() + x).norm() < 1e-12);
    }

    /// Lifted with a vertical force above the arm's weight at the wrist,
    /// the wrist rises and the forearm tips up (ψ > 0).
    #[test]
    fn lifted_at_the_wrist_it_rises() {
        let mut held = arm();
        held.advance(&Vector3::new(0.0, 0.0, 20.0), 0.3);
        let [_, z, psi] = held.pose();
        assert!(z > 0.01 && psi > 0.0, "{:?}", held.pose());
        let lift = held.cuff() - arm().cuff();
        assert!((lift.z - z).abs() < 1e-12);
    }
}
