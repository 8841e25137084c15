//! `limb soak zenoh`: a node on the reference plant (`limb zenoh node`:
//! a `limb-session` session paced at 1 kHz, every step's sample published)
//! and a supervisor ([`limb_zenoh::supervisor::SupervisorStation`], as `limb zenoh
//! send`/`estop`), each with its own Zenoh session over TCP on loopback.
//!
//! Each session: the supervisor starts the estimation, waits for
//! Validated, approves the manipulation, finishes it, asks for an
//! estimation the kernel must refuse, stops (signed) and resets. A seeded
//! draw puts an emergency stop at a random time of the session (or none);
//! it must be acknowledged and end in SafeStop with origin
//! `emergency_stop`. After either stop the supervisor resets at once and
//! every 20 ms while the kernel refuses (`arm_not_still`), then resumes
//! with an estimation at once: a stop within the next second is a trip
//! caused by the resume, and a loss; so is a SafeStop sample whose command
//! does not carry the stop category `hold` (REQ-STOP-001, REQ-STOP-003). Every command is answered (accepted or refused) or counted as
//! missed; every sample the node published is received or counted as lost;
//! every kernel step has its step-log row and every frame its session-log
//! row.

use super::{counted_log, Budget, CountedLog, Ledger, LogRows, MemoryWatch, Soak};
use crate::error::CliError;
use limb_kernel::{Kernel, KernelConfig, StateKind, StopCategory};
use limb_session::kernel_wire::{Cause, Joints, KernelEvent, State};
use limb_sim::noise::Gaussian;
use limb_sim::robot::ReferenceRobot;
use limb_sim::{Plant, PlantParameters};
use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::{LinkSettings, SampleQos};
use limb_zenoh::node::Node;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::supervision::{LivenessPolicy, OnSupervisorLoss};
use limb_zenoh::supervisor::SupervisorStation;
use limb_zenoh::wire::{
    AckOutcome, AckSubject, EventMessage, KernelStatus, SampleMessage, StopOrigin,
    SupervisorCommand, WireFormat,
};
use limb_zenoh::zenoh::Wait;
use limb_zenoh::AdapterError;
use serde::de::DeserializeOwned;
use serde_json::{json, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

const ROBOT: &str = "soak-arm";
const SECRET: &[u8] = b"limb soak secret, 32 bytes long!";
/// How long a command waits for its ack.
const ANSWER: Duration = Duration::from_secs(3);
/// Zenoh lease [ms].
const LEASE_MS: u64 = 1000;
/// Control period of the node.
const PERIOD: Duration = Duration::from_millis(1);
/// Supervisor heartbeat period and the node's liveness timeout (as `limb
/// zenoh node`'s default).
const HEARTBEAT: Duration = Duration::from_millis(50);
const LIVENESS: Duration = Duration::from_millis(250);
/// A whole session's length [s]: the range an emergency stop is drawn
/// from (settle, the 29.3 s estimation motion, the manipulation).
const SESSION_SECONDS: f64 = 36.0;
/// Time for the supervisor's subscriptions to be routed before its
/// samples are counted.
const SETTLE: Duration = Duration::from_millis(100);
/// How long the manipulation runs before the supervisor finishes it.
const MANIPULATION: Duration = Duration::from_secs(4);
/// Pause between resets the kernel refused (the arm not yet still).
const RESET_RETRY: Duration = Duration::from_millis(20);
/// How long the supervisor retries a reset after a stop.
const RESET_PATIENCE: Duration = Duration::from_secs(5);
/// How long a resumed estimation is watched for a stop it caused.
const RESUME_WATCH: Duration = Duration::from_secs(1);
/// The manipulation target [rad].
const TARGET: Joints = Joints {
    shoulder_elevation: 1.0,
    elbow_flexion: 0.6,
};

/// What the supervisor side received, filled by Zenoh's callbacks.
#[derive(Default)]
struct Received {
    /// The step numbers of the samples received.
    steps: BTreeSet<u64>,
    /// The supervisor is set up (connected, subscribed, heard by the node).
    armed: bool,
    /// The first step received once armed.
    first_armed: Option<u64>,
    events: Vec<EventMessage>,
    status: Option<KernelStatus>,
    /// Samples in SafeStop by the stop category their command carried
    /// (`none` for none: a defect).
    stop_samples: BTreeMap<String, u64>,
}

/// The received telemetry, shared with the callbacks.
#[derive(Clone, Default)]
struct Tally(Arc<Mutex<Received>>);

impl Tally {
    fn with<T>(&self, f: impl FnOnce(&mut Received) -> T) -> T {
        let mut received = self
            .0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        f(&mut received)
    }
}

/// The supervisor's subscriptions to telemetry.
fn subscribe<T: DeserializeOwned + Send + 'static>(
    supervisor: &SupervisorStation,
    key: String,
    format: WireFormat,
    tally: &Tally,
    keep: fn(&mut Received, T),
) -> Result<limb_zenoh::zenoh::pubsub::Subscriber<()>, CliError> {
    let tally = tally.clone();
    supervisor
        .session()
        .declare_subscriber(key)
        .callback(move |sample| {
            if let Ok(value) = format.decode::<T>(&sample.payload().to_bytes()) {
                tally.with(|received| keep(received, value));
            }
        })
        .wait()
        .map_err(|error| internal(&AdapterError::from(error)))
}

