//! The drive diagnosis on real hardware: the EMPS benchmark (Janot,
//! Gautier, Brunot, "Data Set and Reference Models of EMPS", Workshop on
//! Nonlinear System Identification Benchmarks, 2019), fitted on its
//! estimation run and scored on its validation run.
//!
//! Acceptance (issue #8): viscous and Coulomb friction are named, the
//! held-out force gap shrinks by at least 85 %, the fitted M, Fv and Fc
//! lie within 10 % of the authors' values, and what remains is localised.

use limb_diagnosis::plant::drive::outcome::{Run, MAX_EFFECTS};
use limb_diagnosis::plant::drive::{diagnose, read, CUTOFF};
use limb_diagnosis::Options;
use std::path::PathBuf;

/// The authors' rigid-body model: M [kg], Fv [N s/m], Fc [N].
const AUTHORS: [(&str, f64); 3] = [("mass", 95.11), ("fv", 203.5), ("fc", 20.39)];

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real/emps")
}

#[test]
fn emps_friction_is_named_fitted_and_closes_the_held_out_gap() {
    let (fit_file, held_file) = (data().join("estimation.csv"), data().join("validation.csv"));
    let fit = read(&fit_file).expect("EMPS estimation run (../shared/data/real/emps)");
    let held = read(&held_file).expect("EMPS validation run");
    let options = Options {
        max_effects: MAX_EFFECTS,
        ..Options::default()
    };
    let answer = diagnose(
        Run {
            name: "estimation.csv",
            log: &fit,
        },
        Some(Run {
            name: "validation.csv",
            log: &held,
        }),
        CUTOFF,
        &options,
    )
    .expect("diagnosis")
    .diagnosis;
    let names: Vec<&str> = answer.effects.iter().map(|e| e.effect.as_str()).collect();
    // Friction first: viscous and Coulomb are the first two effects added.
    assert!(
        names.len() >= 2
            && names[..2].contains(&"viscous_friction")
            && names[..2].contains(&"coulomb_friction"),
        "{names:?}"
    );
    // Each added effect lowers the held-out gap.
    let after: Vec<f64> = answer.effects.iter().map(|e| e.held_out_after).collect();
    assert!(after.windows(2).all(|w| w[1] <= w[0]), "{after:?}");
    assert!(answer.gap.held_out && answer.gap.metric == "nrmse_tau");
    assert!(answer.gap.shrink >= 0.85, "{:?}", answer.gap);
    let fitted = |name: &str| {
        answer
            .nominal
            .get(name)
            .or_else(|| answer.effects.iter().find_map(|e| e.params.get(name)))
            .copied()
    };
    for (name, value) in AUTHORS {
        let mine = fitted(name).unwrap_or(f64::NAN);
        assert!(
            (mine / value - 1.0).abs() < 0.1,
            "{name}: {mine} vs {value}"
        );
    }
    // What remains is localised: in the force, over a stretch of time.
    let remaining = &answer.remaining;
    assert_eq!(remaining.signals, vec!["tau".to_string()]);
    assert!(remaining.t_start.is_some() && remaining.t_end.is_some());
    assert!(answer.unexplained.contains("tau"), "{}", answer.unexplained);
}
