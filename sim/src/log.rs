//! The log format of `plant.md`: a CSV writer for scripted runs and THE
//! strict reader every part of the project uses.
//!
//! # Format
//! Header `t,xd,zd,psid,x,y,z,psi,fx,fz,ty,q1,q2,elbow_x,elbow_z,shoulder_x,shoulder_z`,
//! one row per sample, frame S, SI units (m, rad, s, N, N m). The writer
//! prints every value with Rust's shortest round-tripping `f64` form, so the
//! same parameters and seed give a byte-identical file and reading it back
//! gives the same numbers bit for bit.
//!
//! # What the reader accepts
//! * Required: `t, x, z, psi, fx, fz, ty` (what a real robot gives).
//! * Optional: `xd, zd, psid, y` and the ground truth `q1, q2, elbow_x,
//!   elbow_z, shoulder_x, shoulder_z`; a column may be missing or a value
//!   empty. A present, non-empty optional value must still be a finite
//!   number.
//! * Any other column is ignored; blank lines are skipped.
//!
//! # Errors
//! An empty file, a missing required column, a row with too few fields, a
//! non-numeric or non-finite value, a non-increasing `t` or a log without
//! rows is a [`LogError`] naming the file and the 1-based line. The reader
//! never panics on any text (property-tested).

use crate::plant::Truth;
use crate::scripted::Row;
use limb_kernel::geometry::{Point, Pose, Wrench};
use limb_kernel::path::PathSample;
use limb_session::log::{header, Row as SessionRow};
use std::path::Path;

/// The header the writer emits (`plant.md`).
pub const HEADER: &str =
    "t,xd,zd,psid,x,y,z,psi,fx,fz,ty,q1,q2,elbow_x,elbow_z,shoulder_x,shoulder_z";

/// Columns a log must have.
const REQUIRED: [&str; 7] = ["t", "x", "z", "psi", "fx", "fz", "ty"];
/// Columns a log may have: commanded pose, lateral y, ground truth.
const OPTIONAL: [&str; 10] = [
    "xd",
    "zd",
    "psid",
    "y",
    "q1",
    "q2",
    "elbow_x",
    "elbow_z",
    "shoulder_x",
    "shoulder_z",
];

/// A fault in a log file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LogError {
    /// The file could not be read or written.
    #[error("{file}: {message}")]
    Io {
        /// The file.
        file: String,
        /// What the operating system said.
        message: String,
    },
    /// The text is not a valid log.
    #[error("{file}:{line}: {message}")]
    Malformed {
        /// The file (or `<text>` for in-memory text).
        file: String,
        /// 1-based line of the fault.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// One sample of a log, frame S, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Time stamp [s].
    pub time: f64,
    /// Commanded equilibrium pose x_d [m, m, rad], when logged.
    pub command: Option<Pose>,
    /// Measured grasp pose [m, m, rad].
    pub pose: Pose,
    /// Measured lateral position y [m], when logged.
    pub lateral: Option<f64>,
    /// Measured external wrench f_ext [N, N, N m].
    pub wrench: Wrench,
    /// Ground truth, when all six of its columns are present in this row.
    pub truth: Option<Truth>,
}

impl Record {
    /// The part the kernel's estimators see.
    pub fn path_sample(&self) -> PathSample {
        PathSample {
            time: self.time,
            pose: self.pose,
            wrench: self.wrench,
        }
    }

    /// The record a scripted-run row is written as.
    pub fn from_row(row: &Row) -> Self {
        let m = &row.measurement;
        Self {
            time: m.time,
            command: Some(row.set_point.pose),
            pose: m.pose,
            lateral: Some(m.lateral),
            wrench: m.wrench,
            truth: Some(row.truth),
        }
    }
}

/// The ground-truth columns after the session log's own
/// ([`limb_session::log::COLUMNS`]).
pub const TRUTH_COLUMNS: [&str; 6] = ["q1", "q2", "elbow_x", "elbow_z", "shoulder_x", "shoulder_z"];