fn internal(error: &AdapterError) -> CliError {
    CliError::Internal(format!("zenoh soak: {error}"))
}

/// Commands and e-stops of one session.
#[derive(Default)]
struct Counts {
    commands: u64,
    accepted: u64,
    refused: u64,
    missed: u64,
    estops: u64,
    estop_acks: u64,
    estop_missed: u64,
    /// Resets refused (`arm_not_still`: the stop still moving or the arm
    /// not yet still) before one was accepted.
    resets_refused: u64,
    /// Longest time from the first reset after a stop to the accepted one.
    longest_reset_wait: Duration,
    /// Estimations started at once after an accepted reset.
    resumes: u64,
    /// Resumes the kernel stopped within [`RESUME_WATCH`] (a monitor
    /// tripped by the resume).
    resume_trips: u64,
    /// Stops after which no reset was accepted within [`RESET_PATIENCE`].
    never_reset: u64,
}

/// The supervisor's script, the emergency stop at `estop_at` after
/// `start` (if any).
struct Script<'a> {
    supervisor: &'a mut SupervisorStation,
    node: &'a Node<CountedLog>,
    start: Instant,
    /// The soak's end: the script stops waiting there.
    budget: Budget,
    estop_at: Option<Duration>,
    estop_sent: bool,
    counts: Counts,
}

