//! The `limb-plant/1` messages (`../shared/spec/external-plant.md`):
//! strict decoding of what the plant sends, encoding of what limb sends.
//!
//! # Decisions where the spec is silent
//! - Handshake: `protocol` and `dt` are required; `name` (default
//!   `"unnamed plant"`) and `truth` (default: none) may be absent; truth
//!   names must be distinct non-empty strings. `dt` must be finite and in
//!   (0, [`MAX_DT`]] s.
//! - A line's type is its key: `end` first, then `frame`; an object with
//!   neither is an unknown message (a second handshake included).
//! - Unknown keys are ignored, as the spec says, and counted by name
//!   ([`Decoded::unknown`]) so the session reports them: nothing is
//!   dropped silently.
//! - `NaN`/`Infinity` are not JSON; a line holding such a token where a
//!   number stands is reported as [`Fault::NonFinite`] of that field, not
//!   as a malformed line.
//! - The first frame's `t` may be any finite number; later frames must
//!   increase strictly.

use crate::error::Fault;
use limb_kernel::command::CommandMode;
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Command, PathSample};
use serde_json::{Map, Value};
use std::fmt::Write as _;

/// The protocol this client speaks.
pub const PROTOCOL: &str = "limb-plant/1";
/// Longest line either side may send, newline excluded [bytes].
pub const MAX_LINE: usize = 65_536;
/// Largest plant period accepted [s] (a slower plant would age every frame
/// past the kernel's sensor-age limit).
pub const MAX_DT: f64 = 0.01;

/// The plant's first line.
#[derive(Debug, Clone, PartialEq)]
pub struct Handshake {
    /// The plant's period [s].
    pub dt: f64,
    /// The plant's name for itself.
    pub name: String,
    /// The ground-truth names every frame carries, in order.
    pub truth: Vec<String>,
}

/// One frame of the plant.
#[derive(Debug, Clone, PartialEq)]
pub struct PlantFrame {
    /// Robot stamp, grasp pose and external wrench (frame S).
    pub sample: PathSample,
    /// Lateral grasp position y [m], when sent.
    pub y: Option<f64>,
    /// Lateral force fy [N], when sent.
    pub fy: Option<f64>,
    /// Ground truth, in the handshake's order.
    pub truth: Vec<f64>,
}

/// A line of the plant after its handshake.
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    /// A frame.
    Frame(PlantFrame),
    /// The plant ends the session, for this reason.
    End(String),
}

/// A decoded line and the keys it held that this version does not know.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded<T> {
    /// The message.
    pub message: T,
    /// Unknown keys (dotted: `frame.vx`), ignored.
    pub unknown: Vec<String>,
}

/// Parses `line` as a JSON object.
fn object(line: &[u8]) -> Result<Map<String, Value>, Fault> {
    match serde_json::from_slice::<Value>(line) {
        Ok(Value::Object(map)) => Ok(map),
        Ok(other) => Err(Fault::Malformed(format!("a JSON {}", kind(&other)))),
        Err(error) => Err(non_finite_token(line)
            .map_or_else(|| Fault::Malformed(error.to_string()), Fault::NonFinite)),
    }
}

/// The key before the first bare `NaN`/`Infinity` token of `line`, if it
/// has one (outside strings).
fn non_finite_token(line: &[u8]) -> Option<String> {
    let text = std::str::from_utf8(line).ok()?;
    let mut in_string = false;
    let mut escaped = false;
    let mut last_key = String::new();
    let mut string_start = 0;
    let bytes = text.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        if in_string {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => {
                    in_string = false;
                    let rest = text[i + 1..].trim_start();
                    if rest.starts_with(':') {
                        last_key = text[string_start..i].to_string();
                    }
                }
                _ => {}
            }
            continue;
        }
        if b == b'"' {
            in_string = true;
            string_start = i + 1;
        } else if bytes[i..].starts_with(b"NaN") || bytes[i..].starts_with(b"Infinity") {
            return Some(last_key);
        }
    }
    None
}

fn kind(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "boolean",
        Value::Number(_) => "number",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    }
}

/// A required finite number `key` of `map` (`at`: its path for messages).
fn number(map: &Map<String, Value>, key: &str, at: &str) -> Result<f64, Fault> {
    match map.get(key) {
        None => Err(Fault::MissingField(format!("{at}{key}"))),
        Some(value) => finite(value, &format!("{at}{key}")),
    }
}

