//! Golden messages: every example in `PROTOCOL.md` marked
//! `<!-- golden: NAME -->` is exactly what this crate encodes for NAME, and
//! decodes back to the same value. A change of any field name, tag, unit or
//! kernel spelling breaks this test (and the document must follow, with a
//! new protocol version when old readers would misread it).

use limb_kernel::command::CommandMode;
use limb_kernel::config::{ConfigError, ConfigField, ConfigProblem, Interval, SafetyLimits};
use limb_kernel::geometry::{Point, Pose, PoseRate, Wrench};
use limb_kernel::impedance::Saturation;
use limb_kernel::lift::LiftEnd;
use limb_kernel::monitor::{Limit, Violation};
use limb_kernel::motion::SetPoint;
use limb_kernel::state::TargetError;
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::validate::Rejection;
use limb_kernel::RefusalReason;
use limb_kernel::{Command, PathSample, Refusal, Request, StateKind, StopReason};
use limb_session::kernel_wire::{Joints, KernelRefusal, PlanarPoint};
use limb_zenoh::auth::CommandKey;
use limb_zenoh::keys::Keys;
use limb_zenoh::wire::{
    Ack, AckOutcome, AckSubject, ArmModel, CommandMessage, EmergencyStopMessage, EventMessage,
    Heartbeat, KernelStatus, LinkMessage, NodeCounters, RefuseReason, SampleMessage, StopOrigin,
    SupervisorCommand, WireFormat,
};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;

/// The example key of `PROTOCOL.md` (not a secret).
const EXAMPLE_SECRET: &[u8] = b"limb example key, not a secret!!";

fn approve() -> CommandMessage {
    CommandMessage {
        sequence: 1_764_600_000_000_000,
        command: SupervisorCommand::ApproveManipulation {
            target: Joints {
                shoulder_elevation: 0.6,
                elbow_flexion: 0.8,
            },
        },
    }
}

fn violation() -> Violation {
    Violation::new(Limit::ElbowFlexion, 3.0, 2.4)
}

fn refusal(reason: RefusalReason) -> KernelRefusal {
    Refusal {
        request: Request::ApproveManipulation(limb_kernel::arm::JointAngles {
            shoulder_elevation: 0.6,
            elbow_flexion: 3.0,
        }),
        state: StateKind::Validated,
        reason,
    }
    .into()
}

fn command_report() -> limb_session::kernel_wire::CommandReport {
    Command {
        state: StateKind::Manipulate,
        mode: CommandMode::Track,
        set_point: Some(SetPoint {
            pose: Pose::new(0.31, 0.12, 0.9),
            velocity: PoseRate {
                x: 0.01,
                z: 0.02,
                psi: 0.05,
            },
            acceleration: PoseRate {
                x: 0.0,
                z: -0.1,
                psi: 0.0,
            },
        }),
        wrench: Wrench::new(1.5, -2.0, 0.1),
        saturation: Saturation {
            force: false,
            torque: false,
            speed: true,
            non_finite: false,
        },
        stop: None,
    }
    .into()
}

/// What a message encodes to (as a JSON value and as indented text in
/// field order), and a check that a golden text decodes back to it.
fn both_ways<T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug>(value: &T) -> Expected {
    let encoded: Value = serde_json::from_slice(&WireFormat::Json.encode(value).unwrap()).unwrap();
    let pretty = serde_json::to_string_pretty(value).unwrap();
    let expected = format!("{value:?}");
    let decode = Box::new(move |golden: &Value| {
        let bytes = serde_json::to_vec(golden).unwrap();
        let decoded: T = WireFormat::Json.decode(&bytes).unwrap();
        assert_eq!(format!("{decoded:?}"), expected);
    });
    (encoded, pretty, decode)
}

type Expected = (Value, String, Box<dyn Fn(&Value)>);
type Golden = BTreeMap<&'static str, Expected>;

