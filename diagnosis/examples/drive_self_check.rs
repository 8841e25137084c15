//! The blind self-check of the drive diagnosis:
//! `cargo run --release -p limb-diagnosis --example drive_self_check -- N SEED`.
use limb_diagnosis::plant::drive::blind::run;
use limb_diagnosis::Options;

fn main() {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<u64>().ok());
    let count = args.next().flatten().unwrap_or(20) as usize;
    let seed = args.next().flatten().unwrap_or(1);
    let start = std::time::Instant::now();
    let report = run(count, seed, &Options::default());
    for t in &report.trials {
        println!(
            "{} {:<5} withheld {:?} found {:?} shrink {:.2}",
            t.seed, t.correct, t.withheld, t.found, t.shrink
        );
    }
    println!(
        "singles top-1 {}/{}; pairs exact {}/{}, both found {}/{}; {:.1?}",
        report.single_top1,
        report.singles,
        report.pair_exact,
        report.pairs,
        report.pair_both_found,
        report.pairs,
        start.elapsed()
    );
}