impl Script<'_> {
    /// Sends `command`; counts its ack or its absence. True when accepted.
    fn command(&mut self, command: SupervisorCommand) -> Result<bool, CliError> {
        self.counts.commands += 1;
        match self.supervisor.request(command, ANSWER) {
            Ok(ack) => match ack.outcome {
                AckOutcome::Accepted { .. } => {
                    self.counts.accepted += 1;
                    return Ok(true);
                }
                AckOutcome::Refused { .. } => self.counts.refused += 1,
            },
            Err(AdapterError::Timeout(_)) => self.counts.missed += 1,
            Err(error) => return Err(internal(&error)),
        }
        Ok(false)
    }

    /// Right after a stop (the first reset within the ack's round trip,
    /// well under 50 ms), resets every [`RESET_RETRY`] until the kernel
    /// accepts (it refuses `arm_not_still` while the stop's set-point moves
    /// or the arm is not still), then resumes at once with an estimation
    /// and watches it for [`RESUME_WATCH`]: a stop then is a trip caused by
    /// the resume (REQ-STOP-003).
    fn reset_and_resume(&mut self) -> Result<(), CliError> {
        let first = Instant::now();
        loop {
            if self.command(SupervisorCommand::Reset)? {
                break;
            }
            if first.elapsed() >= RESET_PATIENCE || self.budget.spent() {
                self.counts.never_reset += 1;
                return Ok(());
            }
            self.counts.resets_refused += 1;
            std::thread::sleep(RESET_RETRY);
        }
        self.counts.longest_reset_wait = self.counts.longest_reset_wait.max(first.elapsed());
        let grasp = |s| s == StateKind::Grasp;
        if !self.wait(grasp, ANSWER)? || !self.command(SupervisorCommand::StartEstimation)? {
            return Ok(());
        }
        self.counts.resumes += 1;
        // An emergency stop falling due meanwhile is not the resume's.
        let stopped = |s| s == StateKind::SafeStop;
        if self.wait(stopped, RESUME_WATCH)?
            && self.node.view().state() == Some(StateKind::SafeStop)
        {
            self.counts.resume_trips += 1;
        }
        Ok(())
    }

    /// Waits until the node's state satisfies `until` or `limit` passes;
    /// false when the emergency stop fell due (and was sent) or the soak's
    /// time ran out meanwhile.
    fn wait(
        &mut self,
        until: impl Fn(StateKind) -> bool,
        limit: Duration,
    ) -> Result<bool, CliError> {
        let deadline = Instant::now() + limit;
        loop {
            if self.estop_due() {
                self.estop()?;
                return Ok(false);
            }
            if self.budget.spent() {
                return Ok(false);
            }
            if self.node.view().state().is_some_and(&until) || Instant::now() >= deadline {
                return Ok(true);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    fn estop_due(&self) -> bool {
        !self.estop_sent && self.estop_at.is_some_and(|at| self.start.elapsed() >= at)
    }

    /// Sends the emergency stop and waits for its ack.
    fn estop(&mut self) -> Result<(), CliError> {
        self.estop_sent = true;
        self.counts.estops += 1;
        let sequence = self.supervisor.emergency_stop().map_err(|e| internal(&e))?;
        let ack = self.supervisor.wait_ack(
            |ack| ack.subject == AckSubject::EmergencyStop && ack.sequence == Some(sequence),
            ANSWER,
        );
        match ack {
            Ok(_) => self.counts.estop_acks += 1,
            Err(AdapterError::Timeout(_)) => self.counts.estop_missed += 1,
            Err(error) => return Err(internal(&error)),
        }
        Ok(())
    }

    /// The whole session's script; false when the e-stop or the soak's end
    /// cut it short.
    fn run(&mut self) -> Result<bool, CliError> {
        let any = |_: StateKind| false;
        let settled = self.wait(any, Duration::from_millis(200))?;
        if !settled {
            return Ok(false);
        }
        self.command(SupervisorCommand::StartEstimation)?;
        let validated = |s| matches!(s, StateKind::Validated | StateKind::SafeStop);
        if !self.wait(validated, Duration::from_secs(60))? {
            return Ok(false);
        }
        self.command(SupervisorCommand::ApproveManipulation { target: TARGET })?;
        if !self.wait(any, MANIPULATION)? {
            return Ok(false);
        }
        self.command(SupervisorCommand::FinishManipulation)?;
        if !self.wait(any, Duration::from_millis(100))? {
            return Ok(false);
        }
        // Refused by the kernel (not in Grasp): still answered.
        self.command(SupervisorCommand::StartEstimation)?;
        if self.estop_due() {
            self.estop()?;
            return Ok(false);
        }
        self.command(SupervisorCommand::Stop)?;
        self.reset_and_resume()?;
        Ok(true)
    }
}

/// What one session showed.
struct Session {
    format: WireFormat,
    estop_at: Option<f64>,
    counts: Counts,
    /// Transitions into SafeStop, by origin (or cause, without one).
    stops: BTreeMap<String, u64>,
    /// Each of them, its kernel time and the state it stopped.
    stop_times: Vec<String>,
    /// SafeStop samples by their stop category.
    stop_samples: BTreeMap<String, u64>,
    steps: u64,
    rows: LogRows,
    stale_steps: u64,
    published: u64,
    received: u64,
    dropped_at_node: u64,
    overruns: u64,
    /// Steps after the last status the supervisor received (their samples
    /// are not judged: the node's drop count for them is unknown).
    tail_steps: u64,
    /// Steps published before the first sample the supervisor received
    /// once set up (while its subscriptions were being routed; not
    /// judged).
    before_subscription: u64,
    completed: bool,
}

/// The name of a SafeStop transition: its origin, else its cause.
fn stop_of(event: &EventMessage) -> Option<String> {
    let KernelEvent::Transition {
        to: State::SafeStop,
        cause,
        ..
    } = &event.event
    else {
        return None;
    };
    Some(match (event.origin, cause) {
        (Some(StopOrigin::EmergencyStop), _) => "emergency_stop".into(),
        (Some(StopOrigin::Command), _) => "command".into(),
        (Some(StopOrigin::SupervisorLost), _) => "supervisor_lost".into(),
        (None, Cause::Stop { reason }) => reason
            .violation
            .as_ref()
            .map_or_else(|| reason.name.clone(), |v| v.limit_name.clone()),
        (None, other) => wire_name(other),
    })
}

fn event_time(event: &EventMessage) -> f64 {
    match &event.event {
        KernelEvent::Transition { time, .. }
        | KernelEvent::Refused { time, .. }
        | KernelEvent::LiftEnded { time, .. } => time.unwrap_or(f64::NAN),
    }
}

/// How the wire spells `value` (its serde name, or its tag for a tagged
/// enum), never its Rust `Debug`.
fn wire_name(value: &impl serde::Serialize) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(name)) => name,
        Ok(object) => object["cause"].as_str().unwrap_or("?").to_string(),
        Err(_) => "?".into(),
    }
}