fn messages() -> Golden {
    let mut m: Golden = BTreeMap::new();
    m.insert("command", both_ways(&approve()));
    m.insert(
        "command_update_limits",
        both_ways(&CommandMessage {
            sequence: 1_764_600_000_000_001,
            // Explicit values: the golden pins the shape, not the defaults.
            command: SupervisorCommand::UpdateLimits {
                limits: SafetyLimits {
                    max_force: 45.0,
                    max_torque: 8.0,
                    max_force_rate: 250.0,
                    max_speed: 0.15,
                    rate_window: 0.05,
                    shoulder_elevation: Interval::new(-0.05, 2.0),
                    elbow_flexion: Interval::new(-0.35, 2.6),
                    max_model_mismatch: 0.03,
                    table_tolerance: 0.005,
                    workspace_x: Interval::new(-0.1, 0.9),
                    workspace_z: Interval::new(-0.01, 0.9),
                    max_sensor_age: 0.02,
                },
            },
        }),
    );
    m.insert(
        "estop",
        both_ways(&EmergencyStopMessage {
            sequence: 1_764_600_000_000_002,
        }),
    );
    m.insert(
        "heartbeat",
        both_ways(&Heartbeat {
            sequence: 1_764_600_000_050_000,
        }),
    );
    m.insert(
        "ack_accepted",
        both_ways(&Ack {
            subject: AckSubject::Request,
            sequence: Some(1_764_600_000_000_000),
            outcome: AckOutcome::Accepted {
                state: StateKind::Manipulate.into(),
            },
        }),
    );
    m.insert(
        "ack_estop",
        both_ways(&Ack {
            subject: AckSubject::EmergencyStop,
            sequence: Some(1_764_600_000_000_002),
            outcome: AckOutcome::Accepted {
                state: StateKind::SafeStop.into(),
            },
        }),
    );
    let refused = |reason| Ack::refused(Some(1_764_600_000_000_000), reason);
    m.insert(
        "ack_kernel_refusal",
        both_ways(&refused(RefuseReason::Kernel {
            refusal: refusal(RefusalReason::Target(TargetError::JointLimits(violation()))),
        })),
    );
    m.insert(
        "ack_not_allowed",
        both_ways(&refused(RefuseReason::Kernel {
            refusal: refusal(RefusalReason::NotAllowedInState),
        })),
    );
    m.insert(
        "ack_unauthorised",
        both_ways(&refused(RefuseReason::Unauthorised)),
    );
    m.insert(
        "ack_replayed",
        both_ways(&refused(RefuseReason::Replayed {
            last_accepted: 1_764_600_000_000_000,
        })),
    );
    m.insert("ack_busy", both_ways(&refused(RefuseReason::Busy)));
    m.insert(
        "ack_malformed",
        both_ways(&Ack::refused(
            None,
            RefuseReason::Malformed {
                detail: "expected value at line 1 column 1".into(),
            },
        )),
    );
    m.insert(
        "ack_invalid_limits",
        both_ways(&refused(RefuseReason::InvalidLimits {
            error: ConfigError::new(ConfigField::ElbowFlexion, ConfigProblem::EmptyInterval).into(),
        })),
    );
    m.insert(
        "ack_limits_not_allowed",
        both_ways(&refused(RefuseReason::LimitsNotAllowedInState {
            state: StateKind::Manipulate.into(),
        })),
    );
    m.insert(
        "event_transition",
        both_ways(&EventMessage {
            sequence: 4,
            kernel_dropped: 0,
            event: TraceEvent {
                time: 12.5,
                event: Event::Transition {
                    from: StateKind::Validated,
                    to: StateKind::Manipulate,
                    cause: Cause::Request(Request::ApproveManipulation(
                        limb_kernel::arm::JointAngles {
                            shoulder_elevation: 0.6,
                            elbow_flexion: 0.8,
                        },
                    )),
                },
            }
            .into(),
            origin: None,
        }),
    );
    m.insert(
        "event_stop",
        both_ways(&EventMessage {
            sequence: 5,
            kernel_dropped: 0,
            event: TraceEvent {
                time: 14.25,
                event: Event::Transition {
                    from: StateKind::Manipulate,
                    to: StateKind::SafeStop,
                    cause: Cause::Stop(StopReason::Monitor(Violation::new(
                        Limit::ForceMagnitude,
                        61.0,
                        60.0,
                    ))),
                },
            }
            .into(),
            origin: None,
        }),
    );
    m.insert(
        "event_emergency_stop",
        both_ways(&EventMessage {
            sequence: 7,
            kernel_dropped: 0,
            event: TraceEvent {
                time: 16.5,
                event: Event::Transition {
                    from: StateKind::Manipulate,
                    to: StateKind::SafeStop,
                    cause: Cause::Request(Request::Stop),
                },
            }
            .into(),
            origin: Some(StopOrigin::EmergencyStop),
        }),
    );
    m.insert(
        "event_model_rejected",
        both_ways(&EventMessage {
            sequence: 2,
            kernel_dropped: 0,
            event: TraceEvent {
                time: 31.5,
                event: Event::Transition {
                    from: StateKind::Estimate,
                    to: StateKind::SafeStop,
                    cause: Cause::Stop(StopReason::ModelRejected(
                        Rejection::UpperArmLengthOutOfRange(0.5),
                    )),
                },
            }
            .into(),
            origin: None,
        }),
    );
    m.insert(
        "event_refused",
        both_ways(&EventMessage {
            sequence: 6,
            kernel_dropped: 0,
            event: TraceEvent {
                time: 15.0,
                event: Event::Refused(Refusal {
                    request: Request::FinishManipulation,
                    state: StateKind::SafeStop,
                    reason: RefusalReason::NotAllowedInState,
                }),
            }
            .into(),
            origin: None,
        }),
    );
    m.insert(
        "event_lift_ended",
        both_ways(&EventMessage {
            sequence: 3,
            kernel_dropped: 0,
            event: TraceEvent {
                time: 9.75,
                event: Event::LiftEnded(LiftEnd::JointMargin(Limit::ShoulderElevation)),
            }
            .into(),
            origin: None,
        }),
    );
    m.insert(
        "sample",
        both_ways(&SampleMessage {
            step: 12_500,
            time: 12.5,
            sent_at_ns: 1_764_600_012_500_000_000,
            frame: PathSample {
                time: 12.499,
                pose: Pose::new(0.3, 0.11, 0.88),
                wrench: Wrench::new(0.5, -1.0, 0.02),
            }
            .into(),
            command: command_report(),
        }),
    );
    m.insert(
        "link_lost",
        both_ways(&LinkMessage::SupervisorLost {
            time: 20.0,
            silence: 0.251,
            stopped: true,
        }),
    );
    m.insert(
        "link_back",
        both_ways(&LinkMessage::SupervisorBack { time: 21.0 }),
    );
    m.insert(
        "status",
        both_ways(&KernelStatus {
            time: 12.5,
            state: StateKind::Manipulate.into(),
            supervisor_present: true,
            counters: NodeCounters {
                steps: 12_500,
                overruns: 3,
                samples_dropped: 0,
                reliable_dropped: 0,
                kernel_events_dropped: 0,
                heartbeats_replayed: 0,
                estop_acks_dropped: 0,
            },
        }),
    );
    m.insert(
        "arm",
        both_ways(&ArmModel {
            upper_arm_length: 0.3,
            forearm_length: 0.25,
            shoulder: PlanarPoint::from(Point::new(0.0, 0.45)),
        }),
    );
    m
}

