//! `--log FILE.mcap`: the session log as MCAP, opened by the official
//! Python reader (`tests/python`, pinned `mcap`) with as many frames and
//! steps as the CSV log of the same session has rows, and read by `limb
//! estimate` and `limb diagnose` to the CSV's answer.

mod common;

use std::path::PathBuf;
use std::process::Command;

fn limb(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .unwrap()
}

/// The tests' Python with the `mcap` reader: `tests/python/.venv`
/// (`tests/python/setup.sh`; `.ci/run` runs it). Missing in CI is a
/// failure; elsewhere the reader check says it skipped.
fn reader() -> Option<PathBuf> {
    let python = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/python/.venv/bin/python"
    ));
    common::tool_ready(&python, "tests/python/setup.sh").then_some(python)
}

#[test]
fn an_mcap_session_log_holds_the_csv_logs_rows_and_reads_to_the_same_answers() {
    let dir = std::env::temp_dir();
    let id = std::process::id();
    let mcap = dir.join(format!("limb-mcap-{id}.mcap"));
    let csv = dir.join(format!("limb-mcap-{id}.csv"));
    let steps_csv = dir.join(format!("limb-mcap-{id}.steps.csv"));
    let (mcap_s, csv_s) = (mcap.to_str().unwrap(), csv.to_str().unwrap());
    let a = common::json_of(&limb(&["run", "--log", mcap_s, "--json"]));
    let b = common::json_of(&limb(&["run", "--log", csv_s, "--json"]));
    assert_eq!(a["command_hash"], b["command_hash"]);
    let frames = std::fs::read_to_string(&csv).unwrap().lines().count() - 1;
    let steps = std::fs::read_to_string(&steps_csv).unwrap().lines().count() - 1;
    if let Some(python) = reader() {
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/python/read_mcap.py");
        let out = Command::new(python)
            .args([script, mcap_s])
            .output()
            .unwrap();
        let read = common::json_of(&out);
        assert_eq!(read["counts"]["/limb/frame"], frames as u64);
        assert_eq!(read["counts"]["/limb/step"], steps as u64);
        assert_eq!(
            read["counts"]["/limb/event"],
            a["events"].as_array().unwrap().len()
        );
        assert_eq!(read["counts"]["/limb/config"], 1);
        assert_eq!(read["counts"]["/limb/model"], 1);
        assert_eq!(
            read["channels"]["/limb/frame"]["schema_encoding"],
            "jsonschema"
        );
        assert_eq!(read["channels"]["/limb/frame"]["message_encoding"], "json");
        let header = std::fs::read_to_string(&csv).unwrap();
        let columns: Vec<&str> = header.lines().next().unwrap().split(',').collect();
        assert_eq!(read["first_frame_keys"], serde_json::json!(columns));
    }
    for command in [&["estimate", "--json"][..], &["diagnose", "--json"][..]] {
        let answer = |file: &str| {
            let mut args = vec![command[0], file];
            args.extend(&command[1..]);
            common::json_of(&limb(&args))
        };
        assert_eq!(answer(mcap_s), answer(csv_s), "{}", command[0]);
    }
    for file in [mcap, csv, steps_csv] {
        let _ = std::fs::remove_file(file);
    }
}

/// A file that is not MCAP, named `.mcap`, is bad input (exit 2, one line).
#[test]
fn a_broken_mcap_log_is_bad_input() {
    let file = std::env::temp_dir().join(format!("limb-broken-{}.mcap", std::process::id()));
    std::fs::write(&file, b"t,x\n1,2\n").unwrap();
    let out = limb(&["estimate", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not an MCAP file"));
    let _ = std::fs::remove_file(file);
}
