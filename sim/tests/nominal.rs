//! Cross-implementation check (plant.md): with noise off, the grasp path of
//! each of the six benchmark arms matches `shared/data/nominal/caseN.csv`
//! from an independent implementation within 0.5 mm RMS, psi within 1 mrad.

use limb_sim::scripted::estimation_run;
use limb_sim::{Plant, PlantParameters, BENCHMARK_ARMS as ARMS};

fn reference(case: usize) -> Vec<(f64, f64, f64, f64)> {
    let path = format!(
        "{}/../../shared/data/nominal/case{case}.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (t, x, z, psi) = (col("t"), col("x"), col("z"), col("psi"));
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|s| s.parse().unwrap()).collect();
            (v[t], v[x], v[z], v[psi])
        })
        .collect()
}

#[test]
fn noise_off_reproduces_the_independent_nominal_logs() {
    for (i, (l1, l2)) in ARMS.iter().enumerate() {
        let mut params = PlantParameters::new(*l1, *l2);
        params.noise = false;
        let mut plant = Plant::new(params).unwrap();
        let ours = estimation_run(&mut plant).unwrap();
        let theirs = reference(i + 1);
        let n = ours.len().min(theirs.len());
        assert!(
            n + 2 >= theirs.len().max(ours.len()),
            "case {}: {} vs {} rows",
            i + 1,
            ours.len(),
            theirs.len()
        );
        let (mut path, mut angle) = (0.0, 0.0);
        for (a, b) in ours.iter().zip(&theirs).take(n) {
            let p = a.measurement.pose;
            assert!((a.measurement.time - b.0).abs() < 1e-6);
            path += (p.x - b.1).powi(2) + (p.z - b.2).powi(2);
            angle += (p.psi - b.3).powi(2);
        }
        let (path, angle) = ((path / n as f64).sqrt(), (angle / n as f64).sqrt());
        println!(
            "case {}: grasp path RMS {:.4} mm, psi RMS {:.4} mrad",
            i + 1,
            path * 1e3,
            angle * 1e3
        );
        // plant.md's bar is 0.5 mm RMS; the README states 0.0004 mm and
        // 0.0003 mrad (measured: 0.000374-0.000383 mm, 0.000262-0.000271
        // mrad; rounding to the reference's six decimals gives up to 0.00041 mm and
        // 0.00029 mrad RMS), so the test holds that figure plus one unit
        // of its last digit: a change that degrades the match shows here.
        assert!(path < 0.5e-6, "case {}: path RMS {path}", i + 1);
        assert!(angle < 0.4e-6, "case {}: psi RMS {angle}", i + 1);
    }
}
