//! Test support: reads the shared plant.md logs (std only, tests and
//! examples). Ground-truth columns are returned separately, for scoring.

use limb_kernel::estimation::tilt::PlaneTilt;
use limb_kernel::geometry::{Point, Pose, Wrench};
use limb_kernel::path::PathSample;

/// The shared data directory beside the repository.
pub const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data");

/// A log: the path the estimator sees (recorded as the kernel records it,
/// in the arm's plane its lateral column shows; a vertical one without
/// the column), that plane's tilt, and the logged ground-truth shoulder.
pub struct Log {
    pub path: Vec<PathSample>,
    // Read by the online estimator's tests; the table example runs only
    // the offline methods, which read no tilt.
    #[allow(dead_code)]
    pub tilt: PlaneTilt,
    pub shoulder: Option<Point>,
}

/// Reads `DATA/relative`; panics on malformed data (test input is trusted).
pub fn read(relative: &str) -> Log {
    let file = format!("{DATA}/{relative}");
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::trim)
        .collect();
    let column = |name: &str| header.iter().position(|h| *h == name);
    let required = |name: &str| column(name).unwrap_or_else(|| panic!("{file}: no column {name}"));
    let [t, x, z, psi, fx, fz, ty] = ["t", "x", "z", "psi", "fx", "fz", "ty"].map(required);
    let (sx, sz) = (column("shoulder_x"), column("shoulder_z"));
    let y = column("y");
    let mut tilt = PlaneTilt::new();
    let mut path = Vec::new();
    let mut shoulder = None;
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').collect();
        let value = |i: usize| fields[i].trim().parse::<f64>().expect("number");
        let measured = PathSample {
            time: value(t),
            pose: Pose::new(value(x), value(z), value(psi)),
            wrench: Wrench::new(value(fx), value(fz), value(ty)),
        };
        // As the kernel records it (REQ-EST-011).
        path.push(tilt.record(&measured, y.map_or(0.0, value)));
        if let (Some(sx), Some(sz)) = (sx, sz) {
            shoulder = Some(Point::new(value(sx), value(sz)));
        }
    }
    Log {
        path,
        tilt,
        shoulder,
    }
}

/// Arm lengths (l1, l2) [m] of benchmark case 1..=6 (plant.md Table 1).
pub fn case_lengths(case: usize) -> (f64, f64) {
    let l1 = [0.33, 0.33, 0.30, 0.30, 0.27, 0.27][case - 1];
    let l2 = [0.20, 0.18, 0.20, 0.18, 0.20, 0.18][case - 1];
    (l1, l2)
}

/// One labelled effect log of `effects/labels.json`.
pub struct Labelled {
    pub file: String,
    pub effect: String,
    pub l1: f64,
    pub l2: f64,
    /// The entry as written (its `params` read by [`Labelled::parameter`]).
    #[allow(dead_code)] // read by the tests, not by `examples/estimation_table.rs`
    entry: String,
}

impl Labelled {
    /// The effect's parameter `key` [SI].
    #[allow(dead_code)] // used by the tests, not by `examples/estimation_table.rs`
    pub fn parameter(&self, key: &str) -> f64 {
        field(&self.entry, key).parse().expect("a number")
    }
}

/// The value of `"key":` in a flat JSON entry, as written.
fn field(entry: &str, key: &str) -> String {
    let start = entry.find(&format!("\"{key}\":")).expect("key") + key.len() + 3;
    entry[start..]
        .split([',', '\n'])
        .next()
        .expect("value")
        .trim()
        .trim_matches('"')
        .to_string()
}

/// The labelled effect logs (a minimal reader of the flat labels file).
pub fn labelled_effects() -> Vec<Labelled> {
    let labels = std::fs::read_to_string(format!("{DATA}/effects/labels.json")).expect("labels");
    labels
        .split("\n {")
        .skip(1)
        .map(|entry| {
            let field = |key: &str| field(entry, key);
            Labelled {
                file: field("file"),
                effect: field("effect"),
                l1: field("l1").parse().expect("l1"),
                l2: field("l2").parse().expect("l2"),
                entry: entry.to_string(),
            }
        })
        .collect()
}
