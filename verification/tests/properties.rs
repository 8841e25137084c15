//! Properties of the kernel under arbitrary sequences of sensor frames
//! (NaN and infinities included), clock readings and requests.
//!
//! Every step and request goes through the checking functions of
//! `limb_verification::checks`; the run also counts which states it
//! visited and fails if the sequences never reached Manipulate or SafeStop,
//! so the gating and latching properties are never checked vacuously.

use limb_kernel::arm::{ArmGeometry, JointAngles};
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, StateKind};
use limb_verification::checks::{checked_step, envelope_violation, SessionOracle};
use limb_verification::scenario::{
    arm, lift_angles, FRAME_PERIOD, LIFT_DURATION, LIFT_WRENCH, TARGET,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::cell::RefCell;
use std::collections::BTreeSet;

/// One thing that happens to the kernel.
#[derive(Clone, Debug)]
enum Op {
    /// A frame with arbitrary content; the clock advances by `dt` and the
    /// frame is stamped `lag` seconds before the clock.
    Frame {
        dt: f64,
        lag: f64,
        pose: Pose,
        wrench: Wrench,
    },
    /// A fresh frame at the last good pose.
    Hold { dt: f64 },
    /// A fresh frame at the last good pose with a wrench around the limits.
    Push { dt: f64, wrench: Wrench },
    /// A fresh frame displaced from the last good pose (table, workspace,
    /// joint limits, model fit).
    Nudge {
        dt: f64,
        dx: f64,
        dz: f64,
        dpsi: f64,
    },
    /// The wrench moves smoothly to `wrench` over 1 s, slower than the
    /// force-rate limit, so only the magnitude limits can trip.
    Ramp { wrench: Wrench },
    /// The pose moves smoothly by (dx, dz, dpsi) over 4 s, slower than the
    /// speed limit, so only the geometric limits can trip.
    Drift { dx: f64, dz: f64, dpsi: f64 },
    /// From Grasp: start estimating and feed the whole synthetic lift.
    Lift,
    /// An operator request.
    Ask(Request),
}

fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1.0..1.0f64,
        1 => -100.0..100.0f64,
        1 => any::<f64>(),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
    ]
}

fn request() -> impl Strategy<Value = Request> {
    prop_oneof![
        1 => Just(Request::StartEstimation),
        3 => Just(Request::ApproveManipulation(TARGET)),
        1 => (number(), number()).prop_map(|(a, b)| Request::ApproveManipulation(JointAngles {
            shoulder_elevation: a,
            elbow_flexion: b,
        })),
        1 => Just(Request::FinishManipulation),
        1 => Just(Request::Stop),
        1 => Just(Request::Reset),
    ]
}

fn op() -> impl Strategy<Value = Op> {
    let dt = prop_oneof![8 => 0.0..0.02f64, 1 => number()];
    prop_oneof![
        // Lags around the watchdog's 20 ms age limit, on both sides.
        3 => (dt.clone(), prop_oneof![3 => 0.0..0.01f64, 1 => 0.0..0.04f64, 1 => number()],
              (number(), number(), number()), (number(), number(), number()))
            .prop_map(|(dt, lag, (x, z, psi), (fx, fz, ty))| Op::Frame {
                dt, lag, pose: Pose::new(x, z, psi), wrench: Wrench::new(fx, fz, ty),
            }),
        3 => dt.clone().prop_map(|dt| Op::Hold { dt }),
        2 => (dt.clone(), -70.0..70.0f64, -70.0..70.0f64, -12.0..12.0f64)
            .prop_map(|(dt, fx, fz, ty)| Op::Push { dt, wrench: Wrench::new(fx, fz, ty) }),
        2 => (dt.clone(), -0.3..0.3f64, -0.3..0.3f64, -1.0..1.0f64)
            .prop_map(|(dt, dx, dz, dpsi)| Op::Nudge { dt, dx, dz, dpsi }),
        2 => (-70.0..70.0f64, -70.0..70.0f64, -12.0..12.0f64)
            .prop_map(|(fx, fz, ty)| Op::Ramp { wrench: Wrench::new(fx, fz, ty) }),
        2 => (-0.2..0.2f64, -0.2..0.2f64, -1.5..1.5f64)
            .prop_map(|(dx, dz, dpsi)| Op::Drift { dx, dz, dpsi }),
        2 => Just(Op::Lift),
        4 => request().prop_map(Op::Ask),
    ]
}

