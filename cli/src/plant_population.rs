//! `limb population` on external plants: one whole kernel session per
//! plant command (`--plant-cmd`, repeatable) or per subject of the MyoArm
//! plant (`--plant myoarm --subjects NAME,NAME|all`), two at a time, and
//! the table of what each shows against the plant's anatomical truth:
//! validated or refused (and why), the model's errors, the joint extremes
//! from the plant's own joints, the largest interaction force, the final
//! state. The kernel runs with its default configuration: nothing is tuned
//! per subject and no truth reaches it.

use crate::arm_model::ArmModel;
use crate::error::{emit, print_json, CliError};
use crate::external::{endpoint, myoarm_command, plant_session, NamedPlant, PlantArgs, RobotError};
use crate::session_report::{JointExtremes, SessionReport};
use limb_kernel::{KernelConfig, StateKind};
use limb_plant::Endpoint;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Duration;

/// The plant options of `limb population`.
#[derive(Debug, Clone, clap::Args)]
pub struct PlantPopulationArgs {
    /// One session on the external plant started as this command line
    /// (repeatable: one session each).
    #[arg(long)]
    pub plant_cmd: Vec<String>,
    /// One session per subject of this plant of the repository.
    #[arg(long, value_enum, requires = "subjects")]
    pub plant: Option<NamedPlant>,
    /// The subjects (comma-separated), or `all` (the plant's list).
    #[arg(long, value_delimiter = ',')]
    pub subjects: Vec<String>,
    /// Seconds to wait for each line of a plant.
    #[arg(long, default_value_t = 10.0)]
    pub plant_timeout: f64,
    /// Write each session's log to DIR/NAME.csv.
    #[arg(long)]
    pub log_dir: Option<PathBuf>,
    /// The arm the estimator assumes (default `person`; `limb run --arm`).
    #[arg(long, value_enum)]
    pub arm: Option<ArmModel>,
}

impl PlantPopulationArgs {
    /// True when a plant population is asked for.
    pub fn given(&self) -> bool {
        !self.plant_cmd.is_empty() || self.plant.is_some()
    }
}

/// One plant's (or subject's) session.
#[derive(Clone, Debug, Serialize)]
pub struct SubjectOutcome {
    /// The subject's name, or the plant command.
    pub name: String,
    /// `tuning` or `held-out`, where the plant's subject list says (its
    /// `role`).
    pub group: Option<String>,
    /// The validator accepted a model.
    pub validated: bool,
    /// Why the kernel stopped instead of validating, in words.
    pub refusal: Option<String>,
    /// True l1, l2 [m] at the session's start.
    pub truth: [Option<f64>; 2],
    /// The model's l1, l2 [m].
    pub model: Option<[f64; 2]>,
    /// Model errors l1, l2 [m] (signed), shoulder and elbow distance [m].
    pub error_l1: Option<f64>,
    /// Error of l2 [m].
    pub error_l2: Option<f64>,
    /// Distance of the shoulder from the truth [m].
    pub error_shoulder: Option<f64>,
    /// Distance of the elbow at t = 0 from the truth [m].
    pub error_elbow: Option<f64>,
    /// Standard uncertainty of l1, l2 as the estimator reported it [m].
    pub uncertainty: Option<[f64; 2]>,
    /// Joint extremes during Estimate (the plant's own joints) [rad].
    pub estimate_joints: JointExtremes,
    /// Joint extremes during Manipulate [rad].
    pub manipulate_joints: JointExtremes,
    /// Largest measured interaction force [N].
    pub max_force_n: f64,
    /// State at the end.
    pub final_state: StateKind,
    /// The whole session (manipulation included) completed.
    pub completed: bool,
    /// The robot failure that ended the session, if one did.
    pub robot_error: Option<RobotError>,
}

/// Why the kernel stopped in Estimate, in words, if it did.
pub fn refusal(report: &SessionReport) -> Option<String> {
    report
        .events
        .iter()
        .find(|line| line.what.starts_with("Estimate → SafeStop"))
        .map(|line| line.what.clone())
}

/// The stop that ended Estimate, in the kernel's vocabulary: the stop
/// reason's name and what it names (`monitor: elbow_flexion`,
/// `model_rejected: geometry_inconsistent`), if Estimate was stopped.
pub fn refusal_reason(report: &SessionReport) -> Option<String> {
    let line = report
        .events
        .iter()
        .find(|line| line.what.starts_with("Estimate → SafeStop"))?;
    let event = serde_json::to_value(&line.event).ok()?;
    let reason = &event["reason"];
    let name = reason["name"].as_str()?;
    let detail = reason["violation"]["limit_name"]
        .as_str()
        .or_else(|| reason["cause"]["name"].as_str());
    Some(match detail {
        Some(detail) => format!("{name}: {detail}"),
        None => name.to_string(),
    })
}

