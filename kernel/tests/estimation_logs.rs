//! The estimators on the six noisy benchmark logs of `plant.md` (Table 1).
//! Ground truth (Table 1 lengths, logged shoulder) is used only to score.

mod support {
    pub mod logs;
}

use limb_kernel::arm::elbow_from_grasp;
use limb_kernel::config::ValidationLimits;
use limb_kernel::estimation::online::{OnlineEstimator, OnlinePhase};
use limb_kernel::estimation::outlier::OUTLIER_REACH;
use limb_kernel::estimation::refine::{Progress, Refinement, ITERATIONS, SAMPLES_PER_STEP};
use limb_kernel::estimation::{estimate_arm, EstimateError, Method};
use limb_kernel::estimation::{estimate_online, ArmEstimate};
use limb_kernel::estimation::{DEPARTURE_WINDOW, LIFT_PSI};
use limb_kernel::geometry::Pose;
use limb_kernel::path::PathSample;
use limb_kernel::path::PATH_CAPACITY;
use limb_kernel::validate::validate;
use support::logs;

/// Margin over a figure the READMEs state (README.md, Estimation;
/// kernel/src/estimation/README.md, its tables) [m]: they give millimetres
/// to two decimals, so 0.01 mm covers their rounding (≤ 0.005 mm) and no
/// more; a change that costs more accuracy than that fails here, and the
/// figures are then re-measured, not the bounds loosened.
const MARGIN: f64 = 0.01e-3;

/// Errors |Δl1|, |Δl2| and the shoulder distance [m] of `estimate` on
/// noisy log `case`, printed in mm.
fn noisy_errors(case: usize, name: &str, estimate: &ArmEstimate, log: &logs::Log) -> [f64; 3] {
    let (l1, l2) = logs::case_lengths(case);
    let shoulder = log.shoulder.expect("truth column");
    let errors = [
        (estimate.upper_arm_length - l1).abs(),
        (estimate.forearm_length - l2).abs(),
        estimate.shoulder.distance(shoulder),
    ];
    println!(
        "case {case} {name}: l1 {:.4} mm, l2 {:.4} mm, shoulder {:.4} mm",
        errors[0] * 1e3,
        errors[1] * 1e3,
        errors[2] * 1e3
    );
    errors
}

/// Asserts `errors` (l1, l2, shoulder) within `claimed` [m] plus
/// [`MARGIN`].
fn assert_within(errors: [f64; 3], claimed: [f64; 3], what: &str) {
    for ((error, claimed), name) in errors.iter().zip(claimed).zip(["l1", "l2", "shoulder"]) {
        assert!(
            *error <= claimed + MARGIN,
            "{what}: {name} {:.4} mm beyond the stated {:.3} mm",
            error * 1e3,
            claimed * 1e3
        );
    }
}

/// `Auto` recovers l1, l2 and the shoulder on all six arms within the
/// README's 0.10 / 0.02 / 0.12 mm (measured: 0.104 / 0.019 / 0.116 mm at
/// worst) plus [`MARGIN`], and the default validator accepts every
/// estimate.
#[test]
fn auto_is_accurate_and_validated_on_the_six_noisy_logs() {
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let estimate = estimate_arm(&log.path, Method::Auto).expect("estimate");
        let errors = noisy_errors(case, "auto", &estimate, &log);
        assert_within(errors, [0.10e-3, 0.02e-3, 0.12e-3], &format!("case {case}"));
        let grasp_start = log.path[0].pose.point();
        validate(&estimate, grasp_start, &ValidationLimits::default())
            .unwrap_or_else(|r| panic!("case {case}: rejected {r:?}"));
    }
}

