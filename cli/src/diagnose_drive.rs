//! `limb diagnose-drive`: the gap diagnosis of one actuated axis
//! (`spec/drive.md`) — which unmodelled effects a drive log shows beyond
//! the rigid inverse model, in the order they earn their parameters, and
//! how far each shrinks the gap on held-out data.
//!
//! * `limb diagnose-drive FIT.csv --validate HELD.csv [--json]
//!   [--report FILE.html]`: fitted on FIT, scored on the whole of HELD.
//! * `limb diagnose-drive FIT.csv [--json]`: alternating 1 s blocks of FIT
//!   are held out (the output says so).
//! * `limb diagnose-drive --self-check N [--seed S] [--json]`: the blind
//!   self-check on simulated drives (see `limb_diagnosis::plant::drive::blind`).
//!
//! Bad input (an unreadable or malformed log, logs that differ in their
//! columns, a log too short to hold out, a bad flag) is one line on stderr
//! naming the file and line, exit 2.

use crate::diagnose::write_report;
use crate::error::{emit, print_json, CliError};
use limb_diagnosis::plant::drive::blind;
use limb_diagnosis::plant::drive::outcome::{Diagnosis, Run, MAX_EFFECTS};
use limb_diagnosis::plant::drive::{diagnose, read, DriveError, CUTOFF};
use limb_diagnosis::report::Subject;
use limb_diagnosis::Options;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `limb diagnose-drive`.
#[derive(clap::Args, Debug)]
pub struct DiagnoseDriveArgs {
    /// Fit run: a drive log (CSV `t,ref,q,tau[,q_load][,f_ext]`, SI units).
    #[arg(required_unless_present = "self_check")]
    fit: Option<PathBuf>,
    /// Held-out run of the same drive, scored whole (without it, alternating 1 s blocks of FIT are held out).
    #[arg(long, value_name = "HELDOUT.csv")]
    validate: Option<PathBuf>,
    /// Zero-phase low-pass cut-off of positions and force [Hz].
    #[arg(long, default_value_t = CUTOFF)]
    cutoff: f64,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Write a self-contained HTML report here (the scored run's force
    /// against the rigid model and the chosen effects, residuals, ranking).
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    /// Run the blind self-check on N simulated drives instead (no FIT log).
    #[arg(long, value_name = "N", conflicts_with_all = ["fit", "validate", "report"])]
    self_check: Option<usize>,
    /// Seed of the self-check's draws and noise.
    #[arg(long, default_value_t = 1, requires = "self_check")]
    seed: u64,
}

/// Runs `limb diagnose-drive` on logs.
///
/// # Errors
/// [`CliError::BadInput`] for a bad log or flag, [`CliError::Internal`]
/// when the engine fails.
pub fn run(args: &DiagnoseDriveArgs) -> Result<(), CliError> {
    if let Some(count) = args.self_check {
        return self_check(count, args.seed, args.json);
    }
    let Some(fit_file) = &args.fit else {
        return Err(CliError::BadInput(
            "diagnose-drive: a FIT log is required".into(),
        ));
    };
    let read_log = |file: &PathBuf| read(file).map_err(|e| CliError::BadInput(e.to_string()));
    let fit = read_log(fit_file)?;
    let held = args.validate.as_ref().map(read_log).transpose()?;
    let (fit_name, held_name) = (
        fit_file.display().to_string(),
        args.validate.as_ref().map(|f| f.display().to_string()),
    );
    let options = Options {
        max_effects: MAX_EFFECTS,
        ..Options::default()
    };
    let diagnosed = diagnose(
        Run {
            name: &fit_name,
            log: &fit,
        },
        held.as_ref()
            .zip(held_name.as_deref())
            .map(|(log, name)| Run { name, log }),
        args.cutoff,
        &options,
    )
    .map_err(|e: DriveError| {
        if e.is_bad_input() {
            CliError::BadInput(e.to_string())
        } else {
            CliError::Internal(e.to_string())
        }
    })?;
    if let Some(path) = &args.report {
        let source = match &held_name {
            Some(held) => format!("{held} (fitted on {fit_name})"),
            None => fit_name.clone(),
        };
        write_report(
            path,
            &Subject {
                model: &diagnosed.scored,
                selection: &diagnosed.selection,
                source: &source,
                held_out: &diagnosed.diagnosis.held_out_data,
                facts: &[],
                curves: &[],
            },
        )?;
    }
    if args.json {
        print_json(&diagnosed.diagnosis)
    } else {
        emit(&text(&diagnosed.diagnosis))
    }
}

/// The blind self-check: `count` simulated drives from `seed`.
fn self_check(count: usize, seed: u64, json: bool) -> Result<(), CliError> {
    let report = blind::run(count, seed, &Options::default());
    if json {
        return print_json(&report);
    }
    let mut out = String::new();
    for trial in &report.trials {
        let _ = writeln!(
            out,
            "seed {}: withheld {:?}, found {:?} ({})",
            trial.seed,
            trial.withheld,
            trial.found,
            if trial.correct { "right" } else { "wrong" }
        );
    }
    let _ = writeln!(
        out,
        "single effects: top-1 {}/{}; pairs: exact set {}/{}, both found {}/{}",
        report.single_top1,
        report.singles,
        report.pair_exact,
        report.pairs,
        report.pair_both_found,
        report.pairs
    );
    emit(&out)
}

/// The answer for a reader.
fn text(answer: &Diagnosis) -> String {
    let mut out = String::new();
    let nominal: Vec<String> = answer
        .nominal
        .iter()
        .map(|(k, v)| format!("{k} = {v:.4}"))
        .collect();
    let _ = writeln!(out, "held out: {}", answer.held_out_data);
    let _ = writeln!(out, "nominal rigid model: {}", nominal.join(", "));
    let gap = &answer.gap;
    let _ = writeln!(
        out,
        "effects, in the order added (held-out {} after each):",
        gap.metric
    );
    for (i, effect) in answer.effects.iter().enumerate() {
        let params: Vec<String> = effect
            .params
            .iter()
            .map(|(k, v)| {
                let unit = effect.units.get(k).map_or("", String::as_str);
                format!("{k} = {v:.4} {unit}")
            })
            .collect();
        let _ = writeln!(
            out,
            "  {}. {} ({}) -> {:.4}",
            i + 1,
            effect.effect,
            params.join(", "),
            effect.held_out_after
        );
    }
    let _ = writeln!(
        out,
        "gap {}: {:.4} -> {:.4} (shrink {:.1} %, held out)",
        gap.metric,
        gap.before,
        gap.after,
        100.0 * gap.shrink
    );
    let _ = writeln!(out, "unexplained: {}", answer.unexplained);
    out
}
