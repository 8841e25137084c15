//! The body the lengths are put on (`--arm rod|person`,
//! `spec/human-arm.md` "A person's build"): a person's forearm and hand
//! weigh more than the dummy's rod and carry their mass further out, so a
//! person's log read on the dummy's rods shows a "mass mismatch" that is
//! only the build. Read on the person's build, the same log is clean, and
//! a real excess (a cast) is still found: as the forearm's weight moment,
//! which a slow lift cannot split between a heavier forearm
//! (`mass_mismatch`) and one whose mass lies further beyond the cuff
//! (`cuff_offset`'s `along`); `spec/human-arm.md` says why.

use limb_diagnosis::plant::arm::blind::simulate_on;
use limb_diagnosis::plant::arm::{diagnose, ArmBuild, Diagnosis, Lengths};
use limb_sim::effects::Effect;
use limb_sim::log::Record;
use limb_sim::{scripted, ArmParameters, Plant, PlantParameters};

/// A held-out arm of a person's proportions (not the reference person's
/// lengths, so the cube law is exercised) and its noise seed.
const ARM: (f64, f64) = (0.312, 0.236);
const SEED: u64 = 9_117;

/// The person's log with `effects`, diagnosed on `build`, lengths fitted.
fn read_on(build: ArmBuild, effects: &[Effect]) -> Diagnosis {
    let records = simulate_on(ArmBuild::Person, ARM.0, ARM.1, SEED, effects).unwrap();
    diagnose(Lengths::Fitted, build, &records, 2, &|_| {})
        .unwrap()
        .diagnosis
}

fn arm_error(d: &Diagnosis) -> f64 {
    (d.arm.l1 - ARM.0).abs().max((d.arm.l2 - ARM.1).abs())
}

#[test]
fn a_persons_log_read_on_the_dummys_rods_shows_a_mass_mismatch() {
    let d = read_on(ArmBuild::Rod, &[]);
    assert_eq!(d.effect, "mass_mismatch", "{:?}", d.effects);
    let factor = d.effects[0].params["factor"];
    assert!(factor > 1.5, "factor {factor}");
}

#[test]
fn a_persons_log_read_on_a_persons_build_is_clean() {
    let d = read_on(ArmBuild::Person, &[]);
    assert!(d.effects.is_empty(), "{:?}", d.effects);
    assert!(arm_error(&d) < 0.001, "arm {:?}", d.arm);
}

/// A person's arm that rests bent (the shoulder 5 cm above the elbow on
/// the table, `shoulder_height`) is a person's arm, not an effect: on a
/// person's build the arm's fit holds the shoulder's height with the
/// lengths (started at the kernel's estimate of the shoulder and the
/// elbow), so the log reads clean with the arm and the height right.
/// Without the height in the fit, the bent rest reads as
/// `shoulder_rhythm` and `cuff_offset` (`diagnosis/README.md`).
#[test]
fn a_raised_shoulder_is_part_of_a_persons_arm() {
    let raised = Effect::new("shoulder_height", &[("height", 0.05)]).unwrap();
    let d = read_on(ArmBuild::Person, &[raised]);
    assert!(d.effects.is_empty(), "{:?}", d.effects);
    assert!(arm_error(&d) < 0.001, "arm {:?}", d.arm);
    assert!(
        (d.arm.shoulder[1] - 0.05).abs() < 0.001,
        "shoulder {:?}",
        d.arm.shoulder
    );
}

/// The forearm's gravity moment the effects found, over the build's:
/// `mass_mismatch`'s factor times `cuff_offset`'s (l2 + along) / l2.
fn forearm_moment_factor(d: &Diagnosis) -> f64 {
    d.effects
        .iter()
        .map(|e| match e.effect.as_str() {
            "mass_mismatch" => e.params["factor"],
            "cuff_offset" => (d.arm.l2 + e.params["along"]) / d.arm.l2,
            _ => 1.0,
        })
        .product()
}

#[test]
fn a_cast_on_a_persons_forearm_is_found_as_the_forearms_weight() {
    let d = read_on(ArmBuild::Person, &[cast()]);
    assert!(
        ["mass_mismatch", "cuff_offset"].contains(&d.effect.as_str()),
        "{:?}",
        d.effects
    );
    let factor = forearm_moment_factor(&d);
    assert!(
        (factor - 1.5).abs() < 0.05,
        "moment x{factor}: {:?}",
        d.effects
    );
}

/// Open (issue 35): the cast's log is read as `cuff_offset` (along
/// 0.118 m, the same moment) and then a `shoulder_rhythm` of -0.048 m/rad
/// that a 96 mm longer upper arm pays for (l1 0.408 m for 0.312 m): the
/// held-out criterion does not yet prefer the one effect that explains
/// the log with the arm right.
#[test]
#[ignore = "issue 35: a cast's arm comes back 96 mm long (cuff_offset + shoulder_rhythm)"]
fn a_cast_leaves_the_arm_within_3_mm() {
    let d = read_on(ArmBuild::Person, &[cast()]);
    assert!(arm_error(&d) < 0.003, "arm {:?}: {:?}", d.arm, d.ranking);
}

fn cast() -> Effect {
    Effect::new("mass_mismatch", &[("factor", 1.5)]).unwrap()
}

/// A log that ends before the upper arm leaves the table holds nothing
/// of the upper arm's length: the wrist's path and wrench do not move
/// with l1 while the table bears the upper arm. The diagnosis says so
/// (`arm.resolution` null for l1, `arm.unresolved` names it) instead of
/// passing the fit's l1 off as the arm's; the forearm, which did move, is
/// told finely. The whole log tells both (the `cast` MyoArm subject,
/// whose lift ended at its force margin before the upper arm rose, read
/// 209 mm long without this).
#[test]
fn a_length_the_log_holds_nothing_of_is_reported_as_not_resolved() {
    let records = simulate_on(ArmBuild::Person, ARM.0, ARM.1, SEED, &[]).unwrap();
    // When the upper arm leaves the table, from the same run's truth
    // (which the diagnosis's records do not carry).
    let truth: Vec<Record> = {
        let mut params = PlantParameters::new(ARM.0, ARM.1);
        params.arm = ArmParameters::built(ArmBuild::Person, ARM.0, ARM.1);
        params.seed = SEED;
        let mut plant = Plant::new(params).unwrap();
        let rows = scripted::estimation_run(&mut plant).unwrap();
        rows.iter().map(Record::from_row).collect()
    };
    let rest = truth[0].truth.unwrap().q[0];
    let lifted = truth
        .iter()
        .position(|r| r.truth.is_some_and(|t| t.q[0] > rest + 1e-4))
        .unwrap();
    let forearm_only = &records[..lifted];
    assert!(forearm_only.last().unwrap().time > 5.0, "{lifted} samples");
    let read = |records| {
        diagnose(Lengths::Fitted, ArmBuild::Person, records, 2, &|_| {})
            .unwrap()
            .diagnosis
            .arm
    };
    let arm = read(forearm_only);
    assert_eq!(arm.unresolved, ["l1"], "{arm:?}");
    let [l1, l2] = arm.resolution.unwrap();
    assert!(l1.is_none() && l2.is_some_and(|r| r < 0.001), "{arm:?}");
    let whole = read(&records);
    assert!(whole.unresolved.is_empty(), "{whole:?}");
}
