//! Unmodelled effects (`plant.md`, "Unmodelled effects"): what real data may
//! contain that the reference plant lacks. Each effect lives in its own
//! module with its physics, units and parameter ranges.
//!
//! # Theory of operation
//! An [`Effect`] is built from its name and `KEY=VALUE` settings
//! ([`Effect::parse`]) or from named values ([`Effect::new`]); both check
//! every key is known, none is missing or repeated and every value lies in
//! its documented range (no silent clamping). [`CATALOGUE`] lists each
//! effect's parameters ([`Parameter`]: unit, range, description), for a
//! diagnosis engine that fits them; the engine's candidates use the same
//! type with their search ranges. A list of effects becomes an
//! [`Effects`] set (at most one of each) that
//! [`crate::Plant::with_effects`] applies:
//!
//! * measurement side (change what `measure()` returns): `backlash`,
//!   `quantization`, `latency`, `grasp_compliance`, `plane_tilt`;
//! * dynamics side (change the plant): `joint_friction`, `mass_mismatch`,
//!   `shoulder_drift`, `active_torque`, `grasp_slip`, and a person's arm's
//!   own: `passive_stiffness`, `spasticity`, `shoulder_rhythm`,
//!   `cuff_offset`, `shoulder_height`.
//!
//! [`measurement`] applies the measurement side to a noise-free record
//! without the plant, as a diagnosis predicts it.
//!
//! With no effect the plant is bit-identical to the nominal one.

use alloc::string::{String, ToString};
use alloc::vec;
use alloc::vec::Vec;

pub mod active_torque;
pub mod backlash;
pub mod cuff_offset;
pub mod grasp_compliance;
pub mod grasp_slip;
pub mod joint_friction;
pub mod latency;
pub mod mass_mismatch;
pub mod measurement;
pub mod passive_stiffness;
pub mod plane_tilt;
pub mod quantization;
pub mod shoulder_drift;
pub mod shoulder_height;
pub mod shoulder_rhythm;
pub mod spasticity;

pub use active_torque::ActiveTorque;
pub use backlash::Backlash;
pub use cuff_offset::CuffOffset;
pub use grasp_compliance::GraspCompliance;
pub use grasp_slip::GraspSlip;
pub use joint_friction::JointFriction;
pub use latency::Latency;
pub use mass_mismatch::MassMismatch;
pub use passive_stiffness::PassiveStiffness;
pub use plane_tilt::PlaneTilt;
pub use quantization::Quantization;
pub use shoulder_drift::ShoulderDrift;
pub use shoulder_height::ShoulderHeight;
pub use shoulder_rhythm::ShoulderRhythm;
pub use spasticity::Spasticity;

/// How a parameter's range is walked by a search: evenly, or evenly in
/// its logarithm (for quantities spanning decades: stiffness, friction).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Evenly between `min` and `max`.
    Linear,
    /// Evenly in `ln` between `min > 0` and `max`.
    Logarithmic,
}

/// One parameter: name, SI unit, range (inclusive), how a search walks
/// the range, and what it is. In [`CATALOGUE`] the range is what `--set`
/// allows; a diagnosis candidate carries its search range, inside the
/// allowed one ([`Parameter::searched`]).
///
/// # Invariants
/// `min <= max`, both finite; as a search range `min < max`, and
/// `min > 0` for [`Scale::Logarithmic`] (checked by
/// [`Parameter::is_valid`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parameter {
    /// Name as in `--set NAME=VALUE` and the diagnosis output.
    pub name: &'static str,
    /// SI unit.
    pub unit: &'static str,
    /// Smallest value (allowed, or searched).
    pub min: f64,
    /// Largest value (allowed, or searched).
    pub max: f64,
    /// How a search walks the range.
    pub scale: Scale,
    /// What it is.
    pub description: &'static str,
}

impl Parameter {
    /// A parameter named `name` in `unit` over [`min`, `max`], walked
    /// linearly.
    pub const fn new(
        name: &'static str,
        unit: &'static str,
        min: f64,
        max: f64,
        description: &'static str,
    ) -> Self {
        Self {
            name,
            unit,
            min,
            max,
            scale: Scale::Linear,
            description,
        }
    }

    /// The same parameter walked by `scale`.
    pub const fn scaled(self, scale: Scale) -> Self {
        Self { scale, ..self }
    }

    /// The same parameter searched over [`min`, `max`] by `scale` (a
    /// diagnosis's search range, inside the allowed one).
    pub const fn searched(self, min: f64, max: f64, scale: Scale) -> Self {
        Self {
            min,
            max,
            scale,
            ..self
        }
    }

