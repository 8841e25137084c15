//! Commands over real Zenoh sessions: accepted, refused and acknowledged;
//! authorisation; queryables; in-order reliable telemetry.

mod common;

use common::lift::Lift;
use common::{connect, link_settings, rig, wait_until, RigOptions, TIMEOUT};
use limb_kernel::config::{Interval, SafetyLimits};
use limb_kernel::{KernelConfig, StateKind};
use limb_session::kernel_wire::KernelEvent;
use limb_session::Supervisor as _;
use limb_verification::scenario::TARGET;
use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::Link;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::wire::{
    AckOutcome, AckSubject, ArmModel, CommandMessage, EventMessage, RefuseReason, StateSnapshot,
    StopOrigin, SupervisorCommand, WireFormat,
};
use std::time::Duration;
use zenoh::Wait;

fn accepted(state: StateKind) -> AckOutcome {
    AckOutcome::Accepted {
        state: state.into(),
    }
}

/// The name of the kernel's refusal reason, for a kernel refusal.
fn refused_by_kernel(outcome: &AckOutcome) -> Option<&str> {
    match outcome {
        AckOutcome::Refused {
            reason: RefuseReason::Kernel { refusal },
        } => Some(&refusal.reason.name),
        _ => None,
    }
}

/// A reset right after a stop, sent again every 20 ms while the kernel
/// refuses it as `arm_not_still` (the stop's set-point still on its way to
/// rest, REQ-STOP-003), for at most 3 s: the last answer, and the refusals
/// before it.
fn reset_when_still(
    supervisor: &mut limb_zenoh::supervisor::SupervisorStation,
) -> (AckOutcome, u32) {
    let start = std::time::Instant::now();
    let mut refusals = 0;
    loop {
        let ack = supervisor
            .request(SupervisorCommand::Reset, TIMEOUT)
            .unwrap();
        if refused_by_kernel(&ack.outcome) != Some("arm_not_still")
            || start.elapsed() > Duration::from_secs(3)
        {
            return (ack.outcome, refusals);
        }
        refusals += 1;
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Every command goes through the kernel's guards and is acknowledged; a
/// reset right after a stop is refused as `arm_not_still` until the stop's
/// hold has settled, then accepted (REQ-SM-006, REQ-STOP-003).
#[test]
fn commands_go_through_the_kernel_guards_and_are_acknowledged() {
    let mut rig = rig(RigOptions::default());
    let s = &mut rig.supervisor;
    assert_eq!(rig.node.view().state(), Some(StateKind::Validated));

    let ack = s
        .request(SupervisorCommand::FinishManipulation, TIMEOUT)
        .unwrap();
    assert_eq!(
        refused_by_kernel(&ack.outcome),
        Some("not_allowed_in_state")
    );
    let approve = SupervisorCommand::ApproveManipulation {
        target: TARGET.into(),
    };
    let ack = s.request(approve, TIMEOUT).unwrap();
    assert_eq!(ack.subject, AckSubject::Request);
    assert_eq!(ack.outcome, accepted(StateKind::Manipulate));
    let ack = s
        .request(SupervisorCommand::FinishManipulation, TIMEOUT)
        .unwrap();
    assert_eq!(ack.outcome, accepted(StateKind::Validated));

    // A target outside the joint limits is the kernel's to refuse.
    let mut far = TARGET;
    far.elbow_flexion = 3.0;
    let ack = s
        .request(
            SupervisorCommand::ApproveManipulation { target: far.into() },
            TIMEOUT,
        )
        .unwrap();
    assert_eq!(refused_by_kernel(&ack.outcome), Some("target"));

    let ack = s
        .request(
            SupervisorCommand::UpdateLimits {
                limits: SafetyLimits::default(),
            },
            TIMEOUT,
        )
        .unwrap();
    assert_eq!(ack.outcome, accepted(StateKind::Validated));
    let bad = SafetyLimits {
        workspace_x: Interval::new(1.0, 0.0),
        ..SafetyLimits::default()
    };
    let ack = s
        .request(SupervisorCommand::UpdateLimits { limits: bad }, TIMEOUT)
        .unwrap();
    assert!(matches!(
        ack.outcome,
        AckOutcome::Refused {
            reason: RefuseReason::InvalidLimits { .. }
        }
    ));

    let ack = s.request(SupervisorCommand::Stop, TIMEOUT).unwrap();
    assert_eq!(ack.outcome, accepted(StateKind::SafeStop));
    // Right after the stop the arm's hold is still settling: refused, by
    // name, then accepted.
    let (outcome, refusals) = reset_when_still(s);
    assert_eq!(outcome, accepted(StateKind::Grasp));
    assert!(refusals > 0, "a reset at once was accepted");
    assert!(wait_until(TIMEOUT, || rig.node.view().state()
        == Some(StateKind::Grasp))
    .is_some());
    rig.close();
}

#[test]
fn malformed_replayed_and_unsigned_commands_change_nothing() {
    let rig = rig(RigOptions::default());
    let s = &rig.supervisor;
    let key = common::key();
    let is_request_refusal = |ack: &limb_zenoh::wire::Ack| {
        ack.subject == AckSubject::Request && matches!(ack.outcome, AckOutcome::Refused { .. })
    };

    for bad in [
        &b"{not json"[..],
        br#"{"sequence": 1, "command": {"command": "fly"}}"#,
    ] {
        s.send_raw(bad, Some(&key)).unwrap();
        let ack = s.wait_ack(is_request_refusal, TIMEOUT).unwrap();
        assert!(matches!(
            ack.outcome,
            AckOutcome::Refused {
                reason: RefuseReason::Malformed { .. }
            }
        ));
    }

    let stop = WireFormat::Json
        .encode(&CommandMessage {
            sequence: 5,
            command: SupervisorCommand::Stop,
        })
        .unwrap();
    s.send_raw(&stop, None).unwrap();
    let ack = s.wait_ack(is_request_refusal, TIMEOUT).unwrap();
    assert_eq!(ack.sequence, Some(5));
    assert!(matches!(
        ack.outcome,
        AckOutcome::Refused {
            reason: RefuseReason::Unauthorised
        }
    ));

    // A signed Reset, then the same bytes again: the copy is a replay.
    let reset = WireFormat::Json
        .encode(&CommandMessage {
            sequence: 9,
            command: SupervisorCommand::Reset,
        })
        .unwrap();
    s.send_raw(&reset, Some(&key)).unwrap();
    let first = s.wait_ack(|a| a.sequence == Some(9), TIMEOUT).unwrap();
    assert!(refused_by_kernel(&first.outcome).is_some());
    s.send_raw(&reset, Some(&key)).unwrap();
    let replay = s.wait_ack(|a| a.sequence == Some(9), TIMEOUT).unwrap();
    assert_eq!(
        replay.outcome,
        AckOutcome::Refused {
            reason: RefuseReason::Replayed { last_accepted: 9 }
        }
    );
    assert_eq!(rig.node.view().state(), Some(StateKind::Validated));
    rig.close();
}

/// Security: a session without the command key cannot approve a
/// manipulation, but its emergency stop still stops the robot.
#[test]
fn an_unauthorised_approval_is_refused_while_its_emergency_stop_works() {
    let rig = rig(RigOptions::default());
    let intruder_key = CommandKey::new(b"not the robot's secret key!!").unwrap();
    let mut intruder = connect(&rig.endpoint, rig.format, intruder_key);
    let ack = intruder
        .request(
            SupervisorCommand::ApproveManipulation {
                target: TARGET.into(),
            },
            TIMEOUT,
        )
        .unwrap();
    assert_eq!(
        ack.outcome,
        AckOutcome::Refused {
            reason: RefuseReason::Unauthorised
        }
    );
    std::thread::sleep(Duration::from_millis(20));
    assert_eq!(rig.node.view().state(), Some(StateKind::Validated));

    let sequence = intruder.emergency_stop().unwrap();
    let ack = intruder
        .wait_ack(|a| a.subject == AckSubject::EmergencyStop, TIMEOUT)
        .unwrap();
    assert_eq!(ack.sequence, Some(sequence));
    assert_eq!(ack.outcome, accepted(StateKind::SafeStop));
    assert!(wait_until(TIMEOUT, || rig.node.view().state()
        == Some(StateKind::SafeStop))
    .is_some());
    intruder.close().unwrap();
    rig.close();
}

#[test]
fn queryables_answer_state_configuration_and_arm_model() {
    for format in [WireFormat::Json, WireFormat::Cbor] {
        let rig = rig(RigOptions {
            format,
            ..RigOptions::default()
        });
        let s = &rig.supervisor;
        let keys = s.keys().clone();
        let snapshot = (0..100)
            .find_map(|_| {
                std::thread::sleep(Duration::from_millis(10));
                s.query::<StateSnapshot>(&keys.state(), TIMEOUT).ok()
            })
            .unwrap();
        assert_eq!(snapshot.status.state, StateKind::Validated.into());
        assert_eq!(snapshot.config, KernelConfig::default());
        let arm: ArmModel = s.query(&keys.arm(), TIMEOUT).unwrap();
        assert_eq!(Some(arm), snapshot.arm);
        // The scripted lift's arm: l1 = 0.30 m, l2 = 0.20 m.
        assert!((arm.upper_arm_length - 0.30).abs() < 0.02, "{arm:?}");
        assert!((arm.forearm_length - 0.20).abs() < 0.002, "{arm:?}");
        let config: KernelConfig = s.query(&keys.config(), TIMEOUT).unwrap();
        assert_eq!(config, KernelConfig::default());
        rig.close();
    }
}

/// Reliable telemetry: every event, in order, none lost (CBOR).
#[test]
fn events_arrive_in_order_without_loss() {
    const COMMANDS: usize = 60;
    let mut rig = rig(RigOptions {
        format: WireFormat::Cbor,
        ..RigOptions::default()
    });
    let (tx, events) = std::sync::mpsc::channel();
    let format = rig.format;
    let _subscriber = rig
        .supervisor
        .session()
        .declare_subscriber(rig.supervisor.keys().event())
        .callback(move |sample| {
            let event = format.decode::<EventMessage>(&sample.payload().to_bytes());
            let _ = tx.send(event.map(|e| e.sequence).ok());
        })
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(100));
    // A burst larger than the loop's command queue: each command is
    // acknowledged, as a kernel refusal (one kernel event each) or as busy.
    let mut pending = std::collections::HashSet::new();
    for _ in 0..COMMANDS {
        pending.insert(rig.supervisor.send(SupervisorCommand::Reset).unwrap());
    }
    let mut kernel_refusals = 0;
    let mut busy = 0;
    while !pending.is_empty() {
        let ack = rig
            .supervisor
            .wait_ack(
                |a| a.sequence.is_some_and(|s| pending.contains(&s)),
                TIMEOUT,
            )
            .unwrap();
        ack.sequence.map(|s| pending.remove(&s));
        match ack.outcome {
            AckOutcome::Refused {
                reason: RefuseReason::Busy,
            } => busy += 1,
            outcome => {
                assert!(refused_by_kernel(&outcome).is_some(), "{outcome:?}");
                kernel_refusals += 1;
            }
        }
    }
    assert_eq!(kernel_refusals + busy, COMMANDS);
    assert!(kernel_refusals >= limb_zenoh::supervision::COMMAND_QUEUE);
    std::thread::sleep(Duration::from_millis(100));
    let received: Vec<u64> = events.try_iter().map(Option::unwrap).collect();
    assert!(
        received.len() >= kernel_refusals,
        "{} events",
        received.len()
    );
    let first = received[0];
    let expected: Vec<u64> = (first..first + received.len() as u64).collect();
    assert_eq!(received, expected);
    rig.close();
}

/// A kernel after the synthetic lift in the test's own loop, a link whose
/// supervision that loop calls, and a connected supervisor that has sent
/// the approval of the manipulation (`sequence`).
struct Attached {
    kernel: Box<limb_kernel::Kernel>,
    lift: Lift,
    link: Link,
    supervision: limb_zenoh::supervision::Supervision,
    supervisor: limb_zenoh::supervisor::SupervisorStation,
    sequence: u64,
}

fn attached() -> Attached {
    let (kernel, lift) = Lift::reference().kernel_after_lift();
    let endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port().unwrap());
    let config = peer_config(std::slice::from_ref(&endpoint), &[], 1000).unwrap();
    let settings = link_settings(&RigOptions::default());
    let (link, supervision) = Link::open(config, &settings, *kernel.config()).unwrap();
    let mut supervisor = connect(&endpoint, settings.format, common::key());
    let sequence = supervisor
        .send(SupervisorCommand::ApproveManipulation {
            target: TARGET.into(),
        })
        .unwrap();
    Attached {
        kernel,
        lift,
        link,
        supervision,
        supervisor,
        sequence,
    }
}

