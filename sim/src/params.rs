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

/// How a segment's mass is spread along it: where its centre of mass is
/// and how large its inertia about that centre is, both relative to the
/// segment's length l and mass m (so they scale with a subject's size).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassDistribution {
    /// Distance of the centre of mass from the proximal joint, along the
    /// segment, as a fraction of l [1].
    pub centre: f64,
    /// d in I_c = m l² / d, the inertia about the centre of mass for
    /// rotation in the arm's plane [1].
    pub inertia_divisor: f64,
}

impl MassDistribution {
    /// A uniform rod (plant.md): centre at l / 2, I_c = m l² / 12.
    pub const ROD: Self = Self {
        centre: 0.5,
        inertia_divisor: 12.0,
    };
}

/// A segment of the reference person: its mass at a reference length and
/// how the mass is spread (see [`ArmParameters::person`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PersonSegment {
    /// The reference length [m] (joint centre to joint centre, or elbow
    /// centre to the cuff for the forearm).
    pub length: f64,
    /// Its mass at that length [kg].
    pub mass: f64,
    /// Its spread of mass.
    pub distribution: MassDistribution,
}

/// The reference person's upper arm (humerus; MoBL-ARMS, Holzbaur et al.
/// 2005, a 50th-percentile adult male, as MyoSuite's `myoarm_r` compiles
/// it): glenohumeral to elbow centre 0.2907 m, 1.998 kg, centre of mass at
/// 0.485 l, I_c = m l² / 13.37 about the elbow's flexion axis.
/// `plants/myoarm/segments.py` measures these; `spec/human-arm.md`
/// compares them with Winter's tables.
pub const PERSON_UPPER_ARM: PersonSegment = PersonSegment {
    length: 0.2907,
    mass: 1.998,
    distribution: MassDistribution {
        centre: 0.485,
        inertia_divisor: 13.37,
    },
};

/// The reference person's forearm and hand (ulna, radius, rigid hand and
/// fingers; as [`PERSON_UPPER_ARM`]): elbow centre to the cuff 0.2216 m,
/// 1.783 kg, centre of mass at 0.719 l (the hand lies beyond the cuff),
/// I_c = m l² / 4.24.
pub const PERSON_FOREARM: PersonSegment = PersonSegment {
    length: 0.2216,
    mass: 1.783,
    distribution: MassDistribution {
        centre: 0.719,
        inertia_divisor: 4.24,
    },
};

/// Which body the arm's lengths are put on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ArmBuild {
    /// plant.md's dummy: uniform rods of 1.55 kg and 1.317 kg whatever
    /// their length.
    #[default]
    Rod,
    /// A person: the reference person scaled to the lengths
    /// ([`ArmParameters::person`]).
    Person,
}

impl ArmBuild {
    /// Its name, as `--arm` spells it: `rod` or `person`.
    pub fn name(self) -> &'static str {
        match self {
            ArmBuild::Rod => "rod",
            ArmBuild::Person => "person",
        }
    }
}

/// The passive arm, frame S (shoulder at (l1 + l2, 0)).
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
    /// The upper arm's spread of mass (the dummy's: a uniform rod).
    pub upper_arm_distribution: MassDistribution,
    /// The forearm's spread of mass (the dummy's: a uniform rod).
    pub forearm_distribution: MassDistribution,
    /// Gravity [m/s²].
    pub gravity: f64,
}

impl ArmParameters {
    /// An arm of lengths l1, l2 [m] with the dummy's masses: uniform rods.
    pub fn new(upper_arm_length: f64, forearm_length: f64) -> Self {
        Self {
            upper_arm_length,
            forearm_length,
            upper_arm_mass: 1.55,
            forearm_mass: 1.317,
            upper_arm_distribution: MassDistribution::ROD,
            forearm_distribution: MassDistribution::ROD,
            gravity: 9.81,
        }
    }

    /// A person's arm of lengths l1, l2 [m]: each segment the reference
    /// person's ([`PERSON_UPPER_ARM`], [`PERSON_FOREARM`]) scaled
    /// isometrically to its length, so its mass goes with the length cubed
    /// (constant density and proportions) and its centre of mass and
    /// inertia divisor are the reference's.
    pub fn person(upper_arm_length: f64, forearm_length: f64) -> Self {
        let scaled = |segment: &PersonSegment, length: f64| {
            let k = length / segment.length;
            segment.mass * k * k * k
        };
        Self {
            upper_arm_mass: scaled(&PERSON_UPPER_ARM, upper_arm_length),
            forearm_mass: scaled(&PERSON_FOREARM, forearm_length),
            upper_arm_distribution: PERSON_UPPER_ARM.distribution,
            forearm_distribution: PERSON_FOREARM.distribution,
            ..Self::new(upper_arm_length, forearm_length)
        }
    }

    /// The arm of lengths l1, l2 [m] on `build`.
    pub fn built(build: ArmBuild, upper_arm_length: f64, forearm_length: f64) -> Self {
        match build {
            ArmBuild::Rod => Self::new(upper_arm_length, forearm_length),
            ArmBuild::Person => Self::person(upper_arm_length, forearm_length),
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
        for (name, d) in [
            ("upper arm", a.upper_arm_distribution),
            ("forearm", a.forearm_distribution),
        ] {
            if !(d.centre.is_finite() && d.centre > 0.0 && d.centre <= 1.5) {
                return Err(format!(
                    "the {name}'s centre of mass must lie in (0, 1.5] of its length, got {}",
                    d.centre
                ));
            }
            if !(d.inertia_divisor.is_finite() && d.inertia_divisor > 0.0) {
                return Err(format!(
                    "the {name}'s inertia divisor must be finite and positive, got {}",
                    d.inertia_divisor
                ));
            }
        }
        if !a.gravity.is_finite() {
            return Err(format!("gravity must be finite, got {}", a.gravity));
        }
        Ok(())
    }
}
