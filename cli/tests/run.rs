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

/// REQ-MON-008, REQ-MON-011, REQ-EST-004: the six benchmark arms and the short
/// (0.24, 0.16) arm: the session completes with no monitor event, the
/// person's elbow hyperextends at most 5° and the shoulder stays inside its
/// configured limit during Estimate (the plant's true joints), and the
/// model is within 0.55 mm of the truth, the README's figure (measured
/// with the online estimator and shaped lift: worst 0.47 mm on l1 and
/// 0.51 mm on the shoulder for l1 0.27 m, l2 0.18 m, 0.08 mm on l2 for the
/// short arm; default seed).
/// `step_time` and `joint_extremes` are reported as `../shared/spec/cli.md`
/// says.
#[test]
fn every_benchmark_arm_completes_inside_the_joint_limits() {
    let config: Value = serde_json::from_str(&limb(&["config"]).1).unwrap();
    let shoulder_limit = config["limits"]["shoulder_elevation"]["high"]
        .as_f64()
        .unwrap();
    let arms = limb_sim::BENCHMARK_ARMS.into_iter().chain([(0.24, 0.16)]);
    for (l1, l2) in arms {
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
            assert!(error.abs() < 0.55e-3, "arm {l1}/{l2}: {key} = {error}");
        }
        let estimate = &report["joint_extremes"]["estimate"];
        let hyperextension = estimate["max_hyperextension"].as_f64().unwrap();
        let shoulder = estimate["max_shoulder_elevation"].as_f64().unwrap();
        assert!(
            hyperextension <= 5f64.to_radians(),
            "arm {l1}/{l2}: {hyperextension}"
        );
        assert!(shoulder <= shoulder_limit, "arm {l1}/{l2}: {shoulder}");
        let time = &report["step_time"];
        for key in ["median_s", "p999_s", "max_s"] {
            assert!(time[key].as_f64().unwrap() > 0.0, "{key}: {time}");
        }
        assert!(time["median_s"].as_f64() <= time["max_s"].as_f64());
        assert!(time["max_state"].is_string(), "{time}");
    }
}

/// `--log` writes the session in the plant.md format: every frame, with
/// the commanded set-point and the truth (on the reference plant every
/// kernel step has a fresh frame), and the step log beside it with a row
/// per kernel step; `limb estimate` reads the log back (at the kernel's
/// path rate): both methods find the arm within 1 mm, and the validator
/// accepts the kernel's (`online`). `auto`'s independent Hough check on
/// this closed-loop lift's 0.67 rad upper-arm arc is good to about 2 mm,
/// not its 1 mm agreement limit: its l1 moved by 1.35 mm (299.29 →
/// 297.95 mm, `auto`'s own 299.70 → 299.74) when the lift's conclusion
/// grew by 11 held samples (REQ-EST-007, 2026-12-04), and `auto` then
/// refused the arm as `methods_disagree` 1.8 mm. So `auto` must be
/// accepted or refused for that reason only, by at most 2 mm; its
/// validation is judged on plant.md's open-loop logs (1.4 rad,
/// `kernel/tests/estimation_logs.rs`).
#[test]
fn the_session_log_is_read_back_by_limb_estimate() {
    let file = std::env::temp_dir().join(format!("limb-run-log-{}.csv", std::process::id()));
    let log = file.to_str().unwrap();
    let (code, out, err) = limb(&["run", "--json", "--log", log]);
    assert_eq!(code, 0, "{err}");
    let report: Value = serde_json::from_str(&out).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,xd,zd,psid,x,y,z,psi,fx,fz,ty,q1,q2,elbow_x,elbow_z,shoulder_x,shoulder_z"
    );
    assert_eq!(lines.count() as u64, report["steps"].as_u64().unwrap());
    let steps_file = file.with_extension("steps.csv");
    let steps = std::fs::read_to_string(&steps_file).unwrap();
    let _ = std::fs::remove_file(&steps_file);
    assert_eq!(
        steps.lines().count() as u64 - 1,
        report["steps"].as_u64().unwrap()
    );
    assert!(steps
        .lines()
        .skip(1)
        .all(|line| line.split(',').nth(3) == Some("0")));
    for method in ["auto", "online"] {
        let (code, out, err) = limb(&["estimate", log, "--method", method, "--json"]);
        assert_eq!(code, 0, "{method}: {err}");
        let estimate: Value = serde_json::from_str(&out).unwrap();
        let disagreement = estimate["evidence"]["method_disagreement"].as_f64();
        let hough_only = method == "auto"
            && estimate["rejection_check"] == "methods_disagree"
            && disagreement.is_some_and(|d| d <= 2e-3);
        if !hough_only {
            assert_eq!(estimate["validated"], true, "{method}: {out}");
            assert!(estimate["rejection"].is_null());
        }
        assert!(
            (estimate["l1"].as_f64().unwrap() - 0.30).abs() < 1e-3,
            "{method}: {out}"
        );
        assert!(
            (estimate["l2"].as_f64().unwrap() - 0.20).abs() < 1e-3,
            "{method}: {out}"
        );
    }
    let _ = std::fs::remove_file(&file);
}

/// A force limit below the lift force trips SafeStop and says why.
#[test]
fn a_force_limit_below_the_lift_force_stops_with_the_reason() {
    let (code, out, _) = limb(&["run", "--max-force", "20"]);
    assert_eq!(code, 0);
    assert!(out.contains("Estimate → SafeStop"), "{out}");
    assert!(out.contains("force_magnitude"), "{out}");
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

/// A refused configuration names the field and the problem, not a group.
#[test]
fn a_refused_configuration_names_its_field() {
    let (code, _, err) = limb(&["run", "--max-force", "0"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("limits.max_force: not_positive"), "{err}");
}
