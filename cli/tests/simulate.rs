//! `limb simulate` against `../shared/spec/cli.md`, and the strict log
//! reader through `limb estimate`.

use std::path::PathBuf;
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

fn limb(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .expect("run limb")
}

/// A fresh file path under the system temp dir, unique to this process and call.
fn temp_file(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "limb-simulate-test-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn simulate(extra: &[&str]) -> Vec<u8> {
    let out = temp_file("log.csv");
    let name = out.to_str().unwrap();
    let mut args = vec!["simulate", "--l1", "0.3", "--l2", "0.2", "--out", name];
    args.extend_from_slice(extra);
    let result = limb(&args);
    assert_eq!(
        result.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    std::fs::read(&out).unwrap()
}

#[test]
fn same_parameters_and_seed_give_a_byte_identical_log() {
    let a = simulate(&["--seed", "7"]);
    assert_eq!(a, simulate(&["--seed", "7"]));
    assert_ne!(a, simulate(&["--seed", "8"]));
    let effect = [
        "--seed",
        "3",
        "--effect",
        "backlash",
        "--set",
        "width=0.02",
        "--effect",
        "latency",
        "--set",
        "delay=0.05",
    ];
    let b = simulate(&effect);
    assert_eq!(b, simulate(&effect));
    let text = String::from_utf8(b).unwrap();
    assert!(text.starts_with(
        "t,xd,zd,psid,x,y,z,psi,fx,fz,ty,q1,q2,elbow_x,elbow_z,shoulder_x,shoulder_z\n"
    ));
}

#[test]
fn default_noise_is_on_and_off_is_exact() {
    let on = simulate(&[]);
    assert_eq!(on, simulate(&["--noise", "on", "--seed", "1"]));
    assert_ne!(on, simulate(&["--noise", "off"]));
}

#[test]
fn the_log_it_writes_is_estimated() {
    let out = temp_file("log.csv");
    let name = out.to_str().unwrap();
    let run = limb(&["simulate", "--l1", "0.3", "--l2", "0.2", "--out", name]);
    assert_eq!(run.status.code(), Some(0));
    let fit = limb(&["estimate", name, "--json"]);
    assert_eq!(fit.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&fit.stdout).unwrap();
    assert!((json["l1"].as_f64().unwrap() - 0.3).abs() < 2e-3, "{json}");
}

#[test]
fn bad_flags_and_values_exit_2_with_one_line() {
    let out = temp_file("log.csv");
    let name = out.to_str().unwrap();
    let cases: [&[&str]; 8] = [
        &["--l1", "0.3", "--out", name],
        &["--l1", "x", "--l2", "0.2", "--out", name],
        &["--l1", "-0.3", "--l2", "0.2", "--out", name],
        &[
            "--l1", "0.3", "--l2", "0.2", "--noise", "loud", "--out", name,
        ],
        &[
            "--l1", "0.3", "--l2", "0.2", "--effect", "wobble", "--out", name,
        ],
        &[
            "--l1", "0.3", "--l2", "0.2", "--effect", "backlash", "--set", "wide=1", "--out", name,
        ],
        &[
            "--l1", "0.3", "--l2", "0.2", "--effect", "backlash", "--set", "width=5", "--out", name,
        ],
        &[
            "--l1",
            "0.3",
            "--l2",
            "0.2",
            "--set",
            "width=0.01",
            "--effect",
            "backlash",
            "--out",
            name,
        ],
    ];
    for case in cases {
        let mut args = vec!["simulate"];
        args.extend_from_slice(case);
        let result = limb(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(result.stdout.is_empty());
    }
}

#[test]
fn malformed_logs_through_estimate_exit_2_naming_the_line() {
    let header = "t,x,z,psi,fx,fz,ty\n";
    let good = "0,0,0,0,0,0,0\n";
    let cases = [
        (
            "missing-column.csv",
            "t,x,z,psi,fx,fz\n0,0,0,0,0,0\n".to_string(),
            1,
        ),
        ("nan.csv", format!("{header}{good}0.01,0,NaN,0,0,0,0\n"), 3),
        (
            "text.csv",
            format!("{header}{good}0.01,0,0,zero,0,0,0\n"),
            3,
        ),
        (
            "backwards.csv",
            format!("{header}0.02,0,0,0,0,0,0\n0.01,0,0,0,0,0,0\n"),
            3,
        ),
        ("empty.csv", String::new(), 1),
    ];
    for (file, text, line) in cases {
        let path = temp_file(file);
        std::fs::write(&path, text).unwrap();
        let name = path.to_str().unwrap();
        let result = limb(&["estimate", name, "--json"]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{file}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{file}: {stderr}");
        assert!(
            stderr.contains(&format!("{name}:{line}:")),
            "{file}: {stderr}"
        );
        assert!(result.stdout.is_empty(), "{file}");
    }
}