impl SubjectOutcome {
    fn of(
        name: String,
        group: Option<String>,
        report: &SessionReport,
        failure: Option<RobotError>,
    ) -> Self {
        let joints = |state: &str| {
            report
                .joint_extremes
                .get(state)
                .copied()
                .unwrap_or_default()
        };
        let model = report.model.as_ref();
        Self {
            name,
            group,
            validated: model.is_some(),
            refusal: refusal(report),
            truth: [report.truth.l1, report.truth.l2],
            model: model.map(|m| [m.l1, m.l2]),
            error_l1: model.and_then(|m| m.error_l1),
            error_l2: model.and_then(|m| m.error_l2),
            error_shoulder: model.and_then(|m| m.error_shoulder),
            error_elbow: model.and_then(|m| m.error_elbow),
            uncertainty: model.and_then(|m| Some([m.uncertainty_l1?, m.uncertainty_l2?])),
            estimate_joints: joints("estimate"),
            manipulate_joints: joints("manipulate"),
            max_force_n: report.max_force_n,
            final_state: report.final_state,
            completed: report.completed,
            robot_error: failure,
        }
    }
}

/// The plant population's figures.
#[derive(Clone, Debug, Serialize)]
pub struct PlantPopulationReport {
    /// Sessions run.
    pub sessions: usize,
    /// Sessions whose model was validated.
    pub validated: usize,
    /// Validated models within 5 mm of the truth in l1 and l2.
    pub within_5mm: usize,
    /// Validated models more than 10 mm off in l1 or l2.
    pub over_10mm: usize,
    /// Sessions that ended in a robot failure.
    pub robot_failures: usize,
    /// Every session, in the order asked.
    pub outcomes: Vec<SubjectOutcome>,
}

/// A session to run: its name, group and plant.
struct Job {
    name: String,
    group: Option<String>,
    endpoint: Endpoint,
}

/// The subjects of the MyoArm plant: (name, group), from its own list.
fn myoarm_subjects() -> Result<Vec<(String, Option<String>)>, CliError> {
    let line = myoarm_command("--list-subjects")?;
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("exec {line}"))
        .output()
        .map_err(|e| CliError::Internal(format!("listing the MyoArm subjects: {e}")))?;
    let value: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| {
        CliError::Internal(format!(
            "the MyoArm plant's --list-subjects did not print JSON ({e}): {}",
            String::from_utf8_lossy(&out.stderr)
        ))
    })?;
    let subjects = value
        .as_array()
        .ok_or_else(|| CliError::Internal("--list-subjects: not a JSON array".into()))?;
    Ok(subjects
        .iter()
        .filter_map(|s| {
            let name = s["name"].as_str()?.to_string();
            let group = s["role"].as_str().or_else(|| s["group"].as_str());
            Some((name, group.map(String::from)))
        })
        .collect())
}

fn jobs(args: &PlantPopulationArgs, seed: u64) -> Result<Vec<Job>, CliError> {
    let mut jobs: Vec<Job> = args
        .plant_cmd
        .iter()
        .map(|line| Job {
            name: line.clone(),
            group: None,
            endpoint: Endpoint::Command(line.clone()),
        })
        .collect();
    let Some(plant) = args.plant else {
        return Ok(jobs);
    };
    if plant != NamedPlant::Myoarm {
        return Err(CliError::BadInput("--subjects needs --plant myoarm".into()));
    }
    let known = myoarm_subjects()?;
    let chosen: Vec<(String, Option<String>)> = if args.subjects.iter().any(|s| s == "all") {
        known
    } else {
        args.subjects
            .iter()
            .map(|name| {
                known
                    .iter()
                    .find(|(n, _)| n == name)
                    .cloned()
                    .ok_or_else(|| CliError::BadInput(format!("no MyoArm subject {name:?}")))
            })
            .collect::<Result<_, _>>()?
    };
    for (name, group) in chosen {
        let plant_args = PlantArgs {
            plant_cmd: None,
            plant_tcp: None,
            plant: Some(NamedPlant::Myoarm),
            subject: Some(name.clone()),
            plant_timeout: args.plant_timeout,
        };
        if let Some(endpoint) = endpoint(&plant_args, seed)? {
            jobs.push(Job {
                name,
                group,
                endpoint,
            });
        }
    }
    Ok(jobs)
}