/// The paper's methods on noise of `plant.md` stay within the worst
/// errors of kernel/src/estimation/README.md's table (l1 / l2 / shoulder:
/// Hough 0.14 / 0.03 / 0.18 mm, measured 0.136 / 0.032 / 0.177 mm; Kåsa
/// 0.09 / 0.07 / 0.14 mm, measured 0.094 / 0.066 / 0.144 mm) plus
/// [`MARGIN`].
#[test]
fn hough_and_ls_are_as_accurate_as_their_table_on_the_six_noisy_logs() {
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        for (method, claimed) in [
            (Method::Hough, [0.14e-3, 0.03e-3, 0.18e-3]),
            (Method::Ls, [0.09e-3, 0.07e-3, 0.14e-3]),
        ] {
            let e = estimate_arm(&log.path, method).expect("estimate");
            let errors = noisy_errors(case, &format!("{method:?}"), &e, &log);
            assert_within(errors, claimed, &format!("case {case} {method:?}"));
        }
    }
}

/// Outliers (every 37th sample thrown 5 cm off) and a short corrupted
/// stretch (0.2 s, 10 cm off, in either phase) move the `Auto` estimate by
/// less than 0.25 mm (measured: 0.005, 0.035 and 0.0004 mm; without its
/// robust weights the outliers alone shift a fit by about 5 cm / 37).
#[test]
fn outliers_and_a_corrupted_stretch_move_auto_by_less_than_a_quarter_millimetre() {
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
        let moved = moved(&e, &clean);
        assert!(moved < 0.25e-3, "{name}: moved {moved} m: {e:?}");
    }
}

/// How far estimate `e` lies from `reference`: the largest of the length
/// differences and the elbow and shoulder distances [m].
fn moved(e: &ArmEstimate, reference: &ArmEstimate) -> f64 {
    (e.upper_arm_length - reference.upper_arm_length)
        .abs()
        .max((e.forearm_length - reference.forearm_length).abs())
        .max(e.shoulder.distance(reference.shoulder))
        .max(e.elbow.distance(reference.elbow))
}

/// Errors (|Δl1|, |Δl2|, shoulder distance) [m] of `method` on a log.
fn errors(log: &logs::Log, l1: f64, l2: f64, method: Method) -> [f64; 3] {
    let e = estimate_arm(&log.path, method).expect("estimate");
    let shoulder = log.shoulder.expect("truth column");
    [
        (e.upper_arm_length - l1).abs(),
        (e.forearm_length - l2).abs(),
        e.shoulder.distance(shoulder),
    ]
}

/// On every labelled effect log `Auto` is never worse than the paper's
/// Kåsa fit by more than 1 mm (l1, l2, shoulder), and for grasp compliance
/// and grasp slip it is within the errors measured for kernel/src/
/// estimation/README.md's table (l1 / l2 / shoulder: compliance 0.40 /
/// 0.85 / 1.23 mm, slip 0.012 / 0.028 / 0.060 mm; the README: 0.9 mm on
/// l2, 0.06 mm on the shoulder) plus [`MARGIN`] where Kåsa is off by the
/// README's 237 mm on l2 (compliance) and 22.7 mm on the shoulder (slip).
#[test]
fn auto_is_never_worse_than_kasa_and_corrects_compliance_and_slip() {
    for labelled in logs::labelled_effects() {
        let log = logs::read(&format!("effects/{}", labelled.file));
        let auto = errors(&log, labelled.l1, labelled.l2, Method::Auto);
        let kasa = errors(&log, labelled.l1, labelled.l2, Method::Ls);
        for (a, k) in auto.iter().zip(&kasa) {
            assert!(
                a - k <= 1e-3,
                "{}: auto {auto:?} kasa {kasa:?}",
                labelled.effect
            );
        }
        // Measured: compliance 0.396 / 0.846 / 1.232 mm, slip 0.012 /
        // 0.028 / 0.060 mm (l1, l2, shoulder); Kåsa 236.72 mm on the
        // compliance log's l2, 22.71 mm on the slip log's shoulder.
        let claims = match labelled.effect.as_str() {
            "grasp_compliance" => Some(([0.40e-3, 0.85e-3, 1.23e-3], 1, 236.7e-3)),
            "grasp_slip" => Some(([0.012e-3, 0.028e-3, 0.060e-3], 2, 22.7e-3)),
            _ => None,
        };
        if let Some((claimed, axis, kasa_off)) = claims {
            println!(
                "{}: auto {:.4?} mm, kasa {:.4?} mm",
                labelled.effect,
                auto.map(|a| a * 1e3),
                kasa.map(|k| k * 1e3)
            );
            assert_within(auto, claimed, &labelled.effect);
            assert!(
                kasa[axis] >= kasa_off - MARGIN,
                "{}: {kasa:?}",
                labelled.effect
            );
        }
    }
}

