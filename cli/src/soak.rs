//! `limb soak kuka|zenoh`: long runs that count what was lost.
//!
//! A soak is a sequence of whole sessions (Grasp → estimation → Validated →
//! manipulation) on the reference arm, each with a seeded random
//! disturbance (an FRI fault, an emergency stop) or none, over real
//! sockets on loopback, for a wall-clock time. Every message is either
//! answered or counted as missed, every disturbance must end in its named
//! stop, and every kernel step must have its row in the step log (every
//! fresh one its row in the frame log). The
//! output is one JSON object of counts; `--report FILE` also writes the
//! figures into that Markdown file (`benchmarks/soak.md`), replacing the
//! adapter's section.
//!
//! Modules: [`kuka`] (the FRI client against the simulated controller),
//! [`zenoh`] (a node supervised over Zenoh); here: the arguments, the
//! session log row count, the memory samples and the report.

mod kuka;
mod report;
mod zenoh;

use crate::error::{print_json, CliError};
use clap::{Args, Subcommand};
use limb_kernel::trace::{Cause, Event, TraceEvent};
use limb_kernel::{Request, StateKind, StopCategory, StopReason};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// `limb soak` arguments.
#[derive(Args)]
pub struct SoakArgs {
    #[command(subcommand)]
    adapter: Adapter,
}

#[derive(Subcommand)]
enum Adapter {
    /// The KUKA FRI client (kernel inside, `limb kuka run`'s session)
    /// against the simulated controller at 1 kHz over loopback UDP, with
    /// seeded random FRI faults.
    Kuka {
        #[command(flatten)]
        common: Common,
        /// FRI version: 1.11, 1.14, 1.15, 1.16, 2.5 or 2.7.
        #[arg(long = "fri-version", default_value = "2.7")]
        fri_version: String,
        /// Do not pace the controller: each cycle as soon as the reply is
        /// in, on the robot's clock (outcomes independent of the machine's
        /// load; the clock-stall and clock-repeat faults are left out).
        #[arg(long)]
        unpaced: bool,
        /// Cut each session after this many controller cycles, faults
        /// starting within them (a session with a fault runs on until the
        /// fault is judged): CI's short run on a debug build.
        #[arg(long)]
        session_cycles: Option<u64>,
        /// Run only session K of the seed's sequence (0-based, as the
        /// losses name them; unpaced only, where a session does not
        /// depend on the time left): a reported loss rerun alone.
        #[arg(long, value_name = "K", requires = "unpaced")]
        session: Option<u64>,
        /// With `--session`: also write that session's log to this CSV
        /// file (plant.md columns, as `limb kuka run --log`).
        #[arg(long, value_name = "FILE.csv", requires = "session")]
        session_log: Option<PathBuf>,
    },
    /// A node on the reference plant (`limb zenoh node`) at 1 kHz
    /// telemetry, supervised over Zenoh on loopback, with seeded random
    /// emergency stops.
    Zenoh {
        #[command(flatten)]
        common: Common,
    },
}

/// What every soak takes.
#[derive(Args)]
struct Common {
    /// Wall-clock time of the soak [s] (the last session is cut there).
    #[arg(long, default_value_t = 600.0)]
    seconds: f64,
    /// Seed of the disturbances, their times and the measurement noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the figures into this Markdown file, replacing the adapter's
    /// section (e.g. benchmarks/soak.md).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Accepted for symmetry with the other commands: the output is JSON.
    #[arg(long)]
    json: bool,
}

/// Session details kept for the report (the first ones).
const DETAILS: usize = 40;
/// Losses kept in words (all are counted).
const LOSSES: usize = 40;

/// What a soak keeps across its sessions, bounded: the soak's own memory
/// must not grow with the number of sessions, so that its peak memory is
/// the adapters'.
#[derive(Default)]
struct Ledger {
    sessions: u64,
    /// Sums of the numeric fields of the sessions' records.
    sums: BTreeMap<String, u64>,
    /// The first [`DETAILS`] sessions' records.
    details: Vec<Value>,
    /// The first [`LOSSES`] losses.
    losses: Vec<String>,
    lost: u64,
}

