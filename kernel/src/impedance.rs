//! Cartesian impedance command generator in the sagittal plane (paper 000
//! eq. 9-12, frame S).
//!
//! # Theory of operation
//! The robot should behave as a mass-spring-damper about the virtual
//! equilibrium x_d(t). Per axis i ∈ {x, z, psi}:
//!
//! ```text
//! F_i = Λ_i ẍ_d,i − D_i (ẋ_i − ẋ_d,i) − K_i (x_i − x_d,i),   D_i = 2 ζ sqrt(K_i Λ_i)
//! ```
//!
//! The inertia term uses the set-point acceleration only (inertia shaping
//! as feed-forward): a measured acceleration is too noisy to differentiate
//! twice at 1 kHz. The generator outputs the equilibrium set-point for a
//! robot whose own controller realises the impedance, and the wrench for a
//! robot that takes a wrench overlay.
//!
//! # Saturation (never silent)
//! The set-point speed is limited to `max_speed` and the wrench to
//! `max_force` (force magnitude, direction kept) and `max_torque`; each
//! saturation is flagged in [`Saturation`]. A non-finite input yields a zero
//! wrench with the `non_finite` flag, never NaN.

use crate::config::ImpedanceGains;
use crate::geometry::{Pose, PoseRate, Wrench};
use crate::motion::SetPoint;

/// Which saturations acted on one command.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Saturation {
    /// The force magnitude was limited.
    pub force: bool,
    /// The torque was limited.
    pub torque: bool,
    /// The set-point speed was limited.
    pub speed: bool,
    /// An input was not finite; the wrench was replaced by zero.
    pub non_finite: bool,
}

impl Saturation {
    /// True when any saturation acted.
    pub fn any(&self) -> bool {
        self.force || self.torque || self.speed || self.non_finite
    }
}

/// The impedance law with its limits.
///
/// # Invariants
/// Built from a checked [`crate::config::KernelConfig`]: gains positive and
/// finite, limits positive and finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpedanceLaw {
    stiffness: [f64; 3],
    damping: [f64; 3],
    inertia: [f64; 3],
    max_force: f64,
    max_torque: f64,
    max_speed: f64,
}

/// What the generator produces for one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpedanceOutput {
    /// Equilibrium set-point after speed saturation.
    pub set_point: SetPoint,
    /// Wrench to apply to the arm at the grasp [N, N, N m], saturated.
    pub wrench: Wrench,
    /// Saturations that acted.
    pub saturation: Saturation,
}

impl ImpedanceLaw {
    /// The law for `gains`, saturating at `max_force` [N], `max_torque`
    /// [N m] and set-point speed `max_speed` [m/s].
    pub fn new(gains: &ImpedanceGains, max_force: f64, max_torque: f64, max_speed: f64) -> Self {
        let mut damping = [0.0; 3];
        for (d, (k, m)) in damping
            .iter_mut()
            .zip(gains.stiffness.iter().zip(gains.inertia.iter()))
        {
            *d = 2.0 * gains.damping_ratio * libm::sqrt(k * m);
        }
        Self {
            stiffness: gains.stiffness,
            damping,
            inertia: gains.inertia,
            max_force,
            max_torque,
            max_speed,
        }
    }

    /// Damping D [N s/m, N s/m, N m s/rad].
    pub fn damping(&self) -> [f64; 3] {
        self.damping
    }