/// Attach: another loop owns the kernel and calls the supervision's
/// `limb_session::Supervisor` hooks around its own steps.
#[test]
fn another_loop_can_attach_the_supervision_hooks() {
    let Attached {
        mut kernel,
        lift,
        link,
        mut supervision,
        supervisor,
        sequence,
    } = attached();
    let origin = lift.origin();
    let epoch = supervision.epoch();
    let mut ack = None;
    // The other adapter's loop: bounded to 500 steps of about 5 ms.
    for _ in 0..500 {
        let now = origin + epoch.elapsed().as_secs_f64();
        supervision.before_step(&mut kernel, now, true);
        let frame = lift.frame(now);
        let command = kernel.step(Some(&frame), now);
        supervision.after_step(&kernel, &frame, &command, now);
        let wait = Duration::from_millis(5);
        if let Ok(found) = supervisor.wait_ack(|a| a.sequence == Some(sequence), wait) {
            ack = Some(found);
            break;
        }
    }
    assert_eq!(ack.unwrap().outcome, accepted(StateKind::Manipulate));
    assert_eq!(kernel.state().kind(), StateKind::Manipulate);
    supervisor.close().unwrap();
    link.close().unwrap();
}

/// REQ-ADP-003: A loop that steps far faster than the publisher thread publishes
/// samples (an unpaced simulation on a loaded machine) loses samples, never
/// the ack of a command: samples take at most half the outbound queue.
/// (They used to fill all of it; the ack was dropped, and the whole KUKA
/// session under Zenoh, `tests/robots.rs`, wedged.)
#[test]
fn a_flood_of_samples_does_not_crowd_out_an_ack() {
    let mut a = attached();
    let frame = a.lift.frame(a.lift.origin());
    let mut ack = None;
    // Each round: two thousand steps at once, far more samples than the
    // publisher thread can put meanwhile, then the command (once it has
    // arrived) is applied while they wait.
    let start = std::time::Instant::now();
    for round in 0u32.. {
        if start.elapsed() > TIMEOUT {
            break;
        }
        let now = a.lift.origin() + f64::from(round) * 1e-3;
        for _ in 0..2_000 {
            let command = a.kernel.step(Some(&frame), now);
            a.supervision.after_step(&a.kernel, &frame, &command, now);
        }
        a.supervision.before_step(&mut a.kernel, now, true);
        let wait = Duration::from_millis(5);
        if let Ok(found) = a
            .supervisor
            .wait_ack(|k| k.sequence == Some(a.sequence), wait)
        {
            ack = Some(found);
            break;
        }
    }
    let counters = a.supervision.counters();
    eprintln!("{counters:?}");
    assert!(counters.samples_dropped > 0, "the publisher kept up");
    assert_eq!(counters.reliable_dropped, 0);
    let ack = ack.unwrap_or_else(|| panic!("no ack within {TIMEOUT:?}"));
    assert_eq!(ack.outcome, accepted(StateKind::Manipulate));
    a.supervisor.close().unwrap();
    a.link.close().unwrap();
}

