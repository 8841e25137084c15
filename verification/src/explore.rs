//! Exhaustive breadth-first exploration of the kernel's state machine over
//! an event alphabet, checking the safety properties of [`crate::checks`]
//! on every transition.
//!
//! # Theory of operation
//! The concrete kernel state is large (time, path, rate window), so states
//! are grouped by an abstraction: the [`StateKind`] plus, in SafeStop, the
//! kind of stop reason. The first concrete kernel that reaches an abstract
//! state represents it; every event of the alphabet is applied to every
//! representative, each transition is checked, and new abstract states are
//! queued. The search ends when no new abstract state appears (a fixpoint)
//! or at the depth bound, and reports what it covered.

use crate::checks::{checked_step, SessionOracle};
use crate::scenario::{
    arm as arm_of, lift_angles, FRAME_PERIOD, LIFT_DURATION, LIFT_WRENCH, TARGET,
};
use limb_kernel::arm::{ArmGeometry, JointAngles};
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::monitor::Limit;
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, State, StateKind, StopReason};
use std::collections::{BTreeSet, VecDeque};

/// The event alphabet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A fresh frame at the current pose.
    Frame,
    /// A frame whose force is beyond the limit.
    ForceSpike,
    /// A frame one second old.
    StaleFrame,
    /// The synthetic lift: frames following the scenario arm until the
    /// estimation motion ends (or the lift does).
    Lift,
    /// The same lift of an arm whose forearm (0.08 m) is implausibly short:
    /// the validator must reject it.
    ImplausibleLift,
    /// An operator request.
    Ask(Request),
}

/// Every event the exploration applies.
pub const ALPHABET: [Event; 11] = [
    Event::Frame,
    Event::ForceSpike,
    Event::StaleFrame,
    Event::Lift,
    Event::ImplausibleLift,
    Event::Ask(Request::StartEstimation),
    Event::Ask(Request::ApproveManipulation(TARGET)),
    Event::Ask(Request::ApproveManipulation(JointAngles {
        shoulder_elevation: 0.6,
        elbow_flexion: -0.6,
    })),
    Event::Ask(Request::FinishManipulation),
    Event::Ask(Request::Stop),
    Event::Ask(Request::Reset),
];

/// Abstract state: the state's name and, in SafeStop, why.
pub type AbstractState = (StateKind, Option<StopKind>);

/// Kinds of stop reasons distinguished by the abstraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum StopKind {
    /// A monitor, with its limit code.
    Monitor(u16),
    /// The operator.
    Operator,
    /// Estimation or validation failed.
    Estimation,
    /// Anything else.
    Other,
}

/// What the exploration covered.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Report {
    /// Distinct abstract states reached.
    pub states: BTreeSet<AbstractState>,
    /// Transitions applied and checked.
    pub transitions: usize,
    /// Distinct abstract transitions (from, event index, to).
    pub edges: BTreeSet<(AbstractState, usize, AbstractState)>,
    /// Deepest level explored.
    pub depth: usize,
}

#[derive(Clone)]
struct Node {
    kernel: Box<Kernel>,
    oracle: SessionOracle,
    now: f64,
    pose: Pose,
}

fn abstract_state(kernel: &Kernel) -> AbstractState {
    let stop = match kernel.state() {
        State::SafeStop(stop) => Some(match stop.reason() {
            StopReason::Monitor(violation) => StopKind::Monitor(violation.limit.code()),
            StopReason::Operator => StopKind::Operator,
            StopReason::EstimationFailed(_) | StopReason::ModelRejected(_) => StopKind::Estimation,
            _ => StopKind::Other,
        }),
        _ => None,
    };
    (kernel.state().kind(), stop)
}

