//! The coupled robot–arm plant: state, one integration step, measurement.
//!
//! # Theory of operation (`plant.md`)
//! With x = FK(q), ẋ = J q̇, ẍ = J q̈ + J̇ q̇ the robot's wrist wrench
//! F = −Λ(ẍ − ẍ_d) − D(ẋ − ẋ_d) − K(x − x_d) couples into the arm as
//!
//! ```text
//! (M + Jᵀ Λ J) q̈ = Jᵀ F0 − C − g_h + Aᵀ λ,
//! F0 = −(Λ (J̇ q̇ − ẍ_d) + D (J q̇ − ẋ_d) + K (x − x_d)),
//! ```
//!
//! λ from the table's active set ([`crate::contact`]). Semi-implicit Euler
//! at [`STEP`]: velocities from accelerations first, then positions from the
//! new velocities. The robot logs f_ext = −F.
//!
//! # Unmodelled effects
//! [`Plant::with_effects`] adds the effects of [`crate::effects`]: friction
//! and active torque change the generalised forces, mass mismatch and
//! grasp slip the arm's parameters, shoulder drift moves the whole arm;
//! a person's arm's own effects: passive stiffness and spasticity add
//! joint torques, shoulder rhythm moves the shoulder with the elevation,
//! cuff offset moves the grasp off the forearm's line and lengthens its
//! rod, shoulder height starts the arm in a rest posture the table's
//! coordinates count from;
//! compliance, tilt, latency, backlash and quantization change what
//! [`Plant::measure`] returns, in that order, noise being added before the
//! quantization. Without effects no extra arithmetic is done, so the nominal
//! plant is bit-identical.

use crate::contact::{self, ActiveSet, CANDIDATES};
use crate::dynamics::{apply, apply_transpose, arm_terms, arm_terms_with_rod, Vec2};
use crate::effects::shoulder_height::Rest;
use crate::effects::{Effects, Spasticity};
use crate::noise::Gaussian;
use crate::params::PlantParameters;
use crate::sensing::{
    Measurement, ANGLE_NOISE, FORCE_NOISE, POSITION_NOISE, POTENTIOMETER_RESOLUTION, STEP,
    TORQUE_NOISE,
};
use alloc::collections::VecDeque;
use alloc::format;
use alloc::string::String;
use limb_kernel::geometry::{Point, Pose, Wrench};
use limb_kernel::motion::SetPoint;

/// Ground truth of the dummy arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truth {
    /// Joint angles as the potentiometers give them [rad].
    pub q: Vec2,
    /// Elbow position [m].
    pub elbow: Point,
    /// Shoulder position [m].
    pub shoulder: Point,
}

/// The dynamics of one instant: accelerations and the robot's wrench.
#[derive(Clone, Copy, Debug)]
struct Instant {
    qdd: Vec2,
    lambda: Vec2,
    pose: [f64; 3],
    wrench: [f64; 3],
}

/// What the robot's sensors see before noise: pose (x, z, psi), lateral y
/// and f_ext, exact.
#[derive(Clone, Copy, Debug)]
struct Sensed {
    pose: [f64; 3],
    lateral: f64,
    wrench: [f64; 3],
}

/// The projected state and its dynamics at one instant (see
/// [`Plant::resolve`]).
type Resolved = (Vec2, Vec2, Option<Instant>);

