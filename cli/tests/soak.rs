//! `limb soak kuka --session K`: one session of a soak rerun alone, its
//! log kept.

use std::process::Command;

mod common;

/// REQ-SM-009: session 191 of `limb soak kuka --unpaced --session-cycles
/// 1500 --seed 1` (fault-free) ended in ForceRate 95 ms in, in Grasp: the
/// hold latched on the first frame was 2 mrad off the resting arm, and when
/// the robot began to follow the joint-position overlay turned that step
/// into a 14 N one-period spike. Rerun alone it now holds its grasp and
/// starts the estimation, and its log has a row for every step on a fresh
/// frame.
#[test]
fn req_sm_009_the_soak_session_that_stopped_in_grasp_now_holds() {
    let log = std::env::temp_dir().join(format!("limb-soak-191-{}.csv", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args([
            "soak",
            "kuka",
            "--unpaced",
            "--session-cycles",
            "1500",
            "--seconds",
            "300",
            "--seed",
            "1",
            "--session",
            "191",
            "--session-log",
        ])
        .arg(&log)
        .output()
        .unwrap();
    let json = common::json_of(&out);
    assert_eq!(json["nothing_lost"], true, "{json}");
    assert_eq!(json["figures"]["sessions"], 1);
    let session = &json["figures"]["sessions_detail"][0];
    assert_eq!(session["stop"], serde_json::Value::Null, "{session}");
    assert_eq!(session["fault"], serde_json::Value::Null);
    let text = std::fs::read_to_string(&log).unwrap();
    std::fs::remove_file(&log).unwrap();
    let rows = text.lines().count() as u64 - 1;
    assert!(text.starts_with("t,xd,zd,psid,x,"), "{}", &text[..40]);
    assert_eq!(rows, session["log_rows"].as_u64().unwrap());
    assert!(rows >= 1400, "{rows} rows");
}

/// `--session` needs the unpaced soak (a paced session depends on the time
/// left); asked without it, the command says so and exits 2.
#[test]
fn a_session_alone_needs_the_unpaced_soak() {
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["soak", "kuka", "--session", "3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--unpaced"), "{err}");
}
