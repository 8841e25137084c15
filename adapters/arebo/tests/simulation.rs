//! Acceptance tests against the in-process simulator (SJM + AREBO
//! sensing); deterministic (seeded).

use limb_arebo::sim::{self, Setup};

/// Calibration recovers ψx within 1°, the shoulder origin and l within
/// 5 mm, and the polysine median errors stay under 1°, with encoder
/// quantisation, without and with the 1° backlash dead-band (compensated).
#[test]
fn calibration_recovers_the_arm() {
    for backlash in [[0.0; 3], [1f64.to_radians(); 3]] {
        let setup = Setup {
            backlash,
            compensated_backlash: backlash,
            ..Setup::default()
        };
        let model = sim::calibrate(setup, 1).unwrap();
        assert!((model.psi_x() - setup.psi_x).abs() < 1f64.to_radians());
        assert!((model.origin() - setup.origin).norm() < 0.005);
        assert!((model.length() - setup.length).abs() < 0.005);
        let errors = sim::polysine_experiment(setup, &model, 30.0, 2);
        assert!(errors.flexion < 1f64.to_radians() && errors.abduction < 1f64.to_radians());
    }
}

/// Figure 17's shape: α rises while ξ = 0.6, decays after trial 100 and
/// toward 0 after trial 200; success is partial while impaired and all
/// but certain when healthy.
#[test]
fn adaptive_weight_support_has_the_shape_of_figure_17() {
    let setup = Setup::default();
    let model = sim::calibrate(setup, 1).unwrap();
    let trials = sim::weight_support_experiment(setup, &model, 300, 3);
    let alpha = |k: usize| trials[k - 1].alpha;
    let success = |a: usize, b: usize| {
        trials[a - 1..b].iter().filter(|t| t.succeeded).count() as f64 / (b + 1 - a) as f64
    };
    assert!((alpha(1) - 0.3).abs() < 1e-12);
    let early_peak = trials[..30].iter().map(|t| t.alpha).fold(0.0, f64::max);
    assert!(early_peak > 0.45, "α within 30 trials {early_peak}");
    let block_peak = trials[..100].iter().map(|t| t.alpha).fold(0.0, f64::max);
    assert!((0.5..0.75).contains(&block_peak), "α peak {block_peak}");
    assert!(
        alpha(200) < 0.25 && alpha(200) < alpha(100),
        "α at 200 {}",
        alpha(200)
    );
    assert!(alpha(300) < 0.05, "α at 300 {}", alpha(300));
    assert!(
        (0.5..0.85).contains(&success(1, 100)),
        "{}",
        success(1, 100)
    );
    let late_block_2 = trials[150..200].iter().map(|t| t.alpha).sum::<f64>() / 50.0;
    assert!(
        (0.03..0.3).contains(&late_block_2),
        "α late in block 2 {late_block_2}"
    );
    assert!(success(201, 300) > 0.95);
}