/// The plant.
#[derive(Clone, Debug)]
pub struct Plant {
    params: PlantParameters,
    /// The robot's damping D (of `params.robot`, which never changes).
    damping: [f64; 3],
    /// Joint angles in the table's coordinates (see [`Plant::joint_angles`]).
    q: Vec2,
    qd: Vec2,
    steps: u64,
    set_point: SetPoint,
    noise: Gaussian,
    effects: Effects,
    /// Backlash follower of psi [rad].
    follower: f64,
    /// Sensed values of past steps, newest last (latency only).
    history: VecDeque<Sensed>,
    /// Shoulder displacement from its rest position (x, z) [m].
    shoulder_offset: Vec2,
    /// Shoulder velocity (x, z) [m/s] (shoulder drift only).
    shoulder_velocity: Vec2,
    /// The grasp slip has happened.
    slipped: bool,
    /// Elbow speeds q̇2 of the last steps, newest last (spasticity only:
    /// the reflex sees the one its delay ago).
    elbow_speeds: VecDeque<f64>,
    /// The rest posture the table's coordinates count from (shoulder
    /// height only; see [`Plant::joint_angles`]).
    rest: Option<Rest>,
    /// This instant's [`Plant::resolve`], once computed: a
    /// [`Plant::measure`] and the [`Plant::step`] after it share it (the
    /// state, set-point and time are the same), so an instant's dynamics
    /// are solved once. Cleared by [`Plant::set`] and [`Plant::step`].
    resolved: Option<Resolved>,
}

impl Plant {
    /// The plant at rest (q = (0, 0), or a raised shoulder's rest posture),
    /// t = 0, holding x_d at the grasp pose.
    ///
    /// # Errors
    /// The first invalid parameter.
    pub fn new(params: PlantParameters) -> Result<Self, String> {
        Self::with_effects(params, Effects::default())
    }

    /// The plant with unmodelled `effects` (see [`crate::effects`]).
    /// `mass_mismatch` is applied to the arm's parameters here.
    ///
    /// # Errors
    /// The first invalid parameter.
    pub fn with_effects(mut params: PlantParameters, effects: Effects) -> Result<Self, String> {
        if let Some(mass) = effects.mass_mismatch {
            params.arm.forearm_mass *= mass.factor;
        }
        params.check()?;
        let rest = match effects.shoulder_height {
            Some(raised) => Some(raised.rest(params.arm.upper_arm_length).ok_or_else(|| {
                format!(
                    "shoulder_height {} m is not below the upper arm's length {} m",
                    raised.height, params.arm.upper_arm_length
                )
            })?),
            None => None,
        };
        Ok(Self {
            params,
            damping: params.robot.damping(),
            q: [0.0, 0.0],
            qd: [0.0, 0.0],
            steps: 0,
            set_point: SetPoint::default(),
            noise: Gaussian::new(params.seed),
            effects,
            follower: 0.0,
            history: VecDeque::new(),
            shoulder_offset: [0.0, 0.0],
            shoulder_velocity: [0.0, 0.0],
            slipped: false,
            elbow_speeds: VecDeque::new(),
            rest,
            resolved: None,
        })
    }

    /// The effects this plant applies.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }

    /// Parameters.
    pub fn params(&self) -> &PlantParameters {
        &self.params
    }

    /// Plant time [s]: steps × [`STEP`], so it does not drift.
    pub fn time(&self) -> f64 {
        self.steps as f64 * STEP
    }

    /// Joint angles and velocities (q, q̇) [rad, rad/s].
    pub fn state(&self) -> (Vec2, Vec2) {
        (self.joint_angles(self.q), self.qd)
    }

    /// The set-point the robot follows until the next [`Plant::set`].
    pub fn set(&mut self, set_point: SetPoint) {
        self.set_point = set_point;
        self.resolved = None;
    }

    /// The set-point the robot follows.
    pub fn set_point(&self) -> SetPoint {
        self.set_point
    }

    /// The joint angles of the table's coordinates `q` (the plant's state:
    /// (0, 0) at rest, the table's bounds at 0): the same but under a
    /// raised shoulder, whose rest posture they count from (see
    /// `effects::shoulder_height`).
    fn joint_angles(&self, q: Vec2) -> Vec2 {
        match self.rest {
            Some(rest) => [q[0] + rest.q[0], q[1] + rest.q[1]],
            None => q,
        }
    }