impl Ledger {
    /// Adds one session's `record` (its numbers summed, the record kept
    /// while there is room).
    fn add(&mut self, record: Value) {
        self.sessions += 1;
        if let Value::Object(fields) = &record {
            for (name, value) in fields {
                if let Some(number) = value.as_u64() {
                    *self.sums.entry(name.clone()).or_default() += number;
                }
            }
        }
        if self.details.len() < DETAILS {
            self.details.push(record);
        }
    }

    /// Counts a loss, kept in words while there is room.
    fn lose(&mut self, what: String) {
        self.lost += 1;
        if self.losses.len() < LOSSES {
            self.losses.push(what);
        }
    }

    /// The soak's verdict and figures: `figures` with the sums, the
    /// details and `memory` added.
    fn finish(self, adapter: &'static str, mut figures: Value, memory: &MemoryWatch) -> Soak {
        figures["sessions"] = json!(self.sessions);
        figures["totals"] = json!(self.sums);
        figures["memory"] = memory.json();
        figures["losses_counted"] = json!(self.lost);
        figures["sessions_detail"] = json!(self.details);
        Soak {
            adapter,
            figures,
            losses: self.losses,
        }
    }
}

/// The verdict and figures of one soak, before they are printed.
pub struct Soak {
    /// `kuka` or `zenoh`.
    adapter: &'static str,
    /// The counts (printed as JSON, rendered in the report).
    figures: Value,
    /// What was lost or wrong, in words (empty: nothing).
    losses: Vec<String>,
}

/// Runs `limb soak ...`: prints the JSON counts, writes the report, exits
/// 1 when something was lost.
pub fn run(args: SoakArgs) -> Result<(), CliError> {
    let common = match &args.adapter {
        Adapter::Kuka { common, .. } | Adapter::Zenoh { common } => common,
    };
    let budget = common.budget()?;
    let (soak, flags) = match &args.adapter {
        Adapter::Kuka {
            fri_version,
            unpaced,
            session_cycles,
            session,
            session_log,
            ..
        } => {
            let options = kuka::Options {
                version: fri_version
                    .parse()
                    .map_err(|error| CliError::BadInput(format!("--fri-version: {error}")))?,
                unpaced: *unpaced,
                session_cycles: *session_cycles,
                only: *session,
                only_log: session_log.clone(),
            };
            let soak = kuka::soak(&budget, common.seed, &options)?;
            let unpaced = if *unpaced { " --unpaced" } else { "" };
            let cut = session_cycles.map_or(String::new(), |n| format!(" --session-cycles {n}"));
            let only = session.map_or(String::new(), |k| format!(" --session {k}"));
            (
                soak,
                format!(" --fri-version {fri_version}{unpaced}{cut}{only}"),
            )
        }
        Adapter::Zenoh { .. } => (zenoh::soak(&budget, common.seed)?, String::new()),
    };
    let _ = common.json;
    let command = format!(
        "limb soak {} --seconds {} --seed {}{flags}",
        soak.adapter, common.seconds, common.seed
    );
    // The unpaced KUKA soak has its own section of the report.
    let section = match &args.adapter {
        Adapter::Kuka { unpaced: true, .. } => "kuka-unpaced",
        _ => soak.adapter,
    };
    let output = json!({
        "adapter": soak.adapter,
        "section": section,
        "command": command,
        "seed": common.seed,
        "seconds": common.seconds,
        "machine": machine(&budget),
        "figures": soak.figures,
        "losses": soak.losses,
        "nothing_lost": soak.losses.is_empty(),
    });
    if let Some(path) = &common.report {
        report::write(path, &output)?;
    }
    print_json(&output)?;
    if soak.losses.is_empty() {
        Ok(())
    } else {
        Err(CliError::Internal(format!(
            "soak {}: {}",
            soak.adapter,
            soak.losses.join("; ")
        )))
    }
}