/// Runs one session per plant of `args`, two at a time.
pub fn population(
    args: &PlantPopulationArgs,
    seed: u64,
) -> Result<PlantPopulationReport, CliError> {
    let jobs = jobs(args, seed)?;
    if let Some(dir) = &args.log_dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::BadInput(format!("{}: {e}", dir.display())))?;
    }
    let timeout = Duration::from_secs_f64(args.plant_timeout);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<SubjectOutcome, CliError>>>> =
        Mutex::new(jobs.iter().map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = jobs.get(i) else { break };
                let log = args.log_dir.as_ref().map(|dir| {
                    let file: String = job
                        .name
                        .chars()
                        .map(|c| {
                            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                                c
                            } else {
                                '_'
                            }
                        })
                        .collect();
                    dir.join(format!("{file}.csv"))
                });
                let outcome = plant_session(
                    &job.endpoint,
                    args.arm
                        .unwrap_or(ArmModel::Person)
                        .apply(KernelConfig::default()),
                    timeout,
                    log.as_deref(),
                    None,
                )
                .map(|s| {
                    SubjectOutcome::of(
                        job.name.clone(),
                        job.group.clone(),
                        &s.report,
                        s.failure.as_ref().map(RobotError::from),
                    )
                });
                if let Ok(mut results) = results.lock() {
                    results[i] = Some(outcome);
                }
            });
        }
    });
    let outcomes: Vec<SubjectOutcome> = results
        .into_inner()
        .map_err(|_| CliError::Internal("a session thread panicked".into()))?
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err(CliError::Internal("a session did not run".into()))))
        .collect::<Result<_, _>>()?;
    let errors = |o: &SubjectOutcome| {
        o.error_l1
            .zip(o.error_l2)
            .map(|(a, b)| a.abs().max(b.abs()))
    };
    Ok(PlantPopulationReport {
        sessions: outcomes.len(),
        validated: outcomes.iter().filter(|o| o.validated).count(),
        within_5mm: outcomes
            .iter()
            .filter(|o| errors(o).is_some_and(|e| e <= 5e-3))
            .count(),
        over_10mm: outcomes
            .iter()
            .filter(|o| errors(o).is_some_and(|e| e > 10e-3))
            .count(),
        robot_failures: outcomes.iter().filter(|o| o.robot_error.is_some()).count(),
        outcomes,
    })
}

/// The report as a Markdown table (the README's).
pub fn table(report: &PlantPopulationReport) -> String {
    let mm = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |v| format!("{:+.1}", v * 1e3));
    let mut text = String::from(
        "| subject | group | Estimate | l1 err [mm] | l2 err [mm] | shoulder off [mm] | elbow off [mm] \
         | max shoulder elev. [°] | max hyperext. [°] | max force [N] | final state |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for o in &report.outcomes {
        let estimate = match (&o.robot_error, o.validated, &o.refusal) {
            (Some(e), _, _) => format!("robot failure: {}", e.code),
            (None, true, _) => "validated".to_string(),
            (None, false, Some(reason)) => format!("refused: {}", reason.replace('|', "/")),
            (None, false, None) => "not reached".to_string(),
        };
        text.push_str(&format!(
            "| {} | {} | {estimate} | {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {} |\n",
            o.name,
            o.group.as_deref().unwrap_or("–"),
            mm(o.error_l1),
            mm(o.error_l2),
            o.error_shoulder
                .map_or_else(|| "–".into(), |v| format!("{:.1}", v * 1e3)),
            o.error_elbow
                .map_or_else(|| "–".into(), |v| format!("{:.1}", v * 1e3)),
            o.estimate_joints
                .max_shoulder_elevation
                .max(o.manipulate_joints.max_shoulder_elevation)
                .to_degrees(),
            o.estimate_joints
                .max_hyperextension
                .max(o.manipulate_joints.max_hyperextension)
                .to_degrees(),
            o.max_force_n,
            o.final_state,
        ));
    }
    text.push_str(&format!(
        "\n{} sessions: {} validated, {} within 5 mm (l1 and l2), {} over 10 mm, {} robot failures\n",
        report.sessions, report.validated, report.within_5mm, report.over_10mm, report.robot_failures
    ));
    text
}

/// `limb population` on plants.
pub fn run(args: &PlantPopulationArgs, seed: u64, json: bool) -> Result<(), CliError> {
    let report = population(args, seed)?;
    if json {
        print_json(&report)
    } else {
        emit(&table(&report))
    }
}