/// One frame: its time stamp advances by one frame period, the clock by
/// that plus `age` (a stale frame when `age` exceeds the watchdog's limit).
fn frame(node: &mut Node, pose: Pose, wrench: Wrench, age: f64) -> Result<(), String> {
    node.now += FRAME_PERIOD + age;
    let sample = PathSample {
        time: node.now - age,
        pose,
        wrench,
    };
    checked_step(&mut node.kernel, &mut node.oracle, &sample, node.now)
        .map(|_| ())
        .map_err(|failure| format!("{failure} at t = {}", node.now))
}

fn apply(node: &mut Node, event: Event, arm: &ArmGeometry) -> Result<(), String> {
    match event {
        Event::Frame => frame(node, node.pose, LIFT_WRENCH, 0.0),
        Event::ForceSpike => frame(node, node.pose, Wrench::new(0.0, 2.0 * 45.0, 0.0), 0.0),
        Event::StaleFrame => frame(node, node.pose, LIFT_WRENCH, 1.0),
        Event::Lift => lift(node, arm),
        Event::ImplausibleLift => lift(node, &arm_of(0.30, 0.08)),
        Event::Ask(request) => {
            let before = node.kernel.state().kind();
            let result = node.kernel.request(request, node.now);
            if result.is_err() && node.kernel.state().kind() != before {
                return Err(format!("refused {request:?} changed the state"));
            }
            node.oracle
                .observe_events(&mut node.kernel)
                .map_err(|failure| format!("{failure} after {request:?}"))
        }
    }
}

/// Frames following the synthetic lift of `arm` until the estimation
/// motion ends (or the lift does).
fn lift(node: &mut Node, arm: &ArmGeometry) -> Result<(), String> {
    let start = node.now;
    let mut t = 0.0;
    while t < LIFT_DURATION {
        t += FRAME_PERIOD;
        node.pose = arm.forward(lift_angles(t));
        node.now = start + t - FRAME_PERIOD;
        frame(node, node.pose, LIFT_WRENCH, 0.0)?;
        if node.kernel.state().kind() != StateKind::Estimate && t > 1.0 {
            break;
        }
    }
    Ok(())
}

/// Explores from a fresh kernel (configuration `config`, scenario arm l1 =
/// 0.30 m, l2 = 0.20 m) up to `max_depth` events deep.
///
/// # Errors
/// The first property that failed, with the event path that led there.
pub fn explore(config: KernelConfig, max_depth: usize) -> Result<Report, String> {
    let arm = arm_of(0.30, 0.20);
    let kernel = Kernel::new(config).map_err(|e| format!("config: {e:?}"))?;
    let mut root = Node {
        kernel: Box::new(kernel),
        oracle: SessionOracle::default(),
        now: 0.0,
        pose: arm.forward(lift_angles(0.0)),
    };
    apply(&mut root, Event::Frame, &arm)?;
    let mut report = Report {
        states: BTreeSet::from([abstract_state(&root.kernel)]),
        transitions: 0,
        edges: BTreeSet::new(),
        depth: 0,
    };
    let mut queue = VecDeque::from([(root, 0usize, Vec::new())]);
    while let Some((node, depth, path)) = queue.pop_front() {
        report.depth = report.depth.max(depth);
        if depth == max_depth {
            continue;
        }
        let from = abstract_state(&node.kernel);
        for (index, event) in ALPHABET.iter().enumerate() {
            let mut next = node.clone();
            let mut next_path = path.clone();
            next_path.push(*event);
            apply(&mut next, *event, &arm).map_err(|e| format!("{e}; path {next_path:?}"))?;
            report.transitions += 1;
            let to = abstract_state(&next.kernel);
            report.edges.insert((from, index, to));
            if report.states.insert(to) {
                queue.push_back((next, depth + 1, next_path));
            }
        }
    }
    Ok(report)
}

/// Whether a limit code is one the exploration is expected to trip.
pub fn expected_stop_limits() -> [u16; 3] {
    [
        Limit::ForceMagnitude.code(),
        Limit::StaleSensor.code(),
        Limit::Speed.code(),
    ]
}
