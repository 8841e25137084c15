//! The session logs: every frame the kernel stepped on as one CSV row in
//! the format of `plant.md`, which `limb estimate` and `limb diagnose`
//! read ([`SessionLog`]), and every kernel step as one row of the step log
//! ([`StepLog`]), silences included.
//!
//! # Frame log format
//! The columns [`COLUMNS`] — `t,xd,zd,psid,x,y,z,psi,fx,fz,ty`: the
//! robot's stamp, the commanded set-point pose x_d, the measured grasp
//! pose (y when the robot measures it) and the external wrench, frame S,
//! SI units — then the robot's own columns ([`Logged`]; the reference
//! plant adds its ground truth `q1,q2,elbow_x,elbow_z,shoulder_x,
//! shoulder_z`). An absent value is empty. Every number is printed in
//! Rust's shortest round-trip `f64` form: reading it back gives the same
//! bits. One row per frame the kernel stepped on, written as the session
//! runs (a crash loses at most the buffered rows).
//!
//! # Step log format
//! A step on no new frame (the robot was silent, or its stamps jumped
//! past the kernel's `max_sensor_age`: the kernel steps on the last frame
//! at the new time and its watchdog judges) has no row of its own in the
//! frame log: its `t` would repeat the previous row's, which `plant.md`
//! readers refuse. The step log has one row per kernel step, in order,
//! with the columns [`STEP_COLUMNS`]: `step` (0, 1, …), `now` (kernel time
//! [s]), `t` (the stamp of the frame stepped on), `stale` (1 on the last
//! frame again, else 0), `state` and `mode` (of the command: `Grasp` …
//! `SafeStop`, `Track`/`Hold`/`Stop`), the commanded set-point `xd,zd,psid`
//! (empty without one), the commanded wrench `fx_cmd,fz_cmd,ty_cmd` [N,
//! N, N m] and `saturated` (1 when a saturation acted). Its rows with
//! `stale` 0 are the frame log's rows, one for one; a watchdog stop during
//! a silence is the step log's row with `stale` 1 and `state` SafeStop.

use crate::robot::Frame;
use crate::run::{Observer, Step};
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Command, StateKind};
use std::fmt::Write as _;
use std::io::{self, Write};

/// The columns every session log has, in order.
pub const COLUMNS: [&str; 11] = [
    "t", "xd", "zd", "psid", "x", "y", "z", "psi", "fx", "fz", "ty",
];

/// A robot's own columns of the session log, after [`COLUMNS`].
pub trait Logged {
    /// Their names.
    fn columns(&self) -> Vec<&str> {
        Vec::new()
    }
    /// Their values for the frame just stepped, one per column (`None`:
    /// empty), appended to `out`.
    fn values(&self, _out: &mut Vec<Option<f64>>) {}
}

/// One row of a log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row<'a> {
    /// Robot stamp [s].
    pub time: f64,
    /// Commanded set-point pose, when there was one.
    pub command: Option<Pose>,
    /// Measured grasp pose.
    pub pose: Pose,
    /// Measured lateral y [m], when measured.
    pub lateral: Option<f64>,
    /// Measured external wrench.
    pub wrench: Wrench,
    /// The robot's own columns.
    pub extra: &'a [Option<f64>],
}

impl<'a> Row<'a> {
    /// The row of `frame`, stepped on with `command`; `extra` are the
    /// robot's own columns.
    pub fn of(frame: &Frame, command: &Command, extra: &'a [Option<f64>]) -> Self {
        let sample = &frame.sample;
        Row {
            time: sample.time,
            command: command.set_point.map(|s| s.pose),
            pose: sample.pose,
            lateral: frame.lateral,
            wrench: sample.wrench,
            extra,
        }
    }

    /// The row's values, one per column ([`COLUMNS`], then the robot's
    /// own); `None` is empty.
    pub fn values(&self) -> impl Iterator<Item = Option<f64>> + '_ {
        let command = self.command.map(|p| [p.x, p.z, p.psi]);
        let base = [
            Some(self.time),
            command.map(|c| c[0]),
            command.map(|c| c[1]),
            command.map(|c| c[2]),
            Some(self.pose.x),
            self.lateral,
            Some(self.pose.z),
            Some(self.pose.psi),
            Some(self.wrench.fx),
            Some(self.wrench.fz),
            Some(self.wrench.ty),
        ];
        base.into_iter().chain(self.extra.iter().copied())
    }

    /// Appends the row and its line end to `text`.
    pub fn write(&self, text: &mut String) {
        for (i, field) in self.values().enumerate() {
            if i > 0 {
                text.push(',');
            }
            if let Some(value) = field {
                // Writing into a String cannot fail.
                let _ = write!(text, "{value}");
            }
        }
        text.push('\n');
    }
}

