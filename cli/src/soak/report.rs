//! The soak's figures as Markdown: one section per soak (`kuka`,
//! `kuka-unpaced`, `zenoh`) in `benchmarks/soak.md`, between `<!--
//! soak:SECTION -->` and `<!-- /soak:SECTION -->`, replaced by each run
//! (the rest of the file is kept; a missing file or section is created).

use crate::error::CliError;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The file's first lines when it is created.
const TITLE: &str = "# Soak runs\n\n\
Written by `limb soak kuka|zenoh --report benchmarks/soak.md` (see the \
README, Benchmarks). Each section is the adapter's latest run: totals, \
memory, then one row per session.\n";

/// Writes `output` (the soak's JSON) into its adapter's section of `path`.
///
/// # Errors
/// [`CliError::BadInput`] when the file cannot be read or written.
pub fn write(path: &Path, output: &Value) -> Result<(), CliError> {
    let section = output["section"].as_str().unwrap_or("soak");
    let (open, close) = (
        format!("<!-- soak:{section} -->"),
        format!("<!-- /soak:{section} -->"),
    );
    let old = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => TITLE.to_string(),
        Err(error) => {
            return Err(CliError::BadInput(format!("{}: {error}", path.display())));
        }
    };
    let section = format!("{open}\n{}{close}", render(output));
    let text = match (old.find(&open), old.find(&close)) {
        (Some(start), Some(end)) if end > start => {
            format!("{}{section}{}", &old[..start], &old[end + close.len()..])
        }
        _ => format!("{}\n{section}\n", old.trim_end()),
    };
    std::fs::write(path, text)
        .map_err(|error| CliError::BadInput(format!("{}: {error}", path.display())))
}

/// A JSON value in a table cell.
fn cell(value: &Value) -> String {
    match value {
        Value::Null => "—".into(),
        Value::String(text) => text.replace('|', "\\|"),
        other => other.to_string().replace('|', "\\|"),
    }
}

/// `figures` as `name | value` rows, nested objects flattened with dots.
fn rows(prefix: &str, value: &Value, out: &mut String) {
    match value {
        Value::Object(fields) => {
            for (name, field) in fields {
                if name == "sessions_detail" {
                    continue;
                }
                let name = if prefix.is_empty() {
                    name.clone()
                } else {
                    format!("{prefix}.{name}")
                };
                rows(&name, field, out);
            }
        }
        other => {
            let _ = writeln!(out, "| {prefix} | {} |", cell(other));
        }
    }
}

/// The section's text.
fn render(output: &Value) -> String {
    let mut out = String::new();
    let machine = &output["machine"];
    let _ = writeln!(
        out,
        "## {}\n\nCommand: `{}` ({} build), seed {}.\n\nMachine: {}, {} cores, load average (1, 5, 15 min) {} at the start, {} at the end.\n\nNothing lost: **{}**.{}\n",
        match output["section"].as_str() {
            Some("kuka") => "KUKA FRI client against the simulated controller, paced at 1 kHz",
            Some("kuka-unpaced") => "KUKA FRI client against the simulated controller, unpaced",
            _ => "Zenoh node supervised over Zenoh, 1 kHz",
        },
        cell(&output["command"]),
        cell(&machine["build"]),
        output["seed"],
        cell(&machine["cpu"]),
        machine["cores"],
        cell(&machine["load_average_at_start"]),
        cell(&machine["load_average_at_end"]),
        output["nothing_lost"],
        output["losses"]
            .as_array()
            .filter(|l| !l.is_empty())
            .map(|l| {
                let words: Vec<String> = l.iter().map(cell).collect();
                format!(" Lost or wrong: {}.", words.join("; "))
            })
            .unwrap_or_default(),
    );
    out.push_str("| figure | value |\n|---|---|\n");
    rows("", &output["figures"], &mut out);
    if let Some(sessions) = output["figures"]["sessions_detail"].as_array() {
        if let Some(Value::Object(first)) = sessions.first() {
            let names: Vec<&String> = first.keys().collect();
            let _ = writeln!(
                out,
                "\n| session | {} |\n|---|{}",
                names
                    .iter()
                    .map(|n| n.replace('_', " "))
                    .collect::<Vec<_>>()
                    .join(" | "),
                "---|".repeat(names.len())
            );
            for (index, session) in sessions.iter().enumerate() {
                let cells: Vec<String> = names.iter().map(|n| cell(&session[n.as_str()])).collect();
                let _ = writeln!(out, "| {index} | {} |", cells.join(" | "));
            }
        }
    }
    out
}