/// The online estimator replayed over each log is within the READMEs'
/// 0.106 mm of l1 and 0.084 mm of l2, its shoulder within 0.167 mm (the
/// worst measured; `Auto`: 0.10 / 0.02 / 0.12 mm), plus [`MARGIN`].
#[test]
fn online_estimate_is_accurate_on_the_six_noisy_logs() {
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let estimate =
            estimate_online(&log.path, &ValidationLimits::default(), &log.tilt).expect("estimate");
        let errors = noisy_errors(case, "online", &estimate, &log);
        assert_within(
            errors,
            [0.106e-3, 0.084e-3, 0.167e-3],
            &format!("case {case}"),
        );
    }
}

/// The labelled effect log of `effect`, its online estimate and the
/// estimate's |error| in l1 and l2 [m].
fn online_on_labelled(effect: &str) -> (logs::Labelled, logs::Log, ArmEstimate, [f64; 2]) {
    let labelled = logs::labelled_effects()
        .into_iter()
        .find(|l| l.effect == effect)
        .expect("the labelled log");
    let log = logs::read(&format!("effects/{}", labelled.file));
    let estimate =
        estimate_online(&log.path, &ValidationLimits::default(), &log.tilt).expect("estimate");
    let off = [
        (estimate.upper_arm_length - labelled.l1).abs(),
        (estimate.forearm_length - labelled.l2).abs(),
    ];
    (labelled, log, estimate, off)
}

/// REQ-EST-007: on the labelled quantization log (x and z read to
/// 4.4 mm, psi to 0.66°) the online estimate is validated with l1 and l2
/// within the measured 0.27 / 1.37 mm plus [`MARGIN`], and reports the
/// quantizer's step as its resolution (4.44 mm); read as recorded (the
/// reader off by hand) l1 came out 0.54 and l2 1.96 mm off. The six noisy
/// logs, whose files repeat a value now and then (written to 1 µm),
/// report none.
#[test]
fn req_est_007_a_quantized_log_is_estimated_and_validated() {
    let (_, log, estimate, off) = online_on_labelled("quantization");
    println!(
        "quantization: {:.3?} mm, {:?}",
        off.map(|e| e * 1e3),
        estimate.evidence
    );
    assert!(
        off[0] <= 0.27e-3 + MARGIN && off[1] <= 1.37e-3 + MARGIN,
        "{off:?}"
    );
    assert!((estimate.evidence.resolution - 4.44e-3).abs() < 0.01e-3);
    let start = log.path[0].pose.point();
    assert!(validate(&estimate, start, &ValidationLimits::default()).is_ok());
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let estimate =
            estimate_online(&log.path, &ValidationLimits::default(), &log.tilt).expect("estimate");
        assert!(
            estimate.evidence.resolution == 0.0,
            "case {case}: {:?}",
            estimate.evidence
        );
    }
}

/// REQ-EST-011: the labelled plane-tilt log (the arm's plane tilted by
/// 11.4° about x, written by an independent implementation) is recorded
/// in its plane: the online estimate is validated with l1 and l2 within
/// the measured 0.002 / 0.04 mm plus [`MARGIN`] and reports the tilt
/// within 0.1 mrad. Seen failing read in S alone (the lateral column left
/// out, by hand): refused, `shoulder_off_table` 3.4 mm, l1 and l2 2.6 and
/// 2.7 mm short; scaled in the refinement alone, the same (the online
/// split was the ellipse's).
#[test]
fn req_est_011_the_shared_tilted_log_is_read_in_its_plane() {
    let (labelled, log, estimate, off) = online_on_labelled("plane_tilt");
    let tilt = estimate
        .evidence
        .plane_tilt
        .expect("the online method reads it");
    println!(
        "plane_tilt: {:.3?} mm, tilt {tilt:.5} of {:.5} rad",
        off.map(|e| e * 1e3),
        labelled.parameter("angle")
    );
    let start = log.path[0].pose.point();
    let verdict = validate(&estimate, start, &ValidationLimits::default());
    assert!(verdict.is_ok(), "{verdict:?}");
    assert!(
        off[0] <= 0.002e-3 + MARGIN && off[1] <= 0.04e-3 + MARGIN,
        "{off:?}"
    );
    assert!((tilt - labelled.parameter("angle")).abs() <= 1e-4);
}