    /// The invariants of a search range hold.
    pub fn is_valid(&self) -> bool {
        self.min.is_finite()
            && self.max.is_finite()
            && self.min < self.max
            && (self.scale == Scale::Linear || self.min > 0.0)
    }

    /// The value at unit coordinate `u` (projected onto [0, 1]).
    ///
    /// With the `std` feature only: it uses the host's `ln` and `exp`, as
    /// the diagnosis always has, so that its answers stay the same to the
    /// last bit.
    #[cfg(feature = "std")]
    pub fn value(&self, u: f64) -> f64 {
        let u = if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) };
        match self.scale {
            Scale::Linear => self.min + u * (self.max - self.min),
            Scale::Logarithmic => (self.min.ln() + u * (self.max.ln() - self.min.ln())).exp(),
        }
    }

    /// The unit coordinate of `value` (the inverse of [`Parameter::value`]
    /// inside the range, projected onto [0, 1] outside it). With the
    /// `std` feature only, as [`Parameter::value`].
    #[cfg(feature = "std")]
    pub fn unit_of(&self, value: f64) -> f64 {
        let u = match self.scale {
            Scale::Linear => (value - self.min) / (self.max - self.min),
            Scale::Logarithmic => {
                (value.max(self.min).ln() - self.min.ln()) / (self.max.ln() - self.min.ln())
            }
        };
        if u.is_nan() {
            0.5
        } else {
            u.clamp(0.0, 1.0)
        }
    }
}

/// An effect's name and parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Descriptor {
    /// Name as in `plant.md`.
    pub name: &'static str,
    /// Its parameters, in the order [`Effect::values`] gives them.
    pub parameters: &'static [Parameter],
}

/// Every effect of `plant.md` (except `none`, the absence of effects): the
/// ten of a robot's gap, then the five of a person's arm (`spec/human-arm.md`).
pub const CATALOGUE: [Descriptor; 15] = [
    Descriptor {
        name: "joint_friction",
        parameters: &joint_friction::PARAMETERS,
    },
    Descriptor {
        name: "backlash",
        parameters: &backlash::PARAMETERS,
    },
    Descriptor {
        name: "quantization",
        parameters: &quantization::PARAMETERS,
    },
    Descriptor {
        name: "latency",
        parameters: &latency::PARAMETERS,
    },
    Descriptor {
        name: "grasp_compliance",
        parameters: &grasp_compliance::PARAMETERS,
    },
    Descriptor {
        name: "mass_mismatch",
        parameters: &mass_mismatch::PARAMETERS,
    },
    Descriptor {
        name: "plane_tilt",
        parameters: &plane_tilt::PARAMETERS,
    },
    Descriptor {
        name: "shoulder_drift",
        parameters: &shoulder_drift::PARAMETERS,
    },
    Descriptor {
        name: "active_torque",
        parameters: &active_torque::PARAMETERS,
    },
    Descriptor {
        name: "grasp_slip",
        parameters: &grasp_slip::PARAMETERS,
    },
    Descriptor {
        name: "passive_stiffness",
        parameters: &passive_stiffness::PARAMETERS,
    },
    Descriptor {
        name: "spasticity",
        parameters: &spasticity::PARAMETERS,
    },
    Descriptor {
        name: "shoulder_rhythm",
        parameters: &shoulder_rhythm::PARAMETERS,
    },
    Descriptor {
        name: "cuff_offset",
        parameters: &cuff_offset::PARAMETERS,
    },
    Descriptor {
        name: "shoulder_height",
        parameters: &shoulder_height::PARAMETERS,
    },
];

/// The descriptor of the effect called `name`.
pub fn descriptor(name: &str) -> Option<&'static Descriptor> {
    CATALOGUE.iter().find(|d| d.name == name)
}

