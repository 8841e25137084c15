//! The blind self-check of the drive diagnosis, small enough for CI: six
//! simulated drives from seed 1 (three single effects or none, three
//! pairs). The bar is below the large-N figures of diagnosis/README.md
//! (a none trial of this seed gains a spurious `latency`), so a
//! regression in attribution, not the draw, fails it.

use limb_diagnosis::plant::drive::blind::run;
use limb_diagnosis::Options;

#[test]
fn six_blind_drives_are_mostly_diagnosed_right() {
    let report = run(6, 1, &Options::default());
    assert_eq!((report.singles, report.pairs), (3, 3));
    assert!(report.single_top1 >= 2, "{:#?}", report.trials);
    assert!(report.pair_both_found >= 3, "{:#?}", report.trials);
}
