//! A person's arm's own effects (`spec/human-arm.md`), each on a log of
//! the development self-check (seed 4242, `--focus human`; not a blind
//! seed), diagnosed without the arm lengths: the effect is named first,
//! its parameters come back, the arm is corrected to 3 mm, and the
//! report draws the fitted curve. Small ones on purpose: a spasticity of
//! 5 σ (identifiable), a shoulder rhythm of 4 σ once the lengths absorb
//! what they can.

mod common;

use common::{arm_error, diagnosed};
use limb_diagnosis::plant::arm::blind::simulate;
use limb_diagnosis::plant::arm::curves::curves;
use limb_diagnosis::plant::arm::{diagnose, ArmBuild, Lengths};
use limb_diagnosis::report::{page, Subject};
use limb_sim::effects::Effect;

/// Diagnoses the case and checks the answer, the parameters within
/// `tolerance` (relative) and the arm within 3 mm.
fn named((l1, l2): (f64, f64), seed: u64, name: &str, params: &[(&str, f64)], tolerance: f64) {
    let effect = Effect::new(name, params).unwrap();
    let d = diagnosed(l1, l2, seed, &[effect]);
    assert_eq!(d.effect, name, "{:?}", d.effects);
    for (key, value) in params {
        let fitted = d.effects[0].params[*key];
        assert!(
            ((fitted - value) / value).abs() < tolerance,
            "{name}.{key}: {fitted} for {value}"
        );
    }
    let error = arm_error(&d, l1, l2);
    assert!(error < 0.003, "arm {:?} for ({l1}, {l2}): {error} m", d.arm);
}

#[test]
fn a_passive_stiffness_is_named_with_its_torques() {
    named(
        (0.344_307_648_690_117_93, 0.229_474_247_929_122_9),
        276_763_109_816_436,
        "passive_stiffness",
        &[
            ("shoulder", 0.343_746_977_543_004_4),
            ("elbow", 0.070_301_588_818_488_46),
        ],
        0.05,
    );
}

#[test]
fn a_small_spasticity_is_named() {
    // 6.7 σ with the true arm, 5.3 σ identifiable; the threshold (5 mrad/s)
    // is far below the lift's speeds, so only the gain is asked for.
    let (l1, l2) = (0.358_098_099_229_181_8, 0.189_020_771_580_348_58);
    let (gain, threshold) = (0.346_460_137_125_089_6, 0.005_430_749_845_109_677);
    let effect = Effect::new("spasticity", &[("gain", gain), ("threshold", threshold)]).unwrap();
    let d = diagnosed(l1, l2, 580_656_044_972_934, &[effect]);
    assert_eq!(d.effect, "spasticity", "{:?}", d.effects);
    let fitted = d.effects[0].params["gain"];
    assert!(
        ((fitted - gain) / gain).abs() < 0.2,
        "gain {fitted} for {gain}"
    );
    assert!(arm_error(&d, l1, l2) < 0.003, "{:?}", d.arm);
}

#[test]
fn a_small_shoulder_rhythm_is_named_not_taken_for_a_longer_arm() {
    named(
        (0.355_823_587_332_209_53, 0.217_533_375_430_047_72),
        931_188_210_942_541,
        "shoulder_rhythm",
        &[
            ("x", 0.002_226_039_931_366_757),
            ("z", 0.003_672_815_705_330_78),
        ],
        0.2,
    );
}

/// The report of a cuff offset draws what it means: the grasp's place
/// against the forearm's elevation, with the fitted parameters.
#[test]
fn a_cuff_offset_is_named_and_its_report_draws_the_grasp_off_the_line() {
    let (l1, l2) = (0.253_195_367_297_407_4, 0.173_056_418_711_326_54);
    let (across, along) = (0.006_615_723_613_578_954, -0.018_497_293_857_174_753);
    let effect = Effect::new("cuff_offset", &[("across", across), ("along", along)]).unwrap();
    let records = simulate(l1, l2, 241_495_304_274_520, &[effect]).unwrap();
    let diagnosed = diagnose(Lengths::Fitted, ArmBuild::Rod, &records, 2, &|_| {}).unwrap();
    let d = &diagnosed.diagnosis;
    assert_eq!(d.effect, "cuff_offset", "{:?}", d.effects);
    let fitted = &d.effects[0].params;
    assert!(
        ((fitted["across"] - across) / across).abs() < 0.05,
        "{fitted:?}"
    );
    assert!((fitted["along"] - along).abs() < 0.005, "{fitted:?}");
    assert!(arm_error(d, l1, l2) < 0.003, "{:?}", d.arm);
    let charts = curves(d);
    assert_eq!(charts.len(), 1);
    assert!(charts[0].title.starts_with("cuff_offset"));
    let html = page(&Subject {
        model: &diagnosed.model,
        selection: &diagnosed.selection,
        source: "cuff.csv",
        held_out: "alternating 1 s blocks",
        facts: &[],
        curves: &charts,
    });
    assert!(html.contains("What the fitted effects mean"));
    assert!(html.contains("forearm elevation psi [rad]"));
    assert!(html.contains("cuff_offset: grasp off the forearm"));
}
