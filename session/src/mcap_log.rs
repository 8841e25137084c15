//! The session log as MCAP (`--log FILE.mcap`): the frame log, the step
//! log and the kernel's events of [`crate::log`] as typed channels, for
//! the robotics tools that open MCAP (Foxglove, PlotJuggler, the `mcap`
//! CLI and readers).
//!
//! # Format
//! Every message is a JSON object (message encoding `json`) with a JSON
//! Schema (schema encoding `jsonschema`), the encoding Foxglove and
//! PlotJuggler read without plugins. Times are nanoseconds: a message's
//! `log_time` is the kernel time of its step (events: their own time), its
//! `publish_time` the robot's stamp.
//!
//! | topic | schema | one message per | fields |
//! |---|---|---|---|
//! | `/limb/frame` | `limb.Frame` | frame the kernel stepped on | the frame log's columns ([`crate::log::COLUMNS`], then the robot's own), `null` where the CSV is empty; the channel's metadata `columns` lists them in order |
//! | `/limb/step` | `limb.Step` | kernel step (silences included) | the step log's columns ([`crate::log::STEP_COLUMNS`]) |
//! | `/limb/event` | `limb.Event` | transition, refusal or lift end | `time` [s], `text` |
//! | any, by [`McapLog::record`] | the caller's | – | the caller's JSON (the CLI: `/limb/config` once at the start, `/limb/model` at each validated model) |
//!
//! The frame channel holds exactly the CSV's rows and numbers (shortest
//! round-trip decimals), so a reader rebuilds the CSV text from it
//! ([`frames_as_csv`]): `limb estimate` and `limb diagnose` read an MCAP
//! log through the same parser as a CSV one.

use crate::log::{Logged, Row, COLUMNS, STEP_COLUMNS};
use crate::robot::Frame;
use crate::run::{Observer, Step};
use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, StateKind};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::{Seek, Write};

/// Topic of the frame log.
pub const FRAME_TOPIC: &str = "/limb/frame";
/// Topic of the step log.
pub const STEP_TOPIC: &str = "/limb/step";
/// Topic of the kernel's events.
pub const EVENT_TOPIC: &str = "/limb/event";

/// A JSON Schema for an object of `fields`, each `number`/`null` or, for
/// the names in `strings`, a string.
fn schema(title: &str, fields: &[&str], strings: &[&str]) -> String {
    let mut text = format!(
        "{{\"$schema\":\"https://json-schema.org/draft/2020-12/schema\",\"title\":\"{title}\",\"type\":\"object\",\"properties\":{{"
    );
    for (i, field) in fields.iter().enumerate() {
        let kind = if strings.contains(field) {
            "\"string\""
        } else {
            "[\"number\",\"null\"]"
        };
        let _ = write!(
            text,
            "{}\"{field}\":{{\"type\":{kind}}}",
            if i > 0 { "," } else { "" }
        );
    }
    text.push_str("}}");
    text
}

/// Nanoseconds of `seconds` (0 for a negative or non-finite time).
fn nanos(seconds: f64) -> u64 {
    if seconds.is_finite() && seconds > 0.0 {
        (seconds * 1e9).round() as u64
    } else {
        0
    }
}

/// Appends `"key":value` (`null` for `None`) to `text`.
fn field(text: &mut String, key: &str, value: Option<f64>) {
    if !text.ends_with('{') {
        text.push(',');
    }
    match value {
        Some(v) if v.is_finite() => {
            let _ = write!(text, "\"{key}\":{v}");
        }
        _ => {
            let _ = write!(text, "\"{key}\":null");
        }
    }
}

/// A JSON string literal of `text`.
fn string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// An [`Observer`] writing the session to an MCAP file as it runs; the
/// first error is kept and the session goes on ([`McapLog::finish`]
/// reports it).
pub struct McapLog<W: Write + Seek> {
    writer: mcap::Writer<W>,
    frame: Option<(u16, Vec<String>)>,
    step: u16,
    event: u16,
    topics: BTreeMap<String, u16>,
    sequence: u32,
    steps: u64,
    extra: Vec<Option<f64>>,
    text: String,
    error: Option<String>,
}

