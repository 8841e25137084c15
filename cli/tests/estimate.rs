//! `limb estimate` against `../shared/spec/cli.md`: JSON keys, exit codes.

mod common;

use std::process::Command;

const CASE3: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/noisy/case3.csv"
);

fn limb(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .expect("run limb")
}

#[test]
fn json_has_the_contract_keys_for_every_method() {
    for method in ["hough", "ls", "auto"] {
        let out = limb(&["estimate", CASE3, "--method", method, "--json"]);
        let json = common::json_of(&out);
        assert!((json["l1"].as_f64().unwrap() - 0.300).abs() < 1e-3);
        assert!((json["l2"].as_f64().unwrap() - 0.200).abs() < 1e-3);
        for key in ["elbow", "shoulder"] {
            assert_eq!(json[key].as_array().map(Vec::len), Some(2), "{key}");
        }
        assert_eq!(json["method"], method);
        assert_eq!(json["samples"], 2917);
    }
}

#[test]
fn method_defaults_to_auto() {
    let out = limb(&["estimate", CASE3, "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["method"], "auto");
}

#[test]
fn malformed_csv_exits_2_naming_file_and_line() {
    let dir = std::env::temp_dir().join(format!("limb-estimate-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.csv");
    std::fs::write(
        &file,
        "t,x,z,psi,fx,fz,ty\n0,0,0,0,0,0,0\n0.01,0,oops,0,0,0,0\n",
    )
    .unwrap();
    let name = file.to_str().unwrap();
    let out = limb(&["estimate", name, "--json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty(), "no partial JSON");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains(&format!("{name}:3")), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn missing_file_exits_2() {
    assert_eq!(
        limb(&["estimate", "/nonexistent/log.csv"]).status.code(),
        Some(2)
    );
}

#[test]
fn ground_truth_columns_are_ignored() {
    let text = std::fs::read_to_string(CASE3).unwrap();
    // Keep t..ty (the columns a real robot gives), drop the ground truth.
    let robot_only: String = text
        .lines()
        .map(|line| line.split(',').take(11).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let dir = std::env::temp_dir().join(format!("limb-estimate-truth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("robot_only.csv");
    std::fs::write(&file, robot_only).unwrap();
    let json = |path: &str| -> serde_json::Value {
        serde_json::from_slice(&limb(&["estimate", path, "--json"]).stdout).expect("JSON")
    };
    let (full, robot) = (json(CASE3), json(file.to_str().unwrap()));
    for key in ["l1", "l2", "elbow", "shoulder", "samples"] {
        assert_eq!(full[key], robot[key], "{key}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