/// An optional finite number `key` of `map`.
fn optional_number(map: &Map<String, Value>, key: &str, at: &str) -> Result<Option<f64>, Fault> {
    map.get(key)
        .map(|value| finite(value, &format!("{at}{key}")))
        .transpose()
}

fn finite(value: &Value, field: &str) -> Result<f64, Fault> {
    match value.as_f64() {
        Some(v) if v.is_finite() => Ok(v),
        Some(_) => Err(Fault::NonFinite(field.to_string())),
        None => Err(Fault::WrongType {
            field: field.to_string(),
            expected: "a number",
        }),
    }
}

/// The keys of `map` outside `known`, prefixed by `at`.
fn unknown_keys(map: &Map<String, Value>, known: &[&str], at: &str) -> Vec<String> {
    map.keys()
        .filter(|k| !known.contains(&k.as_str()))
        .map(|k| format!("{at}{k}"))
        .collect()
}

/// Decodes the plant's handshake.
///
/// # Errors
/// [`Fault::Malformed`], [`Fault::MissingField`], [`Fault::WrongType`],
/// [`Fault::NonFinite`], or [`Fault::Handshake`] for another protocol, an
/// unusable `dt` or bad truth names.
pub fn decode_handshake(line: &[u8]) -> Result<Decoded<Handshake>, Fault> {
    let map = object(line)?;
    let protocol = match map.get("protocol") {
        None => return Err(Fault::MissingField("protocol".into())),
        Some(Value::String(p)) => p,
        Some(_) => {
            return Err(Fault::WrongType {
                field: "protocol".into(),
                expected: "a string",
            })
        }
    };
    if protocol != PROTOCOL {
        return Err(Fault::Handshake(format!(
            "protocol {protocol:?}, this client speaks {PROTOCOL}"
        )));
    }
    let dt = number(&map, "dt", "")?;
    if !(dt > 0.0 && dt <= MAX_DT) {
        return Err(Fault::Handshake(format!(
            "dt = {dt} s is outside (0, {MAX_DT}] s"
        )));
    }
    let name = match map.get("name") {
        None => "unnamed plant".to_string(),
        Some(Value::String(n)) => n.clone(),
        Some(_) => {
            return Err(Fault::WrongType {
                field: "name".into(),
                expected: "a string",
            })
        }
    };
    let truth = match map.get("truth") {
        None => Vec::new(),
        Some(Value::Array(names)) => truth_names(names)?,
        Some(_) => {
            return Err(Fault::WrongType {
                field: "truth".into(),
                expected: "an array of names",
            })
        }
    };
    Ok(Decoded {
        message: Handshake { dt, name, truth },
        unknown: unknown_keys(&map, &["protocol", "dt", "name", "truth"], ""),
    })
}

fn truth_names(names: &[Value]) -> Result<Vec<String>, Fault> {
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for name in names {
        match name {
            Value::String(n) if !n.is_empty() && !out.contains(n) => out.push(n.clone()),
            Value::String(n) if n.is_empty() => {
                return Err(Fault::Handshake("an empty truth name".into()))
            }
            Value::String(n) => {
                return Err(Fault::Handshake(format!("truth name {n:?} given twice")))
            }
            _ => {
                return Err(Fault::WrongType {
                    field: "truth".into(),
                    expected: "an array of names",
                })
            }
        }
    }
    Ok(out)
}

