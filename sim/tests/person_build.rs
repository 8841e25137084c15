//! A person's build (`ArmParameters::person`, `spec/human-arm.md`): the
//! reference person's segments scaled isometrically to the arm's lengths,
//! their mass spread as measured (centre of mass, inertia), and the
//! equations of motion reading that spread.

use limb_sim::dynamics::arm_terms;
use limb_sim::{
    ArmBuild, ArmParameters, MassDistribution, PlantParameters, PERSON_FOREARM, PERSON_UPPER_ARM,
};

#[test]
fn the_reference_lengths_give_the_reference_person_and_mass_goes_with_length_cubed() {
    let reference = ArmParameters::person(PERSON_UPPER_ARM.length, PERSON_FOREARM.length);
    assert!((reference.upper_arm_mass - PERSON_UPPER_ARM.mass).abs() < 1e-12);
    assert!((reference.forearm_mass - PERSON_FOREARM.mass).abs() < 1e-12);
    let larger = ArmParameters::person(1.1 * PERSON_UPPER_ARM.length, 0.9 * PERSON_FOREARM.length);
    assert!((larger.upper_arm_mass / PERSON_UPPER_ARM.mass - 1.331).abs() < 1e-9);
    assert!((larger.forearm_mass / PERSON_FOREARM.mass - 0.729).abs() < 1e-9);
    assert_eq!(larger.forearm_distribution, PERSON_FOREARM.distribution);
    assert_eq!(
        ArmParameters::built(ArmBuild::Rod, 0.3, 0.2),
        ArmParameters::new(0.3, 0.2)
    );
}

/// Gravity and the mass matrix of plant.md's equations with each link's
/// centre of mass at c_i and inertia I_i about it, written out here.
#[test]
fn the_equations_of_motion_read_where_the_mass_is() {
    let a = ArmParameters::person(0.31, 0.24);
    let (q, qd) = ([0.4, 1.1], [0.0, 0.0]);
    let terms = arm_terms(&a, q, qd);
    let (m1, m2, g) = (a.upper_arm_mass, a.forearm_mass, a.gravity);
    let (c1, c2) = (
        0.31 * PERSON_UPPER_ARM.distribution.centre,
        0.24 * PERSON_FOREARM.distribution.centre,
    );
    let i2 = m2 * 0.24 * 0.24 / PERSON_FOREARM.distribution.inertia_divisor;
    let psi = q[0] + q[1];
    let gravity = [
        m1 * g * c1 * q[0].cos() + m2 * g * (0.31 * q[0].cos() + c2 * psi.cos()),
        m2 * g * c2 * psi.cos(),
    ];
    for (ours, theirs) in terms.gravity.iter().zip(gravity) {
        assert!((ours - theirs).abs() < 1e-12, "{terms:?}");
    }
    assert!((terms.mass[1][1] - (i2 + m2 * c2 * c2)).abs() < 1e-12);
    // The dummy's rods at the same lengths carry less, nearer the joints.
    let rod = arm_terms(&ArmParameters::new(0.31, 0.24), q, qd);
    assert!(terms.gravity[1] > 1.5 * rod.gravity[1]);
}

#[test]
fn a_spread_of_mass_off_the_segment_or_not_finite_is_refused() {
    for (centre, divisor) in [
        (0.0, 12.0),
        (1.6, 12.0),
        (f64::NAN, 12.0),
        (0.5, 0.0),
        (0.5, f64::INFINITY),
    ] {
        let mut params = PlantParameters::new(0.3, 0.2);
        params.arm.forearm_distribution = MassDistribution {
            centre,
            inertia_divisor: divisor,
        };
        let error = params.check().unwrap_err();
        assert!(error.contains("forearm"), "{error}");
    }
    let mut params = PlantParameters::new(0.3, 0.2);
    params.arm = ArmParameters::person(0.3, 0.2);
    assert_eq!(params.check(), Ok(()));
}
