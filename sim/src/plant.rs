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

use crate::contact::{self, ActiveSet, CANDIDATES};
use crate::dynamics::{apply, apply_transpose, arm_terms, Vec2};
use crate::noise::Gaussian;
use crate::params::PlantParameters;
use limb_kernel::geometry::{Point, Pose, Wrench};
use limb_kernel::motion::SetPoint;

/// Integration step [s] (0.5 ms).
pub const STEP: f64 = 0.0005;
/// Resolution of the ground-truth potentiometers [rad] (10 bit).
pub const POTENTIOMETER_RESOLUTION: f64 = 0.0047;

/// What the robot measures, frame S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Time [s].
    pub time: f64,
    /// Grasp pose [m, m, rad].
    pub pose: Pose,
    /// Lateral position y [m] (zero plus noise in the plane of S).
    pub lateral: f64,
    /// External wrench estimate f_ext [N, N, N m].
    pub wrench: Wrench,
}

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

/// The plant.
#[derive(Clone, Debug)]
pub struct Plant {
    params: PlantParameters,
    q: Vec2,
    qd: Vec2,
    steps: u64,
    set_point: SetPoint,
    noise: Gaussian,
}

impl Plant {
    /// The plant at rest at q = (0, 0), t = 0, holding x_d at the grasp pose.
    ///
    /// # Errors
    /// The first invalid parameter.
    pub fn new(params: PlantParameters) -> Result<Self, String> {
        params.check()?;
        Ok(Self {
            params,
            q: [0.0, 0.0],
            qd: [0.0, 0.0],
            steps: 0,
            set_point: SetPoint::default(),
            noise: Gaussian::new(params.seed),
        })
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
        (self.q, self.qd)
    }

    /// The set-point the robot follows until the next [`Plant::set`].
    pub fn set(&mut self, set_point: SetPoint) {
        self.set_point = set_point;
    }

    /// The set-point the robot follows.
    pub fn set_point(&self) -> SetPoint {
        self.set_point
    }

    fn dynamics(&self, q: Vec2, qd: Vec2, set: ActiveSet) -> Option<Instant> {
        let a = &self.params.arm;
        let r = &self.params.robot;
        let d = r.damping();
        let t = arm_terms(a, q, qd);
        let v = apply(&t.jacobian, qd);
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
        let rhs = [
            jf[0] - t.coriolis[0] - t.gravity[0],
            jf[1] - t.coriolis[1] - t.gravity[1],
        ];
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

    /// Chooses the active set and returns the projected state with its
    /// dynamics (`plant.md`'s rule; the last candidate when none qualifies).
    fn resolve(&self) -> (Vec2, Vec2, Option<Instant>) {
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

    /// The exact (noise-free) pose and wrench of this instant.
    fn exact(&self) -> ([f64; 3], [f64; 3]) {
        let (_, _, instant) = self.resolve();
        instant.map_or(([f64::NAN; 3], [f64::NAN; 3]), |i| {
            (i.pose, [-i.wrench[0], -i.wrench[1], -i.wrench[2]])
        })
    }

    /// One step of [`STEP`] seconds.
    pub fn step(&mut self) {
        let (mut q, mut qd, instant) = self.resolve();
        if let Some(instant) = instant {
            for i in 0..2 {
                qd[i] += instant.qdd[i] * STEP;
                q[i] += qd[i] * STEP;
            }
        }
        contact::clamp(&mut q, &mut qd);
        self.q = q;
        self.qd = qd;
        self.steps += 1;
    }

    /// What the robot measures now (draws noise when noise is on).
    pub fn measure(&mut self) -> Measurement {
        let (pose, wrench) = self.exact();
        let on = self.params.noise;
        let mut n = |sigma: f64| if on { self.noise.sample(sigma) } else { 0.0 };
        let (px, pz, ppsi) = (n(1e-4), n(1e-4), n(1e-3));
        let lateral = n(1e-4);
        let (fx, fz, ty) = (n(0.5), n(0.5), n(0.025));
        Measurement {
            time: self.time(),
            pose: Pose::new(pose[0] + px, pose[1] + pz, pose[2] + ppsi),
            lateral,
            wrench: Wrench::new(wrench[0] + fx, wrench[1] + fz, wrench[2] + ty),
        }
    }

    /// Ground truth now.
    pub fn truth(&self) -> Truth {
        let a = &self.params.arm;
        let (l1, l2) = (a.upper_arm_length, a.forearm_length);
        let shoulder = Point::new(l1 + l2, 0.0);
        let round = |v: f64| (v / POTENTIOMETER_RESOLUTION).round() * POTENTIOMETER_RESOLUTION;
        Truth {
            q: [round(self.q[0]), round(self.q[1])],
            elbow: Point::new(shoulder.x - l1 * self.q[0].cos(), l1 * self.q[0].sin()),
            shoulder,
        }
    }
}