/// The `<!-- golden: NAME -->` blocks of PROTOCOL.md: NAME → the JSON (or,
/// for `-hex` names, the hex text) of the fenced block that follows.
fn documented() -> BTreeMap<String, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/PROTOCOL.md");
    let text = std::fs::read_to_string(path).unwrap();
    let mut blocks = BTreeMap::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let Some(name) = line
            .trim()
            .strip_prefix("<!-- golden: ")
            .and_then(|l| l.strip_suffix(" -->"))
        else {
            continue;
        };
        let fence = lines.next().unwrap_or_default();
        assert!(fence.starts_with("```"), "{name}: a fenced block follows");
        let body: Vec<&str> = lines
            .by_ref()
            .take_while(|l| !l.starts_with("```"))
            .collect();
        let previous = blocks.insert(name.to_owned(), body.join("\n"));
        assert!(previous.is_none(), "{name} twice");
    }
    blocks
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn the_documented_messages_are_the_encoded_ones() {
    let documented = documented();
    let mut checked = 0;
    for (name, (encoded, pretty, decode)) in messages() {
        let text = documented
            .get(name)
            .unwrap_or_else(|| panic!("PROTOCOL.md lacks {name}:\n{pretty}"));
        let golden: Value = serde_json::from_str(text)
            .unwrap_or_else(|e| panic!("{name}: not JSON ({e}):\n{text}"));
        assert_eq!(golden, encoded, "{name}: PROTOCOL.md differs:\n{pretty}");
        decode(&golden);
        checked += 1;
    }
    // The command example is the exact payload (compact JSON); its
    // signature and its CBOR encoding.
    let payload = WireFormat::Json.encode(&approve()).unwrap();
    assert_eq!(documented["command"].trim().as_bytes(), payload.as_slice());
    let keys = Keys::new("arm1").unwrap();
    let key = CommandKey::new(EXAMPLE_SECRET).unwrap();
    let signature = hex(&key.sign(&keys.request(), &payload));
    assert_eq!(
        documented["command-signature-hex"].trim(),
        signature,
        "signature of the command's exact text"
    );
    let cbor = hex(&WireFormat::Cbor.encode(&approve()).unwrap());
    assert_eq!(
        documented["command-cbor-hex"].replace(['\n', ' '], ""),
        cbor
    );
    assert_eq!(
        documented.len(),
        checked + 2,
        "every golden block is checked"
    );
}
