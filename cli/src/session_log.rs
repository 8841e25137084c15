//! What every robot command (`limb run`, `limb kuka run`, `limb arebo run
//! --kernel`, `limb zenoh node`) keeps of its `limb-session` session: the
//! session log file (`--log`) and the kernel's events for the JSON output.

use crate::error::CliError;
use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, StateKind};
use limb_session::kernel_wire::KernelEvent;
use limb_session::log::{Logged, SessionLog, StepLog};
use limb_session::mcap_log::McapLog;
use limb_session::operator::describe;
use limb_session::Observer;
use limb_session::{Frame, Step};
use serde_json::{json, Value};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// An open session log: the frame log (plant.md) and its step log as CSV,
/// or both with the kernel's events, configuration and model as MCAP
/// (`limb_session::mcap_log`), chosen by the file's extension (`.mcap`).
pub enum Log {
    /// `FILE.csv` and `FILE.steps.csv`.
    Csv(SessionLog<BufWriter<File>>, StepLog<BufWriter<File>>),
    /// `FILE.mcap`.
    Mcap(Box<McapLog<BufWriter<File>>>),
}

impl<R: Logged + ?Sized> Observer<R> for Log {
    fn after_step(&mut self, robot: &R, frame: &Frame, state: StateKind, command: &Command) {
        match self {
            Log::Csv(frames, _) => frames.after_step(robot, frame, state, command),
            Log::Mcap(log) => log.after_step(robot, frame, state, command),
        }
    }

    fn event(&mut self, event: &TraceEvent) {
        if let Log::Mcap(log) = self {
            Observer::<R>::event(log.as_mut(), event);
        }
    }

    fn stepped(&mut self, step: &Step<'_>) {
        match self {
            Log::Csv(_, steps) => Observer::<R>::stepped(steps, step),
            Log::Mcap(log) => Observer::<R>::stepped(log.as_mut(), step),
        }
    }
}

/// A JSON Schema that admits any object (the configuration's and the
/// model's fields are the kernel's serde names).
const ANY_OBJECT: &str =
    r#"{"$schema":"https://json-schema.org/draft/2020-12/schema","type":"object"}"#;

impl Log {
    /// Records `value` on `topic` at kernel time `time` [s] (MCAP only: the
    /// CSV logs hold frames and steps alone).
    pub fn record(&mut self, topic: &str, schema: &str, time: f64, value: &impl serde::Serialize) {
        if let Log::Mcap(log) = self {
            if let Ok(json) = serde_json::to_string(value) {
                log.record(topic, schema, ANY_OBJECT, time, &json);
            }
        }
    }
}

/// The log at `path`, when one is asked for.
pub struct LogFile;

impl LogFile {
    /// Creates the log at `path`: MCAP for `.mcap`, else the frame log
    /// and the step log beside it ([`steps_path`]); none without a path.
    ///
    /// # Errors
    /// [`CliError::BadInput`] when a file cannot be created.
    pub fn create(path: Option<&Path>) -> Result<Option<Log>, CliError> {
        path.map(|path| {
            let open = |path: &Path| {
                File::create(path)
                    .map(BufWriter::new)
                    .map_err(|error| cannot_write(path, &error))
            };
            if is_mcap(path) {
                let log = McapLog::new(open(path)?)
                    .map_err(|error| CliError::BadInput(format!("{}: {error}", path.display())))?;
                return Ok(Log::Mcap(Box::new(log)));
            }
            Ok(Log::Csv(
                SessionLog::new(open(path)?),
                StepLog::new(open(&steps_path(path))?),
            ))
        })
        .transpose()
    }

    /// Flushes `log` (written to `path`).
    ///
    /// # Errors
    /// [`CliError::BadInput`] when a row could not be written.
    pub fn finish(log: Option<Log>, path: Option<&Path>) -> Result<(), CliError> {
        match (log, path) {
            (Some(Log::Csv(frames, steps)), Some(path)) => {
                frames
                    .finish()
                    .map_err(|error| cannot_write(path, &error))?;
                let steps_path = steps_path(path);
                steps
                    .finish()
                    .map(drop)
                    .map_err(|error| cannot_write(&steps_path, &error))
            }
            (Some(Log::Mcap(log)), Some(path)) => log
                .finish()
                .and_then(|mut out| out.flush().map_err(|e| e.to_string()))
                .map_err(|error| {
                    CliError::BadInput(format!("{}: cannot write the log: {error}", path.display()))
                }),
            _ => Ok(()),
        }
    }
}

/// True for a `.mcap` path.
fn is_mcap(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

/// The records of the session log at `path`: CSV (plant.md) or the frame
/// channel of an MCAP session log, read by the same parser.
///
/// # Errors
/// [`CliError::BadInput`] naming the file (and line) of the first fault.
pub fn read_records(path: &Path) -> Result<Vec<limb_sim::log::Record>, CliError> {
    if !is_mcap(path) {
        return limb_sim::log::read(path).map_err(|error| CliError::BadInput(error.to_string()));
    }
    let name = path.display();
    let bytes =
        std::fs::read(path).map_err(|error| CliError::BadInput(format!("{name}: {error}")))?;
    let text = limb_session::mcap_log::frames_as_csv(&bytes)
        .map_err(|error| CliError::BadInput(format!("{name}: {error}")))?;
    limb_sim::log::parse(&text).map_err(|(line, message)| {
        CliError::BadInput(format!(
            "{name}: frame {}: {message}",
            line.saturating_sub(1)
        ))
    })
}

/// The step log beside the frame log `path`: `FILE.csv` → `FILE.steps.csv`.
pub fn steps_path(path: &Path) -> PathBuf {
    let stem = match path.extension() {
        Some(extension) if extension == "csv" => path.with_extension(""),
        _ => path.to_path_buf(),
    };
    let mut name = stem.into_os_string();
    name.push(".steps.csv");
    PathBuf::from(name)
}

fn cannot_write(path: &Path, error: &std::io::Error) -> CliError {
    CliError::BadInput(format!("{}: cannot write the log: {error}", path.display()))
}

/// The kernel's events of a session, in order.
#[derive(Default)]
pub struct EventRecord(pub Vec<TraceEvent>);

impl<R: ?Sized> Observer<R> for EventRecord {
    fn event(&mut self, event: &TraceEvent) {
        self.0.push(*event);
    }
}

impl EventRecord {
    /// The events as JSON: time, words and the event as data (as
    /// `limb run --json`).
    pub fn json(&self) -> Value {
        self.0
            .iter()
            .map(|event| {
                json!({
                    "time": event.time,
                    "what": describe(event),
                    "event": KernelEvent::from(*event),
                })
            })
            .collect()
    }
}