fn event_from(event: &EventMessage) -> Option<State> {
    match &event.event {
        KernelEvent::Transition { from, .. } => Some(*from),
        _ => None,
    }
}

fn session(
    budget: Budget,
    seed: u64,
    estop_at: Option<f64>,
    format: WireFormat,
) -> Result<Session, CliError> {
    let key = CommandKey::new(SECRET).map_err(|e| internal(&e))?;
    let port = free_loopback_port().map_err(|e| internal(&e))?;
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let settings = LinkSettings {
        robot_id: ROBOT.into(),
        format,
        command_key: key.clone(),
        sample_decimation: 1,
        sample_qos: SampleQos::BATCHED,
        status_period: 0.05,
        liveness: LivenessPolicy {
            timeout: LIVENESS,
            on_loss: OnSupervisorLoss::Stop,
        },
    };
    let mut params = PlantParameters::new(0.30, 0.20);
    params.seed = seed;
    let plant = Plant::new(params).map_err(CliError::Internal)?;
    let kernel = Box::new(
        Kernel::new(KernelConfig::default())
            .map_err(|e| CliError::Internal(format!("kernel configuration: {e}")))?,
    );
    let robot = ReferenceRobot::new(plant, 1.0 / PERIOD.as_secs_f64(), f64::INFINITY);
    let listen =
        peer_config(std::slice::from_ref(&endpoint), &[], LEASE_MS).map_err(|e| internal(&e))?;
    let log = counted_log(None)?;
    let node = Node::spawn_observed(listen, &settings, Some(PERIOD), kernel, robot, log)
        .map_err(|e| internal(&e))?;
    let connect =
        peer_config(&[], std::slice::from_ref(&endpoint), LEASE_MS).map_err(|e| internal(&e))?;
    let mut supervisor =
        SupervisorStation::connect(connect, ROBOT, format, key).map_err(|e| internal(&e))?;
    let tally = Tally::default();
    let keys = supervisor.keys().clone();
    let _samples = subscribe(
        &supervisor,
        keys.sample(),
        format,
        &tally,
        |r, s: SampleMessage| {
            r.steps.insert(s.step);
            if s.command.state == State::SafeStop {
                let category = s.command.stop.map_or("none", StopCategory::name);
                *r.stop_samples.entry(category.into()).or_default() += 1;
            }
            if r.armed && r.first_armed.is_none() {
                r.first_armed = Some(s.step);
            }
        },
    )?;
    let _events = subscribe(
        &supervisor,
        keys.event(),
        format,
        &tally,
        |r, e: EventMessage| {
            r.events.push(e);
        },
    )?;
    let _status = subscribe(
        &supervisor,
        keys.kernel_alive(),
        format,
        &tally,
        |r, s: KernelStatus| {
            if r.status
                .is_none_or(|last| s.counters.steps >= last.counters.steps)
            {
                r.status = Some(s);
            }
        },
    )?;
    supervisor.wait_for_node(ANSWER).map_err(|e| internal(&e))?;
    supervisor
        .start_heartbeat(HEARTBEAT)
        .map_err(|e| internal(&e))?;
    std::thread::sleep(SETTLE);
    tally.with(|received| received.armed = true);
    let mut script = Script {
        supervisor: &mut supervisor,
        node: &node,
        start: Instant::now(),
        budget,
        estop_at: estop_at.map(Duration::from_secs_f64),
        estop_sent: false,
        counts: Counts::default(),
    };
    let completed = script.run()?;
    if script.estop_sent {
        // The stop must show as its event before the reset.
        let stopped = |s| s == StateKind::SafeStop;
        script.wait(stopped, ANSWER)?;
        script.reset_and_resume()?;
    }
    let counts = std::mem::take(&mut script.counts);
    // Telemetry of the last steps on its way.
    std::thread::sleep(Duration::from_millis(300));
    let (_, outcome, log) = node.end().map_err(|e| internal(&e))?;
    std::thread::sleep(Duration::from_millis(200));
    supervisor.close().map_err(|e| internal(&e))?;
    let received = tally.with(std::mem::take);
    let status = received.status.unwrap_or(KernelStatus {
        time: 0.0,
        state: State::Grasp,
        supervisor_present: false,
        counters: Default::default(),
    });
    // Samples are judged from the first one received once the supervisor
    // was set up (the node steps and publishes while the supervisor
    // connects and its subscriptions are routed) to the last status
    // received (which carries the node's drop count).
    let judged = status.counters.steps;
    let first = received.first_armed.unwrap_or(judged).min(judged);
    let mut stops = BTreeMap::new();
    let mut stop_times = Vec::new();
    for event in &received.events {
        if let Some(name) = stop_of(event) {
            let from = event_from(event).map_or("?".into(), |s| wire_name(&s));
            stop_times.push(format!("{name} at {:.3} s in {from}", event_time(event)));
            *stops.entry(name).or_default() += 1;
        }
    }
    Ok(Session {
        format,
        estop_at,
        counts,
        stops,
        stop_times,
        stop_samples: received.stop_samples,
        steps: outcome.steps,
        rows: LogRows::of(log)?,
        stale_steps: outcome.stale_steps,
        published: (judged - first).saturating_sub(status.counters.samples_dropped),
        received: received.steps.range(first..judged).count() as u64,
        before_subscription: first,
        dropped_at_node: status.counters.samples_dropped,
        overruns: status.counters.overruns,
        tail_steps: outcome.steps.saturating_sub(judged),
        completed,
    })
}

