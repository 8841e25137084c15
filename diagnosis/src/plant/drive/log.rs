//! The drive log of `spec/drive.md`: one actuated axis, CSV, SI units.
//!
//! # Format
//! Header row naming the columns (any order; other columns are ignored),
//! then one row per sample:
//!
//! | column | required | meaning |
//! |---|---|---|
//! | `t` | yes | time [s], strictly increasing |
//! | `ref` | yes | commanded position [m or rad] |
//! | `q` | yes | actuator-side position [m or rad], in load units |
//! | `tau` | yes | actuator force or torque [N or N m] |
//! | `q_load` | no | load-side position [m or rad] |
//! | `f_ext` | no | known external force or torque on the load [N or N m] |
//!
//! # Errors
//! The reader is strict: an empty file, a missing required column, a row
//! with a missing field, a non-numeric or non-finite value, a
//! non-increasing `t`, an optional column with an empty value, or a log
//! with fewer than [`MIN_SAMPLES`] rows is a [`DriveLogError`] naming the
//! file and the 1-based line. It never panics on any text
//! (property-tested).

use std::path::Path;

/// Fewest samples a drive log must hold (the zero-phase filter and the
/// derivatives need a few dozen).
pub const MIN_SAMPLES: usize = 32;

/// Column names, in [`DriveLog`] field order: required, then optional.
const COLUMNS: [&str; 6] = ["t", "ref", "q", "tau", "q_load", "f_ext"];
/// How many of [`COLUMNS`] are required.
const REQUIRED: usize = 4;

/// A fault in a drive log: the project's log error, naming the file (and
/// the 1-based line).
pub type DriveLogError = limb_sim::log::LogError;

/// One drive log, column by column (all columns the same length, SI
/// units).
///
/// # Invariants
/// At least [`MIN_SAMPLES`] samples; `t` strictly increasing; every value
/// finite; `q_load` and `f_ext`, when present, as long as `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveLog {
    /// Time [s].
    pub t: Vec<f64>,
    /// Commanded position [m or rad].
    pub reference: Vec<f64>,
    /// Actuator-side position [m or rad].
    pub q: Vec<f64>,
    /// Actuator force or torque [N or N m].
    pub tau: Vec<f64>,
    /// Load-side position [m or rad], where a second encoder exists.
    pub q_load: Option<Vec<f64>>,
    /// Known external force or torque on the load [N or N m].
    pub f_ext: Option<Vec<f64>>,
}

impl DriveLog {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// `true` when there are no samples (never, for a log the reader made).
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// Reads the drive log at `file`.
///
/// # Errors
/// [`DriveLogError`] naming the file (and line) of the first fault.
pub fn read(file: &Path) -> Result<DriveLog, DriveLogError> {
    let name = file.display().to_string();
    let text = std::fs::read_to_string(file).map_err(|error| DriveLogError::Io {
        file: name.clone(),
        message: error.to_string(),
    })?;
    parse(&text).map_err(|(line, message)| DriveLogError::Malformed {
        file: name,
        line,
        message,
    })
}

/// One field as a finite number.
fn number(field: Option<&&str>, name: &str, line: usize) -> Result<f64, (usize, String)> {
    let field = field
        .map(|f| f.trim())
        .filter(|f| !f.is_empty())
        .ok_or_else(|| (line, format!("missing value for `{name}`")))?;
    match field.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(value),
        Ok(_) => Err((line, format!("`{name}` is not finite: {field}"))),
        Err(_) => Err((line, format!("`{name}` is not a number: {field:?}"))),
    }
}

