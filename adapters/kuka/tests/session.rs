//! Session logic tests (pure, no I/O).

use limb_kuka::messages::*;
use limb_kuka::session::*;
use limb_kuka::FriVersion;

struct Fixed(CommandIntent);
impl Controller for Fixed {
    fn on_monitoring(&mut self, _view: &MonitoringView, _now: f64) -> CommandIntent {
        self.0
    }
    fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {}
}

const IPO: JointVector = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7];

fn monitoring(
    state: SessionState,
    quality: ConnectionQuality,
    counter: u32,
    multiplier: u32,
) -> FriMonitoringMessage {
    let joints = Some(JointValues {
        value: IPO.to_vec(),
    });
    FriMonitoringMessage {
        header: MessageHeader {
            message_identifier: MONITORING_MESSAGE_ID,
            sequence_counter: counter,
            reflected_sequence_counter: 0,
        },
        connection_info: Some(ConnectionInfo {
            session_state: state as i32,
            quality: quality as i32,
            send_period: Some(1),
            receive_multiplier: Some(multiplier),
        }),
        monitor_data: Some(MessageMonitorData {
            measured_joint_position: joints.clone(),
            commanded_joint_position: joints.clone(),
            ..Default::default()
        }),
        ipo_data: Some(MessageIpoData {
            joint_position: joints,
            client_command_mode: Some(ClientCommandMode::JointPosition as i32),
            ..Default::default()
        }),
        ..Default::default()
    }
}

fn sent_position(reply: &SessionReply) -> Option<Vec<f64>> {
    reply
        .command
        .as_ref()?
        .command_data
        .as_ref()?
        .joint_position
        .as_ref()
        .map(|j| j.value.clone())
}

#[test]
fn idle_sends_nothing() {
    let mut session = ClientSession::new(FriVersion::V2_5, 0.01);
    let reply = session.on_monitoring(
        &monitoring(SessionState::Idle, ConnectionQuality::Excellent, 1, 1),
        &mut Fixed(CommandIntent::Hold),
        0.0,
    );
    assert!(reply.command.is_none());
}

#[test]
fn counters_start_at_zero_and_reflect() {
    let mut session = ClientSession::new(FriVersion::V2_5, 0.01);
    for (index, counter) in [u32::MAX - 1, u32::MAX, 0].into_iter().enumerate() {
        let reply = session.on_monitoring(
            &monitoring(
                SessionState::MonitoringWait,
                ConnectionQuality::Good,
                counter,
                1,
            ),
            &mut Fixed(CommandIntent::Hold),
            0.0,
        );
        let header = reply.command.unwrap().header;
        assert_eq!(header.sequence_counter, index as u32);
        assert_eq!(header.reflected_sequence_counter, counter);
        assert_eq!(header.message_identifier, COMMAND_MESSAGE_ID);
    }
}

/// Which of the MONITORING_READY messages with `counters` were answered.
fn answered(
    session: &mut ClientSession,
    controller: &mut impl Controller,
    counters: impl IntoIterator<Item = u32>,
    multiplier: u32,
) -> Vec<bool> {
    counters
        .into_iter()
        .map(|counter| {
            let message = monitoring(
                SessionState::MonitoringReady,
                ConnectionQuality::Good,
                counter,
                multiplier,
            );
            session
                .on_monitoring(&message, controller, 0.0)
                .command
                .is_some()
        })
        .collect()
}

#[test]
fn answers_every_receive_multiplier_th_message() {
    let mut session = ClientSession::new(FriVersion::V2_5, 0.01);
    let pattern = answered(&mut session, &mut Fixed(CommandIntent::Hold), 0..6, 3);
    assert_eq!(pattern, [false, false, true, false, false, true]);
}

#[test]
fn monitoring_reply_contents_per_version() {
    for version in FriVersion::ALL {
        let mut session = ClientSession::new(version, 0.01);
        let reply = session.on_monitoring(
            &monitoring(SessionState::MonitoringReady, ConnectionQuality::Good, 0, 1),
            &mut Fixed(CommandIntent::Hold),
            0.0,
        );
        assert_eq!(
            sent_position(&reply).is_some(),
            version.is_v1(),
            "{version}"
        );
    }
}

#[test]
fn commanding_wait_syncs_on_ipo() {
    let mut session = ClientSession::new(FriVersion::V2_7, 0.01);
    let reply = session.on_monitoring(
        &monitoring(SessionState::CommandingWait, ConnectionQuality::Good, 0, 1),
        &mut Fixed(CommandIntent::JointPosition([9.0; 7])),
        0.0,
    );
    assert_eq!(sent_position(&reply).unwrap(), IPO.to_vec());
}

#[test]
fn active_target_is_rate_limited_from_ipo_without_jump() {
    let mut session = ClientSession::new(FriVersion::V2_7, 0.01);
    let mut controller = Fixed(CommandIntent::JointPosition([9.0; 7]));
    session.on_monitoring(
        &monitoring(SessionState::CommandingWait, ConnectionQuality::Good, 0, 1),
        &mut controller,
        0.0,
    );
    let reply = session.on_monitoring(
        &monitoring(
            SessionState::CommandingActive,
            ConnectionQuality::Good,
            1,
            1,
        ),
        &mut controller,
        0.001,
    );
    let sent = sent_position(&reply).unwrap();
    for (value, ipo) in sent.iter().zip(IPO) {
        assert!((value - ipo - 0.01).abs() < 1e-12);
    }
}

