//! Diagnoses every labelled log of `../shared/data/effects/` and prints
//! the ranking head, the gap and the time taken.
use limb_diagnosis::arm::ArmModel;
use limb_diagnosis::{select, HoldOut, Options, Problem};
use std::time::Instant;

fn main() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/effects");
    let labels: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("labels.json")).unwrap()).unwrap();
    for label in labels.as_array().unwrap() {
        let file = label["file"].as_str().unwrap();
        let records = limb_sim::log::read(&dir.join(file)).unwrap();
        let (l1, l2) = (label["l1"].as_f64().unwrap(), label["l2"].as_f64().unwrap());
        let start = Instant::now();
        let model = ArmModel::new(l1, l2, &records).unwrap();
        let problem = Problem::split(&model, HoldOut::default()).unwrap();
        let s = select(&problem, &Options::default(), &|_| {}).unwrap();
        let took = start.elapsed();
        let head: Vec<String> = s.steps[0]
            .ranking
            .iter()
            .take(3)
            .map(|r| format!("{} {:.0} {:?}", r.effect, r.criterion, r.params))
            .collect();
        println!("{file}: chose {:?} gap {:.3} -> {:.3} ({:.2}) where {:?} in {:.2?} ({} evals)\n   {}\n   truth {}",
            s.effects.first().map(|e| e.effect.clone()), s.gap.before, s.gap.after, s.gap.shrink, s.location, took, s.evaluations, head.join(" | "), label["params"]);
    }
}
