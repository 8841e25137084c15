//! Unmodelled effects against the nominal plant and against the shared
//! logs of an independent implementation (`shared/data/effects/`).
//!
//! * Every effect, with its `labels.json` parameters and noise off, moves
//!   the log measurably from nominal: some measured channel differs by more
//!   than 3 noise sigmas RMS (x, z, y: 0.1 mm; psi: 1 mrad; fx, fz: 0.5 N;
//!   ty: 0.025 N m).
//! * No effects, or an effect at its neutral value, is byte-identical to
//!   the nominal log.
//! * Our noise-off simulation of each shared log's case and parameters
//!   stays close to that (noisy) log; the numbers are the table in
//!   `sim/README.md`.

use limb_sim::log::{to_csv, Record};
use limb_sim::scripted::{estimation_run, Row};
use limb_sim::{Effect, Effects, Plant, PlantParameters};

const SHARED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/effects");

/// One entry of labels.json.
struct Label {
    file: String,
    l1: f64,
    l2: f64,
    effect: Option<Effect>,
}

fn labels() -> Vec<Label> {
    let text = std::fs::read_to_string(format!("{SHARED}/labels.json")).expect("labels.json");
    let json: serde_json::Value = serde_json::from_str(&text).expect("labels JSON");
    json.as_array()
        .expect("array")
        .iter()
        .map(|entry| {
            let name = entry["effect"].as_str().expect("effect");
            let params: Vec<(&str, f64)> = entry["params"]
                .as_object()
                .expect("params")
                .iter()
                .map(|(k, v)| (k.as_str(), v.as_f64().expect("number")))
                .collect();
            Label {
                file: entry["file"].as_str().expect("file").to_string(),
                l1: entry["l1"].as_f64().expect("l1"),
                l2: entry["l2"].as_f64().expect("l2"),
                effect: (name != "none").then(|| Effect::new(name, &params).expect(name)),
            }
        })
        .collect()
}

fn simulate(l1: f64, l2: f64, noise: bool, effects: &[Effect]) -> Vec<Row> {
    let mut params = PlantParameters::new(l1, l2);
    params.noise = noise;
    let mut plant = Plant::with_effects(params, Effects::new(effects).unwrap()).unwrap();
    estimation_run(&mut plant).unwrap()
}

fn csv(rows: &[Row]) -> String {
    to_csv(&rows.iter().map(Record::from_row).collect::<Vec<_>>())
}

/// Channels x, z, psi, y, fx, fz, ty of a record.
fn channels(r: &Record) -> [f64; 7] {
    [
        r.pose.x,
        r.pose.z,
        r.pose.psi,
        r.lateral.unwrap_or(0.0),
        r.wrench.fx,
        r.wrench.fz,
        r.wrench.ty,
    ]
}

/// Noise sigma of each channel (plant.md).
const SIGMA: [f64; 7] = [1e-4, 1e-4, 1e-3, 1e-4, 0.5, 0.5, 0.025];

/// RMS difference per channel over the common rows.
fn rms(a: &[Record], b: &[Record]) -> [f64; 7] {
    let n = a.len().min(b.len());
    let mut sum = [0.0; 7];
    for (ra, rb) in a.iter().zip(b).take(n) {
        let (ca, cb) = (channels(ra), channels(rb));
        for i in 0..7 {
            sum[i] += (ca[i] - cb[i]).powi(2);
        }
    }
    sum.map(|s| (s / n as f64).sqrt())
}

fn records(rows: &[Row]) -> Vec<Record> {
    rows.iter().map(Record::from_row).collect()
}

#[test]
fn every_effect_moves_the_log_from_nominal() {
    for label in labels() {
        let Some(effect) = label.effect else { continue };
        let nominal = records(&simulate(label.l1, label.l2, false, &[]));
        let with = records(&simulate(label.l1, label.l2, false, &[effect]));
        let d = rms(&with, &nominal);
        let worst = (0..7).map(|i| d[i] / SIGMA[i]).fold(0.0, f64::max);
        assert!(worst > 3.0, "{}: only {worst:.2} sigma RMS", effect.name());
    }
}