/// The header line for a robot's own `columns`.
pub fn header(columns: &[&str]) -> String {
    let mut text = COLUMNS.join(",");
    for column in columns {
        text.push(',');
        text.push_str(column);
    }
    text.push('\n');
    text
}

/// Rows of CSV written to `W` as the session runs, the first write error
/// kept (the session goes on; [`CsvOut::finish`] reports it).
#[derive(Debug)]
struct CsvOut<W: Write> {
    out: W,
    line: String,
    started: bool,
    error: Option<io::Error>,
}

impl<W: Write> CsvOut<W> {
    fn new(out: W) -> Self {
        Self {
            out,
            line: String::new(),
            started: false,
            error: None,
        }
    }

    /// Writes one row that `fill` appends to the line, the `header` line
    /// first when this is the first row.
    fn row(&mut self, header: impl FnOnce() -> String, fill: impl FnOnce(&mut String)) {
        if self.error.is_some() {
            return;
        }
        self.line.clear();
        if !self.started {
            self.started = true;
            self.line.push_str(&header());
        }
        fill(&mut self.line);
        if let Err(error) = self.out.write_all(self.line.as_bytes()) {
            self.error = Some(error);
        }
    }

    fn finish(mut self) -> io::Result<W> {
        if let Some(error) = self.error.take() {
            return Err(error);
        }
        self.out.flush()?;
        Ok(self.out)
    }
}

/// An [`Observer`] writing the frame log to `W` as the session runs.
#[derive(Debug)]
pub struct SessionLog<W: Write> {
    csv: CsvOut<W>,
    extra: Vec<Option<f64>>,
}

impl<W: Write> SessionLog<W> {
    /// A log written to `out` (buffer it: one write per row).
    pub fn new(out: W) -> Self {
        Self {
            csv: CsvOut::new(out),
            extra: Vec::new(),
        }
    }

    /// Flushes the log and returns its writer.
    ///
    /// # Errors
    /// The first write error of the session, or the flush's.
    pub fn finish(self) -> io::Result<W> {
        self.csv.finish()
    }
}

impl<R: Logged + ?Sized, W: Write> Observer<R> for SessionLog<W> {
    fn after_step(&mut self, robot: &R, frame: &Frame, _: StateKind, command: &Command) {
        self.extra.clear();
        robot.values(&mut self.extra);
        let row = Row::of(frame, command, &self.extra);
        self.csv
            .row(|| header(&robot.columns()), |line| row.write(line));
    }
}

/// The step log's columns, in order.
pub const STEP_COLUMNS: [&str; 13] = [
    "step",
    "now",
    "t",
    "stale",
    "state",
    "mode",
    "xd",
    "zd",
    "psid",
    "fx_cmd",
    "fz_cmd",
    "ty_cmd",
    "saturated",
];

/// An [`Observer`] writing the step log (one row per kernel step) to `W`
/// as the session runs.
#[derive(Debug)]
pub struct StepLog<W: Write> {
    csv: CsvOut<W>,
    steps: u64,
}

impl<W: Write> StepLog<W> {
    /// A step log written to `out` (buffer it: one write per row).
    pub fn new(out: W) -> Self {
        Self {
            csv: CsvOut::new(out),
            steps: 0,
        }
    }

    /// Flushes the log and returns its writer.
    ///
    /// # Errors
    /// The first write error of the session, or the flush's.
    pub fn finish(self) -> io::Result<W> {
        self.csv.finish()
    }
}

impl<R: ?Sized, W: Write> Observer<R> for StepLog<W> {
    fn stepped(&mut self, step: &Step<'_>) {
        let index = self.steps;
        self.steps += 1;
        let command = step.command;
        let set_point = command.set_point.map(|s| [s.pose.x, s.pose.z, s.pose.psi]);
        let numbers = [
            Some(step.now),
            Some(step.sample.time),
            Some(f64::from(u8::from(step.stale))),
        ];
        let wrench = [command.wrench.fx, command.wrench.fz, command.wrench.ty];
        self.csv.row(
            || format!("{}\n", STEP_COLUMNS.join(",")),
            |line| {
                // Writing into a String cannot fail.
                let _ = write!(line, "{index}");
                for value in numbers {
                    push(line, value);
                }
                let _ = write!(line, ",{},{}", command.state, command.mode);
                for value in (0..3).map(|i| set_point.map(|p| p[i])) {
                    push(line, value);
                }
                for value in wrench {
                    push(line, Some(value));
                }
                let _ = write!(line, ",{}", u8::from(command.saturation.any()));
                line.push('\n');
            },
        );
    }
}

/// Appends `,value` (`,` alone for `None`) to `line`.
fn push(line: &mut String, value: Option<f64>) {
    line.push(',');
    if let Some(value) = value {
        // Writing into a String cannot fail.
        let _ = write!(line, "{value}");
    }
}