/// Why an effect could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EffectError {
    /// No effect has this name.
    #[error("unknown effect `{0}` (known: {known})", known = known_names())]
    UnknownEffect(String),
    /// The effect has no such parameter.
    #[error("effect `{effect}` has no parameter `{key}` (it has: {known})")]
    UnknownKey {
        /// Effect.
        effect: &'static str,
        /// The key given.
        key: String,
        /// The keys it has.
        known: String,
    },
    /// A parameter was not given.
    #[error("effect `{effect}` needs `{key}`")]
    MissingKey {
        /// Effect.
        effect: &'static str,
        /// The missing key.
        key: &'static str,
    },
    /// A parameter was given twice.
    #[error("effect `{effect}`: `{key}` given twice")]
    RepeatedKey {
        /// Effect.
        effect: &'static str,
        /// The key.
        key: &'static str,
    },
    /// A value is not finite or out of its range.
    #[error("effect `{effect}`: `{key}` = {value} is outside [{min}, {max}] {unit}")]
    OutOfRange {
        /// Effect.
        effect: &'static str,
        /// The key.
        key: &'static str,
        /// The value given.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
        /// Unit.
        unit: &'static str,
    },
    /// A setting is not `KEY=VALUE` with a numeric value.
    #[error("effect setting `{0}` is not KEY=NUMBER")]
    BadSetting(String),
    /// The same effect was added twice.
    #[error("effect `{0}` given twice")]
    RepeatedEffect(&'static str),
}

fn known_names() -> String {
    CATALOGUE.map(|d| d.name).join(", ")
}

/// One unmodelled effect with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Effect {
    /// See [`joint_friction`].
    JointFriction(JointFriction),
    /// See [`backlash`].
    Backlash(Backlash),
    /// See [`quantization`].
    Quantization(Quantization),
    /// See [`latency`].
    Latency(Latency),
    /// See [`grasp_compliance`].
    GraspCompliance(GraspCompliance),
    /// See [`mass_mismatch`].
    MassMismatch(MassMismatch),
    /// See [`plane_tilt`].
    PlaneTilt(PlaneTilt),
    /// See [`shoulder_drift`].
    ShoulderDrift(ShoulderDrift),
    /// See [`active_torque`].
    ActiveTorque(ActiveTorque),
    /// See [`grasp_slip`].
    GraspSlip(GraspSlip),
    /// See [`passive_stiffness`].
    PassiveStiffness(PassiveStiffness),
    /// See [`spasticity`].
    Spasticity(Spasticity),
    /// See [`shoulder_rhythm`].
    ShoulderRhythm(ShoulderRhythm),
    /// See [`cuff_offset`].
    CuffOffset(CuffOffset),
    /// See [`shoulder_height`].
    ShoulderHeight(ShoulderHeight),
}

impl Effect {
    /// The effect `name` with parameters given as (key, value) pairs.
    ///
    /// # Errors
    /// Unknown name or key, a missing or repeated key, a value that is not
    /// finite or lies outside its range.
    pub fn new(name: &str, settings: &[(&str, f64)]) -> Result<Self, EffectError> {
        let d = descriptor(name).ok_or_else(|| EffectError::UnknownEffect(name.to_string()))?;
        let mut values = [f64::NAN; 2];
        let mut given = [false; 2];
        for (key, value) in settings {
            let index = d
                .parameters
                .iter()
                .position(|p| p.name == *key)
                .ok_or_else(|| EffectError::UnknownKey {
                    effect: d.name,
                    key: (*key).to_string(),
                    known: d
                        .parameters
                        .iter()
                        .map(|p| p.name)
                        .collect::<Vec<_>>()
                        .join(", "),
                })?;
            let p = &d.parameters[index];
            if given[index] {
                return Err(EffectError::RepeatedKey {
                    effect: d.name,
                    key: p.name,
                });
            }
            if !(value.is_finite() && p.min <= *value && *value <= p.max) {
                return Err(EffectError::OutOfRange {
                    effect: d.name,
                    key: p.name,
                    value: *value,
                    min: p.min,
                    max: p.max,
                    unit: p.unit,
                });
            }
            given[index] = true;
            values[index] = *value;
        }
        if let Some(missing) = d.parameters.iter().zip(given).find(|(_, g)| !g) {
            return Err(EffectError::MissingKey {
                effect: d.name,
                key: missing.0.name,
            });
        }
        let [a, b] = values;
        Ok(match d.name {
            "joint_friction" => Self::JointFriction(JointFriction {
                coulomb: a,
                viscous: b,
            }),
            "backlash" => Self::Backlash(Backlash { width: a }),
            "quantization" => Self::Quantization(Quantization { pos: a, ang: b }),
            "latency" => Self::Latency(Latency { delay: a }),
            "grasp_compliance" => Self::GraspCompliance(GraspCompliance { k: a }),
            "mass_mismatch" => Self::MassMismatch(MassMismatch { factor: a }),
            "plane_tilt" => Self::PlaneTilt(PlaneTilt { angle: a }),
            "shoulder_drift" => Self::ShoulderDrift(ShoulderDrift { k: a }),
            "active_torque" => Self::ActiveTorque(ActiveTorque { amp: a, freq: b }),
            "grasp_slip" => Self::GraspSlip(GraspSlip { shift: a, at: b }),
            "passive_stiffness" => Self::PassiveStiffness(PassiveStiffness {
                shoulder: a,
                elbow: b,
            }),
            "spasticity" => Self::Spasticity(Spasticity {
                gain: a,
                threshold: b,
            }),
            "shoulder_rhythm" => Self::ShoulderRhythm(ShoulderRhythm { x: a, z: b }),
            "cuff_offset" => Self::CuffOffset(CuffOffset {
                across: a,
                along: b,
            }),
            _ => Self::ShoulderHeight(ShoulderHeight { height: a }),
        })
    }

