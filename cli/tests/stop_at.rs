//! `limb run --stop-at T`: emergency stops across the session on the six
//! benchmark arms of plant.md, and what each did to the arm.

use serde_json::Value;
use std::process::Command;

fn limb(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Kernel time of the first event whose text contains `what`.
fn event_time(report: &Value, what: &str) -> f64 {
    report["events"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["what"].as_str().unwrap().contains(what))
        .unwrap_or_else(|| panic!("no {what} in {report}"))["time"]
        .as_f64()
        .unwrap()
}

/// The five stop times of one arm, from its own session without a stop:
/// the lift at 25 %, 50 % and 90 % of its duration, the hold 0.5 s before
/// the model is validated (the refinement), and the middle of the
/// manipulation move (the grasp moving down at ≈ 2.5 cm/s).
fn stop_times(l1: &str, l2: &str) -> [(&'static str, f64); 5] {
    let plain = limb(&["run", "--l1", l1, "--l2", l2, "--json"]);
    let start = event_time(&plain, "Grasp → Estimate");
    let lift_end = event_time(&plain, "lift ended");
    let validated = event_time(&plain, "Estimate → Validated");
    let manipulate = event_time(&plain, "Validated → Manipulate");
    // The operator finishes 1 s after the target is reached.
    let reached = event_time(&plain, "Manipulate → Validated") - 1.0;
    let lift = |share: f64| start + share * (lift_end - start);
    [
        ("estimate lift 25 %", lift(0.25)),
        ("estimate lift 50 %", lift(0.5)),
        ("estimate lift 90 %", lift(0.9)),
        ("estimate hold", validated - 0.5),
        ("manipulate, mid-move", (manipulate + reached) / 2.0),
    ]
}

/// REQ-STOP-001, REQ-STOP-002: an emergency stop at five times across
/// Estimate (lift, hold) and Manipulate on the six benchmark arms of
/// plant.md is a hold, no monitor trips, the grasp sags at most 2 mm over
/// the 2 s after the stop and the force stays within the configured limit
/// (README table, measured: worst 1.92 mm, mid-manipulation; 0.34 mm in
/// Estimate; 31 N). Before stop categories the same stops let the arm
/// sag up to 21 mm (benchmarks/soak.md, item 6).
#[test]
fn req_stop_002_emergency_stops_hold_the_arm_on_the_six_arms() {
    let config = limb(&["config"]);
    let max_force = config["limits"]["max_force"].as_f64().unwrap();
    let mut table = String::new();
    let mut worst = 0.0f64;
    for (l1, l2) in limb_sim::BENCHMARK_ARMS {
        let (l1, l2) = (l1.to_string(), l2.to_string());
        for (phase, at) in stop_times(&l1, &l2) {
            let at = format!("{at:.3}");
            let report = limb(&["run", "--l1", &l1, "--l2", &l2, "--json", "--stop-at", &at]);
            let stop = &report["stop"];
            let sag = stop["sag_m"].as_f64().unwrap();
            let force = stop["max_force_n"].as_f64().unwrap();
            table.push_str(&format!(
                "{l1}/{l2} {phase} at {at} s: {} {} sag {:.2} mm, max |f| {force:.1} N\n",
                stop["state"],
                stop["category"],
                sag * 1e3
            ));
            assert_eq!(stop["cause"], "emergency_stop", "{l1}/{l2} {phase}: {stop}");
            assert_eq!(stop["category"], "hold", "{l1}/{l2} {phase}: {stop}");
            assert!(stop["watched_s"].as_f64().unwrap() >= 2.0 - 1e-3, "{stop}");
            let expected = if phase.starts_with("estimate") {
                "estimate"
            } else {
                "manipulate"
            };
            assert_eq!(stop["state"], expected, "{l1}/{l2} {phase}: {stop}");
            assert_eq!(report["final_state"], "SafeStop", "{l1}/{l2} {phase}");
            assert!(
                report["monitor_events"].as_array().unwrap().is_empty(),
                "{l1}/{l2} {phase}: {report}"
            );
            assert!(sag <= 2e-3, "{l1}/{l2} {phase}: sag {sag} m\n{table}");
            assert!(force <= max_force, "{l1}/{l2} {phase}: {force} N\n{table}");
            worst = worst.max(sag);
        }
    }
    println!("{table}worst sag {:.2} mm", worst * 1e3);
}

/// `--stop-at` refuses a time that is not one, a session without it has
/// no `stop` object, and the text output names the stop in one line.
#[test]
fn a_bad_stop_time_is_refused_and_no_stop_has_no_object() {
    for bad in ["-1", "NaN", "inf", "soon"] {
        let out = Command::new(env!("CARGO_BIN_EXE_limb"))
            .args(["run", "--json", "--stop-at", bad])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{bad}");
    }
    let report = limb(&["run", "--json"]);
    assert!(report.get("stop").is_none(), "{report}");
    // Without --json the stop is one line of text, by name.
    let out = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["run", "--stop-at", "6"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("stop at 6.000 s in estimate: emergency_stop, category hold;"),
        "{text}"
    );
}