/// Parses drive-log text; a fault is (1-based line, message).
///
/// # Errors
/// The first fault, as described in the module docs.
pub fn parse(text: &str) -> Result<DriveLog, (usize, String)> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let header: Vec<&str> = match lines.next() {
        Some((_, h)) if !h.trim().is_empty() => h.split(',').map(str::trim).collect(),
        _ => return Err((1, "empty file: expected a CSV header".into())),
    };
    let mut at: [Option<usize>; COLUMNS.len()] = [None; COLUMNS.len()];
    for (slot, name) in at.iter_mut().zip(COLUMNS) {
        *slot = header.iter().position(|h| *h == name);
    }
    if let Some(missing) = COLUMNS[..REQUIRED]
        .iter()
        .zip(&at)
        .find_map(|(name, slot)| slot.is_none().then_some(name))
    {
        return Err((1, format!("missing required column `{missing}`")));
    }
    let mut columns: [Vec<f64>; COLUMNS.len()] = Default::default();
    for (line, row) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let fields: Vec<&str> = row.split(',').collect();
        for ((column, slot), name) in columns.iter_mut().zip(&at).zip(COLUMNS) {
            if let Some(index) = slot {
                column.push(number(fields.get(*index), name, line)?);
            }
        }
        if let [.., previous, now] = columns[0].as_slice() {
            if now <= previous {
                return Err((
                    line,
                    format!("time {now} does not increase (previous {previous})"),
                ));
            }
        }
    }
    let [t, reference, q, tau, q_load, f_ext] = columns;
    if t.len() < MIN_SAMPLES {
        return Err((
            text.lines().count().max(2),
            format!(
                "{} samples: a drive log needs at least {MIN_SAMPLES}",
                t.len()
            ),
        ));
    }
    let present = |column: Vec<f64>, slot: Option<usize>| slot.map(|_| column);
    Ok(DriveLog {
        q_load: present(q_load, at[4]),
        f_ext: present(f_ext, at[5]),
        t,
        reference,
        q,
        tau,
    })
}

/// Writes `log` in the drive-log format (shortest round-tripping numbers,
/// so reading it back gives the same values bit for bit).
pub fn to_csv(log: &DriveLog) -> String {
    use std::fmt::Write as _;
    let mut header = String::from("t,ref,q,tau");
    let mut extra: Vec<&[f64]> = Vec::new();
    if let Some(q_load) = &log.q_load {
        header.push_str(",q_load");
        extra.push(q_load);
    }
    if let Some(f_ext) = &log.f_ext {
        header.push_str(",f_ext");
        extra.push(f_ext);
    }
    let mut out = header + "\n";
    for i in 0..log.len() {
        let _ = write!(
            out,
            "{},{},{},{}",
            log.t[i], log.reference[i], log.q[i], log.tau[i]
        );
        for column in &extra {
            let _ = write!(out, ",{}", column.get(i).copied().unwrap_or(0.0));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{parse, to_csv, MIN_SAMPLES};
    use proptest::prelude::*;

    fn rows(n: usize, extra: &str) -> String {
        let mut text = format!("t,ref,q,tau{extra}\n");
        for i in 0..n {
            text += &format!("{},{},{},{}", i as f64 * 0.001, 0.1, 0.1, 1.0);
            if !extra.is_empty() {
                text += ",0.5";
            }
            text += "\n";
        }
        text
    }

    #[test]
    fn reads_required_and_optional_columns() {
        let log = parse(&rows(MIN_SAMPLES, "")).unwrap();
        assert_eq!(log.len(), MIN_SAMPLES);
        assert!(log.q_load.is_none() && log.f_ext.is_none());
        let log = parse(&rows(MIN_SAMPLES, ",f_ext")).unwrap();
        assert_eq!(log.f_ext.as_deref().map(|f| f[3]), Some(0.5));
        assert_eq!(parse(&to_csv(&log)).unwrap(), log);
    }

    #[test]
    fn rejects_faults_with_their_line() {
        let good = rows(MIN_SAMPLES, "");
        assert_eq!(parse("").unwrap_err().0, 1);
        let no_tau = good.replacen("t,ref,q,tau", "t,ref,q,force", 1);
        assert!(parse(&no_tau).unwrap_err().1.contains("`tau`"));
        let nan = good.replacen("0.001,0.1,0.1,1", "0.001,0.1,NaN,1", 1);
        assert_eq!(parse(&nan).unwrap_err().0, 3);
        let word = good.replacen("0.001,0.1,0.1,1", "0.001,0.1,x,1", 1);
        assert!(parse(&word).unwrap_err().1.contains("not a number"));
        let back = good.replacen("0.002,", "0.0005,", 1);
        assert_eq!(parse(&back).unwrap_err().0, 4);
        let short = good.replacen("0.001,0.1,0.1,1", "0.001,0.1,0.1", 1);
        assert_eq!(
            parse(&short).unwrap_err(),
            (3, "missing value for `tau`".into())
        );
        assert!(parse(&rows(MIN_SAMPLES - 1, "")).is_err());
    }

    proptest! {
        #[test]
        fn never_panics_on_arbitrary_text(text in "(?s).{0,400}") {
            let _ = parse(&text);
        }
    }
}
