//! `limb run`: the kernel closes the loop on the reference plant.

use serde_json::Value;
use std::process::Command;

fn limb(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// REQ-MON-008: all six benchmark arms: the session completes with no
/// monitor event and a model within 0.2 mm of the truth, the README's
/// figure (measured: at most 0.166 mm on l1, 0.006 mm on l2 and 0.196 mm on
/// the shoulder, for l1 0.33 m, l2 0.20 m, default seed).
#[test]
fn every_benchmark_arm_completes_without_monitor_events() {
    for (l1, l2) in limb_sim::BENCHMARK_ARMS {
        let (code, out, err) = limb(&[
            "run",
            "--l1",
            &l1.to_string(),
            "--l2",
            &l2.to_string(),
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        let report: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(report["completed"], true, "arm {l1}/{l2}: {out}");
        assert_eq!(
            report["monitor_events"].as_array().unwrap().len(),
            0,
            "arm {l1}/{l2}: {out}"
        );
        for key in ["error_l1", "error_l2", "error_shoulder"] {
            let error = report["model"][key].as_f64().unwrap();
            assert!(error.abs() < 0.2e-3, "arm {l1}/{l2}: {key} = {error}");
        }
    }
}

/// A force limit below the lift force trips SafeStop and says why.
#[test]
fn a_force_limit_below_the_lift_force_stops_with_the_reason() {
    let (code, out, _) = limb(&["run", "--max-force", "20"]);
    assert_eq!(code, 0);
    assert!(out.contains("Estimate → SafeStop"), "{out}");
    assert!(out.contains("ForceMagnitude"), "{out}");
    assert!(out.contains("final state: SafeStop"), "{out}");
}

/// Bad numbers are bad input: exit 2 with one line on stderr.
#[test]
fn bad_arguments_exit_2() {
    for args in [
        ["run", "--l1", "nan"],
        ["run", "--max-force", "-1"],
        ["run", "--l2", "abc"],
    ] {
        let (code, out, err) = limb(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty(), "{args:?}: stdout {out}");
        assert!(!err.trim().is_empty());
    }
}