impl<W: Write + Seek> McapLog<W> {
    /// A log written to `out` (buffer it).
    ///
    /// # Errors
    /// The MCAP writer's, in words.
    pub fn new(out: W) -> Result<Self, String> {
        let options = mcap::WriteOptions::new()
            .profile("")
            .library(concat!("limb-session ", env!("CARGO_PKG_VERSION")))
            .compression(None);
        let mut writer = options.create(out).map_err(|e| e.to_string())?;
        let channel = |writer: &mut mcap::Writer<W>,
                       topic: &str,
                       title: &str,
                       fields: &[&str],
                       strings: &[&str]| {
            let id = writer
                .add_schema(
                    title,
                    "jsonschema",
                    schema(title, fields, strings).as_bytes(),
                )
                .map_err(|e| e.to_string())?;
            writer
                .add_channel(id, topic, "json", &BTreeMap::new())
                .map_err(|e| e.to_string())
        };
        let step = channel(
            &mut writer,
            STEP_TOPIC,
            "limb.Step",
            &STEP_COLUMNS,
            &["state", "mode"],
        )?;
        let event = channel(
            &mut writer,
            EVENT_TOPIC,
            "limb.Event",
            &["time", "text"],
            &["text"],
        )?;
        Ok(Self {
            writer,
            frame: None,
            step,
            event,
            topics: BTreeMap::new(),
            sequence: 0,
            steps: 0,
            extra: Vec::new(),
            text: String::new(),
            error: None,
        })
    }

    fn write(&mut self, channel_id: u16, log_time: f64, publish_time: f64, data: &str) {
        if self.error.is_some() {
            return;
        }
        self.sequence = self.sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: nanos(log_time),
            publish_time: nanos(publish_time),
        };
        if let Err(error) = self.writer.write_to_known_channel(&header, data.as_bytes()) {
            self.error = Some(error.to_string());
        }
    }

    /// Writes `json` (one JSON object) on `topic` at kernel time `time`
    /// [s]; the topic's schema is `schema_name` with `schema` (a JSON
    /// Schema), registered on first use.
    pub fn record(&mut self, topic: &str, schema_name: &str, schema: &str, time: f64, json: &str) {
        let id = match self.topics.get(topic) {
            Some(&id) => id,
            None => {
                let id = self
                    .writer
                    .add_schema(schema_name, "jsonschema", schema.as_bytes())
                    .and_then(|schema| {
                        self.writer
                            .add_channel(schema, topic, "json", &BTreeMap::new())
                    });
                match id {
                    Ok(id) => {
                        self.topics.insert(topic.to_string(), id);
                        id
                    }
                    Err(error) => {
                        self.error.get_or_insert(error.to_string());
                        return;
                    }
                }
            }
        };
        self.write(id, time, time, json);
    }

    /// Ends the file (summary, indexes) and returns its writer.
    ///
    /// # Errors
    /// The first error of the session, or the finish's, in words.
    pub fn finish(mut self) -> Result<W, String> {
        if let Some(error) = self.error.take() {
            return Err(error);
        }
        self.writer.finish().map_err(|e| e.to_string())?;
        Ok(self.writer.into_inner())
    }
}

impl<R: Logged + ?Sized, W: Write + Seek> Observer<R> for McapLog<W> {
    fn after_step(&mut self, robot: &R, frame: &Frame, _: StateKind, command: &Command) {
        if self.frame.is_none() {
            let columns: Vec<String> = COLUMNS
                .iter()
                .copied()
                .chain(robot.columns())
                .map(String::from)
                .collect();
            let names: Vec<&str> = columns.iter().map(String::as_str).collect();
            let metadata = BTreeMap::from([("columns".to_string(), names.join(","))]);
            let id = self
                .writer
                .add_schema(
                    "limb.Frame",
                    "jsonschema",
                    schema("limb.Frame", &names, &[]).as_bytes(),
                )
                .and_then(|schema| {
                    self.writer
                        .add_channel(schema, FRAME_TOPIC, "json", &metadata)
                });
            match id {
                Ok(id) => self.frame = Some((id, columns)),
                Err(error) => {
                    self.error.get_or_insert(error.to_string());
                    return;
                }
            }
        }
        self.extra.clear();
        robot.values(&mut self.extra);
        let Some((id, columns)) = &self.frame else {
            return;
        };
        let id = *id;
        let mut text = std::mem::take(&mut self.text);
        text.clear();
        text.push('{');
        let row = Row::of(frame, command, &self.extra);
        for (name, value) in columns.iter().zip(row.values()) {
            field(&mut text, name, value);
        }
        text.push('}');
        self.write(id, frame.sample.time, frame.sample.time, &text);
        self.text = text;
    }

