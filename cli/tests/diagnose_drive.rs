//! `limb diagnose-drive`: bad input is one line naming file and line, exit 2.

mod common;
use std::process::Command;

#[test]
fn a_malformed_drive_log_is_bad_input_with_file_and_line() {
    let dir = std::env::temp_dir().join(format!("limb-drive-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.csv");
    let mut text = String::from("t,ref,q,tau\n");
    for i in 0..40 {
        text += &format!("{},0,0,1\n", i as f64 * 0.001);
    }
    text = text.replacen("0.003,0,0,1", "0.003,0,inf,1", 1);
    std::fs::write(&file, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["diagnose-drive", file.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("bad.csv:5:") && stderr.contains("`q`"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// EMPS through the CLI: the JSON has the shape of the drive issue (effects
/// in order with the held-out gap after each, the gap, where, what is
/// unexplained) and `--report` writes a page with the force trace and its
/// residual, the effects added and the ranking.
#[test]
fn emps_json_has_the_drive_shape_and_the_report_is_written() {
    let emps = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/real/emps");
    let dir = std::env::temp_dir().join(format!("limb-drive-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let report = dir.join("emps.html");
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args([
            "diagnose-drive",
            &format!("{emps}/estimation.csv"),
            "--validate",
            &format!("{emps}/validation.csv"),
            "--json",
            "--report",
            report.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let json = common::json_of(&out);
    let effects = json["effects"].as_array().unwrap();
    let names: Vec<&str> = effects
        .iter()
        .map(|e| e["effect"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"viscous_friction") && names.contains(&"coulomb_friction"),
        "{names:?}"
    );
    let afters: Vec<f64> = effects
        .iter()
        .map(|e| e["held_out_after"].as_f64().unwrap())
        .collect();
    assert!(
        afters.windows(2).all(|w| w[1] < w[0]),
        "each addition shrinks the gap: {afters:?}"
    );
    let gap = &json["gap"];
    assert_eq!(gap["metric"], "nrmse_tau");
    assert_eq!(gap["held_out"], true);
    assert!(gap["shrink"].as_f64().unwrap() >= 0.85, "{gap}");
    assert_eq!(gap["after"].as_f64(), afters.last().copied());
    assert_eq!(json["where"]["signals"][0], "tau");
    assert!(json["where"]["t_start"].is_number() && json["where"].get("band_hz").is_some());
    assert!(json["unexplained"].as_str().unwrap().contains("tau"));
    let page = std::fs::read_to_string(&report).unwrap();
    assert_eq!(page.matches("<svg").count(), 2, "trace and residual of tau");
    assert!(page.contains("coulomb_friction") && page.contains("What the chosen effects leave"));
    assert!(!page.contains("<script"), "self-contained");
    let _ = std::fs::remove_dir_all(&dir);
}
