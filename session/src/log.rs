//! The session log: every step of a session as one CSV row in the format
//! of `plant.md`, which `limb estimate` and `limb diagnose` read.
//!
//! # Format
//! The columns [`COLUMNS`] — `t,xd,zd,psid,x,y,z,psi,fx,fz,ty`: the
//! robot's stamp, the commanded set-point pose x_d, the measured grasp
//! pose (y when the robot measures it) and the external wrench, frame S,
//! SI units — then the robot's own columns ([`Logged`]; the reference
//! plant adds its ground truth `q1,q2,elbow_x,elbow_z,shoulder_x,
//! shoulder_z`). An absent value is empty. Every number is printed in
//! Rust's shortest round-trip `f64` form: reading it back gives the same
//! bits. One row per frame the kernel stepped on, written as the session
//! runs (a crash loses at most the buffered rows).

use crate::robot::Frame;
use crate::run::Observer;
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
    fn columns(&self) -> &'static [&'static str] {
        &[]
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

impl Row<'_> {
    /// Appends the row and its line end to `text`.
    pub fn write(&self, text: &mut String) {
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
        for (i, field) in base.iter().chain(self.extra).enumerate() {
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

/// An [`Observer`] writing the session log to `W` as the session runs.
#[derive(Debug)]
pub struct SessionLog<W: Write> {
    out: W,
    line: String,
    extra: Vec<Option<f64>>,
    started: bool,
    error: Option<io::Error>,
}

impl<W: Write> SessionLog<W> {
    /// A log written to `out` (buffer it: one write per row).
    pub fn new(out: W) -> Self {
        Self {
            out,
            line: String::new(),
            extra: Vec::new(),
            started: false,
            error: None,
        }
    }

    /// Flushes the log and returns its writer.
    ///
    /// # Errors
    /// The first write error of the session, or the flush's.
    pub fn finish(mut self) -> io::Result<W> {
        if let Some(error) = self.error.take() {
            return Err(error);
        }
        self.out.flush()?;
        Ok(self.out)
    }
}

impl<R: Logged + ?Sized, W: Write> Observer<R> for SessionLog<W> {
    fn after_step(&mut self, robot: &R, frame: &Frame, _: StateKind, command: &Command) {
        if self.error.is_some() {
            return;
        }
        self.line.clear();
        if !self.started {
            self.started = true;
            self.line.push_str(&header(robot.columns()));
        }
        self.extra.clear();
        robot.values(&mut self.extra);
        let sample = &frame.sample;
        Row {
            time: sample.time,
            command: command.set_point.map(|s| s.pose),
            pose: sample.pose,
            lateral: frame.lateral,
            wrench: sample.wrench,
            extra: &self.extra,
        }
        .write(&mut self.line);
        if let Err(error) = self.out.write_all(self.line.as_bytes()) {
            self.error = Some(error);
        }
    }
}