impl Common {
    fn budget(&self) -> Result<Budget, CliError> {
        let length = Duration::try_from_secs_f64(self.seconds)
            .ok()
            .filter(|d| !d.is_zero())
            .ok_or_else(|| CliError::BadInput("--seconds must be a positive number".into()))?;
        Ok(Budget {
            start: Instant::now(),
            length,
            load: load_average(),
        })
    }
}

/// The soak's wall-clock time.
#[derive(Clone)]
struct Budget {
    start: Instant,
    length: Duration,
    /// The load average when it started (`/proc/loadavg`: 1, 5, 15 min).
    load: String,
}

impl Budget {
    fn left(&self) -> Duration {
        self.length.saturating_sub(self.start.elapsed())
    }

    fn spent(&self) -> bool {
        self.left().is_zero()
    }

    /// True once half the time has passed.
    fn past_half(&self) -> bool {
        self.start.elapsed() >= self.length / 2
    }
}

/// A writer that counts the lines written: the session log's rows (minus
/// its header line), without the disk unless a copy is asked for (`limb
/// soak kuka --session K --session-log FILE`).
#[derive(Debug, Default)]
struct LineCount {
    lines: u64,
    copy: Option<io::BufWriter<std::fs::File>>,
}

impl LineCount {
    /// Counts and also writes every byte to a new file at `path`.
    fn copying_to(path: &std::path::Path) -> Result<Self, CliError> {
        let file = std::fs::File::create(path).map_err(|error| {
            CliError::BadInput(format!("--session-log {}: {error}", path.display()))
        })?;
        Ok(Self {
            lines: 0,
            copy: Some(io::BufWriter::new(file)),
        })
    }
}

impl Write for LineCount {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        if let Some(copy) = &mut self.copy {
            copy.write_all(bytes)?;
        }
        self.lines += bytes.iter().filter(|b| **b == b'\n').count() as u64;
        Ok(bytes.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        self.copy.as_mut().map_or(Ok(()), Write::flush)
    }
}

/// The session logs of a soak's session, counted (and copied to files
/// for `--session-log`).
type CountedLog = (
    limb_session::log::SessionLog<LineCount>,
    limb_session::log::StepLog<LineCount>,
);

/// Counting logs; with `copy`, also written to that frame log file and
/// its step log beside it.
fn counted_log(copy: Option<&std::path::Path>) -> Result<CountedLog, CliError> {
    let (frames, steps) = match copy {
        Some(path) => (
            LineCount::copying_to(path)?,
            LineCount::copying_to(&crate::session_log::steps_path(path))?,
        ),
        None => (LineCount::default(), LineCount::default()),
    };
    Ok((
        limb_session::log::SessionLog::new(frames),
        limb_session::log::StepLog::new(steps),
    ))
}

/// Rows of a finished session's logs (their lines less the header).
#[derive(Clone, Copy, Debug, Default)]
struct LogRows {
    /// Frame log rows: one per frame stepped on.
    frames: u64,
    /// Step log rows: one per kernel step.
    steps: u64,
}

impl LogRows {
    /// The rows of `log`, flushed.
    fn of(log: CountedLog) -> Result<Self, CliError> {
        let lines = |count: io::Result<LineCount>| {
            let mut count =
                count.map_err(|error| CliError::Internal(format!("session log: {error}")))?;
            count
                .flush()
                .map_err(|error| CliError::Internal(format!("session log copy: {error}")))?;
            Ok::<_, CliError>(count.lines.saturating_sub(1))
        };
        Ok(Self {
            frames: lines(log.0.finish())?,
            steps: lines(log.1.finish())?,
        })
    }

