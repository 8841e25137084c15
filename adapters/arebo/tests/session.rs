//! AREBO as the robot of a `limb-session` session, over a real
//! pseudo-terminal with the simulated device: the device's own clock and
//! status bits reach the kernel and its watchdog decides. The person holds
//! still (the device's shoulder joint model at a fixed pose); the kernel
//! holds in Grasp until a fault.

use limb_arebo::control::GravityParameters;
use limb_arebo::device::{self, on_simulated_held_arm, DeviceFault, FaultSwitch};
use limb_arebo::human::ShoulderAngles;
use limb_arebo::link::{self, Session};
use limb_arebo::protocol::ControlType;
use limb_arebo::robot::{AreboRobot, AreboStop};
use limb_arebo::safety::{AreboLimit, SafetyLimits};
use limb_arebo::sim::{Setup, SAMPLE_PERIOD};
use limb_kernel::trace::TraceEvent;
use limb_kernel::{Kernel, KernelConfig, StateKind};
use limb_session::operator::describe;
use limb_session::{Observer, Operator, Outcome, SessionPlan, Supervisor};
use std::time::Duration;

/// Frames the device streams at most (one per 5 ms of real time).
const FRAMES: usize = 2_000;
/// The step at which the test's action happens.
const ACT_AT: u64 = 100;

/// A supervisor that requests nothing, does `action` once at step
/// [`ACT_AT`] and is finished when the kernel stops.
struct Bystander<F: FnMut()> {
    steps: u64,
    action: F,
    acted_at: Option<f64>,
}

impl<F: FnMut()> Supervisor for Bystander<F> {
    fn before_step(&mut self, _: &mut Kernel, now: f64, _: bool) {
        self.steps += 1;
        if self.steps == ACT_AT {
            (self.action)();
            self.acted_at = Some(now);
        }
    }

    fn finished(&self, state: StateKind, _: bool) -> bool {
        state == StateKind::SafeStop
    }
}

/// The kernel's events.
#[derive(Default)]
struct Events(Vec<TraceEvent>);

impl<R: ?Sized> Observer<R> for Events {
    fn event(&mut self, event: &TraceEvent) {
        self.0.push(*event);
    }
}

/// A device holding the person still, in real time, showing `faults`, and
/// AREBO in torque mode on it, on the host's clock. The link's own
/// freshness check is set past the kernel's sensor-age limit
/// (`judged_by_kernel`): the kernel's watchdog decides.
fn robot(faults: FaultSwitch) -> (std::thread::JoinHandle<device::DeviceRecord>, AreboRobot) {
    let pty = link::pseudo_terminal().unwrap();
    let still = Box::new(|_: f64| {
        let pose = ShoulderAngles {
            flexion: 0.5,
            abduction: 0.0,
        };
        (pose, [0.0; 2])
    });
    let device = device::spawn_device(
        pty.device.try_clone_native().unwrap(),
        Setup::default(),
        still,
        FRAMES,
        Duration::from_secs_f64(SAMPLE_PERIOD),
        faults,
    )
    .unwrap();
    let session = Session::open(&pty.path, SafetyLimits::judged_by_kernel()).unwrap();
    let robot = AreboRobot::start(session, 0.0, GravityParameters::ASSUMED, None).unwrap();
    (device, robot)
}

/// The kernel, its sensor-age limit at its ceiling (0.1 s, 20 device
/// frames) so that a loaded test machine's read jitter is not a stale
/// frame.
fn kernel() -> Box<Kernel> {
    let mut config = KernelConfig::default();
    config.limits.max_sensor_age = 0.1;
    Box::new(Kernel::new(config).unwrap())
}

/// Runs a session that does `action` at step [`ACT_AT`] and ends it as
/// `limb arebo run` does ([`AreboRobot::finish`]): its outcome (or stop),
/// the kernel time of the action, the events, and the control types the
/// host set on the device, in order.
fn session(
    faults: FaultSwitch,
    action: impl FnMut(),
) -> (
    Result<Outcome, AreboStop>,
    Option<f64>,
    Vec<TraceEvent>,
    Vec<ControlType>,
) {
    let (device, mut robot) = robot(faults);
    let mut kernel = kernel();
    let mut bystander = Bystander {
        steps: 0,
        action,
        acted_at: None,
    };
    let mut events = Events::default();
    let outcome = limb_session::run(&mut kernel, &mut robot, &mut bystander, &mut events);
    robot.finish();
    // The device reads the session's end before the port closes (a pty
    // drops what its master has not read when the slave hangs up).
    std::thread::sleep(Duration::from_millis(100));
    drop(robot);
    let control = device.join().map(|d| d.set_controls).unwrap_or_default();
    (outcome, bystander.acted_at, events.0, control)
}

/// The kernel stopped on `cause` after `acted_at`, and not before.
fn stopped_after(events: &[TraceEvent], acted_at: Option<f64>, cause: &str) {
    let acted_at = acted_at.expect("the action happened");
    let stops: Vec<_> = events
        .iter()
        .filter(|e| describe(e).contains("→ SafeStop"))
        .collect();
    assert_eq!(stops.len(), 1, "{events:?}");
    let stop = stops[0];
    assert!(describe(stop).contains(cause), "{}", describe(stop));
    assert!(stop.time >= acted_at, "{stop:?} before {acted_at}");
}

