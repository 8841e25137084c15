//! The estimators on the six noisy benchmark logs of `plant.md` (Table 1).
//! Ground truth (Table 1 lengths, logged shoulder) is used only to score.

mod support {
    pub mod logs;
}

use limb_kernel::estimation::{estimate_arm, Method};
use limb_kernel::validate::{validate, ValidationLimits};
use support::logs;

/// `Auto` recovers l1 and l2 within 1 mm and the shoulder within 2 mm on all
/// six arms, and the default validator accepts every estimate.
#[test]
fn auto_is_accurate_and_validated_on_the_six_noisy_logs() {
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let (l1, l2) = logs::case_lengths(case);
        let estimate = estimate_arm(&log.path, Method::Auto).expect("estimate");
        let shoulder = log.shoulder.expect("truth column");
        assert!(
            (estimate.upper_arm_length - l1).abs() <= 1e-3,
            "case {case}: l1 {estimate:?}"
        );
        assert!(
            (estimate.forearm_length - l2).abs() <= 1e-3,
            "case {case}: l2 {estimate:?}"
        );
        assert!(
            estimate.shoulder.distance(shoulder) <= 2e-3,
            "case {case}: shoulder {estimate:?}"
        );
        let grasp_start = log.path[0].pose.point();
        validate(&estimate, grasp_start, &ValidationLimits::default())
            .unwrap_or_else(|r| panic!("case {case}: rejected {r:?}"));
    }
}

/// The paper's methods stay within 1 mm too on noise of `plant.md`.
#[test]
fn hough_and_ls_are_within_a_millimetre_on_the_six_noisy_logs() {
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let (l1, l2) = logs::case_lengths(case);
        for method in [Method::Hough, Method::Ls] {
            let e = estimate_arm(&log.path, method).expect("estimate");
            assert!(
                (e.upper_arm_length - l1).abs() <= 1e-3,
                "case {case} {method:?}: {e:?}"
            );
            assert!(
                (e.forearm_length - l2).abs() <= 1e-3,
                "case {case} {method:?}: {e:?}"
            );
        }
    }
}

/// Outliers (every 37th sample thrown 5 cm off) and a short corrupted
/// stretch (0.2 s, 10 cm off, in either phase) move the `Auto` estimate by
/// less than 3 mm.
#[test]
fn outliers_and_a_corrupted_stretch_move_auto_by_less_than_three_mm() {
    let log = logs::read("noisy/case3.csv");
    let clean = estimate_arm(&log.path, Method::Auto).expect("clean");
    let corrupt = |keep: &dyn Fn(usize) -> bool, dx: f64, dz: f64| {
        let mut path = log.path.clone();
        for (index, sample) in path.iter_mut().enumerate() {
            if !keep(index) {
                sample.pose.x += dx;
                sample.pose.z += dz;
            }
        }
        path
    };
    let cases = [
        ("outliers", corrupt(&|i| i % 37 != 0, 0.05, -0.03)),
        (
            "stretch in phase 1",
            corrupt(&|i| !(800..820).contains(&i), 0.0, 0.1),
        ),
        (
            "stretch in phase 2",
            corrupt(&|i| !(1800..1820).contains(&i), 0.0, 0.1),
        ),
    ];
    for (name, path) in cases {
        let e = estimate_arm(&path, Method::Auto).unwrap_or_else(|err| panic!("{name}: {err:?}"));
        let moved = (e.upper_arm_length - clean.upper_arm_length)
            .abs()
            .max((e.forearm_length - clean.forearm_length).abs())
            .max(e.shoulder.distance(clean.shoulder))
            .max(e.elbow.distance(clean.elbow));
        assert!(moved < 3e-3, "{name}: moved {moved} m: {e:?}");
    }
}
