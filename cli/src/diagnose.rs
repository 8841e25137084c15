//! `limb diagnose LOG.csv [--l1 M --l2 M] [--json] [--report FILE.html]`
//! and `limb diagnose --self-check N [--seed S] [--json]`
//! (`../shared/spec/cli.md`): where the sim-to-real gap lies, which
//! unmodelled effect causes it, how far it shrinks on held-out data.
//! The engine is `limb-diagnosis`; this module parses, reports progress
//! on a terminal and prints.

use crate::error::{emit, print_json, CliError};
use indicatif::{ProgressBar, ProgressStyle};
use limb_diagnosis::plant::arm::blind::{self, Summary};
use limb_diagnosis::plant::arm::curves::curves;
use limb_diagnosis::plant::arm::{diagnose, Diagnosis, Lengths};
use limb_diagnosis::report::{self, Subject};
use limb_diagnosis::Progress;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Arguments of `limb diagnose`.
#[derive(clap::Args, Debug)]
pub struct DiagnoseArgs {
    /// The "real" log (plant.md format; ground-truth columns are ignored).
    #[arg(required_unless_present = "self_check")]
    log: Option<PathBuf>,
    /// Upper-arm length of the sim [m], held fixed (absent: fitted).
    #[arg(long, requires = "l2")]
    l1: Option<f64>,
    /// Forearm length of the sim [m], held fixed (absent: fitted).
    #[arg(long, requires = "l1")]
    l2: Option<f64>,
    /// The body the sim puts the lengths on: `rod` (default, plant.md's
    /// dummy: uniform rods of 1.55 kg and 1.317 kg) or `person` (the
    /// reference person's segments scaled to the lengths: a log of a
    /// person's arm, `spec/human-arm.md`).
    #[arg(long, value_enum, default_value = "rod", conflicts_with = "self_check")]
    arm: crate::arm_model::ArmModel,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Write a self-contained HTML report here.
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    /// Blind self-check over N generated logs with withheld effects.
    #[arg(long, value_name = "N", conflicts_with_all = ["log", "l1", "l2", "report"])]
    self_check: Option<usize>,
    /// Seed of the self-check's draws.
    #[arg(long, default_value_t = 1, requires = "self_check")]
    seed: u64,
    /// The effects the self-check draws: `robot` (plant.md's ten, the
    /// README's seeds), `human` (a person's arm's four, pairs with any
    /// other), `all` (the fourteen).
    #[arg(long, default_value = "robot", value_parser = ["robot", "human", "all"], requires = "self_check")]
    focus: String,
    /// Worker threads fitting candidates side by side (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

fn bar(length: usize, unit: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(length as u64);
    let style = ProgressStyle::with_template(&format!(
        "{{spinner}} {{bar:30}} {{pos}}/{{len}} {unit} {{msg}} [{{elapsed}}]"
    ))
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    Some(bar)
}

/// Runs `limb diagnose`.
///
/// # Errors
/// [`CliError::BadInput`] for an unreadable or malformed log, bad arm
/// lengths, a log too short to hold data out or whose commanded motion is
/// not the sim's; [`CliError::Internal`] when the sim fails.
pub fn run(args: &DiagnoseArgs) -> Result<(), CliError> {
    let threads = match args.threads {
        Some(0) => return Err(CliError::BadInput("--threads must be at least 1".into())),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    if let Some(logs) = args.self_check {
        let focus = blind::Focus::parse(&args.focus).unwrap_or(blind::Focus::Robot);
        return self_check(logs, args.seed, threads, focus, args.json);
    }
    let Some(log) = &args.log else {
        return Err(CliError::BadInput("diagnose needs LOG".into()));
    };
    let lengths = match (args.l1, args.l2) {
        (Some(l1), Some(l2)) => Lengths::Given(l1, l2),
        _ => Lengths::Fitted,
    };
    let records = crate::session_log::read_records(log)?;
    let progress = bar(
        limb_diagnosis::plant::arm::effects::candidates(0.0).len(),
        "candidates fitted",
    );
    let tell = |p: Progress| {
        if let Some(bar) = &progress {
            bar.set_position(p.done as u64);
            bar.set_message(p.candidate.to_string());
        }
    };
    let diagnosed =
        diagnose(lengths, args.arm.build(), &records, threads, &tell).map_err(|error| {
            use limb_diagnosis::plant::arm::DiagnoseError as E;
            let text = format!("{}: {error}", log.display());
            match error {
                E::Engine(_) | E::SelfCheck(_) => CliError::Internal(text),
                E::Arm(limb_diagnosis::plant::arm::ArmError::Sim(_)) => CliError::Internal(text),
                E::Arm(_) | E::TooShort(_) => CliError::BadInput(text),
            }
        })?;
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    if let Some(path) = &args.report {
        write_report(
            path,
            &Subject {
                model: &diagnosed.model,
                selection: &diagnosed.selection,
                source: &log.display().to_string(),
                held_out: &diagnosed.diagnosis.held_out,
                facts: &facts(&diagnosed.diagnosis),
                curves: &curves(&diagnosed.diagnosis),
            },
        )?;
    }
    if args.json {
        return print_json(&diagnosed.diagnosis);
    }
    emit(&human(&diagnosed.diagnosis))
}

/// The arm's findings for the report: the corrected arm beside the
/// kernel's estimate, and what remains unexplained.
fn facts(d: &Diagnosis) -> Vec<(String, String)> {
    let a = &d.arm;
    let mut facts = vec![(
        if a.given {
            "arm (given)".to_string()
        } else {
            "arm (fitted, corrected for the effects)".to_string()
        },
        format!(
            "l1 = {:.4} m, l2 = {:.4} m, shoulder ({:.4}, {:.4}) m, on a {} build",
            a.l1, a.l2, a.shoulder[0], a.shoulder[1], a.build
        ),
    )];
    if let Some([l1, l2]) = a.estimate {
        facts.push((
            "kernel estimate (limb estimate, auto)".to_string(),
            format!(
                "l1 = {l1:.4} m, l2 = {l2:.4} m (corrected − estimate: {:+.1} mm, {:+.1} mm)",
                1e3 * (a.l1 - l1),
                1e3 * (a.l2 - l2)
            ),
        ));
    }
    if let Some(resolution) = a.resolution_text() {
        facts.push(("how finely the log tells the arm".to_string(), resolution));
    }
    facts.push((
        "unexplained".to_string(),
        match &d.unexplained {
            None => "nothing beyond the noise".to_string(),
            Some(u) => format!(
                "{:.1} % of the held-out gap, {} {}{}",
                100.0 * u.share,
                u.signals.join(", "),
                match (u.t_start, u.t_end) {
                    (Some(a), Some(b)) => format!("from {a:.2} s to {b:.2} s"),
                    _ => String::new(),
                },
                u.band_hz.map_or(String::new(), |[lo, hi]| format!(
                    ", band {lo:.2}-{hi:.2} Hz"
                ))
            ),
        },
    ));
    facts
}

fn human(d: &Diagnosis) -> String {
    let mut text = format!("effect   {}\n", d.effect);
    for e in &d.effects {
        text += &format!(
            "  added  {:<17} held-out gap after {:.3}  {}\n",
            e.effect,
            e.held_out_after,
            e.parameters_text()
        );
    }
    let a = &d.arm;
    text += &format!(
        "arm      l1 = {:.4} m, l2 = {:.4} m, shoulder ({:.4}, {:.4}) m, on a {} build{}\n",
        a.l1,
        a.l2,
        a.shoulder[0],
        a.shoulder[1],
        a.build,
        match (a.given, a.estimate) {
            (true, _) => " (given)".to_string(),
            (false, Some([l1, l2])) =>
                format!(" (fitted, corrected for the effects; kernel estimate {l1:.4}, {l2:.4})"),
            (false, None) => " (fitted, corrected for the effects)".to_string(),
        }
    );
    if let Some(resolution) = a.resolution_text() {
        text += &format!("         {resolution}\n");
    }
    if let Some(u) = &d.unexplained {
        text += &format!(
            "unexplained {:.1} % of the gap, {}",
            100.0 * u.share,
            u.signals.join(", ")
        );
        if let (Some(a), Some(b)) = (u.t_start, u.t_end) {
            text += &format!(" from {a:.2} s to {b:.2} s");
        }
        if let Some([lo, hi]) = u.band_hz {
            text += &format!(", band {lo:.2}-{hi:.2} Hz");
        }
        text += "\n";
    }
    let g = &d.gap;
    text += &format!(
        "gap      {:.3} -> {:.3} ({}; shrink {:.1} %, held out: {})\n",
        g.before,
        g.after,
        g.metric,
        100.0 * g.shrink,
        d.held_out
    );
    let l = &d.location;
    text += &match (l.t_start, l.t_end) {
        (Some(a), Some(b)) => format!(
            "where    {} from {a:.2} s to {b:.2} s",
            l.signals.join(", ")
        ),
        _ => "where    nowhere beyond the noise".to_string(),
    };
    if let Some([lo, hi]) = l.band_hz {
        text += &format!(", band {lo:.2}-{hi:.2} Hz");
    }
    text += "\nranking  (held-out criterion, share of the gap explained, fitted parameters)\n";
    for r in &d.ranking {
        text += &format!(
            "  {:<17} {:>12.1} {:>7.1} %  {}\n",
            r.effect,
            r.criterion,
            100.0 * r.score,
            r.parameters_text()
        );
    }
    text
}

/// Writes the `--report` page of `subject` to `path`.
///
/// # Errors
/// [`CliError::BadInput`] when the file cannot be written.
pub fn write_report(path: &Path, subject: &Subject) -> Result<(), CliError> {
    std::fs::write(path, report::page(subject)).map_err(|error| {
        CliError::BadInput(format!(
            "{}: cannot write the report: {error}",
            path.display()
        ))
    })
}

fn self_check(
    logs: usize,
    seed: u64,
    threads: usize,
    focus: blind::Focus,
    json: bool,
) -> Result<(), CliError> {
    if logs == 0 {
        return Err(CliError::BadInput(
            "--self-check needs at least one log".into(),
        ));
    }
    let progress = bar(logs, "logs diagnosed");
    let summary = blind::run_focused(logs, seed, threads, focus, &|case| {
        if let Some(bar) = &progress {
            bar.inc(1);
            bar.set_message(format!("{:?} -> {:?}", case.truth, case.added));
        }
    })
    .map_err(|error| CliError::Internal(error.to_string()))?;
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    if json {
        return print_json(&summary);
    }
    emit(&confusion(&summary))
}

fn confusion(s: &Summary) -> String {
    let short = |name: &str| name.chars().take(6).collect::<String>();
    let mut text = format!(
        "blind self-check: {} logs, seed {}, lengths not given\n\
         single-effect and clean logs; rows: withheld effect; columns: first effect added\n{:>17}",
        s.logs, s.seed, ""
    );
    for name in &s.answers {
        text += &format!(" {:>6}", short(name));
    }
    text += "\n";
    for (name, row) in s.classes.iter().zip(&s.confusion) {
        text += &format!("{name:>17}");
        for count in row {
            text += &format!(" {count:>6}");
        }
        text += "\n";
    }
    text += &format!(
        "single-effect and clean logs: {}, top-1 accuracy {:.1} %\n\
         median held-out shrink when right {:.1} %\n\
         median relative parameter error when right {:.1} %\n\
         none answered for effects > 2x noise with the true arm: {} of {}\n\
         none answered for effects > 2x noise once the arm absorbs what it can (the bar): {} of {}\n\
         clean logs accused: {} of {}\n\
         corrected arm within 3 mm: {} of {} single-effect logs\n\
         pairs with both effects named: {} of {}\n",
        s.singles,
        100.0 * s.top1_accuracy,
        100.0 * s.median_shrink,
        100.0 * s.median_parameter_error,
        s.none_for_large_effects,
        s.large_effects,
        s.none_for_identifiable_effects,
        s.identifiable_effects,
        s.clean_accused,
        s.clean,
        s.arm_within_tolerance,
        s.single_effects,
        s.pairs_both_named,
        s.pairs
    );
    text
}
