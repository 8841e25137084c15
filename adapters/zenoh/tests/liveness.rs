//! The supervisor watchdog (lost and hung supervisors, both policies) and
//! the emergency stop with a telemetry consumer that never drains.

mod common;

use common::{rig, wait_until, RigOptions, TIMEOUT};
use limb_kernel::StateKind;
use limb_zenoh::supervision::OnSupervisorLoss;
use limb_zenoh::wire::{LinkMessage, WireFormat};
use std::time::Duration;
use zenoh::Wait;

/// Heartbeat period of the tests' supervisor: 20 Hz.
const HEARTBEAT: Duration = Duration::from_millis(50);
/// The node's liveness timeout: five heartbeat periods, so that a loaded
/// test machine does not miss it by accident.
const LIVENESS_TIMEOUT: Duration = Duration::from_millis(250);

enum Failure {
    /// The supervisor's session closes (process gone).
    Disappears,
    /// The session stays, the heartbeats stop (process hung).
    Hangs,
}

/// Runs one failure under one policy; returns the time from the failure to
/// the node's detection, and the node's state afterwards.
fn supervisor_failure(on_loss: OnSupervisorLoss, failure: Failure) -> (Duration, StateKind) {
    let mut rig = rig(RigOptions {
        on_loss,
        liveness_timeout: LIVENESS_TIMEOUT,
        ..RigOptions::default()
    });
    rig.supervisor.start_heartbeat(HEARTBEAT).unwrap();
    // Armed and quiet: no loss while the heartbeat runs.
    std::thread::sleep(Duration::from_millis(400));
    assert!(rig.node.view().last_loss_silence().is_none());
    assert_eq!(rig.node.view().state(), Some(StateKind::Validated));

    let rig = match failure {
        Failure::Disappears => {
            let common::Rig {
                node, supervisor, ..
            } = rig;
            supervisor.close().unwrap();
            (node, None)
        }
        Failure::Hangs => {
            rig.supervisor.stop_heartbeat();
            (rig.node, Some(rig.supervisor))
        }
    };
    let (node, supervisor) = rig;
    let detected = wait_until(TIMEOUT, || node.view().last_loss_silence().is_some())
        .expect("the loss is detected");
    let silence = node.view().last_loss_silence().unwrap();
    assert!(silence > LIVENESS_TIMEOUT && silence < LIVENESS_TIMEOUT + Duration::from_millis(100));
    std::thread::sleep(Duration::from_millis(20));
    let state = node.view().state().unwrap();
    eprintln!(
        "supervisor {} under {on_loss:?}: detected {detected:?} after the failure \
         (silence {silence:?}), state {state:?}",
        match failure {
            Failure::Disappears => "lost",
            Failure::Hangs => "hung",
        }
    );
    // Detection takes the timeout minus the time since the last heartbeat,
    // plus at most a control period and scheduling delay.
    assert!(detected < LIVENESS_TIMEOUT + Duration::from_millis(150));
    if let Some(supervisor) = supervisor {
        supervisor.close().unwrap();
    }
    node.shutdown().unwrap();
    (detected, state)
}

#[test]
fn a_lost_supervisor_stops_the_kernel_under_the_stop_policy() {
    let (_, state) = supervisor_failure(OnSupervisorLoss::Stop, Failure::Disappears);
    assert_eq!(state, StateKind::SafeStop);
}

#[test]
fn a_hung_supervisor_stops_the_kernel_under_the_stop_policy() {
    let (_, state) = supervisor_failure(OnSupervisorLoss::Stop, Failure::Hangs);
    assert_eq!(state, StateKind::SafeStop);
}

#[test]
fn a_lost_or_hung_supervisor_is_reported_but_tolerated_under_the_continue_policy() {
    for failure in [Failure::Disappears, Failure::Hangs] {
        let (_, state) = supervisor_failure(OnSupervisorLoss::Continue, failure);
        assert_eq!(state, StateKind::Validated);
    }
}

