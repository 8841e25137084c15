//! Runs every proof harness of `limb_verification::proofs` through the
//! `kani` stand-in: each draws its inputs many times from a fixed seed,
//! must accept most draws, and must reach every `kani::cover!`.

use limb_verification::kani_stand_in::run;
use limb_verification::proofs::*;

fn check(name: &str, draws: u64, harness: fn()) {
    let outcome = run(0x5EED ^ draws, draws, harness);
    println!("{name}: {outcome:?}");
    assert!(
        outcome.accepted * 2 > draws,
        "{name}: too many draws rejected: {outcome:?}"
    );
    assert!(
        outcome.unreached.is_empty(),
        "{name}: covers never reached: {:?}",
        outcome.unreached
    );
}

#[test]
fn stand_in_runs_every_harness() {
    check(
        "force monitor",
        20_000,
        proof_force_monitor_trips_beyond_limits,
    );
    check(
        "workspace monitor",
        20_000,
        proof_workspace_monitor_trips_beyond_limits,
    );
    check(
        "joint-limit monitor",
        20_000,
        proof_joint_limit_monitor_trips_beyond_limits,
    );
    check(
        "impedance",
        20_000,
        proof_impedance_wrench_is_saturated_and_finite,
    );
    check("step", 2_000, proof_step_is_total);
    check("gating", 500, proof_manipulate_needs_a_validated_model);
    check("latch", 500, proof_safe_stop_is_latched);
    check("estimator", 5_000, proof_estimator_is_total);
    check(
        "envelope monitor",
        20_000,
        proof_req_mon_011_envelope_monitor_trips_beyond_limits,
    );
}