/// REQ-ADP-002: The device's heartbeat-missing bit (it has stopped assisting) ends the
/// session with that named verdict, motors off.
#[test]
fn a_device_error_bit_stops_the_session_by_name() {
    let faults = FaultSwitch::default();
    let switch = faults.clone();
    let (outcome, acted_at, _, control) =
        session(faults, move || switch.set(DeviceFault::HeartbeatLost));
    assert!(acted_at.is_some());
    // REQ-STOP-001: the device's heartbeat fault is a ramp-down: AREBO is
    // left in its gravity compensation, never switched off.
    assert_eq!(
        control.last(),
        Some(&ControlType::GravityCompensation),
        "{control:?}"
    );
    assert!(!control.contains(&ControlType::Off), "{control:?}");
    let stop = outcome.expect_err("the device error ends the session");
    let violation = stop.violation().expect("a named verdict");
    assert_eq!(
        violation.limit,
        AreboLimit::DeviceHeartbeatMissing,
        "{stop}"
    );
}

/// REQ-ADP-002: A device whose run time stops while it keeps streaming: its frames age
/// against the session clock, and the kernel's watchdog stops on a stale
/// sensor.
#[test]
fn a_frozen_device_clock_is_a_stale_sensor_for_the_kernel() {
    let faults = FaultSwitch::default();
    let switch = faults.clone();
    let (outcome, acted_at, events, control) =
        session(faults, move || switch.set(DeviceFault::FrozenClock));
    let outcome = outcome.unwrap();
    assert_eq!(outcome.final_state, StateKind::SafeStop);
    stopped_after(&events, acted_at, "stale_sensor");
    // REQ-STOP-001: a stale sensor is a ramp-down: torque mode while the
    // kernel ramps its wrench down, then gravity compensation, never off.
    assert_eq!(
        control.last(),
        Some(&ControlType::GravityCompensation),
        "{control:?}"
    );
    assert!(!control.contains(&ControlType::Off), "{control:?}");
}

/// REQ-ADP-002: The host stalls 0.3 s (the device keeps streaming into the pty): the
/// backlog it then reads is as old as the device's clock says, and the
/// kernel's watchdog stops on a stale sensor.
#[test]
fn a_backlog_after_a_host_stall_is_a_stale_sensor_for_the_kernel() {
    let (outcome, acted_at, events, _) = session(FaultSwitch::default(), || {
        std::thread::sleep(Duration::from_millis(300));
    });
    let outcome = outcome.unwrap();
    assert_eq!(outcome.final_state, StateKind::SafeStop);
    stopped_after(&events, acted_at, "stale_sensor");
}

/// The scripted operator's whole session on the held arm: Grasp →
/// Estimate → Validated → Manipulate → Validated, the arm found again.
#[test]
fn a_scripted_session_on_the_held_arm_validates_and_manipulates() {
    let (device, mut robot) = on_simulated_held_arm(8_000).unwrap();
    let mut kernel = kernel();
    let plan = SessionPlan {
        rate: 1.0 / SAMPLE_PERIOD,
        ..SessionPlan::default()
    };
    let mut events = Events::default();
    let outcome = limb_session::run(
        &mut kernel,
        &mut robot,
        &mut Operator::new(plan),
        &mut events,
    )
    .unwrap();
    robot.switch_off();
    drop(robot);
    let _ = device.join();
    for event in &events.0 {
        eprintln!("{:.3} {}", event.time, describe(event));
    }
    eprintln!("{outcome:?}");
    assert!(outcome.completed, "{outcome:?}");
    let model = outcome.model.unwrap();
    assert!((model.upper_arm_length - 0.30).abs() < 5e-3, "{model:?}");
    assert!((model.forearm_length - 0.20).abs() < 5e-3, "{model:?}");
}

/// The scripted operator until `stop_at` [s], then a stop request; the
/// session runs on for 2 s and records the grasp's height and the stop
/// commands' categories from the frames and commands.
struct StopAt {
    operator: Operator,
    stop_at: f64,
    stopped_at: Option<f64>,
    height: Option<f64>,
    lowest: f64,
    now: f64,
    categories: Vec<Option<limb_kernel::StopCategory>>,
}

impl Supervisor for StopAt {
    fn before_step(&mut self, kernel: &mut Kernel, now: f64, following: bool) {
        self.now = now;
        if self.stopped_at.is_none() && now >= self.stop_at {
            kernel.request(limb_kernel::Request::Stop, now).unwrap();
            self.stopped_at = Some(now);
        } else {
            self.operator.before_step(kernel, now, following);
        }
    }

    fn after_step(
        &mut self,
        kernel: &Kernel,
        frame: &limb_kernel::PathSample,
        command: &limb_kernel::Command,
        now: f64,
    ) {
        if self.stopped_at.is_some() {
            self.height.get_or_insert(frame.pose.z);
            self.lowest = self.lowest.min(frame.pose.z);
            self.categories.push(command.stop);
        }
        self.operator.after_step(kernel, frame, command, now);
    }

