//! Planned motions against the closed form of `motion.rs`'s theory of
//! operation: x_d(t) = start + s(τ) Δ, s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, τ = t/T,
//! T = 1.875 |Δ(x, z)| / v_max, and its first two derivatives; the goal
//! held after T. The estimation motion follows its lift.

use limb_kernel::geometry::Pose;
use limb_kernel::motion::{EstimationMotion, EstimationMotionParameters, MinimumJerkMove};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

#[test]
fn minimum_jerk_set_points_follow_the_closed_form() {
    let (start, goal) = (Pose::new(0.1, 0.2, 0.3), Pose::new(0.4, 0.6, 1.3));
    let peak = 0.05;
    let motion = MinimumJerkMove::new(start, goal, peak).unwrap();
    let duration = 1.875 * 0.5 / peak; // |Δ(x, z)| = 0.5 m
    assert!(close(motion.duration(), duration));
    let delta = [goal.x - start.x, goal.z - start.z, goal.psi - start.psi];
    for tau in [0.1, 0.25, 0.5, 0.8, 0.95] {
        let t = tau * duration;
        let s = 10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5);
        let ds = (30.0 * tau.powi(2) - 60.0 * tau.powi(3) + 30.0 * tau.powi(4)) / duration;
        let dds = (60.0 * tau - 180.0 * tau.powi(2) + 120.0 * tau.powi(3)) / duration.powi(2);
        let p = motion.at(t);
        let start = [start.x, start.z, start.psi];
        let got = [
            [p.pose.x, p.pose.z, p.pose.psi],
            [p.velocity.x, p.velocity.z, p.velocity.psi],
            [p.acceleration.x, p.acceleration.z, p.acceleration.psi],
        ];
        for axis in 0..3 {
            assert!(
                close(got[0][axis], start[axis] + s * delta[axis]),
                "pose at τ {tau}"
            );
            assert!(close(got[1][axis], ds * delta[axis]), "velocity at τ {tau}");
            assert!(
                close(got[2][axis], dds * delta[axis]),
                "acceleration at τ {tau}"
            );
        }
    }
    assert_eq!(motion.at(duration * 1.5).pose, goal);
    assert_eq!(motion.at(-1.0).pose, start);
}

#[test]
fn the_estimation_motion_is_its_lift_then_a_hold() {
    let parameters = EstimationMotionParameters::default();
    let motion = EstimationMotion::new(Pose::new(0.0, 0.0, 0.1), &parameters).unwrap();
    let lift = *motion.lift();
    for t in [0.0, 1.0, 5.0, lift.duration() * 0.5, lift.duration() + 1.0] {
        assert_eq!(motion.at(t), lift.at(t));
    }
    assert!(motion.at(lift.duration() * 0.5).velocity.x > 0.0);
    assert!(close(
        motion.total_duration(),
        lift.duration() + parameters.hold_time
    ));
    assert!(!motion.is_finished(motion.total_duration() - 1e-6));
    assert!(motion.is_finished(motion.total_duration()));
}

/// REQ-MON-011: without a provisional forearm (a wrist that never turns: no
/// arc to fit) the shaped lift never commands a set-point beyond
/// `LiftShaping::prior_reach` of the grasp: it pauses there, and ends in
/// `ForearmPhaseTooShort` once `forearm_wait` has passed, not before
/// (HAZ-08).
#[test]
fn req_mon_011_without_a_forearm_the_lift_stays_within_the_prior_reach() {
    use limb_kernel::estimation::online::OnlineEstimator;
    use limb_kernel::estimation::EstimateError;
    use limb_kernel::geometry::Wrench;
    use limb_kernel::lift::{LiftCommand, LiftPhase, LiftSettings, ShapedLift};
    use limb_kernel::{KernelConfig, PathSample};
    let config = KernelConfig::default();
    let grasp = Pose::new(0.45, 0.0, 0.0);
    let motion = EstimationMotion::new(grasp, &config.estimation_motion).unwrap();
    let mut lift = ShapedLift::new(motion, 0.0);
    let online = OnlineEstimator::new();
    let reach = config.lift_shaping.prior_reach;
    let mut paused = None;
    let mut farthest: f64 = 0.0;
    let period = 0.001;
    let steps = ((motion.total_duration() + config.lift_shaping.forearm_wait) / period) as usize;
    for k in 1..=steps + 1000 {
        let now = k as f64 * period;
        let frame = PathSample {
            time: now,
            pose: grasp,
            wrench: Wrench::default(),
        };
        match lift.advance(now, &frame, &online, None, &LiftSettings::of(&config)) {
            Ok(LiftCommand::Move(set_point) | LiftCommand::Hold(set_point)) => {
                farthest = farthest.max(set_point.pose.point().distance(grasp.point()));
                if let LiftPhase::AwaitingForearm { since } = lift.phase() {
                    paused = Some(*since);
                }
            }
            Err(error) => {
                assert_eq!(error, EstimateError::ForearmPhaseTooShort);
                let since = paused.expect("ended without pausing");
                let waited = now - since;
                let wait = config.lift_shaping.forearm_wait;
                assert!(
                    waited > wait && waited <= wait + 2.0 * period,
                    "ended {waited} s into a {wait} s wait"
                );
                assert!(farthest <= reach, "set-point {farthest} m out");
                assert!(
                    farthest > 0.5 * reach,
                    "the lift hardly moved: {farthest} m"
                );
                return;
            }
        }
    }
    panic!("no end after the lift and the wait; set-point reached {farthest} m");
}