#[test]
fn no_effect_or_a_neutral_one_is_byte_identical_to_nominal() {
    let nominal = csv(&simulate(0.30, 0.20, true, &[]));
    let mut plant = Plant::new({
        let mut p = PlantParameters::new(0.30, 0.20);
        p.noise = true;
        p
    })
    .unwrap();
    assert_eq!(csv(&estimation_run(&mut plant).unwrap()), nominal);
    let neutral = [
        ("joint_friction", vec![("coulomb", 0.0), ("viscous", 0.0)]),
        ("backlash", vec![("width", 0.0)]),
        ("quantization", vec![("pos", 0.0), ("ang", 0.0)]),
        ("latency", vec![("delay", 0.0)]),
        ("mass_mismatch", vec![("factor", 1.0)]),
        ("plane_tilt", vec![("angle", 0.0)]),
        ("active_torque", vec![("amp", 0.0), ("freq", 1.0)]),
        ("grasp_slip", vec![("shift", 0.0), ("at", 5.0)]),
        ("passive_stiffness", vec![("shoulder", 0.0), ("elbow", 0.0)]),
        ("spasticity", vec![("gain", 0.0), ("threshold", 0.1)]),
        ("shoulder_rhythm", vec![("x", 0.0), ("z", 0.0)]),
        ("cuff_offset", vec![("across", 0.0), ("along", 0.0)]),
        ("shoulder_height", vec![("height", 0.0)]),
    ];
    for (name, params) in neutral {
        let effect = Effect::new(name, &params).unwrap();
        assert!(
            csv(&simulate(0.30, 0.20, true, &[effect])) == nominal,
            "{name} at its neutral value differs from nominal"
        );
    }
}

/// Allowed RMS difference to a shared log, in noise sigmas per channel
/// (x, z, psi, y, fx, fz, ty). Noise-level agreement is 1 sigma, which
/// the READMEs state (measured: 0.965-1.053 sigma on every channel of
/// every log but two), held to 1.1 sigma; rounding amplifies the noise
/// near quantisation steps (sim/README.md: about 0.6 mm expected for x
/// and z, measured 0.514 / 0.500 mm, psi 2.962 mrad); latency's torque
/// is 1.39 sigma.
fn tolerance(file: &str) -> [f64; 7] {
    match file {
        "quantization.csv" => [6.0, 6.0, 3.1, 1.1, 1.1, 1.1, 1.1],
        "latency.csv" => [1.1, 1.1, 1.1, 1.1, 1.1, 1.1, 1.45],
        _ => [1.1; 7],
    }
}

/// Our noise-off run of each shared log's case and parameters agrees with
/// that noisy log within [`tolerance`]. Run with `--nocapture` for the
/// table of sim/README.md (RMS without / with the effect: x, z [mm],
/// psi [mrad], y [mm], fz [N]).
#[test]
fn simulation_of_each_shared_log_matches_it() {
    for label in labels() {
        let path = std::path::PathBuf::from(format!("{SHARED}/{}", label.file));
        let theirs = limb_sim::log::read(&path).unwrap();
        let effects: Vec<Effect> = label.effect.into_iter().collect();
        let ours = records(&simulate(label.l1, label.l2, false, &effects));
        let nominal = records(&simulate(label.l1, label.l2, false, &[]));
        let (with, without) = (rms(&ours, &theirs), rms(&nominal, &theirs));
        println!(
            "| {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.3} / {:.3} | {:.3} / {:.3} | {:.3} / {:.3} |",
            label.file,
            without[0] * 1e3,
            with[0] * 1e3,
            without[1] * 1e3,
            with[1] * 1e3,
            without[2] * 1e3,
            with[2] * 1e3,
            without[3] * 1e3,
            with[3] * 1e3,
            without[5],
            with[5],
        );
        let limit = tolerance(&label.file);
        for i in 0..7 {
            assert!(
                with[i] < limit[i] * SIGMA[i],
                "{}: channel {i} RMS {} above {} sigma",
                label.file,
                with[i],
                limit[i]
            );
        }
    }
}

