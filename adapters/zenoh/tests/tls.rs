//! Zenoh's TLS transport on loopback (feature `tls`): a node listening on
//! `tls/localhost:<port>` with a certificate made here, a supervisor that
//! trusts it commanding the node, and a supervisor that does not trust it
//! never reaching the node.
#![cfg(feature = "tls")]

mod common;

use common::lift::Lift;

use common::{key, link_settings, RigOptions, ROBOT, TIMEOUT};
use limb_kernel::StateKind;
use limb_zenoh::node::Node;
use limb_zenoh::session::{free_loopback_port, peer_config, set_tls, TlsFiles};
use limb_zenoh::supervisor::SupervisorStation;
use limb_zenoh::wire::{AckOutcome, SupervisorCommand, WireFormat};
use std::path::PathBuf;
use std::time::Duration;

/// A self-signed certificate for `localhost`, its key, and an unrelated
/// one, as PEM files in a fresh directory.
fn certificates(dir: &std::path::Path) -> (PathBuf, PathBuf, PathBuf) {
    std::fs::create_dir_all(dir).unwrap();
    let write = |name: &str, text: String| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let node = rcgen::generate_simple_self_signed(vec!["localhost".to_owned()]).unwrap();
    let other = rcgen::generate_simple_self_signed(vec!["localhost".to_owned()]).unwrap();
    (
        write("node.pem", node.cert.pem()),
        write("node-key.pem", node.signing_key.serialize_pem()),
        write("other.pem", other.cert.pem()),
    )
}

fn supervisor(endpoint: &str, root_ca: PathBuf) -> SupervisorStation {
    let mut config = peer_config(&[], &[endpoint.to_owned()], 1000).unwrap();
    set_tls(
        &mut config,
        &TlsFiles {
            root_ca,
            listener: None,
        },
    )
    .unwrap();
    SupervisorStation::connect(config, ROBOT, WireFormat::Json, key()).unwrap()
}

#[test]
fn commands_over_tls_reach_only_a_node_the_supervisor_trusts() {
    let dir = std::env::temp_dir().join(format!("limb-zenoh-tls-{}", std::process::id()));
    let (certificate, private_key, other) = certificates(&dir);
    let endpoint = format!("tls/localhost:{}", free_loopback_port().unwrap());
    let mut config = peer_config(std::slice::from_ref(&endpoint), &[], 1000).unwrap();
    set_tls(
        &mut config,
        &TlsFiles {
            root_ca: certificate.clone(),
            listener: Some((certificate.clone(), private_key)),
        },
    )
    .unwrap();
    let lift = Lift::reference();
    let (kernel, lift) = lift.kernel_after_lift();
    let node = Node::spawn(
        config,
        &link_settings(&RigOptions::default()),
        Some(Duration::from_millis(2)),
        kernel,
        lift,
    )
    .unwrap();

    let stranger = supervisor(&endpoint, other);
    assert!(stranger.wait_for_node(Duration::from_secs(2)).is_err());

    let mut trusted = supervisor(&endpoint, certificate);
    trusted.wait_for_node(TIMEOUT).unwrap();
    let ack = trusted.request(SupervisorCommand::Stop, TIMEOUT).unwrap();
    assert_eq!(
        ack.outcome,
        AckOutcome::Accepted {
            state: StateKind::SafeStop.into()
        }
    );
    trusted.close().unwrap();
    stranger.close().unwrap();
    node.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
