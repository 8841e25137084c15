//! Acceptance on the independent implementation's labelled logs
//! (`shared/data/effects/`), arm lengths not given: for every log the
//! right effect (or `none`) is added first, its fitted parameters are near
//! the label's, the held-out gap shrinks, and the arm corrected for the
//! effects is within 3 mm of the label's.

use limb_diagnosis::plant::arm::{diagnose, ArmBuild, Lengths};
use std::path::PathBuf;

fn effects_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/effects")
}

/// Relative tolerance of each fitted parameter against the label: the
/// logs are noisy and the arm is fitted with the effect (the viscous
/// friction comes out 5.5 % high beside it); quantization's steps and the
/// slip time are found to the sample, the rest to a few per cent.
const PARAMETER_TOLERANCE: f64 = 0.1;
/// Largest error of each corrected arm length [m] (issue 16's goal).
const ARM_TOLERANCE: f64 = 0.003;
/// Labelled logs the diagnosis without lengths does not get right: none.
/// `grasp_slip.csv` was one until the slip's prediction was anchored at
/// the forearm before the slip (`ArmModel::anchor`): the nominal fit
/// takes the arm after the slip (l2 14.7 mm long), and predicted around
/// that arm the slip removed too little of the gap. A miss must be an
/// honest one (`unexplained`, never `none` or another effect), and a new
/// miss fails this test until the list is brought up to date.
const KNOWN_MISSES: [&str; 0] = [];

#[test]
fn every_labelled_log_is_diagnosed_as_its_effect() {
    let text = std::fs::read_to_string(effects_dir().join("labels.json")).unwrap();
    let labels: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut misses = Vec::new();
    for label in labels.as_array().unwrap() {
        let file = label["file"].as_str().unwrap();
        let records = limb_sim::log::read(&effects_dir().join(file)).unwrap();
        let (l1, l2) = (label["l1"].as_f64().unwrap(), label["l2"].as_f64().unwrap());
        let d = diagnose(Lengths::Fitted, ArmBuild::Rod, &records, 2, &|_| {})
            .unwrap()
            .diagnosis;
        let expected = label["effect"].as_str().unwrap();
        let arm_right =
            (d.arm.l1 - l1).abs() < ARM_TOLERANCE && (d.arm.l2 - l2).abs() < ARM_TOLERANCE;
        if d.effect != expected || !arm_right {
            println!(
                "{file}: {} (arm {} {}) instead of {expected} (arm {l1} {l2})",
                d.effect, d.arm.l1, d.arm.l2
            );
            assert_eq!(d.effect, "unexplained", "{file}: a miss must be honest");
            misses.push(file.to_owned());
            continue;
        }
        assert_eq!(d.ranking.len(), 14, "{file}: every candidate is ranked");
        if expected == "none" {
            assert_eq!(d.gap.shrink, 0.0, "{file}");
            assert!(d.location.signals.is_empty(), "{file}: {:?}", d.location);
            continue;
        }
        assert!(d.gap.shrink > 0.6, "{file}: shrink {}", d.gap.shrink);
        let fitted = &d.effects[0].params;
        for (key, value) in label["params"].as_object().unwrap() {
            let truth = value.as_f64().unwrap();
            let got = fitted[key.as_str()];
            assert!(
                ((got - truth) / truth).abs() < PARAMETER_TOLERANCE,
                "{file}: {key} = {got}, label {truth}"
            );
        }
        let (start, end) = (d.location.t_start.unwrap(), d.location.t_end.unwrap());
        assert!(start < end && !d.location.signals.is_empty(), "{file}");
    }
    assert_eq!(misses, KNOWN_MISSES, "misses against the known ones");
}