impl Session {
    fn json(&self) -> Value {
        json!({
            "format": wire_name(&self.format),
            "estop_at_s": self.estop_at,
            "completed_script": self.completed,
            "commands": self.counts.commands,
            "accepted": self.counts.accepted,
            "refused": self.counts.refused,
            "missed": self.counts.missed,
            "estops": self.counts.estops,
            "estop_acks": self.counts.estop_acks,
            "estop_missed": self.counts.estop_missed,
            "safe_stops": self.stop_times,
            "stop_samples_by_category": self.stop_samples,
            "resets_refused": self.counts.resets_refused,
            "longest_reset_wait_s": self.counts.longest_reset_wait.as_secs_f64(),
            "resumes": self.counts.resumes,
            "resume_trips": self.counts.resume_trips,
            "never_reset": self.counts.never_reset,
            "kernel_steps": self.steps,
            "log_rows": self.rows.frames,
            "step_log_rows": self.rows.steps,
            "stale_steps": self.stale_steps,
            "samples_published": self.published,
            "samples_received": self.received,
            "samples_dropped_at_node": self.dropped_at_node,
            "overruns": self.overruns,
            "tail_steps_not_judged": self.tail_steps,
            "steps_before_subscription": self.before_subscription,
        })
    }
}

/// Runs sessions until `budget` is spent (the last one is cut there).
pub fn soak(budget: &Budget, seed: u64) -> Result<Soak, CliError> {
    let mut draws = Gaussian::new(seed);
    let mut memory = MemoryWatch::default();
    let mut judge = Judge::default();
    for index in 0.. {
        if budget.spent() {
            break;
        }
        // Three sessions in four have an emergency stop, at a random time
        // within the time left.
        let left = budget.left().as_secs_f64().min(SESSION_SECONDS);
        let estop = draws.uniform() < 0.75;
        let at = 0.05 + draws.uniform() * left;
        let format = if index % 2 == 0 {
            WireFormat::Json
        } else {
            WireFormat::Cbor
        };
        let session_seed = seed.wrapping_mul(1000).wrapping_add(index as u64);
        let session = session(budget.clone(), session_seed, estop.then_some(at), format)?;
        judge.add(index, &session);
        memory.after_session(budget);
    }
    Ok(judge.finish(&memory))
}