    /// What is missing against the session's kernel steps, in words:
    /// every step has its step-log row, every step on a new frame its
    /// frame-log row.
    fn missing(&self, steps: u64, stale_steps: u64) -> Option<String> {
        (self.steps != steps || self.frames + stale_steps != steps).then(|| {
            format!(
                "{} step-log rows and {} frame-log rows + {stale_steps} stale steps for {steps} kernel steps",
                self.steps, self.frames
            )
        })
    }
}

/// The words of a stop's cause in the kernel's vocabulary: a monitor
/// limit (`stale_sensor`), `request stop`, or the stop reason.
fn stop_name(cause: &Cause) -> String {
    match cause {
        Cause::Stop(StopReason::Monitor(violation)) => violation.limit.name().into(),
        Cause::Request(Request::Stop) => "request stop".into(),
        Cause::Stop(reason) => reason.to_string(),
        other => other.to_string(),
    }
}

/// The cause of the first transition into SafeStop among `events`, in
/// words, and its stop category.
fn first_stop(events: &[TraceEvent]) -> Option<(String, Option<StopCategory>)> {
    events.iter().find_map(|event| match &event.event {
        Event::Transition {
            to: StateKind::SafeStop,
            cause,
            ..
        } => Some((stop_name(cause), cause.stop_category())),
        _ => None,
    })
}

/// Peak (VmHWM) and current (VmRSS) resident memory of this process [kB].
#[derive(Clone, Copy, Debug, Default)]
struct Memory {
    peak_kb: u64,
    resident_kb: u64,
}

impl Memory {
    /// Read from `/proc/self/status` (zeros where it cannot be read).
    fn now() -> Self {
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        let field = |name: &str| {
            status
                .lines()
                .find_map(|line| line.strip_prefix(name))
                .and_then(|rest| rest.trim().trim_end_matches("kB").trim().parse().ok())
                .unwrap_or(0)
        };
        Self {
            peak_kb: field("VmHWM:"),
            resident_kb: field("VmRSS:"),
        }
    }
}

/// Memory after the first session, at half time and at the end.
#[derive(Default)]
struct MemoryWatch {
    start: Option<Memory>,
    middle: Option<Memory>,
    end: Memory,
}

impl MemoryWatch {
    /// Samples after a session.
    fn after_session(&mut self, budget: &Budget) {
        let now = Memory::now();
        if self.start.is_none() {
            self.start = Some(now);
        } else if self.middle.is_none() && budget.past_half() {
            self.middle = Some(now);
        }
        self.end = now;
    }

    /// Growth of the peak from the middle to the end [kB], where both
    /// were taken.
    fn growth_kb(&self) -> Option<i64> {
        let middle = self.middle.or(self.start)?;
        Some(self.end.peak_kb as i64 - middle.peak_kb as i64)
    }

    fn json(&self) -> Value {
        let sample = |m: Option<Memory>| {
            m.map(|m| json!({ "vm_hwm_kb": m.peak_kb, "vm_rss_kb": m.resident_kb }))
        };
        json!({
            "start": sample(self.start),
            "middle": sample(self.middle),
            "end": sample(Some(self.end)),
            "peak_growth_middle_to_end_kb": self.growth_kb(),
        })
    }
}

/// The 1, 5 and 15 min load averages, in words.
fn load_average() -> String {
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    load.split_whitespace()
        .take(3)
        .collect::<Vec<_>>()
        .join(" ")
}

/// The machine and its load, for the report.
fn machine(budget: &Budget) -> Value {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo
        .lines()
        .find_map(|line| line.strip_prefix("model name"))
        .map(|rest| rest.trim_start_matches([' ', '\t', ':']).to_string());
    let cores = std::thread::available_parallelism().map_or(0, std::num::NonZero::get);
    json!({
        "cpu": model,
        "cores": cores,
        "load_average_at_start": budget.load,
        "load_average_at_end": load_average(),
        "build": if cfg!(debug_assertions) { "debug" } else { "release" },
    })
}
