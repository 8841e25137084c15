//! The FRI client session fed arbitrary monitoring datagrams of one
//! version, with a controller whose intents (hold, joint target, wrench,
//! non-finite) the input chooses. On every reply:
//! * nothing is sent in IDLE, and a duplicate or stale counter gets no reply;
//! * the reply reflects the monitor's counter and encodes for the version;
//! * every value on the wire is finite; a wrench below GOOD quality is zero;
//! * a joint target in COMMANDING_ACTIVE moves at most `max_joint_step`
//!   from the target sent before it (no jump on re-entry).
//!
//! Input: version selector, joint-step byte, then cycles
//! `[control][length lo][length hi][datagram]`; control bits 0-1 pick the
//! intent, bits 2-7 its size.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_kuka::messages::{ClientCommandMode, ConnectionQuality, FriCommandMessage, SessionState};
use limb_kuka::session::{
    ClientSession, CommandIntent, Controller, JointVector, MonitoringView, SequenceCheck,
};
use limb_kuka::{decode_monitoring, encode_command};

/// The controller: answers each message with the intent the input chose.
struct Scripted {
    control: u8,
}

impl Controller for Scripted {
    fn on_monitoring(&mut self, view: &MonitoringView, _now: f64) -> CommandIntent {
        let size = f64::from(self.control >> 2) * 0.01;
        let base = view.measured_joint_position.unwrap_or([0.0; 7]);
        match self.control & 0b11 {
            0 => CommandIntent::Hold,
            1 => CommandIntent::JointPosition(base.map(|q| q + size)),
            2 => CommandIntent::Wrench([size * 100.0, -size, size, 0.0, 0.0, size]),
            _ if self.control & 0b100 == 0 => CommandIntent::JointPosition([f64::NAN; 7]),
            _ => CommandIntent::Wrench([f64::INFINITY; 6]),
        }
    }

    fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {}
}

fn joint_target(command: &FriCommandMessage) -> Option<JointVector> {
    let values = &command
        .command_data
        .as_ref()?
        .joint_position
        .as_ref()?
        .value;
    values.as_slice().try_into().ok()
}

fn all_finite(command: &FriCommandMessage) -> bool {
    command.command_data.as_ref().is_none_or(|data| {
        let joints = data.joint_position.iter().flat_map(|j| &j.value);
        let wrench = data
            .cartesian_wrench_feed_forward
            .iter()
            .flat_map(|w| &w.element);
        joints.chain(wrench).all(|v| v.is_finite())
    })
}

fuzz_target!(|data: &[u8]| {
    let &[selector, step, ref cycles @ ..] = data else {
        return;
    };
    let version = limb_fuzz::fri_version(selector);
    let max_joint_step = f64::from(step) * 1e-4;
    let mut rest: &[u8] = cycles;
    let mut session = ClientSession::new(version, max_joint_step);
    let mut previous_target: Option<JointVector> = None;
    let mut now = 0.0;
    while let &[control, lo, hi, ref tail @ ..] = rest {
        let length = usize::from(u16::from_le_bytes([lo, hi])).min(tail.len());
        let (datagram, next) = tail.split_at(length);
        rest = next;
        now += 0.001;
        let Ok(message) = decode_monitoring(datagram, version) else {
            continue;
        };
        let view = ClientSession::view(&message);
        let mut controller = Scripted { control };
        let reply = session.on_monitoring(&message, &mut controller, now);
        if !reply.sequence.is_handled() {
            assert!(reply.command.is_none(), "a dropped message was answered");
            continue;
        }
        assert!(
            !matches!(
                reply.sequence,
                SequenceCheck::Duplicate | SequenceCheck::Stale { .. }
            ),
            "a duplicate or stale counter was handled"
        );
        if view.session_state < SessionState::CommandingWait {
            previous_target = None;
        }
        let Some(command) = reply.command else {
            continue;
        };
        assert_ne!(view.session_state, SessionState::Idle, "a reply in IDLE");
        assert_eq!(
            command.header.reflected_sequence_counter, view.sequence_counter,
            "the reply does not reflect the monitor's counter"
        );
        assert!(
            all_finite(&command),
            "a non-finite value on the wire: {command:?}"
        );
        encode_command(&command, version).expect("a reply that cannot be sent");
        let wrench_mode = view.client_command_mode == ClientCommandMode::Wrench;
        if wrench_mode && view.quality < ConnectionQuality::Good {
            let wrench = command
                .command_data
                .as_ref()
                .and_then(|d| d.cartesian_wrench_feed_forward.as_ref());
            assert!(
                wrench.is_none_or(|w| w.element.iter().all(|v| *v == 0.0)),
                "a wrench was sent below GOOD quality"
            );
        }
        match view.session_state {
            SessionState::CommandingWait => previous_target = joint_target(&command),
            SessionState::CommandingActive if !wrench_mode => {
                let target = joint_target(&command);
                if let (Some(before), Some(after)) = (previous_target, target) {
                    for (a, b) in before.iter().zip(&after) {
                        // `b` is `a` plus the clamped step, rounded once.
                        let rounding = 2.0 * f64::EPSILON * a.abs().max(b.abs());
                        assert!(
                            (a - b).abs() <= max_joint_step + rounding,
                            "a joint target jumped from {a} to {b} rad (limit {max_joint_step})"
                        );
                    }
                }
                if target.is_some() {
                    previous_target = target;
                }
            }
            _ => {}
        }
    }
});