/// Drives one kernel through `ops`, checking every step and request.
struct Session {
    kernel: Kernel,
    oracle: SessionOracle,
    arm: ArmGeometry,
    now: f64,
    pose: Pose,
    visited: BTreeSet<u8>,
}

impl Session {
    fn new(arm: ArmGeometry) -> Self {
        Self {
            kernel: Kernel::new(KernelConfig::default()).unwrap(),
            oracle: SessionOracle::default(),
            arm,
            now: 0.0,
            pose: Pose::default(),
            visited: BTreeSet::new(),
        }
    }

    fn step(&mut self, frame: PathSample, now: f64) -> Result<(), TestCaseError> {
        let command = checked_step(&mut self.kernel, &mut self.oracle, &frame, now)
            .map_err(|failure| TestCaseError::fail(format!("{failure} at {frame:?}, now {now}")))?;
        self.visited.insert(command.state as u8);
        Ok(())
    }

    /// A frame stamped `now` at clock `now`.
    fn fresh(&mut self, now: f64, pose: Pose, wrench: Wrench) -> Result<(), TestCaseError> {
        self.step(
            PathSample {
                time: now,
                pose,
                wrench,
            },
            now,
        )
    }

    fn ask(&mut self, request: Request) -> Result<(), TestCaseError> {
        let _ = self.kernel.request(request, self.now);
        self.oracle
            .observe_events(&mut self.kernel)
            .map_err(|failure| TestCaseError::fail(format!("{failure} after {request:?}")))?;
        self.visited.insert(self.kernel.state().kind() as u8);
        Ok(())
    }

    /// `frames` fresh frames, 10 ms apart, at `pose` plus the pose offset
    /// and `wrench` replaced by the wrench of `at(s)`, s rising from 0 to 1
    /// with minimum-jerk timing (a zero wrench from `at` keeps `wrench`).
    fn glide(
        &mut self,
        frames: u32,
        pose: Pose,
        wrench: Wrench,
        at: impl Fn(f64) -> (Pose, Wrench),
    ) -> Result<(), TestCaseError> {
        for i in 1..=frames {
            let s = f64::from(i) / f64::from(frames);
            let (offset, w) = at(s * s * s * (10.0 - 15.0 * s + 6.0 * s * s));
            let now = self.advance(FRAME_PERIOD);
            let frame = PathSample {
                time: now,
                pose: Pose::new(pose.x + offset.x, pose.z + offset.z, pose.psi + offset.psi),
                wrench: if w == Wrench::ZERO { wrench } else { w },
            };
            self.step(frame, now)?;
            if self.kernel.state().kind() == StateKind::SafeStop {
                break;
            }
        }
        Ok(())
    }

    fn advance(&mut self, dt: f64) -> f64 {
        if dt.is_finite() && dt >= 0.0 {
            self.now += dt;
        }
        self.now
    }

    fn apply(&mut self, op: &Op) -> Result<(), TestCaseError> {
        match *op {
            Op::Frame {
                dt,
                lag,
                pose,
                wrench,
            } => {
                // A non-finite or negative dt becomes a bad clock reading.
                let now = if dt.is_finite() && dt >= 0.0 {
                    self.advance(dt)
                } else {
                    dt
                };
                self.step(
                    PathSample {
                        time: now - lag,
                        pose,
                        wrench,
                    },
                    now,
                )
            }
            Op::Hold { dt } => {
                let now = self.advance(dt.abs().min(0.02));
                self.fresh(now, self.pose, LIFT_WRENCH)
            }
            Op::Push { dt, wrench } => {
                let now = self.advance(dt.abs().min(0.02));
                self.step(
                    PathSample {
                        time: now,
                        pose: self.pose,
                        wrench,
                    },
                    now,
                )
            }
            Op::Nudge { dt, dx, dz, dpsi } => {
                let now = self.advance(dt.abs().min(0.02));
                let pose = Pose::new(self.pose.x + dx, self.pose.z + dz, self.pose.psi + dpsi);
                self.step(
                    PathSample {
                        time: now,
                        pose,
                        wrench: LIFT_WRENCH,
                    },
                    now,
                )
            }
            Op::Ramp { wrench } => self.glide(100, self.pose, LIFT_WRENCH, |s| {
                let from = LIFT_WRENCH;
                (
                    Pose::default(),
                    Wrench::new(
                        from.fx + s * (wrench.fx - from.fx),
                        from.fz + s * (wrench.fz - from.fz),
                        from.ty + s * (wrench.ty - from.ty),
                    ),
                )
            }),
            Op::Drift { dx, dz, dpsi } => self.glide(400, self.pose, LIFT_WRENCH, |s| {
                (Pose::new(s * dx, s * dz, s * dpsi), Wrench::ZERO)
            }),
            Op::Ask(request) => self.ask(request),
            Op::Lift => {
                if self.kernel.state().kind() != StateKind::Grasp {
                    return Ok(());
                }
                let start = self.advance(FRAME_PERIOD);
                self.pose = self.arm.forward(lift_angles(0.0));
                self.step(
                    PathSample {
                        time: start,
                        pose: self.pose,
                        wrench: LIFT_WRENCH,
                    },
                    start,
                )?;
                self.ask(Request::StartEstimation)?;
                let mut i = 0u32;
                while self.kernel.state().kind() == StateKind::Estimate {
                    i += 1;
                    let t = f64::from(i) * FRAME_PERIOD;
                    if t > LIFT_DURATION {
                        break;
                    }
                    let now = start + t;
                    self.now = now;
                    self.pose = self.arm.forward(lift_angles(t));
                    self.fresh(now, self.pose, LIFT_WRENCH)?;
                }
                Ok(())
            }
        }
    }
}

