//! How `Kernel::step` and `Kernel::request` treat what they are given
//! besides the state machine: a frame that repeats the last time stamp,
//! and a trace nobody drains.

use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::monitor::Limit;
use limb_kernel::state::State;
use limb_kernel::trace::TRACE_CAPACITY;
use limb_kernel::{Kernel, KernelConfig, PathSample, Request, StateKind, StopReason};

const PERIOD: f64 = 0.001;

fn frame(time: f64, fz: f64) -> PathSample {
    PathSample {
        time,
        pose: Pose::default(),
        wrench: Wrench::new(0.0, fz, 0.0),
    }
}

/// A frame that repeats the last time stamp is judged by the absolute
/// monitors but does not enter the rate window (its span from the last
/// frame is zero): a 20 N re-stamped reading, 400 N/s over the 50 ms
/// window were it counted, does not trip the 250 N/s force-rate monitor;
/// the same reading under a new time stamp does.
#[test]
fn a_repeated_time_stamp_does_not_enter_the_rate_window() {
    let config = KernelConfig::default();
    let window = config.limits.rate_window;
    let steps = (2.0 * window / PERIOD) as usize;
    let settled = |kernel: &mut Kernel| {
        for k in 0..=steps {
            let time = k as f64 * PERIOD;
            let command = kernel.step(Some(&frame(time, 0.0)), time);
            assert_eq!(command.state, StateKind::Grasp, "step {k}");
        }
        steps as f64 * PERIOD
    };
    let mut kernel = Kernel::new(config).unwrap();
    let last = settled(&mut kernel);
    let repeated = kernel.step(Some(&frame(last, 20.0)), last + 0.5 * PERIOD);
    assert_eq!(repeated.state, StateKind::Grasp);
    let next = kernel.step(Some(&frame(last + PERIOD, 0.0)), last + PERIOD);
    assert_eq!(next.state, StateKind::Grasp);

    let mut kernel = Kernel::new(config).unwrap();
    let last = settled(&mut kernel);
    let new = kernel.step(Some(&frame(last + PERIOD, 20.0)), last + PERIOD);
    assert_eq!(new.state, StateKind::SafeStop);
}

/// The trace keeps the newest events; those pushed out while nobody
/// drained it are counted, and a drained trace has lost none.
#[test]
fn an_undrained_trace_counts_the_events_it_lost() {
    let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
    kernel.step(Some(&frame(0.0, 0.0)), 0.0);
    assert_eq!(kernel.dropped_events(), 0);
    let refused = TRACE_CAPACITY + 5;
    for k in 0..refused {
        // Not allowed in Grasp: refused, and each refusal is an event.
        assert!(kernel
            .request(Request::FinishManipulation, k as f64 * PERIOD)
            .is_err());
    }
    assert_eq!(kernel.dropped_events(), 5);
    let mut kept = 0;
    while kernel.pop_event().is_some() {
        kept += 1;
    }
    assert_eq!(kept, TRACE_CAPACITY);
}

/// An arm at rest at any height is at rest: during the estimation, a
/// grasp held still 0.3 m above frame S's origin, its forearm at 0.2 rad,
/// reads zero velocity over the rate window (no wrench from the damper
/// while held, no speed stop while lifted), and a drop of
/// 10 mm in 1 ms (0.2 m/s over the 50 ms window) stops.
#[test]
fn an_arm_at_rest_off_the_origin_reads_zero_speed() {
    let config = KernelConfig::default();
    let mut kernel = Kernel::new(config).unwrap();
    let pose = Pose::new(0.1, 0.3, 0.2);
    let at = |k: usize, pose: Pose| PathSample {
        time: k as f64 * PERIOD,
        pose,
        wrench: Wrench::ZERO,
    };
    let steps = (3.0 * config.limits.rate_window / PERIOD) as usize;
    for k in 0..=steps {
        let command = kernel.step(Some(&at(k, pose)), at(k, pose).time);
        assert_eq!(command.state, StateKind::Grasp);
        // Held where it rests, still: neither spring nor damper pulls.
        let w = command.wrench;
        assert!(
            w.fx.abs().max(w.fz.abs()).max(w.ty.abs()) < 1e-9,
            "step {k}: {w:?}"
        );
    }
    let now = at(steps, pose).time;
    assert_eq!(
        kernel.request(Request::StartEstimation, now),
        Ok(StateKind::Estimate)
    );
    // The estimation's motion starts from the held pose.
    match kernel.state() {
        State::Estimate(estimating) => assert_eq!(estimating.grasp_pose(), pose),
        other => panic!("{:?}", other.kind()),
    }
    for k in steps + 1..=2 * steps {
        let command = kernel.step(Some(&at(k, pose)), at(k, pose).time);
        assert_eq!(command.state, StateKind::Estimate, "step {k}");
    }
    let k = 2 * steps + 1;
    let dropped = at(k, Pose::new(0.1, 0.29, 0.2));
    assert_eq!(
        kernel.step(Some(&dropped), dropped.time).state,
        StateKind::SafeStop
    );
}

/// REQ-EST-011: a frame's lateral position is a sensor value like the
/// others: finite, it is taken (any size: only Estimate reads it); not
/// finite, the running kernel stops on a non-finite sensor at once. A
/// frame stepped without one is taken as in the sagittal plane.
#[test]
fn a_non_finite_lateral_position_is_a_faulty_sensor() {
    for lateral in [0.0, -0.3, 2.0] {
        let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
        let command = kernel.step_with_lateral(Some(&frame(0.0, 0.0)), lateral, 0.0);
        assert_eq!(command.state, StateKind::Grasp, "{lateral}");
    }
    for lateral in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut kernel = Kernel::new(KernelConfig::default()).unwrap();
        kernel.step(Some(&frame(0.0, 0.0)), 0.0);
        let command = kernel.step_with_lateral(Some(&frame(PERIOD, 0.0)), lateral, PERIOD);
        assert_eq!(command.state, StateKind::SafeStop, "{lateral}");
        match kernel.stopped().unwrap().reason() {
            StopReason::Monitor(v) => assert_eq!(v.limit, Limit::NonFiniteSensor),
            other => panic!("{other:?}"),
        }
    }
}