#[test]
fn a_zero_hold_is_a_valid_configuration_and_a_negative_one_is_not() {
    use limb_kernel::config::{ConfigError, ConfigField, ConfigProblem};
    use limb_kernel::KernelConfig;
    let mut config = KernelConfig::default();
    config.estimation_motion.hold_time = 0.0;
    assert_eq!(config.check(), Ok(()));
    config.estimation_motion.hold_time = -1e-9;
    assert_eq!(
        config.check(),
        Err(ConfigError::new(
            ConfigField::HoldTime,
            ConfigProblem::Negative
        ))
    );
}

/// A bounded move lasts the longest of its three needs: the grasp-point
/// speed, the forearm rate (T = 1.875 |Δψ| / ω_max, the closed form's
/// peak rate) and the floor; a non-finite rate or floor is refused.
#[test]
fn a_bounded_move_lasts_the_longest_of_its_needs() {
    use limb_kernel::motion::PlanError;
    let start = Pose::new(0.1, 0.2, 0.3);
    // A pure turn of 1 rad at 0.5 rad/s: 3.75 s, longer than the 1 s floor.
    let turn = MinimumJerkMove::bounded(start, Pose::new(0.1, 0.2, 1.3), 0.05, 0.5, 1.0).unwrap();
    assert!(
        close(turn.duration(), 1.875 * 1.0 / 0.5),
        "{}",
        turn.duration()
    );
    // 0.1 m at 0.05 m/s: 3.75 s; the small turn and the floor need less.
    let reach = MinimumJerkMove::bounded(start, Pose::new(0.2, 0.2, 0.31), 0.05, 0.5, 1.0).unwrap();
    assert!(
        close(reach.duration(), 1.875 * 0.1 / 0.05),
        "{}",
        reach.duration()
    );
    // A short move: the floor.
    let short =
        MinimumJerkMove::bounded(start, Pose::new(0.101, 0.2, 0.3), 0.05, 0.5, 1.0).unwrap();
    assert!(close(short.duration(), 1.0), "{}", short.duration());
    for (rate, floor) in [
        (f64::NAN, 1.0),
        (f64::INFINITY, 1.0),
        (0.5, f64::NAN),
        (0.5, f64::INFINITY),
    ] {
        assert_eq!(
            MinimumJerkMove::bounded(start, Pose::new(0.2, 0.2, 0.3), 0.05, rate, floor).err(),
            Some(PlanError::NonFinite),
            "rate {rate}, floor {floor}"
        );
    }
}

/// A sample is due one recording period after the last (to within 1 ppm of
/// it, so rounded 100 Hz time stamps keep every row), never sooner.
#[test]
fn a_path_sample_is_due_one_period_after_the_last() {
    use limb_kernel::geometry::Wrench;
    use limb_kernel::path::{is_due, PATH_SAMPLE_PERIOD};
    use limb_kernel::PathSample;
    let last = PathSample {
        time: 12.0,
        pose: Pose::default(),
        wrench: Wrench::ZERO,
    };
    assert!(is_due(None, 0.0));
    assert!(is_due(Some(&last), 12.0 + PATH_SAMPLE_PERIOD));
    assert!(is_due(
        Some(&last),
        12.0 + PATH_SAMPLE_PERIOD * (1.0 - 5e-7)
    ));
    assert!(!is_due(
        Some(&last),
        12.0 + PATH_SAMPLE_PERIOD * (1.0 - 2e-6)
    ));
    assert!(!is_due(Some(&last), 12.0 + 0.5 * PATH_SAMPLE_PERIOD));
    assert!(!is_due(Some(&last), 12.0));
}