    fn dynamics(&self, table: Vec2, qd: Vec2, set: ActiveSet) -> Option<Instant> {
        let a = &self.params.arm;
        let r = &self.params.robot;
        let d = self.damping;
        let q = self.joint_angles(table);
        let mut t = match self.effects.cuff_offset {
            Some(cuff) => arm_terms_with_rod(a, q, qd, a.forearm_length + cuff.along),
            None => arm_terms(a, q, qd),
        };
        if let Some(cuff) = self.effects.cuff_offset {
            // The grasp sits `across` off the forearm's line: it turns
            // with psi (see `effects::cuff_offset`).
            let psi = q[0] + q[1];
            let psid = qd[0] + qd[1];
            let (s, c) = (libm::sin(psi), libm::cos(psi));
            let shift = cuff.displacement(psi);
            t.pose[0] += shift[0];
            t.pose[1] += shift[1];
            for column in 0..2 {
                t.jacobian[0][column] += cuff.across * c;
                t.jacobian[1][column] -= cuff.across * s;
            }
            t.jacobian_rate[0] -= cuff.across * s * psid * psid;
            t.jacobian_rate[1] -= cuff.across * c * psid * psid;
        }
        if let Some(rest) = self.rest {
            // The shoulder stands where the rest posture puts it.
            t.pose[0] += rest.shift[0];
            t.pose[1] += rest.shift[1];
        }
        if let Some(rhythm) = self.effects.shoulder_rhythm {
            // The shoulder translates with the elevation q1, the arm on
            // it; its weight acts through the rise (see
            // `effects::shoulder_rhythm`).
            let shift = rhythm.displacement(table[0]);
            t.pose[0] += shift[0];
            t.pose[1] += shift[1];
            t.jacobian[0][0] += rhythm.x;
            t.jacobian[1][0] += rhythm.z;
            t.gravity[0] += (a.upper_arm_mass + a.forearm_mass) * a.gravity * rhythm.z;
        }
        let mut v = apply(&t.jacobian, qd);
        if self.effects.shoulder_drift.is_some() {
            // The whole arm rides on the shoulder: the grasp is displaced
            // and moves with it (its acceleration is not fed back, see
            // `effects::shoulder_drift`).
            let (s, sd) = (self.shoulder_offset, self.shoulder_velocity);
            t.pose[0] += s[0];
            t.pose[1] += s[1];
            v[0] += sd[0];
            v[1] += sd[1];
        }
        let sp = &self.set_point;
        let xd = [sp.pose.x, sp.pose.z, sp.pose.psi];
        let vd = [sp.velocity.x, sp.velocity.z, sp.velocity.psi];
        let ad = [sp.acceleration.x, sp.acceleration.z, sp.acceleration.psi];
        let mut f0 = [0.0; 3];
        for i in 0..3 {
            f0[i] = -(r.inertia[i] * (t.jacobian_rate[i] - ad[i])
                + d[i] * (v[i] - vd[i])
                + r.stiffness[i] * (t.pose[i] - xd[i]));
        }
        let mut mass = t.mass;
        for (row, mass_row) in mass.iter_mut().enumerate() {
            for (col, m) in mass_row.iter_mut().enumerate() {
                for (k, lam) in r.inertia.iter().enumerate() {
                    *m += t.jacobian[k][row] * lam * t.jacobian[k][col];
                }
            }
        }
        let jf = apply_transpose(&t.jacobian, f0);
        let mut rhs = [
            jf[0] - t.coriolis[0] - t.gravity[0],
            jf[1] - t.coriolis[1] - t.gravity[1],
        ];
        if let Some(friction) = self.effects.joint_friction {
            let tau = friction.torques(qd);
            rhs[0] += tau[0];
            rhs[1] += tau[1];
        }
        if let Some(active) = self.effects.active_torque {
            rhs[1] += active.torque(self.time());
        }
        if let Some(passive) = self.effects.passive_stiffness {
            let tau = passive.torques(q);
            rhs[0] += tau[0];
            rhs[1] += tau[1];
        }
        if let Some(spasticity) = self.effects.spasticity {
            rhs[1] += spasticity.torque(self.delayed_elbow_speed());
        }
        let (qdd, lambda) = contact::solve(set, &mass, rhs)?;
        let acc = apply(&t.jacobian, qdd);
        let mut wrench = [0.0; 3];
        for i in 0..3 {
            let xdd = acc[i] + t.jacobian_rate[i];
            wrench[i] = -r.inertia[i] * (xdd - ad[i])
                - d[i] * (v[i] - vd[i])
                - r.stiffness[i] * (t.pose[i] - xd[i]);
        }
        Some(Instant {
            qdd,
            lambda,
            pose: t.pose,
            wrench,
        })
    }

