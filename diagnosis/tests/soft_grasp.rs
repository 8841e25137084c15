//! The arm's lengths are solved by Gauss–Newton around a reference arm
//! (`ArmModel::linearise`). Under a very soft grasp the readings move
//! with the arm differently from the nominal sim's (the deflection, force
//! over stiffness, moves with the arm too); with the nominal sim's
//! derivative the solve settled only linearly, 1-3 mm a step, and after
//! the refits the arm was still 16 mm off with a spurious active torque
//! added for what was left (blind self-check seed 161803, log 5: the
//! kernel refused the arm, so the fit starts 4-5 cm from it).

mod common;

use common::{arm_error, diagnosed};
use limb_sim::effects::Effect;

#[test]
fn a_very_soft_grasp_is_one_effect_with_the_arm_corrected() {
    let (l1, l2, k) = (
        0.255_474_934_037_242_7,
        0.160_093_758_592_882_1,
        205.599_734_188_847_7,
    );
    let compliance = Effect::new("grasp_compliance", &[("k", k)]).unwrap();
    let d = diagnosed(l1, l2, 465_097_474_080_156, &[compliance]);
    let names: Vec<&str> = d.effects.iter().map(|e| e.effect.as_str()).collect();
    assert_eq!(names, ["grasp_compliance"], "{:?}", d.effects);
    let fitted = d.effects[0].params["k"];
    assert!(((fitted - k) / k).abs() < 0.01, "k {fitted} for {k}");
    let error = arm_error(&d, l1, l2);
    assert!(error < 0.001, "arm {:?} for ({l1}, {l2}): {error} m", d.arm);
}