/// REQ-ADP-003: Finding 2 of issue 18: two emergency stops in one control period each
/// get their own ack (the second used to overwrite the first's sequence,
/// and the first sender timed out).
#[test]
fn every_emergency_stop_in_one_period_is_acknowledged() {
    let mut rig = rig(RigOptions {
        period: Duration::from_millis(200),
        ..RigOptions::default()
    });
    let mut other = connect(&rig.endpoint, rig.format, common::key());
    let first = rig.supervisor.emergency_stop().unwrap();
    let second = other.emergency_stop().unwrap();
    for (supervisor, sequence) in [(&rig.supervisor, first), (&other, second)] {
        let ack = supervisor
            .wait_ack(
                |a| a.subject == AckSubject::EmergencyStop && a.sequence == Some(sequence),
                TIMEOUT,
            )
            .unwrap_or_else(|e| panic!("no ack for e-stop {sequence}: {e}"));
        assert_eq!(ack.outcome, accepted(StateKind::SafeStop));
    }
    other.close().unwrap();
    rig.close();
}

/// Finding 3 of issue 18: supervisors share the node's sequence. A
/// supervisor that connected first can still command after a later one
/// did (its numbers used to start below the later one's and were refused
/// as replays).
#[test]
fn supervisors_connected_at_different_times_share_the_sequence() {
    let mut rig = rig(RigOptions::default());
    std::thread::sleep(Duration::from_millis(50));
    let mut later = connect(&rig.endpoint, rig.format, common::key());
    let ack = later.request(SupervisorCommand::Stop, TIMEOUT).unwrap();
    assert_eq!(ack.outcome, accepted(StateKind::SafeStop));
    let (outcome, _) = reset_when_still(&mut rig.supervisor);
    assert_eq!(outcome, accepted(StateKind::Grasp));
    // And back: the later supervisor again.
    let ack = later.request(SupervisorCommand::Stop, TIMEOUT).unwrap();
    assert_eq!(ack.outcome, accepted(StateKind::SafeStop));
    later.close().unwrap();
    rig.close();
}