    /// The effect `name` with `KEY=VALUE` settings (as `limb simulate
    /// --effect NAME --set KEY=VALUE` takes them).
    ///
    /// # Errors
    /// A setting that is not `KEY=NUMBER`, or any error of [`Effect::new`].
    pub fn parse<S: AsRef<str>>(name: &str, settings: &[S]) -> Result<Self, EffectError> {
        let pairs = settings
            .iter()
            .map(|s| {
                let s = s.as_ref();
                s.split_once('=')
                    .and_then(|(k, v)| Some((k.trim(), v.trim().parse::<f64>().ok()?)))
                    .ok_or_else(|| EffectError::BadSetting(s.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(name, &pairs)
    }

    /// Name as in `plant.md`.
    pub fn name(&self) -> &'static str {
        self.descriptor().name
    }

    /// Its descriptor.
    pub fn descriptor(&self) -> &'static Descriptor {
        let index = match self {
            Self::JointFriction(_) => 0,
            Self::Backlash(_) => 1,
            Self::Quantization(_) => 2,
            Self::Latency(_) => 3,
            Self::GraspCompliance(_) => 4,
            Self::MassMismatch(_) => 5,
            Self::PlaneTilt(_) => 6,
            Self::ShoulderDrift(_) => 7,
            Self::ActiveTorque(_) => 8,
            Self::GraspSlip(_) => 9,
            Self::PassiveStiffness(_) => 10,
            Self::Spasticity(_) => 11,
            Self::ShoulderRhythm(_) => 12,
            Self::CuffOffset(_) => 13,
            Self::ShoulderHeight(_) => 14,
        };
        &CATALOGUE[index]
    }

    /// Parameter values, in the order of [`Descriptor::parameters`].
    pub fn values(&self) -> Vec<f64> {
        match *self {
            Self::JointFriction(e) => vec![e.coulomb, e.viscous],
            Self::Backlash(e) => vec![e.width],
            Self::Quantization(e) => vec![e.pos, e.ang],
            Self::Latency(e) => vec![e.delay],
            Self::GraspCompliance(e) => vec![e.k],
            Self::MassMismatch(e) => vec![e.factor],
            Self::PlaneTilt(e) => vec![e.angle],
            Self::ShoulderDrift(e) => vec![e.k],
            Self::ActiveTorque(e) => vec![e.amp, e.freq],
            Self::GraspSlip(e) => vec![e.shift, e.at],
            Self::PassiveStiffness(e) => vec![e.shoulder, e.elbow],
            Self::Spasticity(e) => vec![e.gain, e.threshold],
            Self::ShoulderRhythm(e) => vec![e.x, e.z],
            Self::CuffOffset(e) => vec![e.across, e.along],
            Self::ShoulderHeight(e) => vec![e.height],
        }
    }
}

/// A set of effects, at most one of each kind, as the plant applies them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Effects {
    /// Joint friction.
    pub joint_friction: Option<JointFriction>,
    /// Backlash on psi.
    pub backlash: Option<Backlash>,
    /// Pose quantisation.
    pub quantization: Option<Quantization>,
    /// Measurement delay.
    pub latency: Option<Latency>,
    /// Compliant grasp.
    pub grasp_compliance: Option<GraspCompliance>,
    /// Forearm mass error.
    pub mass_mismatch: Option<MassMismatch>,
    /// Tilted arm plane.
    pub plane_tilt: Option<PlaneTilt>,
    /// Yielding shoulder.
    pub shoulder_drift: Option<ShoulderDrift>,
    /// Periodic elbow torque.
    pub active_torque: Option<ActiveTorque>,
    /// Grasp slide.
    pub grasp_slip: Option<GraspSlip>,
    /// Passive elastic joint torques.
    pub passive_stiffness: Option<PassiveStiffness>,
    /// Velocity-dependent elbow reflex.
    pub spasticity: Option<Spasticity>,
    /// Shoulder centre moving with the elevation.
    pub shoulder_rhythm: Option<ShoulderRhythm>,
    /// Grasp off the forearm's line.
    pub cuff_offset: Option<CuffOffset>,
    /// Shoulder above the elbow at rest.
    pub shoulder_height: Option<ShoulderHeight>,
}

impl Effects {
    /// The set of `effects`.
    ///
    /// # Errors
    /// [`EffectError::RepeatedEffect`] when an effect appears twice.
    pub fn new(effects: &[Effect]) -> Result<Self, EffectError> {
        fn put<T>(slot: &mut Option<T>, value: T, name: &'static str) -> Result<(), EffectError> {
            if slot.replace(value).is_some() {
                return Err(EffectError::RepeatedEffect(name));
            }
            Ok(())
        }
        let mut set = Self::default();
        for effect in effects {
            let name = effect.name();
            match *effect {
                Effect::JointFriction(e) => put(&mut set.joint_friction, e, name)?,
                Effect::Backlash(e) => put(&mut set.backlash, e, name)?,
                Effect::Quantization(e) => put(&mut set.quantization, e, name)?,
                Effect::Latency(e) => put(&mut set.latency, e, name)?,
                Effect::GraspCompliance(e) => put(&mut set.grasp_compliance, e, name)?,
                Effect::MassMismatch(e) => put(&mut set.mass_mismatch, e, name)?,
                Effect::PlaneTilt(e) => put(&mut set.plane_tilt, e, name)?,
                Effect::ShoulderDrift(e) => put(&mut set.shoulder_drift, e, name)?,
                Effect::ActiveTorque(e) => put(&mut set.active_torque, e, name)?,
                Effect::GraspSlip(e) => put(&mut set.grasp_slip, e, name)?,
                Effect::PassiveStiffness(e) => put(&mut set.passive_stiffness, e, name)?,
                Effect::Spasticity(e) => put(&mut set.spasticity, e, name)?,
                Effect::ShoulderRhythm(e) => put(&mut set.shoulder_rhythm, e, name)?,
                Effect::CuffOffset(e) => put(&mut set.cuff_offset, e, name)?,
                Effect::ShoulderHeight(e) => put(&mut set.shoulder_height, e, name)?,
            }
        }
        Ok(set)
    }
}

#[cfg(test)]
mod tests {
    use super::{Effect, EffectError, Effects, CATALOGUE};