/// The verdicts so far.
#[derive(Default)]
struct Judge {
    ledger: Ledger,
    stops: BTreeMap<String, u64>,
    scripts_completed: u64,
    resumes: u64,
    resets_refused: u64,
    longest_reset_wait: Duration,
}

impl Judge {
    fn add(&mut self, index: usize, s: &Session) {
        for (name, count) in &s.stops {
            *self.stops.entry(name.clone()).or_default() += count;
        }
        if let Some(missing) = s.rows.missing(s.steps, s.stale_steps) {
            self.ledger.lose(format!("session {index}: {missing}"));
        }
        if s.counts.missed + s.counts.estop_missed > 0 {
            self.ledger.lose(format!(
                "session {index}: {} commands and {} emergency stops without an ack",
                s.counts.missed, s.counts.estop_missed
            ));
        }
        let estop_stops = s.stops.get("emergency_stop").copied().unwrap_or(0);
        let other_stops: u64 = s
            .stops
            .iter()
            .filter(|(name, _)| !matches!(name.as_str(), "emergency_stop" | "command"))
            .map(|(_, count)| count)
            .sum();
        // An e-stop that found the kernel already stopped (by another
        // stop, counted there) moves nothing.
        if estop_stops != s.counts.estops && other_stops == 0 {
            self.ledger.lose(format!(
                "session {index}: {} emergency stops, {estop_stops} SafeStop events with origin emergency_stop",
                s.counts.estops
            ));
        }
        // Every stop of this soak (emergency stops, signed stops) is a
        // hold, on every SafeStop sample (REQ-STOP-001).
        if let Some((category, count)) = s.stop_samples.iter().find(|(c, _)| c.as_str() != "hold") {
            self.ledger.lose(format!(
                "session {index}: {count} SafeStop samples with stop category {category}, expected hold"
            ));
        }
        if s.counts.resume_trips + s.counts.never_reset > 0 {
            self.ledger.lose(format!(
                "session {index}: {} resumes stopped within {} s, {} stops never reset",
                s.counts.resume_trips,
                RESUME_WATCH.as_secs_f64(),
                s.counts.never_reset
            ));
        }
        if s.received != s.published {
            self.ledger.lose(format!(
                "session {index}: {} samples received of {} published",
                s.received, s.published
            ));
        }
        self.scripts_completed += u64::from(s.completed);
        self.resumes += s.counts.resumes;
        self.resets_refused += s.counts.resets_refused;
        self.longest_reset_wait = self.longest_reset_wait.max(s.counts.longest_reset_wait);
        self.ledger.add(s.json());
    }

    fn finish(self, memory: &MemoryWatch) -> Soak {
        let figures = json!({
            "scripts_completed": self.scripts_completed,
            "safe_stops": self.stops,
            "resumes_after_reset": self.resumes,
            "resets_refused_arm_not_still": self.resets_refused,
            "longest_reset_wait_s": self.longest_reset_wait.as_secs_f64(),
        });
        self.ledger.finish("zenoh", figures, memory)
    }
}