#[test]
fn the_loss_and_the_return_of_the_supervisor_are_published() {
    let mut rig = rig(RigOptions {
        on_loss: OnSupervisorLoss::Continue,
        liveness_timeout: LIVENESS_TIMEOUT,
        ..RigOptions::default()
    });
    let (tx, links) = std::sync::mpsc::channel();
    let format = rig.format;
    let _subscriber = rig
        .supervisor
        .session()
        .declare_subscriber(rig.supervisor.keys().link())
        .callback(move |sample| {
            let _ = tx.send(format.decode::<LinkMessage>(&sample.payload().to_bytes()));
        })
        .wait()
        .unwrap();
    rig.supervisor.start_heartbeat(HEARTBEAT).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    rig.supervisor.stop_heartbeat();
    let lost = links.recv_timeout(TIMEOUT).unwrap().unwrap();
    assert!(matches!(
        lost,
        LinkMessage::SupervisorLost { stopped: false, silence, .. } if silence > 0.25
    ));
    rig.supervisor.start_heartbeat(HEARTBEAT).unwrap();
    let back = links.recv_timeout(TIMEOUT).unwrap().unwrap();
    assert!(matches!(back, LinkMessage::SupervisorBack { .. }));
    rig.close();
}

/// REQ-ADP-003: Finding 1 of issue 18: a captured signed heartbeat, replayed after its
/// supervisor hung, does not keep the node supervised: the loss is
/// detected, reported, and the replays are counted.
#[test]
fn a_replayed_heartbeat_does_not_keep_the_supervisor_present() {
    let mut rig = rig(RigOptions {
        on_loss: OnSupervisorLoss::Continue,
        liveness_timeout: LIVENESS_TIMEOUT,
        ..RigOptions::default()
    });
    let key_expr = rig.supervisor.keys().supervisor_alive();
    let (tx, captured) = std::sync::mpsc::channel();
    let _capture = rig
        .supervisor
        .session()
        .declare_subscriber(key_expr.clone())
        .callback(move |sample| {
            let attachment = sample.attachment().map(|a| a.to_bytes().to_vec());
            let _ = tx.send((sample.payload().to_bytes().to_vec(), attachment));
        })
        .wait()
        .unwrap();
    rig.supervisor.start_heartbeat(HEARTBEAT).unwrap();
    let (payload, signature) = captured.recv_timeout(TIMEOUT).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    rig.supervisor.stop_heartbeat();
    // The attacker replays the captured heartbeat at twice the rate.
    for _ in 0..24 {
        let put = rig.supervisor.session().put(&key_expr, payload.clone());
        let put = match &signature {
            Some(signature) => put.attachment(signature.clone()),
            None => put,
        };
        put.wait().unwrap();
        std::thread::sleep(Duration::from_millis(25));
    }
    let silence = rig
        .node
        .view()
        .last_loss_silence()
        .expect("the supervisor's loss is detected despite the replays");
    assert!(silence > LIVENESS_TIMEOUT);
    let status: limb_zenoh::wire::StateSnapshot = rig
        .supervisor
        .query(&rig.supervisor.keys().state(), TIMEOUT)
        .unwrap();
    assert!(!status.status.supervisor_present);
    assert!(status.status.counters.heartbeats_replayed >= 20);
    rig.close();
}

/// REQ-ADP-003: The emergency stop reaches the kernel within one control period of its
/// arrival while the supervisor's own telemetry subscriber is full and
/// never drained (1 kHz samples, a 256-sample FIFO nobody reads).
#[test]
fn an_emergency_stop_is_not_delayed_by_an_undrained_telemetry_consumer() {
    let period = Duration::from_millis(1);
    let mut rig = rig(RigOptions {
        format: WireFormat::Cbor,
        period,
        ..RigOptions::default()
    });
    let stuck = rig
        .supervisor
        .session()
        .declare_subscriber(rig.supervisor.keys().key("telemetry/**"))
        .wait()
        .unwrap();
    // A second of samples: the FIFO (256) is full and stays full.
    std::thread::sleep(Duration::from_secs(1));
    assert!(stuck.len() >= 200, "{} queued", stuck.len());
    assert_eq!(rig.node.view().state(), Some(StateKind::Validated));

    rig.supervisor.emergency_stop().unwrap();
    let reached = wait_until(TIMEOUT, || {
        rig.node.view().state() == Some(StateKind::SafeStop)
    })
    .expect("the emergency stop arrives");
    let in_loop = rig.node.view().last_emergency_stop_delay().unwrap();
    eprintln!("e-stop: send → SafeStop seen {reached:?}; arrival → kernel {in_loop:?}");
    // Arrival to kernel request: one period by construction; the bound adds
    // the scheduling slack of a loaded 2-core machine running other tests.
    assert!(in_loop <= period + Duration::from_millis(20), "{in_loop:?}");
    assert!(reached < Duration::from_millis(250), "{reached:?}");
    drop(stuck);
    rig.close();
}
