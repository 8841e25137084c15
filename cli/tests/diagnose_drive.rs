//! `limb diagnose-drive`: bad input is one line naming file and line, exit 2.
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
