//! The lockstep protocol's cost: the round trip of one step (the command
//! sent, the plant's next frame read and decoded) over a pipe and over TCP
//! to the smallest plant (`limb-echo-plant`, no physics), to plant.md's arm
//! in Python (`plants/toy`, when `python3` is there), beside one step of
//! the embedded reference plant in the same process, and to the MuJoCo
//! MyoArm plant (when `plants/myoarm/setup.sh` has run: its real-time
//! factor is 1 ms over its median). Writes the table to
//! `benchmarks/lockstep.md`.
//!
//! `cargo bench -p limb-plant --bench lockstep`

use limb_kernel::command::{Command, CommandMode};
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::impedance::Saturation;
use limb_kernel::motion::SetPoint;
use limb_kernel::StateKind;
use limb_plant::{Endpoint, PlantRobot};
use limb_session::{Robot, Sensed};
use std::io::{BufRead, BufReader};
use std::process::{Command as Process, Stdio};
use std::time::{Duration, Instant};

const STEPS: usize = 20_000;

fn hold() -> Command {
    Command {
        state: StateKind::Grasp,
        mode: CommandMode::Hold,
        set_point: Some(SetPoint::hold(Pose::new(0.0, 0.0, 0.0))),
        wrench: Wrench::new(0.0, 0.0, 0.0),
        saturation: Saturation::default(),
        stop: None,
    }
}

/// Round trips [s] of `steps` steps of `robot`.
fn round_trips<R: Robot>(robot: &mut R, steps: usize) -> Vec<f64> {
    let command = hold();
    let mut times = Vec::with_capacity(steps);
    if !matches!(robot.sense(), Ok(Sensed::Frame(_))) {
        return times;
    }
    for _ in 0..steps {
        let start = Instant::now();
        let _ = robot.actuate(&command);
        let sensed = robot.sense();
        times.push(start.elapsed().as_secs_f64());
        if !matches!(sensed, Ok(Sensed::Frame(_))) {
            break;
        }
    }
    times
}

fn plant(endpoint: &Endpoint, steps: usize) -> Vec<f64> {
    let Ok(mut robot) = PlantRobot::connect(endpoint, Duration::from_secs(10), 1e9) else {
        return Vec::new();
    };
    let times = round_trips(&mut robot, steps);
    let ending = robot.finish("benchmark done");
    assert!(ending.failure.is_none(), "{:?}", ending.failure);
    times
}

fn tcp_echo() -> Vec<f64> {
    let mut child = Process::new(env!("CARGO_BIN_EXE_limb-echo-plant"))
        .args(["--tcp", "0"])
        .stderr(Stdio::piped())
        .spawn()
        .expect("the echo plant starts");
    let mut line = String::new();
    let _ = BufReader::new(child.stderr.take().expect("stderr")).read_line(&mut line);
    let port = line.trim().trim_start_matches("listening on ").to_string();
    let times = plant(&Endpoint::Tcp(format!("127.0.0.1:{port}")), STEPS);
    let _ = child.wait();
    times
}

fn reference() -> Vec<f64> {
    let plant = limb_sim::Plant::new(limb_sim::PlantParameters::new(0.3, 0.2)).expect("plant");
    let mut robot = limb_sim::robot::ReferenceRobot::new(plant, 1000.0, 1e9);
    round_trips(&mut robot, STEPS)
}

/// Median and 99th percentile [µs].
fn quantiles(mut times: Vec<f64>) -> Option<(f64, f64, usize)> {
    if times.is_empty() {
        return None;
    }
    times.sort_by(f64::total_cmp);
    let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize] * 1e6;
    Some((at(0.5), at(0.99), times.len()))
}

fn main() {
    let toy = concat!(env!("CARGO_MANIFEST_DIR"), "/../../plants/toy/toy_plant.py");
    let runs: Vec<(&str, Vec<f64>)> = vec![
        (
            "reference plant, in process (one step: 2 × 0.5 ms of plant.md's dynamics)",
            reference(),
        ),
        (
            "echo plant, pipe (stdin/stdout of a child)",
            plant(
                &Endpoint::Command(env!("CARGO_BIN_EXE_limb-echo-plant").into()),
                STEPS,
            ),
        ),
        ("echo plant, TCP on loopback", tcp_echo()),
        (
            "plant.md's arm in Python (plants/toy), pipe",
            plant(
                &Endpoint::Command(format!("python3 {toy} --noise on")),
                STEPS / 4,
            ),
        ),
    ];
    let myoarm = concat!(env!("CARGO_MANIFEST_DIR"), "/../../plants/myoarm");
    let python = format!("{myoarm}/.venv/bin/python");
    let mut runs = runs;
    if std::path::Path::new(&python).exists() {
        runs.push((
            "MuJoCo MyoArm (plants/myoarm, subject m50; one 1 ms MuJoCo step per frame), pipe",
            plant(
                &Endpoint::Command(format!("{python} {myoarm}/plant.py --subject m50")),
                STEPS / 4,
            ),
        ));
    }
    let reference_median = quantiles(runs[0].1.clone()).map_or(f64::NAN, |q| q.0);
    let mut table = String::from(
        "# Lockstep round trip of `limb-plant/1`\n\n\
         `cargo bench -p limb-plant --bench lockstep` (written by the benchmark). One step's round\n\
         trip: the command encoded and sent, the plant's next frame read, checked and decoded\n\
         (`PlantRobot::actuate` + `PlantRobot::sense`); the reference plant's row is the same two\n\
         calls on the embedded plant, run side by side in the same process. The kernel's own\n\
         step is not included (see `benchmarks/step.md`). A plant runs faster than real\n\
         time when its median is below its 1 ms period.\n\n\
         | plant, transport | steps | median [µs] | p99 [µs] | median ÷ reference plant |\n\
         |---|---|---|---|---|\n",
    );
    for (name, times) in runs {
        match quantiles(times) {
            Some((median, p99, n)) => table.push_str(&format!(
                "| {name} | {n} | {median:.1} | {p99:.1} | {:.1} |\n",
                median / reference_median
            )),
            None => table.push_str(&format!("| {name} | 0 | not run | | |\n")),
        }
    }
    print!("{table}");
    let out = concat!(env!("CARGO_MANIFEST_DIR"), "/../../benchmarks/lockstep.md");
    if let Err(error) = std::fs::write(out, table) {
        eprintln!("cannot write {out}: {error}");
    }
}
