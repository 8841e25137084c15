//! The kernel over arbitrary sequences of (frame, request, time), drawn
//! structure-aware through `arbitrary`, every step checked by
//! `limb_verification::checks::checked_step` (no Manipulate without a
//! validated model, every violation → SafeStop in the same step, finite
//! saturated commands, SafeStop latched until a reset).
//!
//! # Theory of operation
//! A session starts from one of a few kernels taken from the synthetic
//! lift of `limb_verification::scenario` (in Grasp, part-way through the
//! estimation motion, Validated, Manipulating), so every state is a few
//! actions away; arbitrary frames alone would stop the kernel at once and
//! never reach a validated model. Then each [`Action`] is a frame near the
//! last one (or anywhere, NaN included), a run of frames continuing the
//! synthetic lift, an operator request, or new safety limits. Times move
//! by small steps or jump anywhere, backwards and non-finite included.

use arbitrary::{Arbitrary, Unstructured};
use limb_kernel::arm::{ArmGeometry, JointAngles};
use limb_kernel::config::SafetyLimits;
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, StateKind};
use limb_verification::checks::{checked_step, SessionOracle};
use limb_verification::scenario::{self, FRAME_PERIOD, TARGET};
use std::sync::OnceLock;

/// Most actions one input runs (keeps an execution short).
pub const MAX_ACTIONS: usize = 64;

/// A number: near a reference (small signed steps) or any `f64`.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Value {
    /// The reference plus `steps` × the quantity's small unit.
    Near(i8),
    /// Exactly this, NaN and infinities included.
    Raw(f64),
}

impl Value {
    fn around(self, reference: f64, unit: f64) -> f64 {
        match self {
            Value::Near(steps) => reference + f64::from(steps) * unit,
            Value::Raw(value) => value,
        }
    }
}

/// How far the kernel clock moves before an action.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Tick {
    /// One frame period (10 ms).
    Period,
    /// This many microseconds.
    Micros(u16),
    /// To exactly this time (backwards and non-finite included).
    To(f64),
}

/// One step of a session.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Action {
    /// One frame: pose and wrench near the last frame's, stamped `age`
    /// before the kernel time.
    Frame {
        /// Clock advance.
        tick: Tick,
        /// x, z [0.1 mm], psi [1 mrad] around the last pose.
        pose: [Value; 3],
        /// fx, fz [0.5 N], ty [0.05 N m] around the last wrench.
        wrench: [Value; 3],
        /// Frame age [ms] around 0.
        age: Value,
    },
    /// This many frames (10 ms apart) continuing the synthetic lift.
    Lift(u8),
    /// An operator request.
    Request(RequestChoice),
    /// Replaces one safety limit (a field index) by a value near it.
    UpdateLimit(u8, Value),
}

/// An operator request; the manipulation target is near the scenario's.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum RequestChoice {
    /// Grasp → Estimate.
    StartEstimation,
    /// Validated → Manipulate, to q1, q2 near the scenario target [10 mrad].
    ApproveManipulation(Value, Value),
    /// Manipulate → Validated.
    FinishManipulation,
    /// Anything → SafeStop.
    Stop,
    /// SafeStop → Grasp.
    Reset,
}

/// Where a session starts.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Start {
    /// In Grasp with one resting frame.
    Grasp,
    /// In Estimate, this many seconds (mod 26) into the synthetic lift.
    Lifting(u8),
    /// Validated at the end of the lift.
    Validated,
    /// Manipulating toward the scenario target.
    Manipulating,
}

/// One fuzz input: a start and the actions.
#[derive(Debug)]
pub struct Session {
    /// Where it starts.
    pub start: Start,
    /// What happens (at most [`MAX_ACTIONS`]).
    pub actions: Vec<Action>,
}

impl<'a> Arbitrary<'a> for Session {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        let start = Start::arbitrary(u)?;
        let mut actions = Vec::new();
        while actions.len() < MAX_ACTIONS && !u.is_empty() {
            actions.push(Action::arbitrary(u)?);
        }
        Ok(Self { start, actions })
    }
}

/// A kernel at a point of the scenario, with its clock.
struct Snapshot {
    kernel: Box<Kernel>,
    /// Kernel time [s].
    now: f64,
}

impl Snapshot {
    /// `kernel` at `now`, its trace drained (a session checks only its own
    /// events).
    fn new(mut kernel: Box<Kernel>, now: f64) -> Self {
        while kernel.pop_event().is_some() {}
        Self { kernel, now }
    }
}

/// Seconds of the synthetic lift a [`Start::Lifting`] can begin at.
const LIFT_STARTS: u8 = 26;

struct Starts {
    grasp: Snapshot,
    lifting: Vec<Snapshot>,
    validated: Snapshot,
    manipulating: Snapshot,
}

fn arm() -> ArmGeometry {
    scenario::arm(0.30, 0.25)
}

