//! `shoulder_drift`: the shoulder (trunk) is not fixed: it is a mass of
//! [`TRUNK_MASS`] on a critically damped spring of stiffness `k` [N/m]
//! (damping 2·sqrt(k·m)), driven by the force F the robot applies to the
//! arm (x, z), so that at rest it sits displaced by F / k:
//!
//! ```text
//! m s̈ + 2 sqrt(k m) ṡ + k s = F
//! ```
//!
//! integrated with the plant's semi-implicit Euler step, F being the
//! robot's force of that step. The whole arm moves with the shoulder (the
//! table constraint q1 ≥ 0 is relative to it); the robot sees the
//! displaced grasp and its velocity, not the shoulder's acceleration.
//! While the elbow rests on the table (q1 = 0) the table holds the arm and
//! the shoulder's state (offset and velocity) is held; it only evolves
//! while the elbow is off the table.
//!
//! The mass, the critical damping, the gate and the velocity being held
//! were fitted to the shared log of an independent implementation
//! (`sim/README.md`); the effect keeps its single parameter `k`.

use super::Parameter;

/// Parameters: k [N/m].
pub const PARAMETERS: [Parameter; 1] = [Parameter::new(
    "k",
    "N/m",
    100.0,
    1.0e6,
    "shoulder support stiffness",
)];

/// Mass of the yielding trunk [kg].
pub const TRUNK_MASS: f64 = 5.0;

/// Yielding shoulder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShoulderDrift {
    /// Stiffness [N/m].
    pub k: f64,
}

impl ShoulderDrift {
    /// Critical damping of the trunk, 2·sqrt(k·m) [N s/m].
    pub fn damping(&self) -> f64 {
        2.0 * libm::sqrt(self.k * TRUNK_MASS)
    }

    /// Static shoulder displacement [m] under robot force `force` (x, z)
    /// [N]: F / k.
    pub fn displacement(&self, force: [f64; 2]) -> [f64; 2] {
        [force[0] / self.k, force[1] / self.k]
    }

    /// Advances the shoulder's `offset` [m] and `velocity` [m/s] (x, z) by
    /// one semi-implicit Euler step of `dt` [s] under the robot's force
    /// `force` (x, z) [N]: velocity first, then offset.
    pub fn advance(
        &self,
        force: [f64; 2],
        offset: &mut [f64; 2],
        velocity: &mut [f64; 2],
        dt: f64,
    ) {
        let damping = self.damping();
        for i in 0..2 {
            let acceleration = (force[i] - self.k * offset[i] - damping * velocity[i]) / TRUNK_MASS;
            velocity[i] += acceleration * dt;
            offset[i] += velocity[i] * dt;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ShoulderDrift;

    #[test]
    fn settles_critically_damped_on_the_static_displacement() {
        let drift = ShoulderDrift { k: 1000.0 };
        let force = [20.0, -10.0];
        let (mut s, mut v) = ([0.0; 2], [0.0; 2]);
        let mut previous = 0.0;
        for _ in 0..4000 {
            drift.advance(force, &mut s, &mut v, 0.0005);
            // Critically damped from rest: monotone, no overshoot.
            assert!(s[0] >= previous && s[0] <= 0.02 + 1e-12);
            previous = s[0];
        }
        let target = drift.displacement(force);
        assert!((s[0] - target[0]).abs() < 1e-9 && (s[1] - target[1]).abs() < 1e-9);
    }
}
