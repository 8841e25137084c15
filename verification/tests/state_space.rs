//! REQ-SM-001, REQ-SM-005, REQ-SM-006, REQ-MON-007, REQ-MON-013: breadth-first
//! exploration of the state machine over its event alphabet, every
//! transition checked; every state must be reached and no property may fail.

use limb_kernel::{KernelConfig, StateKind};
use limb_verification::explore::{expected_stop_limits, explore, StopKind};

/// REQ-SM-001, REQ-SM-005, REQ-MON-007, REQ-MON-013: every abstract state
/// and transition reached from a fresh kernel passes every check (a stop
/// only for a cause the inputs show among them).
#[test]
fn req_sm_001_state_space_exploration_finds_no_violation() {
    let report = explore(KernelConfig::default(), 8).unwrap_or_else(|failure| panic!("{failure}"));
    println!(
        "state-space exploration: {} abstract states, {} distinct transitions, {} transitions checked, depth {}",
        report.states.len(),
        report.edges.len(),
        report.transitions,
        report.depth
    );
    for state in &report.states {
        println!("  {state:?}");
    }
    for state in StateKind::ALL {
        assert!(
            report.states.iter().any(|(kind, _)| *kind == state),
            "{state:?} never reached"
        );
    }
    for code in expected_stop_limits() {
        assert!(
            report
                .states
                .contains(&(StateKind::SafeStop, Some(StopKind::Monitor(code)))),
            "no stop by limit {code}"
        );
    }
    assert!(report
        .states
        .contains(&(StateKind::SafeStop, Some(StopKind::Operator))));
    assert!(report
        .states
        .contains(&(StateKind::SafeStop, Some(StopKind::Estimation))));
}