/// An e-stop, a signed stop and a supervisor-loss stop are told apart on
/// `telemetry/event`: each one's transition into SafeStop carries its
/// origin.
#[test]
fn each_stop_event_names_its_origin() {
    let mut rig = rig(RigOptions::default());
    let (tx, events) = std::sync::mpsc::channel();
    let format = rig.format;
    let _subscriber = rig
        .supervisor
        .session()
        .declare_subscriber(rig.supervisor.keys().event())
        .callback(move |sample| {
            if let Ok(event) = format.decode::<EventMessage>(&sample.payload().to_bytes()) {
                let _ = tx.send(event);
            }
        })
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(100));
    // The next transition's origin (refusals and lift events are not
    // stops); an unexpected transition, e.g. a monitor stop, is shown.
    let next_origin = || loop {
        let event = events
            .recv_timeout(TIMEOUT)
            .unwrap_or_else(|e| panic!("no stop event: {e}"));
        if matches!(event.event, KernelEvent::Transition { .. }) {
            println!("{event:?}");
            break event.origin;
        }
    };
    let stop = rig
        .supervisor
        .request(SupervisorCommand::Stop, TIMEOUT)
        .unwrap();
    assert_eq!(stop.outcome, accepted(StateKind::SafeStop));
    assert_eq!(next_origin(), Some(StopOrigin::Command));
    let (reset, _) = reset_when_still(&mut rig.supervisor);
    assert_eq!(reset, accepted(StateKind::Grasp));
    assert_eq!(next_origin(), None, "the reset's transition");
    rig.supervisor.emergency_stop().unwrap();
    assert_eq!(next_origin(), Some(StopOrigin::EmergencyStop));
    let (reset, _) = reset_when_still(&mut rig.supervisor);
    assert_eq!(reset, accepted(StateKind::Grasp));
    assert_eq!(next_origin(), None, "the reset's transition");
    rig.supervisor
        .start_heartbeat(Duration::from_millis(50))
        .unwrap();
    std::thread::sleep(Duration::from_millis(200));
    rig.supervisor.stop_heartbeat();
    assert_eq!(next_origin(), Some(StopOrigin::SupervisorLost));
    rig.close();
}
