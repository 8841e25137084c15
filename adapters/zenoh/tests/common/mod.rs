//! A node and a supervisor on loopback, on free ports, with multicast
//! scouting off: tests never see each other.

// Each test crate uses its own subset of these helpers.
#![allow(dead_code)]

pub mod lift;

use lift::Lift;
use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::{LinkSettings, SampleQos};
use limb_zenoh::node::Node;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::supervision::{LivenessPolicy, OnSupervisorLoss};
use limb_zenoh::supervisor::SupervisorStation;
use limb_zenoh::wire::WireFormat;
use std::time::{Duration, Instant};

pub const ROBOT: &str = "test-arm";
pub const SECRET: &[u8] = b"limb test secret, 32 bytes long!";
pub const TIMEOUT: Duration = Duration::from_secs(5);

pub struct Rig {
    pub node: Node,
    pub supervisor: SupervisorStation,
    pub endpoint: String,
    pub format: WireFormat,
}

pub struct RigOptions {
    pub format: WireFormat,
    pub period: Duration,
    pub on_loss: OnSupervisorLoss,
    pub liveness_timeout: Duration,
    pub validated: bool,
}

impl Default for RigOptions {
    fn default() -> Self {
        Self {
            format: WireFormat::Json,
            period: Duration::from_millis(2),
            on_loss: OnSupervisorLoss::Stop,
            liveness_timeout: Duration::from_millis(150),
            validated: true,
        }
    }
}

pub fn key() -> CommandKey {
    CommandKey::new(SECRET).unwrap()
}

/// The node's link settings for `options`: every sample published, status
/// every 50 ms.
pub fn link_settings(options: &RigOptions) -> LinkSettings {
    LinkSettings {
        robot_id: ROBOT.into(),
        format: options.format,
        command_key: key(),
        sample_decimation: 1,
        sample_qos: SampleQos::BATCHED,
        status_period: 0.05,
        liveness: LivenessPolicy {
            timeout: options.liveness_timeout,
            on_loss: options.on_loss,
        },
    }
}

/// A node (in Validated after the scripted lift, or in Grasp) and a
/// connected supervisor whose commands are routed.
pub fn rig(options: RigOptions) -> Rig {
    let lift = Lift::reference().stepping(options.period);
    let (kernel, lift) = if options.validated {
        lift.kernel_after_lift()
    } else {
        (lift.kernel_in_grasp(), lift)
    };
    let port = free_loopback_port().unwrap();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let settings = link_settings(&options);
    let node = Node::spawn(
        peer_config(std::slice::from_ref(&endpoint), &[], 1000).unwrap(),
        &settings,
        Some(options.period),
        kernel,
        lift,
    )
    .unwrap();
    let supervisor = connect(&endpoint, options.format, key());
    Rig {
        node,
        supervisor,
        endpoint,
        format: options.format,
    }
}

/// Another supervisor session on the same node.
pub fn connect(endpoint: &str, format: WireFormat, key: CommandKey) -> SupervisorStation {
    let config = peer_config(&[], &[endpoint.to_owned()], 1000).unwrap();
    let supervisor = SupervisorStation::connect(config, ROBOT, format, key).unwrap();
    supervisor.wait_for_node(TIMEOUT).unwrap();
    supervisor
}

/// Polls `condition` every millisecond until it holds or `timeout` passes;
/// returns how long it took.
pub fn wait_until(timeout: Duration, condition: impl Fn() -> bool) -> Option<Duration> {
    let start = Instant::now();
    while start.elapsed() < timeout {
        if condition() {
            return Some(start.elapsed());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    None
}

impl Rig {
    pub fn close(self) {
        self.supervisor.close().unwrap();
        self.node.shutdown().unwrap();
    }
}
