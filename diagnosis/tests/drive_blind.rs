//! The blind self-check of the drive diagnosis, small: three simulated
//! drives (seed 1: nothing withheld, Coulomb + Stribeck friction, backlash)
//! are diagnosed right. The large-N figures are in diagnosis/README.md.

use limb_diagnosis::drive::blind::run;
use limb_diagnosis::Options;

#[test]
fn three_blind_drives_are_diagnosed_right() {
    let report = run(3, 1, &Options::default());
    assert_eq!((report.singles, report.pairs), (2, 1));
    assert!(
        report.trials.iter().all(|t| t.correct),
        "{:#?}",
        report.trials
    );
}
