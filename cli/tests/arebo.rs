//! `limb arebo` against a pseudo-terminal.

use limb_arebo::link;
use serde_json::Value;
use std::process::Command;

/// Finding 10 of issue 18: the same fault (a device that never streams)
/// ends `calibrate` and `run` the same way: the motors are commanded off,
/// one JSON document with the stop (cause, stable code, value, bound) is
/// printed, and the exit code is 3 (a safety stop, not an internal error
/// in one command and a success in the other).
#[test]
fn a_safe_stop_exits_3_with_the_same_json_in_calibrate_and_run() {
    for command in [&["calibrate"][..], &["run", "--seconds", "1"]] {
        let pty = link::pseudo_terminal().unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_limb"))
            .arg("arebo")
            .args(command)
            .arg("--device")
            .arg(&pty.path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{command:?}: {stderr}");
        let json: Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
        assert_eq!(json["stop"]["cause"], "violation", "{json}");
        assert!(json["stop"]["code"].is_u64(), "{json}");
        assert!(json["model"].is_null(), "{json}");
        assert!(stderr.contains("safe stop"), "{stderr}");
    }
}