/// REQ-EST-012: on the labelled shoulder-drift log (a trunk of
/// 1 183 N/m, written by an independent implementation) the fixed
/// shoulder is refused by its own evidence and the trunk's fit reads the
/// yield out: validated, l1 and l2 within the measured 0.19 / 0.23 mm
/// plus [`MARGIN`], the trunk's stiffness 1/c within 3 % of the truth.
/// Seen failing with the trunk's fit off (by hand): refused,
/// `upper_arm_residual_too_large` 3.27 mm. On the six noisy logs, whose
/// shoulder is fixed, no trunk is looked for: 0.
#[test]
fn req_est_012_a_yielding_trunk_is_measured_and_read_out() {
    let (labelled, log, estimate, off) = online_on_labelled("shoulder_drift");
    let compliance = estimate
        .evidence
        .trunk_compliance
        .expect("the online method measures it");
    let k = labelled.parameter("k");
    println!(
        "shoulder_drift: {:.3?} mm, trunk {:.0} of {k:.0} N/m, {:?}",
        off.map(|e| e * 1e3),
        -1.0 / compliance,
        estimate.evidence
    );
    let start = log.path[0].pose.point();
    let verdict = validate(&estimate, start, &ValidationLimits::default());
    assert!(verdict.is_ok(), "{verdict:?}");
    assert!(
        off[0] <= 0.19e-3 + MARGIN && off[1] <= 0.23e-3 + MARGIN,
        "{off:?}"
    );
    // The sensor's force is the arm's on the robot: the trunk yields
    // against it, c < 0.
    assert!((-1.0 / compliance - k).abs() <= 0.03 * k, "{compliance}");
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let estimate =
            estimate_online(&log.path, &ValidationLimits::default(), &log.tilt).expect("estimate");
        assert_eq!(estimate.evidence.trunk_compliance, Some(0.0), "case {case}");
    }
}

/// REQ-EST-013: on the labelled grasp-slip log (the grasp slides
/// 14.8 mm along the forearm at 9.84 s, early in the forearm's turn;
/// written by an independent implementation, whose truth after the slip
/// is the arm with l2 + shift, its shoulder moved by it along x) the online
/// estimate reads the jump as a slip and estimates the arm held after it:
/// validated, l1 and l2 + shift within the measured 0.035 / 0.081 mm plus
/// [`MARGIN`], the slide within 0.2 mm (measured 14.70 of 14.81 mm). Seen
/// failing with the slide not fitted (the jump's bound raised, by hand):
/// refused.
#[test]
fn req_est_013_the_shared_slip_is_read_out() {
    let (labelled, log, estimate, _) = online_on_labelled("grasp_slip");
    let shift = labelled.parameter("shift");
    let slide = estimate
        .evidence
        .grasp_slip
        .expect("the online method measures it");
    let off = [
        (estimate.upper_arm_length - labelled.l1).abs(),
        (estimate.forearm_length - (labelled.l2 + shift)).abs(),
    ];
    println!(
        "grasp_slip: {:.3?} mm, slide {:.2} of {:.2} mm, {:?}",
        off.map(|e| e * 1e3),
        slide * 1e3,
        shift * 1e3,
        estimate.evidence
    );
    let start = log.path[0].pose.point();
    let verdict = validate(&estimate, start, &ValidationLimits::default());
    assert!(verdict.is_ok(), "{verdict:?}");
    assert!(
        off[0] <= 0.035e-3 + MARGIN && off[1] <= 0.081e-3 + MARGIN,
        "{off:?}"
    );
    assert!((slide - shift).abs() <= 0.2e-3, "{slide}");
}

