//! Acceptance on the independent implementation's labelled logs
//! (`shared/data/effects/`): for every log the right effect (or `none`)
//! ranks first, its fitted parameters are near the label's, and the
//! held-out gap shrinks.

use limb_diagnosis::verdict::diagnose;
use std::path::PathBuf;

fn effects_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/effects")
}

/// Relative tolerance of each fitted parameter against the label: the
/// logs are noisy, quantization's steps and the slip time are found to
/// the sample, the rest to a few per cent.
const PARAMETER_TOLERANCE: f64 = 0.05;

#[test]
fn every_labelled_log_is_diagnosed_as_its_effect() {
    let text = std::fs::read_to_string(effects_dir().join("labels.json")).unwrap();
    let labels: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut misses = Vec::new();
    for label in labels.as_array().unwrap() {
        let file = label["file"].as_str().unwrap();
        let records = limb_sim::log::read(&effects_dir().join(file)).unwrap();
        let (l1, l2) = (label["l1"].as_f64().unwrap(), label["l2"].as_f64().unwrap());
        let d = diagnose(l1, l2, &records, 2, &|_| {}).unwrap().diagnosis;
        let expected = label["effect"].as_str().unwrap();
        if d.effect != expected {
            misses.push(format!("{file}: {} instead of {expected}", d.effect));
            continue;
        }
        assert_eq!(d.ranking.len(), 10, "{file}: every candidate is ranked");
        if expected == "none" {
            assert_eq!(d.gap.shrink, 0.0, "{file}");
            assert!(d.location.signals.is_empty(), "{file}: {:?}", d.location);
            continue;
        }
        assert!(d.gap.shrink > 0.6, "{file}: shrink {}", d.gap.shrink);
        let fitted = &d.ranking[0].params;
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
    assert!(misses.is_empty(), "misranked: {misses:?}");
}