#[test]
fn non_finite_intent_holds_with_fault() {
    let mut session = ClientSession::new(FriVersion::V1_15, 0.01);
    let reply = session.on_monitoring(
        &monitoring(
            SessionState::CommandingActive,
            ConnectionQuality::Excellent,
            0,
            1,
        ),
        &mut Fixed(CommandIntent::JointPosition([f64::NAN; 7])),
        0.0,
    );
    assert_eq!(reply.fault, Some(SessionFault::NonFiniteIntent));
    assert_eq!(sent_position(&reply).unwrap(), IPO.to_vec());
}

#[test]
fn poor_quality_holds() {
    let mut session = ClientSession::new(FriVersion::V2_5, 0.01);
    let reply = session.on_monitoring(
        &monitoring(
            SessionState::CommandingActive,
            ConnectionQuality::Fair,
            0,
            1,
        ),
        &mut Fixed(CommandIntent::JointPosition([0.0; 7])),
        0.0,
    );
    assert_eq!(sent_position(&reply).unwrap(), IPO.to_vec());
}

fn wrench_monitoring(state: SessionState, counter: u32) -> FriMonitoringMessage {
    let mut message = monitoring(state, ConnectionQuality::Excellent, counter, 1);
    if let Some(ipo) = message.ipo_data.as_mut() {
        ipo.client_command_mode = Some(ClientCommandMode::Wrench as i32);
        ipo.joint_position = None;
    }
    message
}

fn sent_wrench(reply: &SessionReply) -> Option<Vec<f64>> {
    reply
        .command
        .as_ref()?
        .command_data
        .as_ref()?
        .cartesian_wrench_feed_forward
        .as_ref()
        .map(|w| w.element.clone())
}

#[test]
fn sequence_check_classifies_counters_with_wrap() {
    use SequenceCheck::*;
    assert_eq!(SequenceCheck::classify(None, 7), First);
    assert_eq!(SequenceCheck::classify(Some(u32::MAX), 0), InOrder);
    assert_eq!(SequenceCheck::classify(Some(5), 5), Duplicate);
    assert_eq!(SequenceCheck::classify(Some(5), 3), Stale { behind: 2 });
    assert_eq!(
        SequenceCheck::classify(Some(u32::MAX - 1), 2),
        Gap { missed: 3 }
    );
    assert_eq!(SequenceCheck::classify(Some(5000), 0), Resynchronised);
}

#[test]
fn duplicates_and_stale_datagrams_are_dropped_without_calling_the_controller() {
    struct Counting(u32);
    impl Controller for Counting {
        fn on_monitoring(&mut self, _view: &MonitoringView, _now: f64) -> CommandIntent {
            self.0 += 1;
            CommandIntent::Hold
        }
        fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {}
    }
    let mut session = ClientSession::new(FriVersion::V1_15, 0.01);
    let mut controller = Counting(0);
    let pattern = answered(&mut session, &mut controller, [10, 10, 12, 11, 13], 1);
    assert_eq!(pattern, [true, false, true, false, true]);
    assert_eq!(controller.0, 3);
}

#[test]
fn controller_runs_in_idle_but_nothing_is_sent() {
    struct Seen(Vec<SessionState>);
    impl Controller for Seen {
        fn on_monitoring(&mut self, view: &MonitoringView, _now: f64) -> CommandIntent {
            self.0.push(view.session_state);
            CommandIntent::Hold
        }
        fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {}
    }
    let mut session = ClientSession::new(FriVersion::V2_5, 0.01);
    let mut seen = Seen(Vec::new());
    let reply = session.on_monitoring(
        &monitoring(SessionState::Idle, ConnectionQuality::Poor, 1, 1),
        &mut seen,
        0.0,
    );
    assert!(reply.command.is_none());
    assert_eq!(seen.0, [SessionState::Idle]);
}

#[test]
fn wrench_mode_sends_the_wrench_with_the_measured_position() {
    let mut session = ClientSession::new(FriVersion::V2_7, 0.01);
    let wrench = [1.0, -2.0, 3.0, 0.1, 0.2, 0.3];
    let mut controller = Fixed(CommandIntent::Wrench(wrench));
    let wait = session.on_monitoring(
        &wrench_monitoring(SessionState::CommandingWait, 0),
        &mut controller,
        0.0,
    );
    assert_eq!(sent_wrench(&wait).unwrap(), [0.0; 6]);
    assert_eq!(sent_position(&wait).unwrap(), IPO.to_vec());
    let active = session.on_monitoring(
        &wrench_monitoring(SessionState::CommandingActive, 1),
        &mut controller,
        0.001,
    );
    assert_eq!(sent_wrench(&active).unwrap(), wrench.to_vec());
    assert_eq!(sent_position(&active).unwrap(), IPO.to_vec());
    let bad = session.on_monitoring(
        &wrench_monitoring(SessionState::CommandingActive, 2),
        &mut Fixed(CommandIntent::Wrench([f64::NAN; 6])),
        0.002,
    );
    assert_eq!(sent_wrench(&bad).unwrap(), [0.0; 6]);
    assert_eq!(bad.fault, Some(SessionFault::NonFiniteIntent));
    let mismatch = session.on_monitoring(
        &wrench_monitoring(SessionState::CommandingActive, 3),
        &mut Fixed(CommandIntent::JointPosition(IPO)),
        0.003,
    );
    assert_eq!(sent_wrench(&mismatch).unwrap(), [0.0; 6]);
    assert_eq!(mismatch.fault, Some(SessionFault::ModeMismatch));
}