/// REQ-EST-009: on the labelled backlash log (play of 26.1 mrad in psi,
/// which turns twice in the upper-arm phase) the online estimate reads the
/// play out: validated, l1 and l2 within the measured 0.27 / 0.06 mm plus
/// [`MARGIN`], the play measured within 3 mrad of the true width (24.1 of
/// 26.1). Seen failing with the play not read out (each falling sample
/// read as rising, by hand): refused (`residual_bias`, 1.88 mm) with l1
/// 3.89 mm off. On the six noisy logs, which have no play, none is shown
/// above the noise: it is 0.
#[test]
fn req_est_009_the_play_in_psi_is_measured_and_read_out() {
    let (labelled, log, estimate, off) = online_on_labelled("backlash");
    let width = labelled.parameter("width");
    let play = estimate
        .evidence
        .play
        .expect("the online method measures the play");
    println!(
        "backlash: {:.3?} mm, play {:.2} mrad of {:.2}, {:?}",
        off.map(|e| e * 1e3),
        play * 1e3,
        width * 1e3,
        estimate.evidence
    );
    let start = log.path[0].pose.point();
    let verdict = validate(&estimate, start, &ValidationLimits::default());
    assert!(verdict.is_ok(), "{verdict:?}");
    assert!(
        off[0] <= 0.27e-3 + MARGIN && off[1] <= 0.06e-3 + MARGIN,
        "{off:?}"
    );
    assert!((play - width).abs() <= 3e-3, "play {play} of {width}");
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let estimate =
            estimate_online(&log.path, &ValidationLimits::default(), &log.tilt).expect("estimate");
        let play = estimate.evidence.play.expect("measured");
        assert_eq!(play, 0.0, "case {case}");
    }
}

/// REQ-TIME-002: the refinement runs in slices of at most
/// `SAMPLES_PER_STEP` samples: a whole refinement takes at least as many
/// calls as its samples need, and the sliced result is bit-identical to
/// the one-call result (slicing changes when work is done, not what).
#[test]
fn req_time_002_the_refinement_runs_in_bounded_slices() {
    let log = logs::read("noisy/case3.csv");
    let mut online = OnlineEstimator::new();
    for end in 1..=log.path.len() {
        online.record(&log.path[..end], &ValidationLimits::default());
    }
    let (lift, split) = online.split();
    let forearm = split - lift;
    let upper_arm = log.path.len() - split;
    let samples = ITERATIONS * forearm + (ITERATIONS + 1) * upper_arm + forearm + upper_arm;
    let run = |budget: usize| -> (usize, ArmEstimate) {
        let mut refinement = Refinement::after(
            &online,
            log.path.len(),
            &ValidationLimits::default(),
            &log.tilt,
        )
        .expect("split found");
        for calls in 1..=samples {
            if let Progress::Done(outcome) = refinement.advance(&log.path, budget) {
                return (calls, outcome.expect("refined"));
            }
        }
        panic!("the refinement did not finish");
    };
    let (calls, sliced) = run(SAMPLES_PER_STEP);
    let (whole_calls, whole) = run(PATH_CAPACITY);
    assert!(
        calls >= samples / SAMPLES_PER_STEP,
        "{calls} calls for {samples} samples"
    );
    assert!(whole_calls <= 2 * ITERATIONS + 6, "{whole_calls}");
    assert_eq!(sliced, whole);
}

/// One non-finite number anywhere in a sample (its time, pose or wrench)
/// refuses the whole path as `NonFiniteSample`, for every method, where
/// the same path with that sample intact is estimated.
#[test]
fn one_non_finite_number_in_a_good_path_is_refused_by_name() {
    let log = logs::read("noisy/case1.csv");
    let at = log.path.len() / 2;
    let mut spoiled = [log.path.clone(), log.path.clone(), log.path.clone()];
    spoiled[0][at].time = f64::NAN;
    spoiled[1][at].pose.z = f64::INFINITY;
    spoiled[2][at].wrench.fz = f64::NAN;
    for method in [Method::Hough, Method::Ls, Method::Auto, Method::Online] {
        assert!(estimate_arm(&log.path, method).is_ok(), "{method:?}");
        for path in &spoiled {
            assert_eq!(
                estimate_arm(path, method).err(),
                Some(EstimateError::NonFiniteSample),
                "{method:?}"
            );
        }
    }
}

