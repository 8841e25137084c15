//! The kernel's one vocabulary reaches every user: `limb run`, `limb
//! estimate` and `limb diagnose`, text and JSON, hold no Rust `Debug`
//! shape (`Monitor(Violation { … })`, `Some(Estimate)`,
//! `ApproveManipulation(JointAngles { … })`); `limb kuka run` and `limb
//! arebo` are checked in their own tests (`kuka.rs`, `arebo.rs`).

mod common;

use std::process::Command;

const EFFECTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/effects");

fn output(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .unwrap();
    let mut text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.push_str(&String::from_utf8_lossy(&out.stderr));
    text
}

/// The checker itself finds each shape the issue named, and passes the
/// vocabulary's spelling of the same things.
#[test]
fn the_checker_finds_debug_shapes() {
    for shape in [
        "state Some(Estimate)",
        "request ApproveManipulation(JointAngles { shoulder_elevation: 1.0 })",
        "\"rejection\": \"UpperArmLengthOutOfRange(0.0465)\"",
        "\"limit\": \"Kernel(StaleSensor)\"",
        "Violation { limit: ForceMagnitude, value: 45.0 }",
    ] {
        assert!(common::debug_shape(shape).is_some(), "{shape}");
    }
    for fine in [
        "Estimate → SafeStop (stop: monitor: force_magnitude 45.0778 N beyond 45.0000 N)",
        "request approve_manipulation to shoulder elevation 1.0000 rad, elbow flexion 0.6000 rad",
        "{\"limit\": \"stale_sensor\", \"code\": 4}",
        "step time (wall): max 3.1 µs in Estimate",
    ] {
        assert_eq!(common::debug_shape(fine), None, "{fine}");
    }
}

#[test]
fn limb_run_speaks_the_vocabulary() {
    for args in [
        &["run"][..],
        &["run", "--json"],
        &["run", "--max-force", "20"],
        &["run", "--max-force", "20", "--json"],
        &["run", "--digest"],
    ] {
        common::assert_no_debug_shape(&format!("limb {}", args.join(" ")), &output(args));
    }
}

/// A refused estimate (the shared shoulder-drift log: the validator
/// refuses it) and a diagnosis, text and JSON.
#[test]
fn limb_estimate_and_diagnose_speak_the_vocabulary() {
    let refused = format!("{EFFECTS}/shoulder_drift.csv");
    for args in [
        &["estimate", refused.as_str()][..],
        &["estimate", refused.as_str(), "--json"],
        &["diagnose", refused.as_str()],
        &["diagnose", refused.as_str(), "--json"],
    ] {
        let text = output(args);
        common::assert_no_debug_shape(&format!("limb {}", args.join(" ")), &text);
        if args[0] == "estimate" {
            assert!(
                !text.contains("accepted"),
                "the log must be refused: {text}"
            );
        }
    }
}