    fn finished(&self, _: StateKind, _: bool) -> bool {
        self.stopped_at.is_some_and(|at| self.now >= at + 2.0)
    }
}

/// REQ-STOP-001: a stop request during the estimation lift is a hold on
/// AREBO: every stop command is a hold, the device runs torque mode (its
/// gravity compensation plus the held arm's weight) on every frame of the
/// session, never motors off, and the wrist sags at most 2 mm over the
/// 2 s after the stop; at the end the device is handed to gravity
/// compensation, not switched off.
#[test]
fn req_stop_001_a_hold_stop_keeps_arebo_carrying_the_arm() {
    let (device, mut robot) = on_simulated_held_arm(3_000).unwrap();
    let mut kernel = kernel();
    let plan = SessionPlan {
        rate: 1.0 / SAMPLE_PERIOD,
        ..SessionPlan::default()
    };
    let mut supervisor = StopAt {
        operator: Operator::new(plan),
        stop_at: 6.0,
        stopped_at: None,
        height: None,
        lowest: f64::INFINITY,
        now: 0.0,
        categories: Vec::new(),
    };
    let mut events = Events::default();
    let outcome = limb_session::run(&mut kernel, &mut robot, &mut supervisor, &mut events);
    let record = robot.record();
    robot.finish();
    // The device reads the session's end before the port closes.
    std::thread::sleep(Duration::from_millis(100));
    drop(robot);
    let device = device.join().unwrap();
    assert!(outcome.is_ok(), "{outcome:?}");
    assert!(supervisor.stopped_at.is_some(), "{:?}", events.0);
    assert_eq!(kernel.state().kind(), StateKind::SafeStop);
    let stop = kernel.stopped().unwrap();
    assert_eq!(stop.category(), limb_kernel::StopCategory::Hold);
    assert!(supervisor
        .categories
        .iter()
        .all(|c| *c == Some(limb_kernel::StopCategory::Hold)));
    assert!(record.stop_commands[1] > 300, "{record:?}");
    assert!(!record.motors_off);
    let sag = supervisor.height.unwrap() - supervisor.lowest;
    eprintln!("AREBO hold stop at 6 s: sag {:.2} mm", sag * 1e3);
    assert!(sag <= 2e-3, "sag {sag} m");
    let session_frames = usize::try_from(record.frames).unwrap();
    let seen = &device.control[..session_frames.min(device.control.len())];
    assert!(
        seen.iter()
            .skip(1)
            .all(|c| *c == limb_arebo::protocol::ControlType::Torque),
        "{seen:?}"
    );
    use limb_arebo::protocol::ControlType::{GravityCompensation, Torque};
    assert_eq!(device.set_controls, [Torque, GravityCompensation]);
}

/// REQ-STOP-001: a motors-off stop command is the only one that switches
/// AREBO's motors off (control type 0), and the robot sends nothing more.
#[test]
fn req_stop_001_motors_off_switches_arebo_off() {
    use limb_kernel::geometry::Wrench;
    use limb_kernel::{Command, CommandMode, StopCategory};
    use limb_session::{Robot, Sensed};
    let (device, mut robot) = on_simulated_held_arm(400).unwrap();
    let mut command = Command {
        state: StateKind::Grasp,
        mode: CommandMode::Hold,
        set_point: None,
        wrench: Wrench::ZERO,
        saturation: Default::default(),
        stop: None,
    };
    let mut frames = 0;
    while frames < 200 {
        match robot.sense().unwrap() {
            Sensed::Frame(_) => frames += 1,
            Sensed::Silent(_) => {}
            Sensed::Ended => break,
        }
        if frames == 100 {
            command = Command {
                state: StateKind::SafeStop,
                mode: CommandMode::Stop,
                stop: Some(StopCategory::MotorsOff),
                ..command
            };
        }
        robot.actuate(&command).unwrap();
        if robot.record().motors_off {
            break;
        }
    }
    let record = robot.record();
    assert!(record.motors_off, "{record:?}");
    assert_eq!(record.stop_commands[3], 1);
    // The device streams on with its motors off (its status then no longer
    // says torque mode: the host reads that as a device stop).
    for _ in 0..50 {
        match robot.sense() {
            Ok(Sensed::Ended) | Err(_) => break,
            Ok(_) => robot.actuate(&command).unwrap(),
        }
    }
    robot.finish();
    drop(robot);
    let device = device.join().unwrap();
    // Torque mode from the start, motors off at the stop command, and
    // nothing set after it (the end of the session keeps it off).
    use limb_arebo::protocol::ControlType::{Off, Torque};
    assert_eq!(device.set_controls.first(), Some(&Torque), "{device:?}");
    assert_eq!(
        device.set_controls.last(),
        Some(&Off),
        "{:?}",
        device.set_controls
    );
    let first_off = device
        .control
        .iter()
        .skip_while(|c| **c == Off)
        .position(|c| *c == Off);
    assert!(
        first_off.is_some_and(|at| at >= 99),
        "motors off before the stop: {:?}",
        device.control
    );
}