/// The truth columns' values (`None`: empty).
pub fn truth_values(truth: Option<&Truth>) -> [Option<f64>; 6] {
    let values = truth.map(|t| {
        [
            t.q[0],
            t.q[1],
            t.elbow.x,
            t.elbow.z,
            t.shoulder.x,
            t.shoulder.z,
        ]
    });
    core::array::from_fn(|i| values.map(|v| v[i]))
}

/// Writes records as CSV text with [`HEADER`] (the session log's rows
/// with the truth columns); absent values are empty.
pub fn to_csv(records: &[Record]) -> String {
    let mut text = String::with_capacity(200 * (records.len() + 1));
    text.push_str(&header(&TRUTH_COLUMNS));
    for r in records {
        SessionRow {
            time: r.time,
            command: r.command,
            pose: r.pose,
            lateral: r.lateral,
            wrench: r.wrench,
            extra: &truth_values(r.truth.as_ref()),
        }
        .write(&mut text);
    }
    text
}

/// Writes the rows of a scripted run to `file`.
///
/// # Errors
/// [`LogError::Io`] when the file cannot be written.
pub fn write(file: &Path, rows: &[Row]) -> Result<(), LogError> {
    let records: Vec<Record> = rows.iter().map(Record::from_row).collect();
    std::fs::write(file, to_csv(&records)).map_err(|error| LogError::Io {
        file: file.display().to_string(),
        message: error.to_string(),
    })
}

/// Reads the log at `file`.
///
/// # Errors
/// [`LogError`] naming the file (and line) of the first fault.
pub fn read(file: &Path) -> Result<Vec<Record>, LogError> {
    let name = file.display().to_string();
    let text = std::fs::read_to_string(file).map_err(|error| LogError::Io {
        file: name.clone(),
        message: error.to_string(),
    })?;
    parse(&text).map_err(|(line, message)| LogError::Malformed {
        file: name,
        line,
        message,
    })
}