    /// The elbow speed the stretch reflex sees: q̇2 its delay ago (at
    /// rest before the log reaches that far back).
    fn delayed_elbow_speed(&self) -> f64 {
        if self.elbow_speeds.len() >= Spasticity::steps(STEP) {
            self.elbow_speeds.front().copied().unwrap_or(0.0)
        } else {
            0.0
        }
    }

    /// Chooses the active set and returns the projected state with its
    /// dynamics (`plant.md`'s rule; the last candidate when none qualifies).
    fn resolve(&self) -> Resolved {
        let bound = contact::at_bound(self.q, self.qd);
        let mut fallback = (self.q, self.qd, None);
        for set in CANDIDATES {
            if (set.elbow && !bound.elbow) || (set.forearm && !bound.forearm) {
                continue;
            }
            let (mut q, mut qd) = (self.q, self.qd);
            contact::project(set, &mut q, &mut qd);
            let Some(instant) = self.dynamics(q, qd, set) else {
                continue;
            };
            if contact::admissible(set, bound, instant.qdd, instant.lambda) {
                return (q, qd, Some(instant));
            }
            fallback = (q, qd, Some(instant));
        }
        fallback
    }

    /// [`Plant::resolve`] of this instant, computed once per instant.
    fn resolve_once(&mut self) -> Resolved {
        if let Some(resolved) = self.resolved {
            return resolved;
        }
        let resolved = self.resolve();
        self.resolved = Some(resolved);
        resolved
    }

    /// What the sensors see at `instant`, noise-free: grasp compliance and
    /// plane tilt applied.
    fn sense(&self, instant: Option<Instant>) -> Sensed {
        let Some(i) = instant else {
            return Sensed {
                pose: [f64::NAN; 3],
                lateral: f64::NAN,
                wrench: [f64::NAN; 3],
            };
        };
        let wrench = [-i.wrench[0], -i.wrench[1], -i.wrench[2]];
        let mut pose = i.pose;
        if let Some(compliance) = self.effects.grasp_compliance {
            pose = compliance.end_effector(pose, wrench);
        }
        let mut lateral = 0.0;
        if let Some(tilt) = self.effects.plane_tilt {
            let (sin, cos) = (libm::sin(tilt.angle), libm::cos(tilt.angle));
            lateral = pose[1] * sin;
            pose[1] *= cos;
        }
        Sensed {
            pose,
            lateral,
            wrench,
        }
    }

    /// The sensed values of this instant, `latency` old when it is on.
    fn sensed(&mut self) -> Sensed {
        let instant = self.resolve_once().2;
        let now = || self.sense(instant);
        let Some(latency) = self.effects.latency else {
            return now();
        };
        let delay = latency.steps();
        if delay == 0 {
            return now();
        }
        match self.history.len().checked_sub(delay) {
            Some(index) => self.history.get(index).copied().unwrap_or_else(now),
            None => self.history.front().copied().unwrap_or_else(now),
        }
    }

