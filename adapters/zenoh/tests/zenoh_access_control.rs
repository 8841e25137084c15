//! Zenoh's own protection layer: user/password authentication and access
//! control (`session::protect_commands`), under the application-level
//! signatures.

mod common;

use common::lift::Lift;

use common::{link_settings, wait_until, RigOptions, ROBOT, TIMEOUT};
use limb_kernel::StateKind;
use limb_verification::scenario::TARGET;
use limb_zenoh::keys::Keys;
use limb_zenoh::node::Node;
use limb_zenoh::session::{free_loopback_port, peer_config, protect_commands, set_credentials};
use limb_zenoh::supervisor::SupervisorStation;
use limb_zenoh::wire::{AckOutcome, SupervisorCommand};
use limb_zenoh::AdapterError;
use std::time::Duration;

fn session(endpoint: &str, user: &str, password: &str) -> zenoh::Config {
    let mut config = peer_config(&[], &[endpoint.to_owned()], 1000).unwrap();
    set_credentials(&mut config, user, password).unwrap();
    config
}

/// REQ-ADP-003: Security: an observer (a safety panel) holding even the command key
/// cannot approve a manipulation — Zenoh drops its command at the node's
/// ingress — but its emergency stop works; a wrong password never connects.
#[test]
fn access_control_drops_an_observers_command_but_not_its_emergency_stop() {
    let directory = std::env::temp_dir().join(format!("limb-zenoh-acl-{}", std::process::id()));
    std::fs::create_dir_all(&directory).unwrap();
    let dictionary = directory.join("users.txt");
    std::fs::write(
        &dictionary,
        "supervisor:supervisor-password\npanel:panel-password\n",
    )
    .unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port().unwrap());
    let mut node_config = peer_config(std::slice::from_ref(&endpoint), &[], 1000).unwrap();
    set_credentials(&mut node_config, "node", "node-password").unwrap();
    let keys = Keys::new(ROBOT).unwrap();
    protect_commands(&mut node_config, &keys, &dictionary, &["panel".to_owned()]).unwrap();
    let lift = Lift::reference();
    let (kernel, lift) = lift.kernel_after_lift();
    let options = RigOptions::default();
    let node = Node::spawn(
        node_config,
        &link_settings(&options),
        Some(options.period),
        kernel,
        lift,
    )
    .unwrap();

    // A wrong password: the session either fails to open or never reaches
    // the node.
    if let Ok(intruder) = SupervisorStation::connect(
        session(&endpoint, "supervisor", "wrong-password"),
        ROBOT,
        options.format,
        common::key(),
    ) {
        assert!(intruder.wait_for_node(Duration::from_millis(500)).is_err());
        intruder.close().unwrap();
    }

    let connect = |user: &str, password: &str| {
        let supervisor = SupervisorStation::connect(
            session(&endpoint, user, password),
            ROBOT,
            options.format,
            common::key(),
        )
        .unwrap();
        supervisor.wait_for_node(TIMEOUT).unwrap();
        supervisor
    };
    let mut panel = connect("panel", "panel-password");
    let approve = SupervisorCommand::ApproveManipulation {
        target: TARGET.into(),
    };
    let dropped = panel.request(approve, Duration::from_millis(500));
    assert!(
        matches!(dropped, Err(AdapterError::Timeout(_))),
        "{dropped:?}"
    );
    assert_eq!(node.view().state(), Some(StateKind::Validated));

    let mut supervisor = connect("supervisor", "supervisor-password");
    let ack = supervisor.request(approve, TIMEOUT).unwrap();
    assert_eq!(
        ack.outcome,
        AckOutcome::Accepted {
            state: StateKind::Manipulate.into()
        }
    );

    panel.emergency_stop().unwrap();
    assert!(wait_until(TIMEOUT, || node.view().state() == Some(StateKind::SafeStop)).is_some());
    panel.close().unwrap();
    supervisor.close().unwrap();
    node.shutdown().unwrap();
    let _ = std::fs::remove_dir_all(&directory);
}