/// Parses log text; a fault is (1-based line, message).
///
/// # Errors
/// The first fault, as described in the module docs.
pub fn parse(text: &str) -> Result<Vec<Record>, (usize, String)> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(index, line)| (index + 1, line));
    let header = match lines.next() {
        Some((_, header)) if !header.trim().is_empty() => header,
        _ => return Err((1, "empty file: expected a CSV header".to_string())),
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let position = |wanted: &str| names.iter().position(|name| *name == wanted);
    let mut required = [0usize; REQUIRED.len()];
    for (slot, name) in required.iter_mut().zip(REQUIRED) {
        *slot = position(name).ok_or_else(|| (1, format!("missing required column `{name}`")))?;
    }
    let optional = OPTIONAL.map(position);
    let mut records: Vec<Record> = Vec::new();
    for (number, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let number_at = |column: usize, name: &str| -> Result<Option<f64>, (usize, String)> {
            let Some(field) = fields.get(column) else {
                return Ok(None);
            };
            if field.is_empty() {
                return Ok(None);
            }
            let value = field
                .parse::<f64>()
                .map_err(|_| (number, format!("`{name}` is not a number: {field:?}")))?;
            if value.is_finite() {
                Ok(Some(value))
            } else {
                Err((number, format!("`{name}` is not finite: {field}")))
            }
        };
        let mut values = [0.0f64; REQUIRED.len()];
        for ((value, &column), name) in values.iter_mut().zip(&required).zip(REQUIRED) {
            *value = number_at(column, name)?
                .ok_or_else(|| (number, format!("missing value for `{name}`")))?;
        }
        let mut extra = [None; OPTIONAL.len()];
        for ((value, column), name) in extra.iter_mut().zip(optional).zip(OPTIONAL) {
            if let Some(column) = column {
                *value = number_at(column, name)?;
            }
        }
        let [t, x, z, psi, fx, fz, ty] = values;
        if let Some(previous) = records.last() {
            if t <= previous.time {
                return Err((
                    number,
                    format!("time {t} does not increase (previous {})", previous.time),
                ));
            }
        }
        let [xd, zd, psid, y, q1, q2, ex, ez, sx, sz] = extra;
        let command = match (xd, zd, psid) {
            (Some(x), Some(z), Some(psi)) => Some(Pose::new(x, z, psi)),
            _ => None,
        };
        let truth = match (q1, q2, ex, ez, sx, sz) {
            (Some(q1), Some(q2), Some(ex), Some(ez), Some(sx), Some(sz)) => Some(Truth {
                q: [q1, q2],
                elbow: Point::new(ex, ez),
                shoulder: Point::new(sx, sz),
            }),
            _ => None,
        };
        records.push(Record {
            time: t,
            command,
            pose: Pose::new(x, z, psi),
            lateral: y,
            wrench: Wrench::new(fx, fz, ty),
            truth,
        });
    }
    if records.is_empty() {
        return Err((2, "no samples after the header".to_string()));
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::{parse, to_csv, Record};
    use proptest::prelude::*;

    const HEADER: &str = "t,x,z,psi,fx,fz,ty,q1\n";

    #[test]
    fn the_header_is_the_session_log_with_the_truth() {
        let text = limb_session::log::header(&super::TRUTH_COLUMNS);
        assert_eq!(text, format!("{}\n", super::HEADER));
    }

    #[test]
    fn reads_required_columns_and_ignores_extra_and_empty_ones() {
        let records = parse(&format!("{HEADER}0,1,2,3,4,5,6,\n0.01,1,2,3,4,5,6,\n")).unwrap();
        assert_eq!(records.len(), 2);
        assert_eq!(records[1].pose.psi, 3.0);
        assert_eq!(records[1].wrench.ty, 6.0);
        assert_eq!(records[1].truth, None);
        assert_eq!(records[1].command, None);
    }

    #[test]
    fn rejects_faults_with_their_line() {
        let cases = [
            ("", 1),
            ("t,x,z,psi,fx,fz\n0,0,0,0,0,0\n", 1),
            (
                &format!("{HEADER}0,0,0,0,0,0,0,0\n0.1,0,zero,0,0,0,0,0\n") as &str,
                3,
            ),
            (&format!("{HEADER}0,0,0,0,0,0,NaN,0\n"), 2),
            (&format!("{HEADER}0,0,0,0,0,0,inf,0\n"), 2),
            (&format!("{HEADER}0,0,0,0,0,0,0,inf\n"), 2),
            (
                &format!("{HEADER}0.1,0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0,0\n"),
                3,
            ),
            (&format!("{HEADER}0,0,0\n"), 2),
            (HEADER, 2),
        ];
        for (text, line) in cases {
            assert_eq!(parse(text).unwrap_err().0, line, "{text:?}");
        }
    }

    fn finite() -> impl Strategy<Value = f64> {
        prop_oneof![
            -1e6..1e6f64,
            any::<f64>().prop_filter("finite", |v| v.is_finite())
        ]
    }

    proptest! {
        #[test]
        fn never_panics_on_arbitrary_text(text in "(?s).{0,400}") {
            let _ = parse(&text);
        }

        #[test]
        fn never_panics_on_log_like_text(
            lines in proptest::collection::vec("[-0-9.,eEnaNifty ]{0,40}", 0..8)
        ) {
            let _ = parse(&format!("t,x,z,psi,fx,fz,ty,q1\n{}", lines.join("\n")));
        }

        #[test]
        fn write_then_read_round_trips(
            values in proptest::collection::vec(proptest::array::uniform16(finite()), 1..6),
            with_truth in any::<bool>(),
        ) {
            use limb_kernel::geometry::{Point, Pose, Wrench};
            let records: Vec<Record> = values.iter().enumerate().map(|(i, v)| Record {
                time: i as f64 * 0.01,
                command: Some(Pose::new(v[0], v[1], v[2])),
                pose: Pose::new(v[3], v[4], v[5]),
                lateral: Some(v[6]),
                wrench: Wrench::new(v[7], v[8], v[9]),
                truth: with_truth.then(|| crate::plant::Truth {
                    q: [v[10], v[11]],
                    elbow: Point::new(v[12], v[13]),
                    shoulder: Point::new(v[14], v[15]),
                }),
            }).collect();
            let text = to_csv(&records);
            prop_assert_eq!(parse(&text).unwrap(), records);
        }
    }
}
