//! `limb run --plant myoarm --subject NAME`: a whole kernel session on the
//! MuJoCo musculoskeletal arm of `plants/myoarm` (MyoSuite's `myoarm_r`),
//! the plant's Python environment set up by `plants/myoarm/setup.sh`
//! (`.ci/run` runs it: missing in CI is a failure, elsewhere the test
//! says it skipped).

mod common;

use std::path::Path;
use std::process::Command;

fn plant_ready() -> bool {
    let python = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../plants/myoarm/.venv/bin/python"
    );
    common::tool_ready(Path::new(python), "plants/myoarm/setup.sh")
}

/// One session on the 50th-percentile subject: the plant speaks the
/// protocol for the whole session (no robot failure), the kernel runs its
/// estimation lift on it, the truth is the plant's anatomy (glenohumeral
/// centre to elbow centre), the joint extremes come from the model's own
/// joints, and the interaction force stays plausible.
#[test]
fn a_session_runs_on_the_musculoskeletal_arm() {
    if !plant_ready() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["run", "--plant", "myoarm", "--subject", "m50", "--json"])
        .output()
        .unwrap();
    let report = common::json_of(&out);
    assert!(report["robot_error"].is_null(), "{report}");
    assert!(report["plant"]["name"].as_str().unwrap().contains("m50"));
    assert!(
        report["plant"]["frames"].as_u64().unwrap() > 20_000,
        "{}",
        report["plant"]
    );
    let l1 = report["truth"]["l1"].as_f64().unwrap();
    let l2 = report["truth"]["l2"].as_f64().unwrap();
    assert!(
        (0.27..0.31).contains(&l1) && (0.20..0.24).contains(&l2),
        "{l1} {l2}"
    );
    let events: Vec<&str> = report["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| e["what"].as_str())
        .collect();
    assert!(
        events.iter().any(|e| e.starts_with("Grasp → Estimate")),
        "{events:?}"
    );
    let elevation = report["joint_extremes"]["estimate"]["max_shoulder_elevation"]
        .as_f64()
        .unwrap();
    assert!((0.3..2.2).contains(&elevation), "{elevation}");
    let force = report["max_force_n"].as_f64().unwrap();
    assert!(force > 5.0 && force < 60.0, "{force}");
}

/// `--plant myoarm` needs a subject; an unknown subject is the plant's
/// refusal, reported as a robot failure.
#[test]
fn the_myoarm_plant_needs_a_known_subject() {
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["run", "--plant", "myoarm"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    if !plant_ready() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["run", "--plant", "myoarm", "--subject", "nobody", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["completed"], false);
}

/// REQ-MON-014 on the musculoskeletal arm: `cast` (a forearm 50 % heavier;
/// held out for the rhythm prior, but its force trace and m95's were seen
/// when the 3 N margin was chosen) resists the lift more than it may pull. The lift ends on its
/// force margin (42 N, the 45 N limit less 3 N) with the forearm upright
/// and the upper arm still on the table; the arm is held, and the kernel
/// stops with a named cause (the upper arm never moved) before the force
/// monitor has to: no monitor event, the force below its limit throughout
/// (measured 43.3 N at the default noise seed; before REQ-MON-014 the
/// force monitor stopped this session at 45.4 N).
#[test]
fn req_mon_014_a_resisting_arm_ends_the_lift_before_the_force_monitor() {
    if !plant_ready() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["run", "--plant", "myoarm", "--subject", "cast", "--json"])
        .output()
        .unwrap();
    let report = common::json_of(&out);
    assert!(report["robot_error"].is_null(), "{report}");
    let events = report["events"].as_array().unwrap();
    let ended = events
        .iter()
        .find(|e| e["event"]["event"] == "lift_ended")
        .unwrap_or_else(|| panic!("the lift never ended: {report}"));
    let end = &ended["event"]["end"];
    assert_eq!(end["reason"], "force_margin", "{end}");
    assert_eq!(end["bound_n"], 42.0, "{end}");
    assert!(end["force_n"].as_f64().unwrap() >= 42.0, "{end}");
    let stop = events
        .iter()
        .find(|e| e["event"]["to"] == "safe_stop")
        .unwrap_or_else(|| panic!("no stop: {report}"));
    assert_eq!(
        stop["event"]["reason"]["name"], "estimation_failed",
        "{stop}"
    );
    assert!(
        report["monitor_events"].as_array().unwrap().is_empty(),
        "{report}"
    );
    assert!(report["max_force_n"].as_f64().unwrap() < 45.0, "{report}");
}

