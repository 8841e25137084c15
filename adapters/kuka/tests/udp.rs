//! UDP client over real loopback sockets (ports chosen by the OS).

use std::net::UdpSocket;
use std::time::Duration;

use limb_kuka::session::{CommandIntent, Controller, MonitoringView};
use limb_kuka::udp::{CycleOutcome, FriClient};
use limb_kuka::vectors::{example_monitoring, SESSION_STATES};
use limb_kuka::{decode_command, encode_monitoring, FriVersion};

#[derive(Default)]
struct Recorder {
    stale_calls: usize,
}
impl Controller for Recorder {
    fn on_monitoring(&mut self, _view: &MonitoringView, _now: f64) -> CommandIntent {
        CommandIntent::Hold
    }
    fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {
        self.stale_calls += 1;
    }
}

#[test]
fn loopback_session_answers_with_reflected_counter_and_reports_stale() {
    for version in [FriVersion::V1_15, FriVersion::V2_5, FriVersion::V2_7] {
        let loopback = "127.0.0.1:0".parse().unwrap();
        let mut client =
            FriClient::bind(loopback, version, 0.01, Duration::from_millis(20)).unwrap();
        let client_address = client.local_addr().unwrap();
        let robot = UdpSocket::bind("127.0.0.1:0").unwrap();
        robot
            .set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
        let mut controller = Recorder::default();
        for state in SESSION_STATES {
            let message = example_monitoring(state, version);
            robot
                .send_to(
                    &encode_monitoring(&message, version).unwrap(),
                    client_address,
                )
                .unwrap();
            let outcome = client.run_cycle(&mut controller).unwrap();
            assert!(
                matches!(outcome, CycleOutcome::Handled { .. }),
                "{outcome:?}"
            );
            if state == limb_kuka::messages::SessionState::Idle {
                continue;
            }
            let mut buffer = [0u8; 1500];
            let (length, _) = robot.recv_from(&mut buffer).unwrap();
            let reply = decode_command(&buffer[..length], version).unwrap();
            assert_eq!(
                reply.header.reflected_sequence_counter,
                message.header.sequence_counter
            );
        }
        robot.send_to(b"garbage", client_address).unwrap();
        assert!(matches!(
            client.run_cycle(&mut controller).unwrap(),
            CycleOutcome::Rejected(_)
        ));
        assert_eq!(
            client.run_cycle(&mut controller).unwrap(),
            CycleOutcome::Stale
        );
        assert_eq!(controller.stale_calls, 1);
    }
}