    /// The saturated command for measured pose `pose` and velocity
    /// `velocity` about `set_point`.
    pub fn command(&self, pose: Pose, velocity: PoseRate, set_point: SetPoint) -> ImpedanceOutput {
        let mut saturation = Saturation::default();
        let mut set_point = set_point;
        let speed = set_point.velocity.linear_speed();
        if speed > self.max_speed {
            let scale = self.max_speed / speed;
            set_point.velocity.x *= scale;
            set_point.velocity.z *= scale;
            saturation.speed = true;
        }
        let x = [pose.x, pose.z, pose.psi];
        let v = [velocity.x, velocity.z, velocity.psi];
        let xd = [set_point.pose.x, set_point.pose.z, set_point.pose.psi];
        let vd = [
            set_point.velocity.x,
            set_point.velocity.z,
            set_point.velocity.psi,
        ];
        let ad = [
            set_point.acceleration.x,
            set_point.acceleration.z,
            set_point.acceleration.psi,
        ];
        let mut f = [0.0; 3];
        for i in 0..3 {
            f[i] = self.inertia[i] * ad[i]
                - self.damping[i] * (v[i] - vd[i])
                - self.stiffness[i] * (x[i] - xd[i]);
        }
        let mut wrench = Wrench::new(f[0], f[1], f[2]);
        if !wrench.is_finite() {
            saturation.non_finite = true;
            return ImpedanceOutput {
                set_point,
                wrench: Wrench::ZERO,
                saturation,
            };
        }
        let force = wrench.force_magnitude();
        if force > self.max_force {
            let scale = self.max_force / force;
            wrench.fx *= scale;
            wrench.fz *= scale;
            saturation.force = true;
        }
        if libm::fabs(wrench.ty) > self.max_torque {
            wrench.ty = libm::copysign(self.max_torque, wrench.ty);
            saturation.torque = true;
        }
        ImpedanceOutput {
            set_point,
            wrench,
            saturation,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> ImpedanceLaw {
        ImpedanceLaw::new(&ImpedanceGains::default(), 45.0, 8.0, 0.1)
    }

    #[test]
    fn spring_pulls_toward_equilibrium() {
        let out = law().command(
            Pose::new(0.01, 0.0, 0.0),
            PoseRate::ZERO,
            SetPoint::hold(Pose::default()),
        );
        assert!((out.wrench.fx + 2.0).abs() < 1e-12);
        assert!(!out.saturation.any());
    }

    #[test]
    fn damping_matches_plant_md() {
        // D = 2 ζ sqrt(K Λ) = 2·2·sqrt(200·2) = 80 N s/m.
        assert!((law().damping()[0] - 80.0).abs() < 1e-12);
    }

    #[test]
    fn large_error_is_saturated_with_flag() {
        let out = law().command(
            Pose::new(1.0, 1.0, 3.0),
            PoseRate::ZERO,
            SetPoint::hold(Pose::default()),
        );
        assert!((out.wrench.force_magnitude() - 45.0).abs() < 1e-9);
        assert_eq!(out.wrench.ty, -8.0);
        assert!(out.saturation.force && out.saturation.torque);
    }

    #[test]
    fn damping_opposes_motion_relative_to_the_set_point() {
        let out = law().command(
            Pose::default(),
            PoseRate::new(0.01, -0.02, 0.0),
            SetPoint::hold(Pose::default()),
        );
        // F = −D (v − v_d): D = 80 N s/m → (−0.8 N, +1.6 N).
        assert!((out.wrench.fx + 0.8).abs() < 1e-12);
        assert!((out.wrench.fz - 1.6).abs() < 1e-12);
        let tracking = law().command(
            Pose::default(),
            PoseRate::new(0.01, -0.02, 0.0),
            SetPoint {
                pose: Pose::default(),
                velocity: PoseRate::new(0.01, -0.02, 0.0),
                acceleration: PoseRate::new(0.5, 0.0, 0.0),
            },
        );
        // Tracking the set-point velocity leaves only the inertia term Λ ẍ_d.
        assert!((tracking.wrench.fx - 1.0).abs() < 1e-12 && tracking.wrench.fz.abs() < 1e-12);
    }

    #[test]
    fn set_point_speed_is_limited_with_flag() {
        let fast = SetPoint {
            pose: Pose::default(),
            velocity: PoseRate::new(0.3, 0.4, 0.0),
            acceleration: PoseRate::ZERO,
        };
        let out = law().command(Pose::default(), PoseRate::new(0.3, 0.4, 0.0), fast);
        assert!((out.set_point.velocity.linear_speed() - 0.1).abs() < 1e-12);
        assert!((out.set_point.velocity.x - 0.06).abs() < 1e-12);
        assert!(out.saturation.speed && out.saturation.any());
        let at_limit = SetPoint {
            velocity: PoseRate::new(0.1, 0.0, 0.0),
            ..fast
        };
        let out = law().command(Pose::default(), PoseRate::ZERO, at_limit);
        assert!(!out.saturation.speed && !out.saturation.any());
    }

    #[test]
    fn force_exactly_at_the_limit_is_not_flagged() {
        // K = 200 N/m: an error of 0.225 m gives exactly 45 N.
        let out = law().command(
            Pose::new(0.225, 0.0, 0.8),
            PoseRate::ZERO,
            SetPoint::hold(Pose::default()),
        );
        assert_eq!(out.wrench.fx, -45.0);
        assert_eq!(out.wrench.ty, -8.0);
        assert!(!out.saturation.force && !out.saturation.torque);
    }

    #[test]
    fn any_saturation_counts() {
        let none = Saturation::default();
        assert!(!none.any());
        for flagged in [
            Saturation {
                force: true,
                ..none
            },
            Saturation {
                torque: true,
                ..none
            },
            Saturation {
                speed: true,
                ..none
            },
            Saturation {
                non_finite: true,
                ..none
            },
        ] {
            assert!(flagged.any(), "{flagged:?}");
        }
    }

    #[test]
    fn non_finite_gives_zero_wrench() {
        let out = law().command(
            Pose::new(f64::NAN, 0.0, 0.0),
            PoseRate::ZERO,
            SetPoint::hold(Pose::default()),
        );
        assert_eq!(out.wrench, Wrench::ZERO);
        assert!(out.saturation.non_finite);
    }
}