    fn stepped(&mut self, step: &Step<'_>) {
        let command = step.command;
        let set_point = command.set_point.map(|s| [s.pose.x, s.pose.z, s.pose.psi]);
        let mut text = std::mem::take(&mut self.text);
        text.clear();
        let _ = write!(text, "{{\"step\":{}", self.steps);
        self.steps += 1;
        field(&mut text, "now", Some(step.now));
        field(&mut text, "t", Some(step.sample.time));
        field(&mut text, "stale", Some(f64::from(u8::from(step.stale))));
        let _ = write!(
            text,
            ",\"state\":\"{}\",\"mode\":\"{}\"",
            command.state, command.mode
        );
        for (i, name) in ["xd", "zd", "psid"].iter().enumerate() {
            field(&mut text, name, set_point.map(|p| p[i]));
        }
        field(&mut text, "fx_cmd", Some(command.wrench.fx));
        field(&mut text, "fz_cmd", Some(command.wrench.fz));
        field(&mut text, "ty_cmd", Some(command.wrench.ty));
        field(
            &mut text,
            "saturated",
            Some(f64::from(u8::from(command.saturation.any()))),
        );
        text.push('}');
        self.write(self.step, step.now, step.sample.time, &text);
        self.text = text;
    }

    fn event(&mut self, event: &TraceEvent) {
        let mut text = String::from("{");
        field(&mut text, "time", Some(event.time));
        let _ = write!(
            text,
            ",\"text\":{}}}",
            string(&crate::operator::describe(event))
        );
        self.write(self.event, event.time, event.time, &text);
    }
}

/// The frame log of the MCAP file `bytes` as CSV text, as
/// [`crate::log::SessionLog`] wrote it for the same session.
///
/// # Errors
/// The file is not MCAP, has no frame channel, or a frame message is not a
/// JSON object of numbers and nulls; in words.
pub fn frames_as_csv(bytes: &[u8]) -> Result<String, String> {
    let mut text = String::new();
    let mut columns: Option<Vec<String>> = None;
    let stream = mcap::MessageStream::new(bytes).map_err(|e| format!("not an MCAP file: {e}"))?;
    for (index, message) in stream.enumerate() {
        let message = message.map_err(|e| match index {
            0 => format!("not an MCAP file: {e}"),
            _ => format!("MCAP record after message {index}: {e}"),
        })?;
        if message.channel.topic != FRAME_TOPIC {
            continue;
        }
        if columns.is_none() {
            let names = message
                .channel
                .metadata
                .get("columns")
                .ok_or_else(|| format!("{FRAME_TOPIC} has no `columns` metadata"))?;
            text.push_str(names);
            text.push('\n');
            columns = Some(names.split(',').map(String::from).collect());
        }
        let Some(names) = &columns else { continue };
        let value: serde_json::Value = serde_json::from_slice(&message.data)
            .map_err(|e| format!("{FRAME_TOPIC} message {}: {e}", message.sequence))?;
        for (i, name) in names.iter().enumerate() {
            if i > 0 {
                text.push(',');
            }
            match &value[name.as_str()] {
                serde_json::Value::Null => {}
                serde_json::Value::Number(n) => {
                    let v = n
                        .as_f64()
                        .ok_or_else(|| format!("{FRAME_TOPIC}: `{name}` is not a number"))?;
                    let _ = write!(text, "{v}");
                }
                _ => return Err(format!("{FRAME_TOPIC}: `{name}` is not a number")),
            }
        }
        text.push('\n');
    }
    if columns.is_none() {
        return Err(format!("no {FRAME_TOPIC} message"));
    }
    Ok(text)
}
