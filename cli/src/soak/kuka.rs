//! `limb soak kuka`: the FRI client with the kernel inside (an
//! [`limb_kuka::robot::FriRobot`] in a `limb-session` session, as `limb kuka
//! run`) against the simulated controller (`limb kuka sim-controller`), paced
//! at 1 kHz, over real UDP on loopback ([`limb_kuka::loopback`]).
//!
//! Each session starts from Grasp under the scripted operator and ends when
//! it completes a manipulation or stops. A seeded draw picks one fault of
//! [`CASES`] (or none) and a controller cycle to inject it at, anywhere in
//! a whole session's length; a fault ends the session in its named stop
//! (the limb-kuka README's fault table), or is ridden through. Faults that
//! stop the kernel only because the robot stops following ("request stop")
//! do so only while the kernel moves the arm; injected in Grasp or
//! Validated they may be ridden through. A fault ridden through while the
//! arm is still may, while it moves, make the robot miss commands and then
//! catch up with the moving set-point: a force transient that the
//! force-rate monitor may stop (`StoppedByItsTransient`, counted apart).

use super::{counted_log, first_stop, Budget, Ledger, LogRows, MemoryWatch, Soak};
use crate::error::CliError;
use limb_kernel::trace::{Event, TraceEvent};
use limb_kernel::{KernelConfig, StateKind, StopCategory};
use limb_kuka::faults::{FaultKind, FaultSchedule, ScheduledFault};
use limb_kuka::loopback::run_loopback_observed;
use limb_kuka::messages::SessionState;
use limb_kuka::robot::FriRobot;
use limb_kuka::sim_controller::{Pacing, SimSettings, SimStats};
use limb_kuka::FriVersion;
use limb_session::operator::completes_session;
use limb_session::{Observer, Operator, SessionPlan};
use limb_sim::noise::Gaussian;
use limb_sim::PlantParameters;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Controller cycles of a whole fault-free session at 1 kHz (settle, the
/// estimation motion, approval, the manipulation and its 1 s hold: about
/// 26 400): the range a fault's start is drawn from.
const SESSION_CYCLES: u64 = 27_000;
/// Cycles after a ridden-through fault's window within which a stop is
/// still blamed on it.
const AFTERMATH: u64 = 200;
/// Paced: cycles before a stop within which a timing disturbance of the
/// machine (periods lost to an overrun, a reply to a delivered datagram
/// missed) is taken as the stop's cause. The longest reach of such a
/// disturbance: the controller's quality window (100 cycles of misses make
/// the robot stop following); the force-rate monitor's window (50 ms) and
/// the client's watchdog (20 ms) are shorter.
const LOAD_WINDOW: u64 = limb_kuka::sim_controller::QUALITY_WINDOW as u64;

/// What a fault must end in.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Expect {
    /// The session goes on (no stop during the window and its aftermath).
    RideThrough,
    /// SafeStop with this cause and stop category (kernel/src/stop.rs's
    /// table, written here again so that a changed category fails the
    /// soak), whatever the kernel was doing.
    Stop(&'static str, StopCategory),
    /// SafeStop by `request stop` (the robot stopped following; a hold)
    /// when the kernel was moving the arm at injection; otherwise either
    /// that or riding through.
    StopWhileMoving,
}

impl Expect {
    /// The expectation in words (JSON and the report).
    fn name(self) -> String {
        match self {
            Expect::RideThrough => "ride_through".into(),
            Expect::Stop(cause, category) => format!("stop: {cause} ({})", category.name()),
            Expect::StopWhileMoving => "stop_while_moving".into(),
        }
    }
}

/// One fault the soak injects.
struct Case {
    kind: FaultKind,
    cycles: u64,
    expect: Expect,
}

const STALE: Expect = Expect::Stop("stale_sensor", StopCategory::RampDown);
const UNFOLLOWED: Expect = Expect::StopWhileMoving;

/// The faults, with the windows of the limb-kuka README's fault table.
const CASES: [Case; 13] = [
    case(FaultKind::RandomLoss(0.01), 800, Expect::RideThrough),
    case(FaultKind::BurstLoss, 50, STALE),
    case(FaultKind::Delay(2), 300, UNFOLLOWED),
    case(FaultKind::Duplicate, 100, Expect::RideThrough),
    case(FaultKind::Reorder, 8, Expect::RideThrough),
    case(FaultKind::CounterJump(5000), 1, Expect::RideThrough),
    case(FaultKind::PoorQuality, 30, UNFOLLOWED),
    case(FaultKind::Idle, 50, UNFOLLOWED),
    case(FaultKind::Garbage, 100, Expect::RideThrough),
    case(FaultKind::WrongCrc, 5, Expect::RideThrough),
    case(
        FaultKind::ClockBack(5),
        1000,
        Expect::Stop("sensor_time_reversed", StopCategory::RampDown),
    ),
    case(FaultKind::ClockStall, 1000, STALE),
    case(FaultKind::ClockRepeat, 1000, STALE),
];

const fn case(kind: FaultKind, cycles: u64, expect: Expect) -> Case {
    Case {
        kind,
        cycles,
        expect,
    }
}

/// The fault's name in the schedule text (`burst-loss`).
fn fault_name(fault: &ScheduledFault) -> String {
    let text = fault.to_string();
    text.split('@').next().unwrap_or_default().to_string()
}

/// Marks the end of the session (completed or stopped) for the
/// controller's thread, which then stops cycling.
struct EndWatch(Arc<AtomicBool>);

impl Observer<FriRobot> for EndWatch {
    fn event(&mut self, event: &TraceEvent) {
        let stops = matches!(
            event.event,
            Event::Transition {
                to: StateKind::SafeStop,
                ..
            }
        );
        if stops || completes_session(event) {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// What one session showed.
struct Session {
    fault: Option<ScheduledFault>,
    expect: Option<Expect>,
    /// Kernel state just before the fault's window opened (`None`: not
    /// reached).
    state_at_fault: Option<StateKind>,
    /// Controller cycle when the session was seen to end.
    ended_at: Option<u64>,
    stop: Option<String>,
    /// The category of that stop.
    category: Option<StopCategory>,
    completed: bool,
    record: Value,
    rows: LogRows,
    steps: u64,
    stale_steps: u64,
    missed: u64,
    unaccounted_cycles: i64,
    /// The machine's timing disturbances in the [`LOAD_WINDOW`] cycles
    /// before the session ended.
    load_before_end: LoadEvidence,
}

/// Timing disturbances of the machine in a window of cycles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct LoadEvidence {
    /// Send periods lost to overruns.
    periods_lost: u64,
    /// Replies to delivered datagrams that missed their deadline.
    replies_missed: u64,
}

impl LoadEvidence {
    /// The disturbances of `stats` within [`LOAD_WINDOW`] cycles before
    /// `end` (none when the end is unknown).
    fn before(stats: &SimStats, end: Option<u64>) -> Self {
        let Some(end) = end else {
            return Self::default();
        };
        stats
            .disturbances
            .iter()
            .filter(|d| d.cycle <= end && d.cycle + LOAD_WINDOW >= end)
            .fold(Self::default(), |sum, d| Self {
                periods_lost: sum.periods_lost + u64::from(d.periods_lost),
                replies_missed: sum.replies_missed + u64::from(d.reply_missed),
            })
    }

    fn any(&self) -> bool {
        self.periods_lost + self.replies_missed > 0
    }
}

/// How a session's fault ended, judged against what it must end in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Verdict {
    /// Ended as named.
    AsNamed,
    /// A fault the session rides through when the arm is still, injected
    /// while the kernel moved the arm (Estimate, Manipulate), ended in a
    /// ForceRate stop inside its window and aftermath: the robot missed
    /// commands, held, then caught up with the moving set-point, and the
    /// force-rate monitor caught that transient (a safe outcome the fault
    /// caused; counted apart, not a loss).
    StoppedByItsTransient,
    /// Not reached: the session completed or stopped first, or the soak
    /// ended.
    NotReached,
    /// Ended otherwise: a defect or, paced, a stop after the machine
    /// disturbed the loop's timing ([`LoadEvidence`]).
    Otherwise,
}

impl Verdict {
    /// Stable snake_case name (JSON and the report).
    const fn name(self) -> &'static str {
        match self {
            Verdict::AsNamed => "as_named",
            Verdict::StoppedByItsTransient => "stopped_by_its_transient",
            Verdict::NotReached => "not_reached",
            Verdict::Otherwise => "otherwise",
        }
    }
}

impl Session {
    fn verdict(&self) -> Option<Verdict> {
        let fault = self.fault?;
        let expect = self.expect?;
        let Some(state) = self.state_at_fault else {
            return Some(Verdict::NotReached);
        };
        let stopped_in_window = self
            .ended_at
            .is_some_and(|end| end <= fault.start + fault.cycles + AFTERMATH)
            && self.stop.is_some();
        let moving = matches!(state, StateKind::Estimate | StateKind::Manipulate);
        if expect == Expect::RideThrough
            && moving
            && stopped_in_window
            && self.stop.as_deref() == Some("force_rate")
        {
            return Some(Verdict::StoppedByItsTransient);
        }
        let ok = match expect {
            Expect::RideThrough => !stopped_in_window,
            Expect::Stop(name, category) => {
                self.stop.as_deref() == Some(name) && self.category == Some(category)
            }
            Expect::StopWhileMoving => {
                let asked = self.stop.as_deref() == Some("request stop")
                    && self.category == Some(StopCategory::Hold);
                asked || (!moving && !stopped_in_window)
            }
        };
        Some(if ok {
            Verdict::AsNamed
        } else {
            Verdict::Otherwise
        })
    }

    /// The session's record: its outcome and counts.
    fn json(&self) -> Value {
        let mut record = json!({
            "fault": self.fault.map(|f| f.to_string()),
            "expect": self.expect.map(Expect::name),
            "state_at_fault": self.state_at_fault.map(|s| s.title()),
            "ended_at_cycle": self.ended_at,
            "stop": self.stop,
            "category": self.category.map(StopCategory::name),
            "completed": self.completed,
            "verdict": self.verdict().map(Verdict::name),
            "log_rows": self.rows.frames,
            "step_log_rows": self.rows.steps,
            "kernel_steps": self.steps,
            "stale_steps": self.stale_steps,
            "unaccounted_cycles": self.unaccounted_cycles,
            "periods_lost_before_end": self.load_before_end.periods_lost,
            "replies_missed_before_end": self.load_before_end.replies_missed,
        });
        if let (Value::Object(fields), Value::Object(counts)) = (&mut record, &self.record) {
            fields.extend(counts.iter().map(|(k, v)| (k.clone(), v.clone())));
        }
        record
    }
}

/// One session: fault `case` (or none) at `start`, until it ends or
/// `budget` is spent.
fn session(
    options: &Options,
    budget: &Budget,
    seed: u64,
    case: Option<&Case>,
    start: u64,
) -> Result<Session, CliError> {
    let fault = case.map(|case| ScheduledFault {
        start,
        cycles: case.cycles,
        kind: case.kind,
    });
    let mut settings = SimSettings::new(options.version);
    settings.pacing = if options.unpaced {
        Pacing::AsFastAsPossible
    } else {
        Pacing::RealTime
    };
    settings.send_period_ms = 1;
    settings.faults = FaultSchedule::new(fault.into_iter().collect(), seed);
    let mut plant = PlantParameters::new(0.30, 0.20);
    plant.seed = seed;
    let ended = Arc::new(AtomicBool::new(false));
    let observer = (
        counted_log(options.only_log.as_deref())?,
        EndWatch(Arc::clone(&ended)),
    );
    let mut state_at_fault = None;
    let mut ended_at = None;
    let (run, (log, _)) = run_loopback_observed(
        settings,
        plant,
        KernelConfig::default(),
        Operator::new(SessionPlan::default()),
        observer,
        u64::MAX,
        |sim, state| {
            let cycle = sim.stats().cycles;
            if fault.is_some_and(|f| f.start == cycle) {
                state_at_fault = Some(state);
            }
            let over = ended.load(Ordering::Acquire);
            if over {
                ended_at = Some(cycle);
            }
            let cut = options.session_cycles.is_some_and(|n| {
                cycle >= fault.map_or(n, |f| n.max(f.start + f.cycles + AFTERMATH))
            });
            over || cut || budget.spent()
        },
    )
    .map_err(|error| CliError::Internal(format!("KUKA loopback: {error}")))?;
    let stats = run.sim.stats();
    let client = run.robot.record().client;
    let idle = stats.state_cycles[SessionState::Idle as usize];
    let answered = stats.replies_on_time + stats.missed_cycles + idle;
    let unaccounted_cycles = stats.cycles as i64 - answered as i64;
    let stop = first_stop(&run.events);
    Ok(Session {
        fault,
        expect: case.map(|c| c.expect),
        state_at_fault,
        ended_at,
        stop: stop.as_ref().map(|(name, _)| name.clone()),
        category: stop.and_then(|(_, category)| category),
        completed: run.outcome.completed,
        record: json!({
            "cycles": stats.cycles,
            "datagrams_sent": stats.datagrams_sent,
            "datagrams_dropped": stats.datagrams_dropped,
            "replies_on_time": stats.replies_on_time,
            "missed_cycles": stats.missed_cycles,
            "missed_with_delivery": stats.missed_with_delivery,
            "idle_cycles": idle,
            "stray_replies": stats.stray_replies,
            "periods_lost_to_overruns": stats.periods_lost,
            "non_finite_replies": stats.non_finite_replies,
            "client_handled": client.handled,
            "client_answered": client.answered,
            "client_rejected": client.rejected,
            "client_timeouts": client.timeouts,
            "client_duplicates": client.duplicates,
            "client_stale": client.stale_datagrams,
        }),
        rows: LogRows::of(log)?,
        steps: run.outcome.steps,
        stale_steps: run.outcome.stale_steps,
        missed: stats.missed_cycles,
        unaccounted_cycles,
        load_before_end: LoadEvidence::before(stats, ended_at),
    })
}

/// How the KUKA soak runs.
pub struct Options {
    /// Wire version.
    pub version: FriVersion,
    /// The controller runs as fast as the client answers and the session's
    /// clock is the robot's (as `tests/faults.rs`): every outcome is
    /// independent of the machine's speed and load, but a robot clock that
    /// stalls or repeats is not seen (those faults are left out).
    pub unpaced: bool,
    /// Cut each session after this many controller cycles (faults start
    /// within them; a session with a fault runs until its window and
    /// aftermath have passed): short sessions for a slow build.
    pub session_cycles: Option<u64>,
    /// Run only this session of the sequence (unpaced: the draws of the
    /// sessions before it are made and skipped).
    pub only: Option<u64>,
    /// Where to copy the log of the `only` session.
    pub only_log: Option<std::path::PathBuf>,
}

/// True when `case` can be judged under `options`.
fn applies(case: &Case, options: &Options) -> bool {
    let clock_only = matches!(case.kind, FaultKind::ClockStall | FaultKind::ClockRepeat);
    (options.version == FriVersion::V2_7 || case.kind != FaultKind::WrongCrc)
        && !(options.unpaced && clock_only)
}

/// Runs sessions until `budget` is spent.
pub fn soak(budget: &Budget, seed: u64, options: &Options) -> Result<Soak, CliError> {
    let mut draws = Gaussian::new(seed);
    let mut memory = MemoryWatch::default();
    let mut judge = Judge {
        unpaced: options.unpaced,
        ..Judge::default()
    };
    let cases: Vec<&Case> = CASES.iter().filter(|c| applies(c, options)).collect();
    for index in 0_u64.. {
        if budget.spent() {
            break;
        }
        // One draw in (cases + 1): no fault.
        let pick = (draws.uniform() * (cases.len() + 1) as f64) as usize;
        // Paced, within the time left (a 1 ms cycle).
        let left = if options.unpaced {
            SESSION_CYCLES
        } else {
            (budget.left().as_secs_f64() * 1000.0) as u64
        };
        let length = options.session_cycles.unwrap_or(SESSION_CYCLES);
        let start = 1 + (draws.uniform() * length.min(left) as f64) as u64;
        let session_seed = seed.wrapping_mul(1000).wrapping_add(index);
        let case = cases.get(pick).copied();
        match options.only {
            Some(only) if index < only => continue,
            Some(only) if index > only => break,
            _ => {}
        }
        judge.add(index, &session(options, budget, session_seed, case, start)?);
        memory.after_session(budget);
    }
    Ok(judge.finish(&memory))
}

/// The verdicts so far.
#[derive(Default)]
struct Judge {
    unpaced: bool,
    ledger: Ledger,
    by_fault: BTreeMap<String, BTreeMap<String, u64>>,
    unprovoked: BTreeMap<String, u64>,
    machine_caused: BTreeMap<String, u64>,
    completed: u64,
    fault_free_cycles: u64,
    fault_free_missed: u64,
}

impl Judge {
    fn add(&mut self, index: u64, s: &Session) {
        if let Some(missing) = s.rows.missing(s.steps, s.stale_steps) {
            self.ledger.lose(format!("session {index}: {missing}"));
        }
        if s.unaccounted_cycles != 0 {
            self.ledger.lose(format!(
                "session {index}: {} controller cycles neither answered, missed nor IDLE",
                s.unaccounted_cycles
            ));
        }
        let name = s.fault.as_ref().map_or("none".to_string(), fault_name);
        let entry = self.by_fault.entry(name.clone()).or_default();
        *entry.entry("sessions".into()).or_default() += 1;
        let outcome = match (&s.stop, s.completed) {
            (Some(stop), _) => match s.category {
                Some(category) => format!("{stop} ({})", category.name()),
                None => stop.clone(),
            },
            (None, true) => "completed".into(),
            (None, false) => "cut (session length or soak's end)".into(),
        };
        *entry.entry(format!("ended: {outcome}")).or_default() += 1;
        let verdict = s.verdict();
        if let Some(verdict) = verdict {
            *entry.entry(verdict.name().to_string()).or_default() += 1;
        }
        // A stop the fault did not make: before its window, or without one.
        let unmade = matches!(verdict, None | Some(Verdict::NotReached));
        let wrong = verdict == Some(Verdict::Otherwise);
        if let Some(stop) = s.stop.as_ref().filter(|_| unmade || wrong) {
            if unmade {
                *self.unprovoked.entry(stop.clone()).or_default() += 1;
            }
            // Paced, a stop no fault made is the machine's when its timing
            // was disturbed just before (any stop: a late frame, the robot
            // no longer following, the catch-up's force transient);
            // without that evidence it is a loss.
            if !self.unpaced && s.load_before_end.any() {
                *self.machine_caused.entry(stop.clone()).or_default() += 1;
            } else {
                let injected = s.state_at_fault.map_or("not injected".into(), |state| {
                    format!("injected in {state}")
                });
                let expected = s.expect.map_or("no stop".into(), Expect::name);
                self.ledger.lose(format!(
                    "session {index}: fault {name} ({injected}) ended in {outcome}, expected {expected}"
                ));
            }
        }
        self.completed += u64::from(s.completed);
        if s.fault.is_none() {
            self.fault_free_cycles += s.record["cycles"].as_u64().unwrap_or(0);
            self.fault_free_missed += s.missed;
        }
        self.ledger.add(s.json());
    }

    fn finish(self, memory: &MemoryWatch) -> Soak {
        let figures = json!({
            "completed_sessions": self.completed,
            "missed_cycles_fault_free_sessions": self.fault_free_missed,
            "cycles_fault_free_sessions": self.fault_free_cycles,
            "faults": self.by_fault,
            "stops_not_caused_by_an_injected_fault": self.unprovoked,
            "stops_after_the_machine_disturbed_the_timing": self.machine_caused,
        });
        self.ledger.finish("kuka", figures, memory)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use limb_kuka::sim_controller::Disturbance;

    fn stats_with(disturbances: &[(u64, u32, bool)]) -> SimStats {
        SimStats {
            disturbances: disturbances
                .iter()
                .map(|&(cycle, periods_lost, reply_missed)| Disturbance {
                    cycle,
                    periods_lost,
                    reply_missed,
                })
                .collect(),
            ..SimStats::default()
        }
    }

    /// A fault-free session that stopped on `stop` at cycle 5 000, with
    /// the machine's disturbances before it.
    fn stopped(stop: &str, evidence: LoadEvidence) -> Session {
        Session {
            fault: None,
            expect: None,
            state_at_fault: None,
            ended_at: Some(5_000),
            stop: Some(stop.into()),
            category: Some(StopCategory::Hold),
            completed: false,
            record: json!({ "cycles": 5_000 }),
            rows: LogRows {
                frames: 5_000,
                steps: 5_000,
            },
            steps: 5_000,
            stale_steps: 0,
            missed: 0,
            unaccounted_cycles: 0,
            load_before_end: evidence,
        }
    }

    #[test]
    fn only_disturbances_in_the_window_before_the_end_are_evidence() {
        let stats = stats_with(&[(100, 40, false), (4_899, 2, false), (4_950, 0, true)]);
        let evidence = LoadEvidence::before(&stats, Some(5_000));
        assert_eq!(
            evidence,
            LoadEvidence {
                periods_lost: 0,
                replies_missed: 1
            }
        );
        let evidence = LoadEvidence::before(&stats, Some(4_999));
        assert_eq!(evidence.periods_lost, 2);
        // After the end: not a cause.
        assert!(!LoadEvidence::before(&stats, Some(4_000)).any());
        assert!(!LoadEvidence::before(&stats, None).any());
    }

    /// Paced, a stop no fault made is the machine's only with evidence;
    /// unpaced, never.
    #[test]
    fn a_stop_no_fault_made_is_excused_only_by_the_machines_disturbance() {
        let disturbed = LoadEvidence {
            periods_lost: 300,
            replies_missed: 0,
        };
        let outcome = |unpaced: bool, evidence: LoadEvidence, stop: &str| {
            let mut judge = Judge {
                unpaced,
                ..Judge::default()
            };
            judge.add(0, &stopped(stop, evidence));
            let soak = judge.finish(&MemoryWatch::default());
            (
                soak.figures["losses_counted"].as_u64().unwrap(),
                soak.figures["stops_after_the_machine_disturbed_the_timing"][stop].as_u64(),
            )
        };
        assert_eq!(outcome(false, disturbed, "force_rate"), (0, Some(1)));
        assert_eq!(outcome(false, disturbed, "request stop"), (0, Some(1)));
        assert_eq!(
            outcome(false, LoadEvidence::default(), "stale_sensor"),
            (1, None)
        );
        assert_eq!(outcome(true, disturbed, "force_rate"), (1, None));
    }
}