/// The online estimator replayed over each log one sample at a time, as
/// the kernel records it; `each` sees the estimator after every sample.
fn replay_online(path: &[PathSample], mut each: impl FnMut(usize, &OnlineEstimator)) {
    let mut online = OnlineEstimator::new();
    for end in 1..=path.len() {
        online.record(&path[..end], &ValidationLimits::default());
        each(end - 1, &online);
    }
}

/// The online estimator's split and forearm arc by their definitions: lift
/// -off is the first sample whose ψ exceeds `LIFT_PSI`; the forearm phase
/// ends `DEPARTURE_WINDOW` samples before the sample that decides the
/// departure (the window's first); the forearm's arc is the largest ψ of
/// the phase above ψ at lift-off; once caught up, the upper arm's fit
/// holds every sample from the split on but the newest two. A sample with a non-finite pose
/// is not recorded at all.
#[test]
fn the_online_split_and_forearm_arc_follow_their_definitions() {
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let psi = |i: usize| log.path[i].pose.psi;
        let (mut lift, mut departed) = (None, None);
        let mut previous = OnlineEstimator::new();
        replay_online(&log.path, |index, online| {
            if previous.phase() == OnlinePhase::Resting && online.phase() == OnlinePhase::Forearm {
                lift = Some(index);
            }
            if previous.phase() == OnlinePhase::Forearm && online.phase() == OnlinePhase::UpperArm {
                departed = Some(index);
            }
            if index == 1000 {
                let mut spoiled = log.path[..=index].to_vec();
                spoiled[index].pose.x = f64::NAN;
                let mut skipped = previous;
                skipped.record(&spoiled, &ValidationLimits::default());
                assert_eq!(skipped, previous, "case {case}: a NaN pose was recorded");
            }
            previous = *online;
        });
        let (lift, departed) = (lift.expect("lift-off"), departed.expect("departure"));
        assert!(psi(lift) > LIFT_PSI && (0..lift).all(|i| psi(i) <= LIFT_PSI));
        let online = previous;
        assert_eq!(online.split(), (lift, departed + 1 - DEPARTURE_WINDOW));
        let highest = (lift..=departed).map(psi).fold(f64::MIN, f64::max);
        assert_eq!(online.arcs().0, highest - psi(lift), "case {case}");
        // Caught up: every sample from the split to the third newest (the
        // newest two wait for the neighbours their outlier test needs) is
        // in the upper arm's fit; these logs have no isolated outliers.
        let upper = online.upper_arm().expect("provisional upper arm");
        assert_eq!(
            upper.count,
            log.path.len() - online.split().1 - OUTLIER_REACH,
            "case {case}"
        );
    }
}

