//! The report's charts of a person's arm's fitted effects (`limb
//! diagnose --report`): what the fitted parameters mean for the arm, as a
//! clinician-engineer reads them — the passive joint torque against the
//! joint angle, the reflex torque against the elbow's speed, the
//! shoulder centre's path against the upper arm's elevation, the grasp's
//! place off the forearm against its elevation. Each curve is the
//! plant's own model (`limb_sim::effects`) at the fitted parameters.

use super::outcome::Diagnosis;
use crate::report::Curve;
use limb_sim::effects::{
    passive_stiffness, CuffOffset, PassiveStiffness, ShoulderRhythm, Spasticity,
};
use std::collections::BTreeMap;

/// Points per curve.
const POINTS: usize = 121;

fn span(from: f64, to: f64) -> Vec<f64> {
    (0..POINTS)
        .map(|i| from + (to - from) * i as f64 / (POINTS - 1) as f64)
        .collect()
}

fn value(params: &BTreeMap<String, f64>, key: &str) -> f64 {
    params.get(key).copied().unwrap_or(f64::NAN)
}

/// One chart per effect added that belongs to a person's arm, in the
/// order added; empty when none was.
pub fn curves(diagnosis: &Diagnosis) -> Vec<Curve> {
    diagnosis
        .effects
        .iter()
        .filter_map(|e| {
            let p = &e.params;
            let fitted = e.parameters_text();
            match e.effect.as_str() {
                "passive_stiffness" => {
                    let model = PassiveStiffness {
                        shoulder: value(p, "shoulder"),
                        elbow: value(p, "elbow"),
                    };
                    let xs = span(-0.3, 2.5);
                    let [shoulder, elbow] = [0, 1].map(|joint| {
                        xs.iter()
                            .map(|q| {
                                let mut angles = [1.0, 1.25];
                                angles[joint] = *q;
                                model.torques(angles)[joint]
                            })
                            .collect::<Vec<f64>>()
                    });
                    Some(Curve {
                        title: format!("passive_stiffness: passive joint torque ({fitted})"),
                        caption: format!(
                            "The joints' passive elastic torque at the fitted parameters, \
                             against the joint's angle: shoulder elevation q1 above the table \
                             (range {:?} rad), elbow flexion q2 (range {:?} rad, 0 = fully \
                             extended). Positive lifts (flexes); it rises steeply (×e every \
                             {:.2} rad) towards each end of the range.",
                            passive_stiffness::SHOULDER_RANGE,
                            passive_stiffness::ELBOW_RANGE,
                            1.0 / passive_stiffness::STEEPNESS
                        ),
                        abscissa: "joint angle [rad]".into(),
                        unit: "N m".into(),
                        xs,
                        lines: vec![("shoulder".into(), shoulder), ("elbow".into(), elbow)],
                    })
                }
                "spasticity" => {
                    let model = Spasticity {
                        gain: value(p, "gain"),
                        threshold: value(p, "threshold"),
                    };
                    let xs = span(-0.5, 0.5);
                    let torque = xs.iter().map(|v| model.torque(*v)).collect();
                    Some(Curve {
                        title: format!("spasticity: elbow reflex torque ({fitted})"),
                        caption: format!(
                            "The stretch reflex's torque at the elbow against the elbow's \
                             speed (flexion positive) {:.0} ms earlier: zero below the \
                             threshold speed, resisting the motion beyond it.",
                            1000.0 * limb_sim::effects::spasticity::REFLEX_DELAY
                        ),
                        abscissa: "elbow speed q̇2 [rad/s]".into(),
                        unit: "N m".into(),
                        xs,
                        lines: vec![("reflex torque".into(), torque)],
                    })
                }
                "shoulder_rhythm" => {
                    let model = ShoulderRhythm {
                        x: value(p, "x"),
                        z: value(p, "z"),
                    };
                    let xs = span(0.0, 1.6);
                    let [x, z] = [0, 1].map(|axis| {
                        xs.iter()
                            .map(|q| 1000.0 * model.displacement(*q)[axis])
                            .collect::<Vec<f64>>()
                    });
                    Some(Curve {
                        title: format!("shoulder_rhythm: shoulder centre ({fitted})"),
                        caption: "The shoulder centre's displacement from its place at rest \
                                  against the upper arm's elevation q1 (frame S: x towards the \
                                  shoulder, z up); it follows the posture, it does not yield \
                                  to force (that is shoulder_drift)."
                            .into(),
                        abscissa: "upper-arm elevation q1 [rad]".into(),
                        unit: "mm".into(),
                        xs,
                        lines: vec![("x".into(), x), ("z".into(), z)],
                    })
                }
                "cuff_offset" => {
                    let model = CuffOffset {
                        across: value(p, "across"),
                        along: value(p, "along"),
                    };
                    let xs = span(0.0, 1.8);
                    let [x, z] = [0, 1].map(|axis| {
                        xs.iter()
                            .map(|psi| 1000.0 * model.displacement(*psi)[axis])
                            .collect::<Vec<f64>>()
                    });
                    Some(Curve {
                        title: format!("cuff_offset: grasp off the forearm's line ({fitted})"),
                        caption: format!(
                            "The grasp sits {:.1} mm off the forearm's line (dorsal positive) \
                             and the forearm extends {:.1} mm beyond it; the chart is the \
                             grasp's displacement against the forearm's elevation psi, from \
                             where a grasp on the line would be (zero at psi = 0, frame S).",
                            1000.0 * model.across,
                            1000.0 * model.along
                        ),
                        abscissa: "forearm elevation psi [rad]".into(),
                        unit: "mm".into(),
                        xs,
                        lines: vec![("x".into(), x), ("z".into(), z)],
                    })
                }
                _ => None,
            }
        })
        .collect()
}