    #[test]
    fn parses_every_effect_at_its_range_limits() {
        for d in CATALOGUE {
            for pick in [|p: &super::Parameter| p.min, |p: &super::Parameter| p.max] {
                let settings: Vec<String> = d
                    .parameters
                    .iter()
                    .map(|p| format!("{}={}", p.name, pick(p)))
                    .collect();
                let effect = Effect::parse(d.name, &settings).unwrap();
                assert_eq!(effect.name(), d.name);
                let values: Vec<f64> = d.parameters.iter().map(pick).collect();
                assert_eq!(effect.values(), values);
            }
        }
    }

    #[test]
    fn rejects_bad_names_keys_and_values() {
        assert!(matches!(
            Effect::parse("wobble", &["k=1"]),
            Err(EffectError::UnknownEffect(_))
        ));
        assert!(matches!(
            Effect::parse("backlash", &["wide=0.01"]),
            Err(EffectError::UnknownKey { .. })
        ));
        assert!(matches!(
            Effect::parse("joint_friction", &["coulomb=0.1"]),
            Err(EffectError::MissingKey { key: "viscous", .. })
        ));
        assert!(matches!(
            Effect::parse("backlash", &["width=0.01", "width=0.02"]),
            Err(EffectError::RepeatedKey { .. })
        ));
        for bad in ["width=-0.01", "width=1", "width=NaN", "width=inf"] {
            assert!(
                matches!(
                    Effect::parse("backlash", &[bad]),
                    Err(EffectError::OutOfRange { .. })
                ),
                "{bad}"
            );
        }
        assert!(matches!(
            Effect::parse("backlash", &["width"]),
            Err(EffectError::BadSetting(_))
        ));
        let b = Effect::parse("backlash", &["width=0.01"]).unwrap();
        assert_eq!(
            Effects::new(&[b, b]),
            Err(EffectError::RepeatedEffect("backlash"))
        );
    }
}