/// The logged grasp of a person's arm's kinematic effects is where their
/// geometry puts it (`spec/human-arm.md`): with `shoulder_rhythm` the
/// shoulder sits at (L + x q1, z q1) and the grasp l2 from the elbow
/// along the forearm; with `cuff_offset` the grasp is `across` off the
/// forearm's line; with `shoulder_height` the shoulder stands `height`
/// above the elbow resting on the table, the upper arm sloping down to
/// it; frame S's origin the grasp at t = 0 (noise off).
#[test]
fn a_person_s_arm_s_geometry_is_the_logged_grasp() {
    let (l1, l2) = (0.30, 0.20);
    let grasp = |elbow: [f64; 2], psi: f64, across: f64| {
        [
            elbow[0] - l2 * psi.cos() + across * psi.sin(),
            elbow[1] + l2 * psi.sin() + across * psi.cos(),
        ]
    };
    let rhythm = Effect::new("shoulder_rhythm", &[("x", -0.02), ("z", 0.03)]).unwrap();
    let cuff = Effect::new("cuff_offset", &[("across", 0.025), ("along", 0.04)]).unwrap();
    let raised = Effect::new("shoulder_height", &[("height", 0.05)]).unwrap();
    // The upper arm's elevation at rest under the raised shoulder.
    let rest = -(0.05_f64 / l1).asin();
    for (effect, across) in [(rhythm, 0.0), (cuff, 0.025), (raised, 0.0)] {
        let rows = simulate(l1, l2, false, &[effect]);
        let mut largest_q1: f64 = 0.0;
        for row in &rows {
            let (m, t) = (row.measurement, row.truth);
            let g = grasp([t.elbow.x, t.elbow.z], m.pose.psi, across);
            assert!(
                (g[0] - m.pose.x).abs() < 1e-9 && (g[1] - m.pose.z).abs() < 1e-9,
                "{}: grasp {g:?} against the logged ({}, {}) at t = {}",
                effect.name(),
                m.pose.x,
                m.pose.z,
                m.time
            );
            let q1 = t.q[0];
            largest_q1 = largest_q1.max(q1);
            let expected = match effect.name() {
                "shoulder_rhythm" => [l1 + l2 - 0.02 * q1, 0.03 * q1],
                "shoulder_height" => {
                    // The table holds the elbow at its rest height.
                    assert!(q1 >= rest - 0.005, "q1 {q1} below the rest {rest}");
                    [l2 + l1 * rest.cos(), 0.05]
                }
                _ => [l1 + l2, -across],
            };
            // q1 is the potentiometer's (0.0047 rad steps).
            assert!(
                (t.shoulder.x - expected[0]).abs() < 1e-4
                    && (t.shoulder.z - expected[1]).abs() < 1e-4,
                "{}: shoulder {:?} against {expected:?}",
                effect.name(),
                t.shoulder
            );
        }
        assert!(largest_q1 > 0.5, "the lift elevates the upper arm");
    }
}

/// A shoulder the upper arm cannot reach down from is refused with its
/// reason, not clamped: `height` at or above l1 has no rest posture.
#[test]
fn a_shoulder_above_the_upper_arm_s_reach_is_refused() {
    let raise = |height: f64| {
        let effect = Effect::new("shoulder_height", &[("height", height)]).unwrap();
        Plant::with_effects(
            PlantParameters::new(0.2, 0.2),
            Effects::new(&[effect]).unwrap(),
        )
    };
    let refused = raise(0.2).err().unwrap_or_default();
    assert!(
        refused.contains("shoulder_height") && refused.contains("upper arm"),
        "{refused}"
    );
    assert!(raise(0.21).is_err());
    assert!(raise(0.19).is_ok());
}
