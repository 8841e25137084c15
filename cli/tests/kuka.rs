//! `limb kuka run` (client with the kernel) against `limb kuka
//! sim-controller` (simulated controller), two processes over loopback UDP.

mod common;

use serde_json::Value;
use std::net::UdpSocket;
use std::process::{Command, Stdio};

fn json(output: std::process::Output) -> Value {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    common::assert_no_debug_shape("limb kuka", &String::from_utf8_lossy(&output.stdout));
    serde_json::from_slice(&output.stdout).unwrap()
}

/// `limb kuka run CLIENT...` on a free loopback port against `limb kuka
/// sim-controller SIM...` sending to it: their JSON outputs (client, sim).
fn close_the_loop(client: &[&str], sim: &[&str]) -> (Value, Value) {
    // A port the OS just had free.
    let port = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
        .to_string();
    let client = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["kuka", "run", "--port", &port])
        .args(client)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(300));
    let sim = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["kuka", "sim-controller"])
        .args(["--client", &format!("127.0.0.1:{port}")])
        .args(sim)
        .output()
        .unwrap();
    let client = client.wait_with_output().unwrap();
    let text = |o: &std::process::Output| {
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    };
    assert!(
        client.status.success() && sim.status.success(),
        "client: {}\nsim: {}",
        text(&client),
        text(&sim)
    );
    (json(client), json(sim))
}

#[test]
fn run_and_sim_controller_close_the_loop_over_udp() {
    let (client, sim) = close_the_loop(
        &[
            "--fri-version",
            "2.7",
            "--seconds",
            "6",
            "--overlay",
            "wrench",
            "--clock",
            "robot",
        ],
        &[
            "--fri-version",
            "2.7",
            "--cycles",
            "1500",
            "--unpaced",
            "--overlay",
            "wrench",
            "--faults",
            "duplicate@800:10",
        ],
    );
    assert_eq!(sim["commanding_entries"], 1, "{sim}");
    assert_eq!(sim["non_finite_replies"], 0, "{sim}");
    assert!(
        sim["round_trip_us"]["samples"].as_u64().unwrap() > 1400,
        "{sim}"
    );
    assert_eq!(client["client"]["duplicates"], 10, "{client}");
    assert_eq!(
        client["events"][0]["what"],
        "Grasp → Estimate (request start_estimation)"
    );
    // The controller went silent after its 1500 cycles (1.5 s of robot
    // time): the kernel's watchdog stopped it then, not before.
    assert_eq!(client["kernel_state"], "SafeStop", "{client}");
    let stop = &client["events"][1];
    assert!(
        stop["what"].as_str().unwrap().contains("stale_sensor"),
        "{stop}"
    );
    assert!(stop["time"].as_f64().unwrap() >= 1.5, "{stop}");
}

#[test]
fn bad_options_are_refused() {
    for args in [
        &[
            "kuka",
            "sim-controller",
            "--fri-version",
            "1.15",
            "--faults",
            "bogus@1",
        ][..],
        &[
            "kuka",
            "sim-controller",
            "--fri-version",
            "1.15",
            "--overlay",
            "torque",
        ],
        &["kuka", "run", "--fri-version", "9.9"],
    ] {
        let output = Command::new(env!("CARGO_BIN_EXE_limb"))
            .args(args)
            .output()
            .unwrap();
        assert_eq!(output.status.code(), Some(2), "{args:?}");
    }
}

/// The session log of a KUKA loopback session (the whole estimation motion,
/// robot stamps, commanded set-points) is read by `limb estimate`, which
/// finds the arm again, and by `limb diagnose`, which replays its
/// commanded set-point on the reference plant. The controller runs 24 s of robot time (the model
/// is validated at about 22 s), then falls silent: the client's watchdog
/// stops the session and `--until-stopped` ends it.
#[test]
fn a_kuka_session_log_is_estimated_and_diagnosed() {
    let file = std::env::temp_dir().join(format!("limb-kuka-log-{}.csv", std::process::id()));
    let log = file.to_str().unwrap();
    let (client, sim) = close_the_loop(
        &[
            "--fri-version",
            "1.15",
            "--seconds",
            "300",
            "--clock",
            "robot",
            "--until-stopped",
            "--log",
            log,
        ],
        &["--fri-version", "1.15", "--cycles", "24000", "--unpaced"],
    );
    assert_eq!(sim["non_finite_replies"], 0, "{sim}");
    let validated = client["events"].as_array().unwrap().iter().any(|e| {
        e["what"]
            .as_str()
            .unwrap()
            .starts_with("Estimate → Validated")
    });
    assert!(validated, "{client}");
    let limb = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_limb")).args(args).output();
    let estimate = limb(&["estimate", log, "--json"]).unwrap();
    let diagnosis = limb(&["diagnose", log, "--json"]).unwrap();
    let _ = std::fs::remove_file(&file);
    let _ = std::fs::remove_file(file.with_extension("steps.csv"));
    let estimate = json(estimate);
    let l1 = estimate["l1"].as_f64().unwrap();
    let l2 = estimate["l2"].as_f64().unwrap();
    assert!((l1 - 0.30).abs() < 2e-3, "{estimate}");
    assert!((l2 - 0.20).abs() < 2e-3, "{estimate}");
    // Diagnosed without the lengths: the arm corrected for nothing is the
    // simulated person's within 1 mm, no catalogue effect is claimed, and
    // what the KUKA loop adds to the reference plant (the set-point reaches
    // the plant one controller cycle late, through the inverse kinematics
    // and the joint-step limit) stays below one noise sigma.
    let diagnosis = json(diagnosis);
    let arm = &diagnosis["arm"];
    assert_eq!(arm["given"], false, "{diagnosis}");
    let (l1, l2) = (arm["l1"].as_f64().unwrap(), arm["l2"].as_f64().unwrap());
    assert!(
        (l1 - 0.30).abs() < 1e-3 && (l2 - 0.20).abs() < 1e-3,
        "{arm}"
    );
    assert_eq!(
        diagnosis["effects"].as_array().unwrap().len(),
        0,
        "{diagnosis}"
    );
    let gap = diagnosis["gap"]["before"].as_f64().unwrap();
    assert!(gap < 1.0, "{diagnosis}");
    eprintln!(
        "KUKA session log: estimate l1 {:.5} l2 {:.5}; diagnose {} (gap {gap:.3} sigma), arm l1 {l1:.5} l2 {l2:.5}",
        estimate["l1"], estimate["l2"], diagnosis["effect"]
    );
}