    /// One step of [`STEP`] seconds.
    pub fn step(&mut self) {
        let (mut q, mut qd, instant) = self.resolved.take().unwrap_or_else(|| self.resolve());
        if let Some(latency) = self.effects.latency {
            let sensed = self.sense(instant);
            self.history.push_back(sensed);
            while self.history.len() > latency.steps() {
                self.history.pop_front();
            }
        }
        if let (Some(drift), Some(i)) = (self.effects.shoulder_drift, instant) {
            // While the elbow rests on the table the table holds the arm
            // and the trunk's state is held; once it is off, the trunk
            // yields to the robot's force.
            if q[0] > 0.0 {
                drift.advance(
                    [i.wrench[0], i.wrench[1]],
                    &mut self.shoulder_offset,
                    &mut self.shoulder_velocity,
                    STEP,
                );
            }
        }
        if let Some(instant) = instant {
            for i in 0..2 {
                qd[i] += instant.qdd[i] * STEP;
                q[i] += qd[i] * STEP;
            }
        }
        contact::clamp(&mut q, &mut qd);
        if self.effects.spasticity.is_some() {
            self.elbow_speeds.push_back(qd[1]);
            while self.elbow_speeds.len() > Spasticity::steps(STEP) {
                self.elbow_speeds.pop_front();
            }
        }
        self.q = q;
        self.qd = qd;
        self.steps += 1;
        if let Some(slip) = self.effects.grasp_slip {
            if !self.slipped && self.time() >= slip.at {
                self.params.arm.forearm_length += slip.shift;
                self.slipped = true;
            }
        }
    }

    /// What the robot measures now (draws noise when noise is on).
    pub fn measure(&mut self) -> Measurement {
        let Sensed {
            mut pose,
            lateral,
            wrench,
        } = self.sensed();
        if let Some(backlash) = self.effects.backlash {
            self.follower = backlash.follow(self.follower, pose[2]);
            pose[2] = self.follower;
        }
        let on = self.params.noise;
        let mut n = |sigma: f64| if on { self.noise.sample(sigma) } else { 0.0 };
        let (px, pz, ppsi) = (n(POSITION_NOISE), n(POSITION_NOISE), n(ANGLE_NOISE));
        let lateral = lateral + n(POSITION_NOISE);
        let (fx, fz, ty) = (n(FORCE_NOISE), n(FORCE_NOISE), n(TORQUE_NOISE));
        let mut pose = [pose[0] + px, pose[1] + pz, pose[2] + ppsi];
        if let Some(quantization) = self.effects.quantization {
            pose = quantization.apply(pose);
        }
        Measurement {
            time: self.time(),
            pose: Pose::new(pose[0], pose[1], pose[2]),
            lateral,
            wrench: Wrench::new(wrench[0] + fx, wrench[1] + fz, wrench[2] + ty),
        }
    }

    /// Ground truth now.
    pub fn truth(&self) -> Truth {
        let a = &self.params.arm;
        let (l1, l2) = (a.upper_arm_length, a.forearm_length);
        let mut shoulder = [l1 + l2 + self.shoulder_offset[0], self.shoulder_offset[1]];
        if let Some(rest) = self.rest {
            shoulder[0] += rest.shift[0];
            shoulder[1] += rest.shift[1];
        }
        if let Some(rhythm) = self.effects.shoulder_rhythm {
            let shift = rhythm.displacement(self.q[0]);
            shoulder[0] += shift[0];
            shoulder[1] += shift[1];
        }
        if let Some(cuff) = self.effects.cuff_offset {
            // Frame S keeps its origin at the grasp at t = 0, `across`
            // above the forearm's line.
            shoulder[1] -= cuff.across;
        }
        let shoulder = Point::new(shoulder[0], shoulder[1]);
        let round = |v: f64| libm::round(v / POTENTIOMETER_RESOLUTION) * POTENTIOMETER_RESOLUTION;
        let q = self.joint_angles(self.q);
        Truth {
            q: [round(q[0]), round(q[1])],
            elbow: Point::new(
                shoulder.x - l1 * libm::cos(q[0]),
                shoulder.z + l1 * libm::sin(q[0]),
            ),
            shoulder,
        }
    }
}
