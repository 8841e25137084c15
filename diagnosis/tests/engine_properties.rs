//! Properties of the engine on a toy plant whose answer is known: a
//! signal y(t) = sin t observed with unit noise, and three candidate
//! effects (a constant offset, a gain error, a drift). Whatever is
//! planted, the engine names it when it stands above the noise, answers
//! `none` for pure noise, and measures the shrink on held-out blocks.

use limb_diagnosis::model::{Applied, Candidate, Data, Parameter, Series, Signal};
use limb_diagnosis::{select, HoldOut, Model, ModelError, Options, Problem};
use limb_sim::noise::Gaussian;
use proptest::prelude::*;

const SIGNAL: Signal = Signal {
    name: "y",
    unit: "1",
};

struct Toy {
    data: Data,
}

fn effect(candidate: usize, value: f64, t: f64) -> f64 {
    match candidate {
        0 => value,
        1 => value * t.sin(),
        _ => value * t / 10.0,
    }
}

impl Toy {
    fn new(planted: &[(usize, f64)], seed: u64) -> Self {
        let times: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
        let mut noise = Gaussian::new(seed);
        let mut observed = Series::with_capacity(1, times.len());
        for t in &times {
            let extra: f64 = planted.iter().map(|(c, v)| effect(*c, *v, *t)).sum();
            observed
                .push(&[t.sin() + extra + noise.sample(1.0)])
                .unwrap();
        }
        let parameter = |name| Parameter::new(name, "1", -10.0, 10.0, "planted effect's size");
        let candidates = ["offset", "gain", "drift"]
            .into_iter()
            .map(|name| Candidate {
                name,
                parameters: vec![parameter("value")],
            })
            .collect();
        Self {
            data: Data {
                signals: vec![SIGNAL],
                scales: vec![1.0],
                times,
                observed,
                candidates,
            },
        }
    }
}

impl Model for Toy {
    fn data(&self) -> &Data {
        &self.data
    }
    fn noise_floor(&self) -> f64 {
        1.0
    }
    fn gap_metric(&self) -> &'static str {
        "excess_rms"
    }
    fn predict(&self, effects: &[Applied]) -> Result<Series, ModelError> {
        let times = self.times();
        let mut out = Series::with_capacity(1, times.len());
        for t in times {
            let extra: f64 = effects
                .iter()
                .map(|a| effect(a.candidate, a.values[0], *t))
                .sum();
            out.push(&[t.sin() + extra])?;
        }
        Ok(out)
    }
}

fn answer(toy: &Toy) -> (Option<String>, f64) {
    let problem = Problem::split(toy, HoldOut::default()).unwrap();
    let s = select(&problem, &Options::default(), &|_| {}).unwrap();
    assert!(s.gap.held_out);
    (s.effects.first().map(|e| e.effect.clone()), s.gap.shrink)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// A planted effect whose RMS is at least twice the noise (the drift's
    /// RMS is value / sqrt 3, the gain's value / sqrt 2) is named, with its
    /// value to 10 % and a held-out shrink of at least 80 %.
    #[test]
    fn a_planted_effect_is_named(candidate in 0usize..3, magnitude in 3.5f64..8.0, negative: bool, seed: u64) {
        let value = if negative { -magnitude } else { magnitude };
        let toy = Toy::new(&[(candidate, value)], seed);
        let problem = Problem::split(&toy, HoldOut::default()).unwrap();
        let s = select(&problem, &Options::default(), &|_| {}).unwrap();
        let names = ["offset", "gain", "drift"];
        prop_assert_eq!(s.effects.len(), 1);
        prop_assert_eq!(s.effects[0].effect.as_str(), names[candidate]);
        let fitted = s.effects[0].params["value"];
        prop_assert!(((fitted - value) / value).abs() < 0.1, "{} vs {}", fitted, value);
        prop_assert!(s.gap.shrink >= 0.8, "shrink {}", s.gap.shrink);
    }
}

/// Pure noise seldom earns an effect: the held-out criterion has a small
/// false-positive rate (a candidate's held-out gain on noise exceeds its
/// k ln n penalty by chance), so the property is a rate over fixed seeds,
/// not "never" (as a random-seed property it failed now and then: seed
/// 3679207707835070750 was called `gain`, about one CI run in nine).
/// Measured: 2 of the 401 (seed 319 and that seed, both `gain`); the bound
/// is the 2 % the diagnosis allows for clean logs.
#[test]
fn noise_alone_is_seldom_accused() {
    const SEEDS: u64 = 400;
    let mut accused = Vec::new();
    for seed in (0..SEEDS).chain([3_679_207_707_835_070_750]) {
        let (effect, shrink) = answer(&Toy::new(&[], seed));
        match effect {
            None => assert_eq!(shrink, 0.0, "seed {seed}: no effect but shrink {shrink}"),
            Some(effect) => accused.push((seed, effect)),
        }
    }
    eprintln!(
        "accused on pure noise: {} of {}: {accused:?}",
        accused.len(),
        SEEDS + 1
    );
    assert!(
        accused.len() as u64 * 50 <= SEEDS + 1,
        "{} of {} pure-noise toys accused: {accused:?}",
        accused.len(),
        SEEDS + 1
    );
}

#[test]
fn forward_selection_adds_two_planted_effects_in_order_of_size() {
    // Offset 3 and drift −1.5 together: the offset explains more and
    // comes first, the drift second; nothing else earns a place.
    let toy = Toy::new(&[(0, 3.0), (2, -1.5)], 11);
    let problem = Problem::split(&toy, HoldOut::default()).unwrap();
    let options = Options {
        max_effects: 3,
        ..Options::default()
    };
    let s = select(&problem, &options, &|_| {}).unwrap();
    let added: Vec<&str> = s.effects.iter().map(|e| e.effect.as_str()).collect();
    assert_eq!(added, ["offset", "drift"]);
    assert!(s.effects[1].held_out_after < s.effects[0].held_out_after);
    assert!(
        (s.effects[1].params["value"] + 1.5).abs() < 0.15,
        "{:?}",
        s.effects[1].params
    );
}