/// The joint envelope is a property of the arm, not of where frame S's
/// origin lies: the same log moved by (0.2, −0.15) m gives the same worst
/// -case joint angles at every sample; before a provisional forearm there
/// is none; once the provisional upper arm is in use it is the elevation
/// about its shoulder plus three standard deviations of the shoulder's
/// position and the forearm's radius over the reach.
#[test]
fn the_joint_envelope_is_translation_invariant_and_widened_by_its_uncertainty() {
    let prior = ValidationLimits::default();
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let moved: Vec<PathSample> = log
            .path
            .iter()
            .map(|s| PathSample {
                pose: Pose::new(s.pose.x + 0.2, s.pose.z - 0.15, s.pose.psi),
                ..*s
            })
            .collect();
        let mut envelopes = Vec::new();
        let mut widened = 0;
        replay_online(&log.path, |index, online| {
            let (pose, wrench) = (log.path[index].pose, log.path[index].wrench);
            let envelope = online.joint_envelope(pose, wrench, &prior);
            assert_eq!(envelope.is_some(), online.forearm().is_some());
            if let (Some(e), Some(forearm), Some(upper)) =
                (envelope, online.forearm(), online.upper_arm())
            {
                let grasp = online.grasp(pose, wrench);
                let elbow = elbow_from_grasp(grasp, forearm.circle.radius, online.pitch_offset());
                let shoulder = upper.circle.centre;
                let nominal = (elbow.z - shoulder.z).atan2(shoulder.x - elbow.x);
                let spread = 3.0 * (upper.centre_sd + forearm.radius_sd) / elbow.distance(shoulder);
                assert!((e.max_shoulder_elevation - (nominal + spread)).abs() < 1e-9);
                assert!(
                    (e.min_elbow_flexion
                        - (pose.psi - online.pitch_offset() - e.max_shoulder_elevation))
                        .abs()
                        < 1e-12
                );
                widened += 1;
            }
            envelopes.push(envelope);
        });
        assert!(
            widened > 100,
            "case {case}: {widened} samples with an upper arm"
        );
        replay_online(&moved, |index, online| {
            let here = online.joint_envelope(moved[index].pose, moved[index].wrench, &prior);
            match (here, envelopes[index]) {
                (Some(a), Some(b)) => assert!(
                    (a.max_shoulder_elevation - b.max_shoulder_elevation).abs() < 1e-6
                        && (a.min_elbow_flexion - b.min_elbow_flexion).abs() < 1e-6,
                    "case {case} at {index}: {a:?} moved, {b:?} not"
                ),
                (a, b) => assert_eq!(a.is_some(), b.is_some(), "case {case} at {index}"),
            }
        });
    }
}

/// The kernel's own estimator (`Online`: the online split, then the
/// robust refinement) on case 3: its residuals are the logs' noise level
/// (0.05-0.5 mm RMS), and its robust weights ignore a corrupted stretch
/// of the upper-arm phase (0.2 s, 10 cm off: 7.9 mm RMS of residual) to
/// within 0.1 mm. Corruption in the forearm phase is another matter: the
/// provisional forearm (unweighted moments) takes it, the split comes
/// early and the estimate is far off, which the validator refuses
/// (method disagreement); that is the `Auto` cross-check's and the
/// validator's to catch, not the refinement's.
#[test]
fn the_online_refinement_is_robust_to_a_corrupted_upper_arm_stretch() {
    let log = logs::read("noisy/case3.csv");
    let clean = estimate_arm(&log.path, Method::Online).expect("clean");
    let e = clean.evidence;
    for residual in [e.forearm_residual, e.upper_arm_residual] {
        assert!((0.05e-3..0.5e-3).contains(&residual), "{e:?}");
    }
    let mut path = log.path.clone();
    for sample in &mut path[1800..1820] {
        sample.pose.z += 0.1;
    }
    let corrupt = estimate_arm(&path, Method::Online).expect("corrupt");
    let moved = moved(&corrupt, &clean);
    assert!(moved < 1e-4, "moved {moved} m: {corrupt:?}");
    assert!(corrupt.evidence.upper_arm_residual > 10.0 * e.upper_arm_residual);
}

/// The batch phase split (`detect_phases`: a look-ahead window over the
/// whole path) and the kernel's online split (a window behind the newest
/// sample) are two readings of one definition, the forearm leaving its
/// circle: on the six logs they agree to within 5 samples, 0.05 s
/// (measured: 0 to 3), and the batch split stays there with outliers.
#[test]
fn the_batch_and_online_splits_agree() {
    use limb_kernel::estimation::{detect_phases, PointModel};
    for case in 1..=6 {
        let log = logs::read(&format!("noisy/case{case}.csv"));
        let batch = detect_phases(&log.path, &PointModel::GRASP).expect("phases");
        let mut online = OnlineEstimator::new();
        for end in 1..=log.path.len() {
            online.record(&log.path[..end], &ValidationLimits::default());
        }
        let (lift, split) = online.split();
        assert_eq!(batch.forearm.start, lift, "case {case}");
        // Outliers scattered through the phase (one sample in 20 thrown
        // 5 cm off) leave the look-ahead window's count below the share:
        // the split stays.
        let mut scattered = log.path.clone();
        for sample in scattered.iter_mut().step_by(20) {
            sample.pose.x += 0.05;
        }
        let outliers = detect_phases(&scattered, &PointModel::GRASP).expect("phases");
        assert!(
            outliers.forearm.end.abs_diff(batch.forearm.end) <= 5,
            "case {case}: {:?} with outliers, {:?} without",
            outliers.forearm,
            batch.forearm
        );
        assert!(
            batch.forearm.end.abs_diff(split) <= 5,
            "case {case}: batch {:?}, online {lift}..{split}",
            batch.forearm
        );
    }
}