/// REQ-SM-005, REQ-SM-006, REQ-MON-001, REQ-MON-004, REQ-MON-005,
/// REQ-MON-007, REQ-MON-013, REQ-CMD-003, REQ-STOP-002: arbitrary sessions
/// (frames, clocks and requests, NaN and infinities included) keep every
/// per-step and session check of `limb_verification::checks` (a stop's
/// latch: one category, a set-point that stays at rest, a ramp-down's
/// force that never grows; a stop only for a cause the inputs show).
#[test]
fn arbitrary_sessions_keep_every_safety_property() {
    let visited = RefCell::new(BTreeSet::new());
    let strategy = (
        0.22..0.40f64,
        0.15..0.30f64,
        prop::collection::vec(op(), 1..40),
    );
    // A fixed seed: the coverage assertion below must not depend on luck.
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: 200,
            ..Config::default()
        },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    runner
        .run(&strategy, |(l1, l2, ops)| {
            let mut session = Session::new(arm(l1, l2));
            for op in &ops {
                session.apply(op)?;
            }
            visited.borrow_mut().extend(session.visited.iter().copied());
            Ok(())
        })
        .unwrap();
    let visited = visited.into_inner();
    for state in StateKind::ALL {
        assert!(
            visited.contains(&(state as u8)),
            "no generated session reached {state:?}"
        );
    }
}

proptest! {
    /// REQ-MON-011: the Estimate joint-limit monitor agrees with the
    /// independent check on any worst-case joints, finite or not, and the
    /// kernel's online estimator never yields an envelope that hides a
    /// non-finite pose.
    #[test]
    fn req_mon_011_envelope_monitor_matches_the_check(
        shoulder in prop_oneof![-4.0f64..4.0, Just(f64::NAN), Just(f64::INFINITY)],
        elbow in prop_oneof![-4.0f64..4.0, Just(f64::NAN), Just(f64::NEG_INFINITY)],
    ) {
        let config = KernelConfig::default();
        let monitor =
            limb_kernel::monitor::joint_limits::JointLimitMonitor::from_limits(&config.limits);
        let envelope = limb_kernel::monitor::joint_limits::JointEnvelope {
            max_shoulder_elevation: shoulder,
            min_elbow_flexion: elbow,
        };
        prop_assert_eq!(
            monitor.check_envelope(Some(envelope)).is_err(),
            envelope_violation(shoulder, elbow, &config)
        );
    }

    /// REQ-PANIC-001, REQ-CMD-001, REQ-MON-013: any single frame, any
    /// clock: `step` returns a finite command within the limits, and stops
    /// only for a cause the inputs show, from every state a session can be
    /// in after a lift.
    #[test]
    fn step_is_total_for_any_frame(lift in any::<bool>(), ops in prop::collection::vec(op(), 1..8)) {
        let mut session = Session::new(arm(0.30, 0.20));
        if lift {
            session.apply(&Op::Lift)?;
            session.apply(&Op::Ask(Request::ApproveManipulation(TARGET)))?;
        }
        for op in &ops {
            session.apply(op)?;
        }
    }
}
