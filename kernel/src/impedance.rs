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
    /// `velocity` about `set_point`: the set-point's speed limited, the
    /// law's wrench about it, the wrench limited (each flagged).
    pub fn command(&self, pose: Pose, velocity: PoseRate, set_point: SetPoint) -> ImpedanceOutput {
        let mut saturation = Saturation::default();
        let set_point = self.limit_speed(set_point, &mut saturation);
        let wrench = match self.wrench_about(pose, velocity, &set_point) {
            Some(wrench) => self.limit(wrench, &mut saturation),
            None => {
                saturation.non_finite = true;
                Wrench::ZERO
            }
        };
        ImpedanceOutput {
            set_point,
            wrench,
            saturation,
        }
    }

    /// `set_point` with its grasp-point velocity scaled down to
    /// `max_speed` when faster (direction kept; `saturation.speed` set).
    fn limit_speed(&self, set_point: SetPoint, saturation: &mut Saturation) -> SetPoint {
        let mut set_point = set_point;
        let speed = set_point.velocity.linear_speed();
        // A non-finite velocity is left as it is (never divided by: no
        // NaN is made); the law refuses it and the command is flagged
        // non-finite.
        if speed.is_finite() && speed > self.max_speed {
            let scale = self.max_speed / speed;
            set_point.velocity.x *= scale;
            set_point.velocity.z *= scale;
            saturation.speed = true;
        }
        set_point
    }

    /// The law's wrench at `pose`, `velocity` about `set_point`, before
    /// any limit; `None` when an input or one of the law's three terms of
    /// an axis is not finite. Judged term by term so that no NaN is ever
    /// made (∞ − ∞): a sum of finite terms may still overflow to ±∞, which
    /// [`Self::limit`] refuses in turn.
    pub(crate) fn wrench_about(
        &self,
        pose: Pose,
        velocity: PoseRate,
        set_point: &SetPoint,
    ) -> Option<Wrench> {
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
            let inputs = [x[i], v[i], xd[i], vd[i], ad[i]];
            if !inputs.iter().all(|value| value.is_finite()) {
                return None;
            }
            let inertia = self.inertia[i] * ad[i];
            let damping = self.damping[i] * (v[i] - vd[i]);
            let spring = self.stiffness[i] * (x[i] - xd[i]);
            if !(inertia.is_finite() && damping.is_finite() && spring.is_finite()) {
                return None;
            }
            f[i] = inertia - damping - spring;
        }
        Some(Wrench::new(f[0], f[1], f[2]))
    }

    /// `wrench` within the law's force magnitude and torque limits
    /// (scaled, not clipped per axis), each limit that acted flagged in
    /// `saturation`; zero, flagged non-finite, when anything is not finite.
    /// Also applied to a stop's own wrench ([`crate::stop`]), which may
    /// have been commanded under wider limits than the current ones.
    pub fn limit(&self, wrench: Wrench, saturation: &mut Saturation) -> Wrench {
        if !wrench.is_finite() {
            saturation.non_finite = true;
            return Wrench::ZERO;
        }
        let mut wrench = wrench;
        let force = wrench.force_magnitude();
        if force > self.max_force {
            // A magnitude that overflowed (components near f64::MAX) scales
            // the force to zero, and never divides by ∞.
            let scale = if force.is_finite() {
                self.max_force / force
            } else {
                0.0
            };
            wrench.fx *= scale;
            wrench.fz *= scale;
            // A subnormal limit loses the scaling's precision (found by
            // the kernel_sequence fuzz target at 5.4e-312 N): never above
            // the limit, zero force rather than a rounded one.
            // (Rounding of a normal limit, a few ulps, is kept.)
            if wrench.force_magnitude() > self.max_force * (1.0 + 1e-12) {
                wrench.fx = 0.0;
                wrench.fz = 0.0;
            }
            saturation.force = true;
        }
        if libm::fabs(wrench.ty) > self.max_torque {
            wrench.ty = libm::copysign(self.max_torque, wrench.ty);
            saturation.torque = true;
        }
        wrench
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

    /// REQ-CMD-002: a large error saturates force and torque, flagged.
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

/// Proofs of REQ-CMD-001 and REQ-CMD-002.
#[cfg(any(test, kani))]
pub(crate) mod verification {
    use super::*;
    use crate::config::KernelConfig;
    #[cfg(not(kani))]
    use limb_kani_stand_in as kani;

    /// Relative slack of the saturation bounds (the scaling by
    /// limit / magnitude rounds).
    const ROUNDING: f64 = 1e-12;

    /// REQ-CMD-001, REQ-CMD-002: the saturated output `out` against the
    /// output `raw` of the same law without wrench limits, same inputs:
    /// [`check_wrench_limit`], [`check_speed_limit`] and
    /// [`check_speed_bound`].
    pub(super) fn check_saturation(
        law: &ImpedanceLaw,
        inputs_finite: bool,
        raw: &ImpedanceOutput,
        out: &ImpedanceOutput,
        set_point: &SetPoint,
    ) -> Result<(), &'static str> {
        check_wrench_limit(law, inputs_finite, raw, out)?;
        check_speed_limit(set_point, out)?;
        check_speed_bound(set_point, out)
    }

    /// REQ-CMD-001: the limited wrench of `out` against the unlimited one
    /// of `raw`: finite; each force component and the torque within the
    /// limits; whatever differs from the unlimited wrench flagged; a
    /// non-finite input (`inputs_finite` false) flagged and the wrench
    /// zeroed.
    pub(super) fn check_wrench_limit(
        law: &ImpedanceLaw,
        inputs_finite: bool,
        raw: &ImpedanceOutput,
        out: &ImpedanceOutput,
    ) -> Result<(), &'static str> {
        if raw.saturation.force || raw.saturation.torque {
            return Err("the reference law without wrench limits saturated the wrench");
        }
        if !(inputs_finite || out.saturation.non_finite) {
            return Err("a non-finite input not flagged");
        }
        limit_contract(law, raw.wrench, raw.saturation, out.wrench, out.saturation)
    }

    /// REQ-CMD-002: the set-point of `out` against the one asked,
    /// `set_point`: unchanged (bit for bit) unless the speed flag is set;
    /// when it is, only the grasp point's velocity changed, and no
    /// component changed its sign. That the scaled components are not
    /// faster is arithmetic (a product's magnitude against its factor's),
    /// which no solver decides here in 10 min: [`check_speed_bound`], a
    /// property of the proptest.
    pub(super) fn check_speed_limit(
        set_point: &SetPoint,
        out: &ImpedanceOutput,
    ) -> Result<(), &'static str> {
        let ensure = |ok: bool, failure| if ok { Ok(()) } else { Err(failure) };
        let bits = |p: &SetPoint| {
            [
                p.pose.x,
                p.pose.z,
                p.pose.psi,
                p.velocity.x,
                p.velocity.z,
                p.velocity.psi,
                p.acceleration.x,
                p.acceleration.z,
                p.acceleration.psi,
            ]
            .map(f64::to_bits)
        };
        let (asked, got) = (bits(set_point), bits(&out.set_point));
        // Number by number (an array's `==` is a byte loop, memcmp, for
        // the proof); indices 3 and 4 are the grasp point's velocity (x, z).
        let kept =
            |i: usize, (a, g): (&u64, u64)| *a == g || (out.saturation.speed && (i == 3 || i == 4));
        if !asked
            .iter()
            .zip(got)
            .enumerate()
            .all(|(i, pair)| kept(i, pair))
        {
            return Err(if out.saturation.speed {
                "speed saturation changed more than the grasp velocity"
            } else {
                "the set-point changed without the speed flag"
            });
        }
        if !out.saturation.speed {
            return Ok(());
        }
        let (v, w) = (set_point.velocity, out.set_point.velocity);
        ensure(
            v.x.is_sign_negative() == w.x.is_sign_negative()
                && v.z.is_sign_negative() == w.z.is_sign_negative(),
            "speed saturation turned a velocity component round",
        )
    }

    /// REQ-CMD-002: a finite set-point's limited velocity components are
    /// no faster than the asked ones.
    pub(super) fn check_speed_bound(
        set_point: &SetPoint,
        out: &ImpedanceOutput,
    ) -> Result<(), &'static str> {
        let (v, w) = (set_point.velocity, out.set_point.velocity);
        if !v.is_finite()
            || (libm::fabs(w.x) <= libm::fabs(v.x) && libm::fabs(w.z) <= libm::fabs(v.z))
        {
            Ok(())
        } else {
            Err("speed saturation sped a finite component up")
        }
    }

    /// Whether every input of the law is finite.
    fn inputs_finite(pose: Pose, velocity: PoseRate, set_point: &SetPoint) -> bool {
        pose.is_finite()
            && velocity.is_finite()
            && set_point.pose.is_finite()
            && set_point.velocity.is_finite()
            && set_point.acceleration.is_finite()
    }

    /// REQ-CMD-001, the contract of [`ImpedanceLaw::wrench_about`]: no
    /// wrench (`None`) when an input is not finite (`inputs_finite`
    /// false), and never a NaN component. Asserted of the real law by
    /// [`verify_req_cmd_001_law_is_finite_only_on_finite_inputs`] and
    /// assumed by [`stub::wrench_about`], which the whole-kernel harnesses
    /// put in the law's place: one function, so the stub can assume no
    /// more than the proof shows.
    pub(crate) fn law_contract(
        inputs_finite: bool,
        wrench: Option<Wrench>,
    ) -> Result<(), &'static str> {
        match wrench {
            Some(_) if !inputs_finite => Err("a non-finite input made a wrench"),
            Some(w) if w.fx.is_nan() || w.fz.is_nan() || w.ty.is_nan() => Err("the law made a NaN"),
            _ => Ok(()),
        }
    }

    /// REQ-CMD-001, the contract of [`ImpedanceLaw::limit`] on `wrench`
    /// with the flags `before`, giving `limited` and the flags `after`:
    /// flags are only ever added (the speed's left alone); the limited
    /// wrench is finite, each force component within the force limit and
    /// the torque within the torque limit; a non-finite wrench is flagged
    /// and replaced by zero; a finite one keeps its non-finite flag, its
    /// force unless the force flag is set, and its torque unless the
    /// torque flag is; a force or torque within its limit is kept and
    /// not flagged. Asserted of the real limit by
    /// [`verify_req_cmd_001_wrench_limit_is_saturated_and_flagged`] (any
    /// wrench, any flags before) and assumed by [`stub::limit`].
    pub(crate) fn limit_contract(
        law: &ImpedanceLaw,
        wrench: Wrench,
        before: Saturation,
        limited: Wrench,
        after: Saturation,
    ) -> Result<(), &'static str> {
        let ensure = |ok: bool, failure| if ok { Ok(()) } else { Err(failure) };
        ensure(
            after.speed == before.speed
                && (after.force || !before.force)
                && (after.torque || !before.torque)
                && (after.non_finite || !before.non_finite),
            "the limit cleared a flag or set the speed's",
        )?;
        ensure(limited.is_finite(), "the limited wrench is not finite")?;
        let force = law.max_force * (1.0 + ROUNDING);
        ensure(
            libm::fabs(limited.fx) <= force && libm::fabs(limited.fz) <= force,
            "a force component beyond the force limit",
        )?;
        ensure(
            libm::fabs(limited.ty) <= law.max_torque,
            "torque beyond the limit",
        )?;
        if !wrench.is_finite() {
            return ensure(
                after.non_finite && limited == Wrench::ZERO,
                "a non-finite wrench not flagged and replaced by zero",
            );
        }
        ensure(
            after.non_finite == before.non_finite,
            "a finite wrench changed the non-finite flag",
        )?;
        ensure(
            after.force || (limited.fx == wrench.fx && limited.fz == wrench.fz),
            "the force changed without the force flag",
        )?;
        ensure(
            after.torque || limited.ty == wrench.ty,
            "the torque changed without the torque flag",
        )?;
        // Within the limits nothing acts (the force's magnitude is at
        // most |fx| + |fz|, whatever `hypot` rounds to).
        let force_within = libm::fabs(wrench.fx) + libm::fabs(wrench.fz) <= law.max_force;
        ensure(
            !force_within
                || (limited.fx == wrench.fx
                    && limited.fz == wrench.fz
                    && after.force == before.force),
            "a force within the limit was changed or flagged",
        )?;
        ensure(
            libm::fabs(wrench.ty) > law.max_torque
                || (limited.ty == wrench.ty && after.torque == before.torque),
            "a torque within the limit was changed or flagged",
        )
    }

    /// Kani stubs of the law, each any value its proved contract allows.
    #[cfg(kani)]
    pub(crate) mod stub {
        use super::*;

        /// Stub of [`ImpedanceLaw::limit`] by [`limit_contract`]: any
        /// wrench within the limits that the contract allows (the scaling
        /// of a symbolic force by limit / magnitude, a product the solver
        /// must bound, is the limit's own harness's).
        pub(crate) fn limit(
            law: &ImpedanceLaw,
            wrench: Wrench,
            saturation: &mut Saturation,
        ) -> Wrench {
            let before = *saturation;
            let after = Saturation {
                force: kani::any(),
                torque: kani::any(),
                speed: before.speed,
                non_finite: kani::any(),
            };
            let limited = kani::any::<Wrench>();
            kani::assume(limit_contract(law, wrench, before, limited, after).is_ok());
            *saturation = after;
            limited
        }

        /// Stub of [`ImpedanceLaw::wrench_about`] by [`law_contract`]: any
        /// wrench or none (an overflowing term) for finite inputs, none
        /// otherwise: the law's three products per axis on symbolic poses
        /// stay in its own harness, decided in seconds.
        pub(crate) fn wrench_about(
            _law: &ImpedanceLaw,
            pose: Pose,
            velocity: PoseRate,
            set_point: &SetPoint,
        ) -> Option<Wrench> {
            let wrench = if kani::any() {
                Some(kani::any::<Wrench>())
            } else {
                None
            };
            kani::assume(law_contract(inputs_finite(pose, velocity, set_point), wrench).is_ok());
            wrench
        }
    }

    /// The law of the default configuration.
    fn default_law() -> ImpedanceLaw {
        let config = KernelConfig::default();
        let l = &config.limits;
        ImpedanceLaw::new(&config.impedance, l.max_force, l.max_torque, l.max_speed)
    }

    /// REQ-CMD-001, REQ-CMD-002: for any wrench (what
    /// [`ImpedanceLaw::wrench_about`] may give) and any flags set before
    /// (the speed's, earlier in the same command), [`ImpedanceLaw::limit`]
    /// meets [`limit_contract`], which the whole-kernel harnesses assume of
    /// it (and [`check_wrench_limit`], the proptest's, is built on). With
    /// [`verify_req_cmd_001_law_is_finite_only_on_finite_inputs`] and
    /// [`verify_req_cmd_002_set_point_speed_is_limited_and_flagged`] this
    /// covers [`ImpedanceLaw::command`], which is those three steps in
    /// turn. No loop.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    pub(super) fn verify_req_cmd_001_wrench_limit_is_saturated_and_flagged() {
        let law = default_law();
        let wrench = kani::any::<Wrench>();
        let before = Saturation {
            force: kani::any(),
            torque: kani::any(),
            speed: kani::any(),
            non_finite: kani::any(),
        };
        let mut after = before;
        let limited = law.limit(wrench, &mut after);
        assert_eq!(limit_contract(&law, wrench, before, limited, after), Ok(()));
        let fresh = !before.any();
        kani::cover!(fresh && !after.any(), "wrench limit: within limits");
        kani::cover!(fresh && after.force, "wrench limit: force saturated");
        kani::cover!(fresh && after.torque, "wrench limit: torque saturated");
        kani::cover!(fresh && after.non_finite, "wrench limit: non-finite");
    }

    /// REQ-CMD-001: the law's own wrench, before any limit, is refused
    /// (`None`, which [`ImpedanceLaw::command`] flags and replaces by zero)
    /// whenever an input is not finite, and the law never makes a NaN: for
    /// any pose, velocity and set-point. Unwind 6: the law loops over 3
    /// axes, and per axis over its 5 inputs.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(6))]
    pub(super) fn verify_req_cmd_001_law_is_finite_only_on_finite_inputs() {
        let law = default_law();
        let set_point = kani::any::<SetPoint>();
        let (pose, velocity) = (kani::any::<Pose>(), kani::any::<PoseRate>());
        let wrench = law.wrench_about(pose, velocity, &set_point);
        let finite = inputs_finite(pose, velocity, &set_point);
        assert_eq!(law_contract(finite, wrench), Ok(()));
        kani::cover!(wrench.is_some(), "law: a wrench");
        kani::cover!(finite && wrench.is_none(), "law: a term overflowed");
        kani::cover!(!finite, "law: a non-finite input");
    }

    /// REQ-CMD-002: for any set-point, [`ImpedanceLaw::limit_speed`] meets
    /// [`check_speed_limit`]. Unwind 10: the check compares the 9 numbers
    /// of two set-points.
    #[cfg_attr(kani, kani::proof)]
    #[cfg_attr(kani, kani::unwind(10))]
    #[cfg_attr(kani, kani::stub(libm::hypot, crate::kani_stubs::stub::hypot))]
    pub(super) fn verify_req_cmd_002_set_point_speed_is_limited_and_flagged() {
        let law = default_law();
        let set_point = kani::any::<SetPoint>();
        let mut saturation = Saturation::default();
        let limited = law.limit_speed(set_point, &mut saturation);
        let out = ImpedanceOutput {
            set_point: limited,
            wrench: Wrench::ZERO,
            saturation,
        };
        assert_eq!(check_speed_limit(&set_point, &out), Ok(()));
        kani::cover!(saturation.speed, "speed limit: saturated");
        kani::cover!(!saturation.speed, "speed limit: within the limit");
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use proptest::prelude::*;

        #[test]
        fn harnesses_under_the_stand_in() {
            kani::check(
                "wrench limit",
                20_000,
                verify_req_cmd_001_wrench_limit_is_saturated_and_flagged,
            );
            kani::check(
                "law",
                20_000,
                verify_req_cmd_001_law_is_finite_only_on_finite_inputs,
            );
            kani::check(
                "speed limit",
                20_000,
                verify_req_cmd_002_set_point_speed_is_limited_and_flagged,
            );
        }

        fn rate(m: f64) -> impl Strategy<Value = PoseRate> {
            (-m..m, -m..m, -m..m).prop_map(|(x, z, psi)| PoseRate::new(x, z, psi))
        }

        proptest! {
            /// REQ-CMD-001, REQ-CMD-002: with the real `hypot` the law meets
            /// the proofs' check and the force magnitude stays within the
            /// limit (the part the stubbed proofs leave to sampling).
            #[test]
            fn req_cmd_001_force_magnitude_is_saturated(p in rate(2.0), v in rate(2.0),
                                                        sp in rate(2.0), sv in rate(0.5),
                                                        sa in rate(50.0)) {
                let config = KernelConfig::default();
                let l = &config.limits;
                let law = ImpedanceLaw::new(&config.impedance, l.max_force, l.max_torque, l.max_speed);
                let unlimited = ImpedanceLaw { max_force: f64::INFINITY, max_torque: f64::INFINITY,
                                               ..law };
                let set_point = SetPoint {
                    pose: Pose::new(sp.x, sp.z, sp.psi), velocity: sv, acceleration: sa,
                };
                let pose = Pose::new(p.x, p.z, p.psi);
                let out = law.command(pose, v, set_point);
                let raw = unlimited.command(pose, v, set_point);
                prop_assert_eq!(check_saturation(&law, true, &raw, &out, &set_point), Ok(()));
                prop_assert!(out.wrench.force_magnitude() <= l.max_force * (1.0 + ROUNDING));
                prop_assert!(out.set_point.velocity.linear_speed() <= l.max_speed * (1.0 + ROUNDING));
            }
        }
    }
}