fn starts() -> &'static Starts {
    static STARTS: OnceLock<Starts> = OnceLock::new();
    STARTS.get_or_init(|| {
        let arm = arm();
        let grasp = Snapshot::new(Box::new(scenario::kernel_in_grasp(&arm)), 0.0);
        let mut lifting = Vec::new();
        let mut kernel = grasp.kernel.clone();
        let _ = kernel.request(Request::StartEstimation, 0.0);
        let mut i = 0u32;
        for second in 0..u32::from(LIFT_STARTS) {
            while i < second * 100 {
                i += 1;
                let t = f64::from(i) * FRAME_PERIOD;
                kernel.step(Some(&scenario::lift_frame(&arm, t)), t);
            }
            lifting.push(Snapshot::new(kernel.clone(), f64::from(i) * FRAME_PERIOD));
        }
        let (validated, now) = scenario::kernel_after_lift(&arm);
        assert_eq!(
            validated.state().kind(),
            StateKind::Validated,
            "scenario lift"
        );
        let mut manipulating = Box::new(validated.clone());
        manipulating
            .request(Request::ApproveManipulation(TARGET), now)
            .expect("the scenario target is reachable");
        Starts {
            grasp,
            lifting,
            validated: Snapshot::new(Box::new(validated), now),
            manipulating: Snapshot::new(manipulating, now),
        }
    })
}

/// The limits with one number changed: any of `SafetyLimits`'s numbers
/// (the kernel's own list, [`SafetyLimits::number_mut`]), moved by `value`.
fn with_limit(config: &KernelConfig, field: u8, value: Value) -> SafetyLimits {
    let mut l = config.limits;
    if let Some((_, slot)) = l.number_mut(usize::from(field) % SafetyLimits::NUMBERS) {
        *slot = value.around(*slot, *slot * 0.05);
    }
    l
}

/// One step, every property checked.
fn step(kernel: &mut Kernel, oracle: &mut SessionOracle, frame: PathSample, now: f64) {
    if let Err(property) = checked_step(kernel, oracle, &frame, now) {
        panic!("{property} (state {:?})", kernel.state().kind());
    }
}

/// Runs `session`, checking every step; panics with the property that
/// failed (a libFuzzer crash).
pub fn run(session: &Session) {
    let starts = starts();
    let snapshot = match session.start {
        Start::Grasp => &starts.grasp,
        Start::Lifting(second) => &starts.lifting[usize::from(second % LIFT_STARTS)],
        Start::Validated => &starts.validated,
        Start::Manipulating => &starts.manipulating,
    };
    let mut kernel = snapshot.kernel.clone();
    let mut now = snapshot.now;
    let mut oracle = SessionOracle::default();
    oracle.trust_current_model(&kernel);
    let arm = arm();
    let mut lift_time = now;
    let mut last = kernel
        .path()
        .last()
        .copied()
        .unwrap_or_else(|| scenario::lift_frame(&arm, now));
    for action in &session.actions {
        match *action {
            Action::Frame {
                tick,
                pose,
                wrench,
                age,
            } => {
                now = match tick {
                    Tick::Period => now + FRAME_PERIOD,
                    Tick::Micros(us) => now + f64::from(us) * 1e-6,
                    Tick::To(t) => t,
                };
                let p = last.pose;
                let w = last.wrench;
                let frame = PathSample {
                    time: now - age.around(0.0, 1e-3),
                    pose: Pose::new(
                        pose[0].around(p.x, 1e-4),
                        pose[1].around(p.z, 1e-4),
                        pose[2].around(p.psi, 1e-3),
                    ),
                    wrench: Wrench::new(
                        wrench[0].around(w.fx, 0.5),
                        wrench[1].around(w.fz, 0.5),
                        wrench[2].around(w.ty, 0.05),
                    ),
                };
                step(&mut kernel, &mut oracle, frame, now);
                last = frame;
            }
            Action::Lift(frames) => {
                for _ in 0..frames {
                    now += FRAME_PERIOD;
                    lift_time += FRAME_PERIOD;
                    let mut frame = scenario::lift_frame(&arm, lift_time);
                    frame.time = now;
                    step(&mut kernel, &mut oracle, frame, now);
                    last = frame;
                }
            }
            Action::Request(choice) => {
                let request = match choice {
                    RequestChoice::StartEstimation => Request::StartEstimation,
                    RequestChoice::ApproveManipulation(q1, q2) => {
                        Request::ApproveManipulation(JointAngles {
                            shoulder_elevation: q1.around(TARGET.shoulder_elevation, 0.01),
                            elbow_flexion: q2.around(TARGET.elbow_flexion, 0.01),
                        })
                    }
                    RequestChoice::FinishManipulation => Request::FinishManipulation,
                    RequestChoice::Stop => Request::Stop,
                    RequestChoice::Reset => Request::Reset,
                };
                let before = kernel.state().kind();
                let result = kernel.request(request, now);
                if let Err(property) = oracle.observe_events(&mut kernel) {
                    panic!("{property} after {request:?} in {before:?}");
                }
                if matches!(request, Request::Stop) {
                    assert_eq!(
                        kernel.state().kind(),
                        StateKind::SafeStop,
                        "a stop request did not stop"
                    );
                }
                if result.is_err() {
                    assert_eq!(
                        kernel.state().kind(),
                        before,
                        "a refused request changed state"
                    );
                }
            }
            Action::UpdateLimit(field, value) => {
                let limits = with_limit(kernel.config(), field, value);
                let before = *kernel.config();
                let proposed = KernelConfig { limits, ..before };
                let allowed = !matches!(
                    kernel.state().kind(),
                    StateKind::Estimate | StateKind::Manipulate
                );
                let outcome = kernel.update_limits(limits);
                assert_eq!(
                    outcome.is_ok(),
                    allowed && proposed.check().is_ok(),
                    "limits accepted or refused against REQ-SM-007"
                );
                if outcome.is_err() {
                    assert_eq!(
                        *kernel.config(),
                        before,
                        "refused limits changed the config"
                    );
                }
            }
        }
    }
}