/// Decodes a line after the handshake; `truth` are the handshake's names.
///
/// # Errors
/// [`Fault::Malformed`], [`Fault::MissingField`], [`Fault::WrongType`],
/// [`Fault::NonFinite`], [`Fault::TruthMismatch`] or
/// [`Fault::UnknownMessage`]. Time order is the caller's to check.
pub fn decode_message(line: &[u8], truth: &[String]) -> Result<Decoded<Message>, Fault> {
    let map = object(line)?;
    if let Some(reason) = map.get("end") {
        let reason = match reason {
            Value::String(r) => r.clone(),
            other => other.to_string(),
        };
        return Ok(Decoded {
            message: Message::End(reason),
            unknown: unknown_keys(&map, &["end"], ""),
        });
    }
    let Some(frame) = map.get("frame") else {
        let keys: Vec<&str> = map.keys().map(String::as_str).collect();
        return Err(Fault::UnknownMessage(keys.join(", ")));
    };
    let Value::Object(f) = frame else {
        return Err(Fault::WrongType {
            field: "frame".into(),
            expected: "an object",
        });
    };
    let at = "frame.";
    let sample = PathSample {
        time: number(f, "t", at)?,
        pose: Pose::new(
            number(f, "x", at)?,
            number(f, "z", at)?,
            number(f, "psi", at)?,
        ),
        wrench: Wrench::new(
            number(f, "fx", at)?,
            number(f, "fz", at)?,
            number(f, "ty", at)?,
        ),
    };
    let y = optional_number(f, "y", at)?;
    let fy = optional_number(f, "fy", at)?;
    let values = frame_truth(map.get("truth"), truth)?;
    let mut unknown = unknown_keys(&map, &["frame", "truth"], "");
    unknown.extend(unknown_keys(
        f,
        &["t", "x", "y", "z", "psi", "fx", "fy", "fz", "ty"],
        at,
    ));
    Ok(Decoded {
        message: Message::Frame(PlantFrame {
            sample,
            y,
            fy,
            truth: values,
        }),
        unknown,
    })
}

/// The frame's truth values in the order of `names`: exactly those names.
fn frame_truth(truth: Option<&Value>, names: &[String]) -> Result<Vec<f64>, Fault> {
    let map = match truth {
        None if names.is_empty() => return Ok(Vec::new()),
        None => return Err(Fault::MissingField("truth".into())),
        Some(Value::Object(map)) => map,
        Some(_) => {
            return Err(Fault::WrongType {
                field: "truth".into(),
                expected: "an object",
            })
        }
    };
    if let Some(extra) = map.keys().find(|k| !names.contains(k)) {
        return Err(Fault::TruthMismatch(format!("`{extra}` was not announced")));
    }
    names
        .iter()
        .map(|name| match map.get(name) {
            None => Err(Fault::TruthMismatch(format!("`{name}` is missing"))),
            Some(value) => finite(value, &format!("truth.{name}")),
        })
        .collect()
}

/// limb's answer to an accepted handshake.
pub fn accept() -> String {
    format!("{{\"protocol\":\"{PROTOCOL}\"}}\n")
}

/// limb's answer to a refused handshake, or its end of the session.
pub fn refuse_or_end(key: &str, reason: &str) -> String {
    let mut line = serde_json::json!({ key: reason }).to_string();
    line.push('\n');
    line
}

/// The name of `mode` on the wire.
pub const fn mode_name(mode: CommandMode) -> &'static str {
    match mode {
        CommandMode::Track => "track",
        CommandMode::Hold => "hold",
        CommandMode::Stop => "stop",
    }
}

