//! Strict reader of robot logs in the CSV format of `plant.md`.
//!
//! Required columns: `t, x, z, psi, fx, fz, ty` (the ones a real robot
//! gives); any other column (ground truth, commands) is accepted and
//! ignored. Rejected, with the file and the 1-based line: an empty file, a
//! missing required column, a row with too few fields, a non-numeric or
//! non-finite required value, a non-increasing `t`, a log without rows.
//!
//! Self-contained so it can later be swapped for the shared reader.

use crate::error::CliError;
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::path::PathSample;
use std::path::Path;

/// The columns a log must have, in the order they fill a [`PathSample`].
const REQUIRED: [&str; 7] = ["t", "x", "z", "psi", "fx", "fz", "ty"];

/// Reads the log at `file` into path samples (frame S, SI units).
///
/// # Errors
/// [`CliError::BadInput`] naming the file and line of the first fault.
pub fn read(file: &Path) -> Result<Vec<PathSample>, CliError> {
    let name = file.display();
    let text = std::fs::read_to_string(file)
        .map_err(|error| CliError::BadInput(format!("{name}: {error}")))?;
    parse(&text).map_err(|(line, message)| CliError::BadInput(format!("{name}:{line}: {message}")))
}

/// Parses log text; a fault is (1-based line, message).
fn parse(text: &str) -> Result<Vec<PathSample>, (usize, String)> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(index, line)| (index + 1, line));
    let header = match lines.next() {
        Some((_, header)) if !header.trim().is_empty() => header,
        _ => return Err((1, "empty file: expected a CSV header".to_string())),
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut columns = [0usize; REQUIRED.len()];
    for (slot, required) in columns.iter_mut().zip(REQUIRED) {
        *slot = names
            .iter()
            .position(|name| *name == required)
            .ok_or_else(|| (1, format!("missing required column `{required}`")))?;
    }
    let mut samples: Vec<PathSample> = Vec::new();
    for (number, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        let mut values = [0.0f64; REQUIRED.len()];
        for ((value, &column), required) in values.iter_mut().zip(&columns).zip(REQUIRED) {
            let field = fields
                .get(column)
                .ok_or_else(|| (number, format!("missing value for `{required}`")))?
                .trim();
            *value = field
                .parse::<f64>()
                .map_err(|_| (number, format!("`{required}` is not a number: {field:?}")))?;
            if !value.is_finite() {
                return Err((number, format!("`{required}` is not finite: {field}")));
            }
        }
        let [t, x, z, psi, fx, fz, ty] = values;
        if let Some(previous) = samples.last() {
            if t <= previous.time {
                return Err((
                    number,
                    format!("time {t} does not increase (previous {})", previous.time),
                ));
            }
        }
        samples.push(PathSample {
            time: t,
            pose: Pose::new(x, z, psi),
            wrench: Wrench::new(fx, fz, ty),
        });
    }
    if samples.is_empty() {
        return Err((2, "no samples after the header".to_string()));
    }
    Ok(samples)
}

#[cfg(test)]
mod tests {
    use super::parse;

    const HEADER: &str = "t,x,z,psi,fx,fz,ty,q1\n";

    #[test]
    fn reads_required_columns_and_ignores_extra_and_empty_ones() {
        let samples = parse(&format!("{HEADER}0,1,2,3,4,5,6,\n0.01,1,2,3,4,5,6,\n")).unwrap();
        assert_eq!(samples.len(), 2);
        assert_eq!(samples[1].pose.psi, 3.0);
        assert_eq!(samples[1].wrench.ty, 6.0);
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
}
