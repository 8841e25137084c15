//! `limb kuka run` (client with the kernel) against `limb kuka
//! sim-controller` (simulated controller), two processes over loopback UDP.

use serde_json::Value;
use std::net::UdpSocket;
use std::process::{Command, Stdio};

fn json(output: std::process::Output) -> Value {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

#[test]
fn run_and_sim_controller_close_the_loop_over_udp() {
    // A port the OS just had free.
    let port = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
        .to_string();
    let client = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["kuka", "run", "--fri-version", "2.7", "--port", &port])
        .args(["--seconds", "6", "--overlay", "wrench"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(300));
    let sim = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["kuka", "sim-controller", "--fri-version", "2.7"])
        .args(["--client", &format!("127.0.0.1:{port}")])
        .args(["--cycles", "1500", "--unpaced", "--overlay", "wrench"])
        .args(["--faults", "duplicate@800:10"])
        .output()
        .unwrap();
    let sim = json(sim);
    let client = json(client.wait_with_output().unwrap());
    assert_eq!(sim["commanding_entries"], 1, "{sim}");
    assert_eq!(sim["non_finite_replies"], 0, "{sim}");
    assert!(
        sim["round_trip_us"]["samples"].as_u64().unwrap() > 1400,
        "{sim}"
    );
    assert_eq!(client["client"]["duplicates"], 10, "{client}");
    assert_eq!(
        client["events"][0]["what"],
        "Grasp → Estimate (request StartEstimation)"
    );
    // The controller went silent after its 1500 cycles (1.5 s of robot
    // time): the kernel's watchdog stopped it then, not before.
    assert_eq!(client["kernel_state"], "SafeStop", "{client}");
    let stop = &client["events"][1];
    assert!(
        stop["what"].as_str().unwrap().contains("StaleSensor"),
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