/// REQ-STOP-002 on the musculoskeletal arm: an emergency stop in the middle
/// of the lift (11.1 s) on a held-out subject (f95) is a hold that carries
/// the arm: the grasp sags at most 2 mm over the 2 s after it (measured
/// 0.08 mm; 48 stops on the 12 subjects: worst 0.48 mm, README), no monitor
/// trips and the force stays within the limit.
#[test]
fn an_emergency_stop_mid_lift_holds_the_musculoskeletal_arm() {
    if !plant_ready() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args([
            "run",
            "--plant",
            "myoarm",
            "--subject",
            "f95",
            "--json",
            "--stop-at",
            "11.1",
        ])
        .output()
        .unwrap();
    let report = common::json_of(&out);
    let stop = &report["stop"];
    assert_eq!(stop["state"], "estimate", "{stop}");
    assert_eq!(stop["cause"], "emergency_stop", "{stop}");
    assert_eq!(stop["category"], "hold", "{stop}");
    assert!(stop["watched_s"].as_f64().unwrap() >= 2.0 - 1e-3, "{stop}");
    assert!(stop["sag_m"].as_f64().unwrap() <= 2e-3, "{stop}");
    assert!(stop["max_force_n"].as_f64().unwrap() <= 45.0, "{stop}");
    assert!(
        report["monitor_events"].as_array().unwrap().is_empty(),
        "{report}"
    );
}

/// REQ-EST-006 on the twelve MyoArm subjects, closed loop, noise on, the
/// `person` arm (`limb population --plant myoarm --subjects all`; README
/// "A person's arm"): at least 80 % of the non-spastic subjects validated
/// with l1 and l2 within 5 mm of the anatomy (measured at this noise seed,
/// 2026, 9 of 10 since the play in psi is read out: l1 within 2.2 mm, l2
/// within 2.5 mm, the shoulder at rest within 2.3 mm; the tenth, `cast`,
/// refused after its lift ended on the force margin, REQ-MON-014; no
/// subject stopped by a monitor), no subject validated more than 10 mm
/// off, every validated one within those figures with a margin (2.5, 3.0,
/// 3.0 mm; README at seed 4711: l1 3.5 mm, l2 2.6 mm, shoulder 2.1 mm),
/// no joint past its default limit, and
/// every spastic subject validated within 5 mm or stopped with a named
/// cause.
#[test]
fn req_est_006_a_persons_arm_is_estimated_on_the_musculoskeletal_subjects() {
    if !plant_ready() {
        return;
    }
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args([
            "population",
            "--plant",
            "myoarm",
            "--subjects",
            "all",
            "--json",
            // Not the default 10 s: each plant compiles and settles its
            // model before its first line, two at a time, beside the other
            // tests on a 2-core machine (a local CI run under extra load
            // timed one out; what is checked here is the estimate).
            "--plant-timeout",
            "60",
        ])
        .output()
        .unwrap();
    let report = common::json_of(&out);
    let outcomes = report["outcomes"].as_array().unwrap();
    assert_eq!(outcomes.len(), 12, "{report}");
    let (mut plain, mut plain_within) = (0, 0);
    for o in outcomes {
        let name = o["name"].as_str().unwrap();
        assert!(o["robot_error"].is_null(), "{name}: {o}");
        // REQ-MON-014: a subject that resists the lift (cast) is held and
        // refused with a named cause, not stopped by a monitor.
        assert!(
            !o["refusal"].as_str().unwrap_or("").contains("monitor"),
            "{name}: {o}"
        );
        for joints in ["estimate_joints", "manipulate_joints"] {
            let j = &o[joints];
            if j.is_null() {
                continue;
            }
            assert!(
                j["max_hyperextension"].as_f64().unwrap() <= 0.0873,
                "{name}: {o}"
            );
            assert!(
                j["max_shoulder_elevation"].as_f64().unwrap() <= 2.0,
                "{name}: {o}"
            );
        }
        let within = |limit: f64| {
            o["validated"] == true
                && o["error_l1"].as_f64().unwrap().abs() <= limit
                && o["error_l2"].as_f64().unwrap().abs() <= limit
        };
        if o["validated"] == true {
            assert!(within(0.010), "{name} validated more than 10 mm off: {o}");
            assert!(
                o["error_l1"].as_f64().unwrap().abs() <= 2.5e-3,
                "{name}: {o}"
            );
            assert!(
                o["error_l2"].as_f64().unwrap().abs() <= 3.0e-3,
                "{name}: {o}"
            );
            assert!(o["error_shoulder"].as_f64().unwrap() <= 3e-3, "{name}: {o}");
        }
        if name.contains("spastic") {
            let named = o["refusal"].as_str().is_some_and(|r| r.contains("stop:"));
            assert!(within(0.005) || named, "{name}: {o}");
        } else {
            plain += 1;
            plain_within += usize::from(within(0.005));
        }
    }
    assert!(
        plain_within * 10 >= plain * 8,
        "{plain_within} of {plain}: {report}"
    );
}
