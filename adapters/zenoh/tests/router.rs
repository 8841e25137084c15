//! Several robots behind one router (the README's deployment): a Zenoh
//! router in router mode, two nodes and a supervisor station connected to
//! it as clients; the station addresses each robot by its key space
//! (`limb/<robot-id>/@v2/...`), and routing is Zenoh's.

mod common;

use common::lift::Lift;
use common::{key, link_settings, wait_until, RigOptions, TIMEOUT};
use limb_kernel::arm::JointAngles;
use limb_kernel::StateKind;
use limb_zenoh::node::Node;
use limb_zenoh::session::{client_config, free_loopback_port, router_config};
use limb_zenoh::supervisor::SupervisorStation;
use limb_zenoh::wire::{AckOutcome, SupervisorCommand};
use zenoh::Wait;

#[test]
fn one_station_supervises_two_nodes_through_a_router() {
    let router_endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port().unwrap());
    let router = zenoh::open(router_config(std::slice::from_ref(&router_endpoint), 1000).unwrap())
        .wait()
        .unwrap();
    let client = || client_config(std::slice::from_ref(&router_endpoint), 1000).unwrap();
    let options = RigOptions::default();
    let nodes: Vec<Node> = ["arm-a", "arm-b"]
        .into_iter()
        .map(|robot| {
            let mut settings = link_settings(&options);
            settings.robot_id = robot.into();
            let (kernel, lift) = Lift::reference().kernel_after_lift();
            Node::spawn(client(), &settings, Some(options.period), kernel, lift).unwrap()
        })
        .collect();
    let station = |robot: &str| {
        let supervisor =
            SupervisorStation::connect(client(), robot, options.format, key()).unwrap();
        supervisor.wait_for_node(TIMEOUT).unwrap();
        supervisor
    };
    let (mut a, mut b) = (station("arm-a"), station("arm-b"));
    // An e-stop to arm-a stops arm-a only.
    a.emergency_stop().unwrap();
    assert!(wait_until(TIMEOUT, || nodes[0].view().state()
        == Some(StateKind::SafeStop))
    .is_some());
    assert_eq!(nodes[1].view().state(), Some(StateKind::Validated));
    // A signed approval to arm-b moves arm-b only.
    let target = JointAngles {
        shoulder_elevation: 1.0,
        elbow_flexion: 0.6,
    };
    let ack = b
        .request(
            SupervisorCommand::ApproveManipulation {
                target: target.into(),
            },
            TIMEOUT,
        )
        .unwrap();
    assert_eq!(
        ack.outcome,
        AckOutcome::Accepted {
            state: StateKind::Manipulate.into()
        }
    );
    assert_eq!(nodes[0].view().state(), Some(StateKind::SafeStop));
    a.close().unwrap();
    b.close().unwrap();
    for node in nodes {
        node.shutdown().unwrap();
    }
    router.close().wait().unwrap();
}