/// Non-finite samples are skipped, not counted: with seven NaN poses in
/// the forearm phase (the moments then lag the newest sample by seven more)
/// the forearm phase still ends where the departure window begins.
#[test]
fn skipped_samples_do_not_move_the_online_split() {
    let mut path = logs::read("noisy/case2.csv").path;
    let lift = path.iter().position(|s| s.pose.psi > LIFT_PSI).unwrap();
    for sample in &mut path[lift + 100..lift + 107] {
        sample.pose.x = f64::NAN;
    }
    let (mut departed, mut previous) = (None, OnlineEstimator::new());
    replay_online(&path, |index, online| {
        if previous.phase() == OnlinePhase::Forearm && online.phase() == OnlinePhase::UpperArm {
            departed = Some(index);
        }
        previous = *online;
    });
    let departed = departed.expect("departure");
    assert_eq!(previous.split(), (lift, departed + 1 - DEPARTURE_WINDOW));
}

/// REQ-EST-005: isolated outliers (a sample thrown 5.8 cm off, on every
/// 37th or every 11th sample) are left out of the fits and counted: on the
/// six noisy logs the kernel's online estimate moves from its clean answer
/// by at most kernel/src/estimation/README.md's 0.05 mm plus [`MARGIN`]
/// (the requirement: less than 0.1 mm; measured: at most 0.043 mm) and is
/// still validated, and `Auto` on the labelled `none`, compliance and slip
/// logs from its own clean answer by at most that README's 0.08 mm plus
/// [`MARGIN`] (the requirement: less than 0.2 mm; measured: at most
/// 0.077 mm). Before the outlier test: `Auto` 33 mm off on the compliance
/// log (its compliance went undetected) and 22 mm on the slip log; the
/// online estimate 0.5-0.7 m off.
#[test]
fn req_est_005_isolated_outliers_are_left_out_and_counted() {
    use limb_kernel::config::ValidationLimits;
    use limb_kernel::validate::validate;
    let thrown = |path: &[PathSample], every: usize| -> Vec<PathSample> {
        let mut path = path.to_vec();
        for sample in path.iter_mut().step_by(every) {
            sample.pose.x += 0.05;
            sample.pose.z -= 0.03;
        }
        path
    };
    let check = |file: &str, method: Method, bound: f64, validated: bool| {
        let log = logs::read(file);
        let clean = estimate_arm(&log.path, method).expect("clean");
        for every in [37, 11] {
            let path = thrown(&log.path, every);
            let e = estimate_arm(&path, method).unwrap_or_else(|err| panic!("{file}: {err:?}"));
            let moved = moved(&e, &clean);
            assert!(moved < bound, "{file} {method:?} every {every}: {moved} m");
            // Counted: the thrown samples of the two phases (from lift-off
            // on), but the last two samples, which have no full window.
            let lift = path
                .iter()
                .position(|s| s.pose.psi > LIFT_PSI)
                .expect("lift");
            let thrown = (lift..path.len() - OUTLIER_REACH)
                .filter(|i| i % every == 0)
                .count();
            assert_eq!(
                e.evidence.outliers, thrown,
                "{file} {method:?} every {every}"
            );
            if validated {
                let start = log.path[0].pose.point();
                let verdict = validate(&e, start, &ValidationLimits::default());
                assert!(verdict.is_ok(), "{file} every {every}: {verdict:?}");
            }
        }
    };
    for case in 1..=6 {
        check(
            &format!("noisy/case{case}.csv"),
            Method::Online,
            0.05e-3 + MARGIN,
            true,
        );
    }
    for file in ["none", "grasp_compliance", "grasp_slip"] {
        check(
            &format!("effects/{file}.csv"),
            Method::Auto,
            0.08e-3 + MARGIN,
            false,
        );
    }
}
