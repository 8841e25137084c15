//! Parameters of the reference plant, with the defaults of `plant.md`.

use alloc::format;
use alloc::string::String;

/// The six benchmark arms of `plant.md` (the paper's Table 1): (l1, l2) [m],
/// case 1 first.
pub const BENCHMARK_ARMS: [(f64, f64); 6] = [
    (0.33, 0.20),
    (0.33, 0.18),
    (0.30, 0.20),
    (0.30, 0.18),
    (0.27, 0.20),
    (0.27, 0.18),
];

/// The passive arm: uniform rods, frame S (shoulder at (l1 + l2, 0)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmParameters {
    /// Upper-arm length l1 [m].
    pub upper_arm_length: f64,
    /// Forearm length l2 (elbow to grasp) [m].
    pub forearm_length: f64,
    /// Upper-arm mass m1 [kg]; 1.55 kg (the paper's dummy).
    pub upper_arm_mass: f64,
    /// Forearm mass m2 [kg]; 1.317 kg (the paper's dummy).
    pub forearm_mass: f64,
    /// Gravity [m/s²].
    pub gravity: f64,
}

impl ArmParameters {
    /// An arm of lengths l1, l2 [m] with the dummy's masses.
    pub fn new(upper_arm_length: f64, forearm_length: f64) -> Self {
        Self {
            upper_arm_length,
            forearm_length,
            upper_arm_mass: 1.55,
            forearm_mass: 1.317,
            gravity: 9.81,
        }
    }
}

/// The robot's Cartesian impedance at the grasp (x, z, psi).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotParameters {
    /// Inertia Λ: kg, kg, kg m².
    pub inertia: [f64; 3],
    /// Stiffness K: N/m, N/m, N m/rad.
    pub stiffness: [f64; 3],
    /// Damping ratio ζ (D_i = 2 ζ sqrt(K_i Λ_i)).
    pub damping_ratio: f64,
}

impl Default for RobotParameters {
    fn default() -> Self {
        Self {
            inertia: [2.0, 2.0, 0.05],
            stiffness: [200.0, 200.0, 10.0],
            damping_ratio: 2.0,
        }
    }
}

impl RobotParameters {
    /// Damping D: N s/m, N s/m, N m s/rad.
    pub fn damping(&self) -> [f64; 3] {
        let mut d = [0.0; 3];
        for (i, di) in d.iter_mut().enumerate() {
            *di = 2.0 * self.damping_ratio * libm::sqrt(self.stiffness[i] * self.inertia[i]);
        }
        d
    }
}

/// Everything the plant needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantParameters {
    /// The arm.
    pub arm: ArmParameters,
    /// The robot.
    pub robot: RobotParameters,
    /// Measurement noise on (plant.md sigmas) or off.
    pub noise: bool,
    /// Noise seed.
    pub seed: u64,
}

impl PlantParameters {
    /// plant.md defaults for an arm of lengths l1, l2 [m].
    pub fn new(upper_arm_length: f64, forearm_length: f64) -> Self {
        Self {
            arm: ArmParameters::new(upper_arm_length, forearm_length),
            robot: RobotParameters::default(),
            noise: true,
            seed: 1,
        }
    }

    /// Checks every parameter is finite and physically meaningful.
    ///
    /// # Errors
    /// A sentence naming the first bad parameter.
    pub fn check(&self) -> Result<(), String> {
        let a = &self.arm;
        let positive = [
            ("l1", a.upper_arm_length),
            ("l2", a.forearm_length),
            ("m1", a.upper_arm_mass),
            ("m2", a.forearm_mass),
            ("damping ratio", self.robot.damping_ratio),
        ];
        for (name, value) in positive
            .into_iter()
            .chain(self.robot.inertia.iter().map(|v| ("robot inertia", *v)))
            .chain(self.robot.stiffness.iter().map(|v| ("robot stiffness", *v)))
        {
            if !(value.is_finite() && value > 0.0) {
                return Err(format!("{name} must be finite and positive, got {value}"));
            }
        }
        if !a.gravity.is_finite() {
            return Err(format!("gravity must be finite, got {}", a.gravity));
        }
        Ok(())
    }
}
