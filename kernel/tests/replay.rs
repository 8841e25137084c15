//! Replays the shared reference-plant logs through the kernel: the monitors
//! stay quiet on nominal data and the session reaches Validated with the
//! right arm.

use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, State, StateKind};

fn read_log(name: &str) -> Vec<PathSample> {
    let path = format!("{}/../../shared/data/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, x, z, psi, fx, fz, ty) = (
        col("t"),
        col("x"),
        col("z"),
        col("psi"),
        col("fx"),
        col("fz"),
        col("ty"),
    );
    lines
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
            PathSample {
                time: v[t],
                pose: Pose::new(v[x], v[z], v[psi]),
                wrench: Wrench::new(v[fx], v[fz], v[ty]),
            }
        })
        .collect()
}

/// Feeds `log` to a kernel that starts estimating at the first frame, then
/// keeps feeding the last frame (re-stamped) until the motion is over.
fn replay(log: &[PathSample]) -> Kernel {
    let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
    kernel.step(&log[0], log[0].time);
    kernel
        .request(Request::StartEstimation, log[0].time)
        .unwrap();
    for frame in &log[1..] {
        kernel.step(frame, frame.time);
    }
    let mut last = *log.last().unwrap();
    for _ in 0..500 {
        if kernel.state().kind() != StateKind::Estimate {
            break;
        }
        last.time += 0.01;
        kernel.step(&last, last.time);
    }
    kernel
}

/// REQ-EST-002, REQ-MON-008: the six noisy reference logs, replayed
/// through the kernel, trip no monitor and validate an arm within 10 mm.
#[test]
fn req_est_002_noisy_logs_reach_validated_with_the_right_arm() {
    let truth = [
        (0.33, 0.20),
        (0.33, 0.18),
        (0.30, 0.20),
        (0.30, 0.18),
        (0.27, 0.20),
        (0.27, 0.18),
    ];
    for (case, (l1, l2)) in truth.iter().enumerate() {
        let mut kernel = replay(&read_log(&format!("noisy/case{}.csv", case + 1)));
        while let Some(event) = kernel.pop_event() {
            println!("case {}: {event:?}", case + 1);
        }
        let State::Validated(validated) = kernel.state() else {
            panic!("case {}: ended in {:?}", case + 1, kernel.state());
        };
        let arm = validated.arm().geometry();
        println!(
            "case {}: l1 {:.4} l2 {:.4} shoulder {:?}",
            case + 1,
            arm.upper_arm_length(),
            arm.forearm_length(),
            arm.shoulder()
        );
        assert!(
            (arm.upper_arm_length() - l1).abs() < 0.01,
            "case {}",
            case + 1
        );
        assert!(
            (arm.forearm_length() - l2).abs() < 0.01,
            "case {}",
            case + 1
        );
    }
}
