//! REQ-MON-011, REQ-EST-004: `limb population` — 500 random arms (l1
//! 0.22-0.38 m, l2 0.15-0.26 m), noise on, seed 2026 (never used while the
//! lift shaping was tuned; seed 7 was). Every arm stays inside the joint
//! limits during Estimate, and every arm the validator accepts is within
//! 1 mm of the truth in l1 and l2, within three of its reported standard
//! uncertainties on at least 485 of them. `limb population` prints the
//! figures the README quotes.

mod common;

use std::process::Command;

/// REQ-MON-011, REQ-EST-004, REQ-EST-008: 500 random arms stay inside the
/// joint limits during Estimate, every accepted model is within 1 mm and
/// within three standard uncertainties on at least 485 of them.
#[test]
fn five_hundred_random_arms_stay_inside_the_limits_and_within_1_mm() {
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["population", "--arms", "500", "--seed", "2026", "--json"])
        .output()
        .unwrap();
    let report = common::json_of(&out);
    assert_eq!(report["arms"], 500);
    assert_eq!(report["within_limits"], 500, "{}", report["refused"]);
    assert_eq!(report["over_1mm"], 0);
    let validated = report["validated"].as_u64().unwrap();
    let refused: u64 = report["refused"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(
        validated + refused,
        500,
        "every arm is validated or refused with a reason"
    );
    // The README's figures: 500 of 500 (since the lift's hold keeps the
    // joints' slack, REQ-MON-011: before it one short arm was stopped by
    // the elbow monitor), no hyperextension at all, models at most
    // 0.713 mm off.
    assert_eq!(validated, 500, "{}", report["refused"]);
    let hyperextension = report["max_hyperextension"].as_f64().unwrap();
    assert!(
        hyperextension <= 0.01_f64.to_radians(),
        "{hyperextension} rad of hyperextension"
    );
    // REQ-EST-008: the reported standard uncertainty u covers both errors
    // at 3u on 485 of the 500 arms (97 %; at 2u 377, at 1u 153: u is about
    // 1.4 times small on this plant, README).
    let within = &report["within_uncertainty"];
    assert!(within[2].as_u64().unwrap() >= 485, "{within}");
    for outcome in report["outcomes"].as_array().unwrap() {
        if let Some(error) = outcome["error"].as_array() {
            for e in error {
                assert!(e.as_f64().unwrap() <= 0.72e-3, "{outcome}");
            }
        }
    }
}