/// Appends `command` as one line to `out`.
///
/// # Errors
/// `Err` with `out` unchanged when a number of the command is not finite
/// (the kernel never issues one; a plant must never see one).
pub fn encode_command(command: &Command, out: &mut String) -> Result<(), Fault> {
    if !command.is_finite() {
        return Err(Fault::NonFinite("command".into()));
    }
    let _ = write!(
        out,
        "{{\"command\":{{\"mode\":\"{}\"",
        mode_name(command.mode)
    );
    if let Some(s) = &command.set_point {
        let fields = [
            ("xd", s.pose.x),
            ("zd", s.pose.z),
            ("psid", s.pose.psi),
            ("vxd", s.velocity.x),
            ("vzd", s.velocity.z),
            ("vpsid", s.velocity.psi),
            ("axd", s.acceleration.x),
            ("azd", s.acceleration.z),
            ("apsid", s.acceleration.psi),
        ];
        for (key, value) in fields {
            let _ = write!(out, ",\"{key}\":{value}");
        }
    }
    let w = &command.wrench;
    let _ = writeln!(out, ",\"fx\":{},\"fz\":{},\"ty\":{}}}}}", w.fx, w.fz, w.ty);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use limb_kernel::impedance::Saturation;
    use limb_kernel::motion::SetPoint;
    use limb_kernel::StateKind;
    use proptest::prelude::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_string()).collect()
    }

    const FRAME: &str = r#"{"frame":{"t":0.5,"x":0.1,"z":0.2,"psi":0.3,"fx":1,"fz":2,"ty":3}"#;

    #[test]
    fn a_frame_is_decoded_with_its_truth_in_the_handshakes_order() {
        let line = format!(r#"{FRAME},"truth":{{"l2":0.2,"l1":0.3}}}}"#);
        let decoded = decode_message(line.as_bytes(), &names(&["l1", "l2"])).unwrap();
        let Message::Frame(frame) = decoded.message else {
            panic!("not a frame")
        };
        assert_eq!(frame.sample.time, 0.5);
        assert_eq!(frame.sample.pose, Pose::new(0.1, 0.2, 0.3));
        assert_eq!(frame.sample.wrench, Wrench::new(1.0, 2.0, 3.0));
        assert_eq!((frame.y, frame.fy), (None, None));
        assert_eq!(frame.truth, [0.3, 0.2]);
        assert!(decoded.unknown.is_empty());
    }

    /// REQ-ADP-004: each broken frame is refused with its named fault.
    #[test]
    fn each_broken_frame_has_its_named_fault() {
        let truth = names(&["l1"]);
        let cases: [(&str, &str); 8] = [
            (
                r#"{"frame":{"t":0.5,"x":0.1,"z":0.2,"psi":0.3,"fx":1,"ty":3},"truth":{"l1":1}}"#,
                "missing_field",
            ),
            (
                r#"{"frame":{"t":0.5,"x":0.1,"z":0.2,"psi":0.3,"fx":NaN,"fz":2,"ty":3},"truth":{"l1":1}}"#,
                "non_finite",
            ),
            (
                r#"{"frame":{"t":0.5,"x":0.1,"z":0.2,"psi":0.3,"fx":-Infinity,"fz":2,"ty":3},"truth":{"l1":1}}"#,
                "non_finite",
            ),
            (
                r#"{"frame":{"t":0.5,"x":"0.1","z":0.2,"psi":0.3,"fx":1,"fz":2,"ty":3},"truth":{"l1":1}}"#,
                "wrong_type",
            ),
            (
                r#"{"frame":{"t":0.5,"x":0.1,"z":0.2,"psi":0.3,"fx":1,"fz":2,"ty":3},"truth":{"l2":1}}"#,
                "truth_mismatch",
            ),
            (
                r#"{"frame":{"t":0.5,"x":0.1,"z":0.2,"psi":0.3,"fx":1,"fz":2,"ty":3}}"#,
                "missing_field",
            ),
            (r#"{"status":"ok"}"#, "unknown_message"),
            (r#"{"frame":{"t":0.5,"#, "malformed_line"),
        ];
        for (line, code) in cases {
            let fault = decode_message(line.as_bytes(), &truth).unwrap_err();
            assert_eq!(fault.code(), code, "{line}: {fault}");
        }
        let nan = decode_message(cases[1].0.as_bytes(), &truth).unwrap_err();
        assert_eq!(nan, Fault::NonFinite("fx".into()));
    }

    #[test]
    fn unknown_keys_are_ignored_and_named() {
        let line =
            r#"{"frame":{"t":0,"x":0,"z":0,"psi":0,"fx":0,"fz":0,"ty":0,"vx":1},"note":"hi"}"#;
        let decoded = decode_message(line.as_bytes(), &[]).unwrap();
        assert!(matches!(decoded.message, Message::Frame(_)));
        assert_eq!(decoded.unknown, ["note", "frame.vx"]);
    }

    #[test]
    fn the_handshake_is_checked() {
        let ok = r#"{"protocol":"limb-plant/1","dt":0.001,"truth":["q1","q2"],"v":2}"#;
        let decoded = decode_handshake(ok.as_bytes()).unwrap();
        assert_eq!(decoded.message.truth, ["q1", "q2"]);
        assert_eq!(decoded.message.name, "unnamed plant");
        assert_eq!(decoded.unknown, ["v"]);
        for bad in [
            r#"{"protocol":"limb-plant/2","dt":0.001}"#,
            r#"{"protocol":"limb-plant/1","dt":0}"#,
            r#"{"protocol":"limb-plant/1","dt":0.5}"#,
            r#"{"protocol":"limb-plant/1","dt":0.001,"truth":["q1","q1"]}"#,
            r#"{"protocol":"limb-plant/1","dt":0.001,"truth":[""]}"#,
        ] {
            assert_eq!(
                decode_handshake(bad.as_bytes()).unwrap_err().code(),
                "handshake_refused",
                "{bad}"
            );
        }
        assert_eq!(
            decode_handshake(br#"{"dt":0.001}"#).unwrap_err(),
            Fault::MissingField("protocol".into())
        );
    }

    fn command(set_point: Option<[f64; 9]>, wrench: [f64; 3], mode: CommandMode) -> Command {
        Command {
            state: StateKind::Estimate,
            mode,
            set_point: set_point.map(|v| SetPoint {
                pose: Pose::new(v[0], v[1], v[2]),
                velocity: limb_kernel::geometry::PoseRate {
                    x: v[3],
                    z: v[4],
                    psi: v[5],
                },
                acceleration: limb_kernel::geometry::PoseRate {
                    x: v[6],
                    z: v[7],
                    psi: v[8],
                },
            }),
            wrench: Wrench::new(wrench[0], wrench[1], wrench[2]),
            saturation: Saturation::default(),
            stop: None,
        }
    }

    proptest! {
        /// Every finite command is one line of JSON a plant reads back to
        /// the same bits; a command without a set-point has no set-point
        /// keys.
        #[test]
        fn commands_round_trip_exactly(
            values in proptest::array::uniform9(proptest::num::f64::NORMAL | proptest::num::f64::ZERO),
            wrench in proptest::array::uniform3(-1e3..1e3f64),
            with_set_point in any::<bool>(),
        ) {
            let sent = command(with_set_point.then_some(values), wrench, CommandMode::Track);
            let mut line = String::new();
            encode_command(&sent, &mut line).unwrap();
            prop_assert!(line.ends_with('\n') && line.matches('\n').count() == 1);
            let value: Value = serde_json::from_str(&line).unwrap();
            let c = &value["command"];
            prop_assert_eq!(c["mode"].as_str(), Some("track"));
            prop_assert_eq!(c["fx"].as_f64(), Some(wrench[0]));
            prop_assert_eq!(c["ty"].as_f64(), Some(wrench[2]));
            if with_set_point {
                let keys = ["xd", "zd", "psid", "vxd", "vzd", "vpsid", "axd", "azd", "apsid"];
                for (key, v) in keys.iter().zip(values) {
                    prop_assert_eq!(c[*key].as_f64(), Some(v), "{}", key);
                }
            } else {
                prop_assert!(c.get("xd").is_none());
            }
        }

        /// REQ-ADP-004: no line, however broken, panics the decoder: it is
        /// a message or a named fault.
        #[test]
        fn any_line_is_a_message_or_a_fault(line in proptest::collection::vec(any::<u8>(), 0..200)) {
            let _ = decode_message(&line, &names(&["q1"]));
            let _ = decode_handshake(&line);
        }

        /// REQ-ADP-004: the same over valid UTF-8 of any characters, JSON's
        /// own among them (random bytes are rarely valid UTF-8 with a
        /// multi-byte character, the case that once panicked).
        #[test]
        fn any_text_line_is_a_message_or_a_fault(line in "[{}\\[\\]\":,NaInfity0-9. \\PC]{0,80}") {
            let _ = decode_message(line.as_bytes(), &names(&["q1"]));
            let _ = decode_handshake(line.as_bytes());
        }
    }

    /// REQ-ADP-004: a multi-byte character outside a string (here after
    /// a key, and alone) is a malformed line, not a panic: the token scan
    /// reads bytes, never a `str` slice that could start inside a
    /// character (seen: "start byte index 1 is not a char boundary"
    /// on the line `߃`, found by the proptest above).
    #[test]
    fn a_multibyte_character_outside_a_string_is_a_fault() {
        for line in ["\u{7c3}", "{\"q1\": \u{7c3}NaN}", "\u{e9}Infinity"] {
            let decoded = decode_message(line.as_bytes(), &names(&["q1"]));
            assert!(decoded.is_err(), "{line}: {decoded:?}");
            assert!(decode_handshake(line.as_bytes()).is_err(), "{line}");
        }
    }

    #[test]
    fn a_non_finite_command_is_never_sent() {
        let mut line = String::from("kept");
        let bad = command(None, [f64::NAN, 0.0, 0.0], CommandMode::Stop);
        assert_eq!(
            encode_command(&bad, &mut line),
            Err(Fault::NonFinite("command".into()))
        );
        assert_eq!(line, "kept");
    }
}
