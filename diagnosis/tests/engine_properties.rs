//! Properties of the engine on a toy plant whose answer is known: a
//! signal y(t) = sin t observed with unit noise, and three candidate
//! effects (a constant offset, a gain error, a drift); a fourth plantable
//! effect, sin 13t, is no candidate (an effect outside the catalogue).
//! Whatever is planted, the engine names it when it stands above the
//! noise, answers `none` for pure noise, and measures the shrink on
//! held-out blocks.

use limb_diagnosis::model::{grid, Applied, Candidate, Data, Hints, Parameter, Series, Signal};
use limb_diagnosis::{select, HoldOut, Model, ModelError, Options, Problem, Selection};
use limb_sim::noise::Gaussian;
use proptest::prelude::*;

const SIGNAL: Signal = Signal {
    name: "y",
    unit: "1",
};

struct Toy {
    data: Data,
    /// RMS of the residual handed to each candidate's start points.
    hinted: std::sync::Mutex<Vec<f64>>,
}

fn effect(candidate: usize, value: f64, t: f64) -> f64 {
    match candidate {
        0 => value,
        1 => value * t.sin(),
        2 => value * t / 10.0,
        _ => value * (13.0 * t).sin(),
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
            hinted: std::sync::Mutex::new(Vec::new()),
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
    fn starts(&self, _candidate: usize, hints: &Hints) -> Vec<Vec<f64>> {
        if let Some(r) = &hints.residual {
            let column = r.column(0);
            let rms = (column.iter().map(|v| v * v).sum::<f64>() / column.len() as f64).sqrt();
            self.hinted.lock().unwrap().push(rms);
        }
        grid(1, 9)
    }
}

/// The engine's selection on `toy`, alternating 1 s blocks held out.
fn selection(toy: &Toy, options: &Options) -> Selection {
    let problem = Problem::split(toy, HoldOut::default()).unwrap();
    select(&problem, options, &|_| {}).unwrap()
}

fn answer(toy: &Toy) -> (Option<String>, f64) {
    let s = selection(toy, &Options::default());
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
        let s = selection(&toy, &Options::default());
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
    let options = Options {
        max_effects: 3,
        ..Options::default()
    };
    let s = selection(&toy, &options);
    let added: Vec<&str> = s.effects.iter().map(|e| e.effect.as_str()).collect();
    assert_eq!(added, ["offset", "drift"]);
    assert!(s.effects[1].held_out_after < s.effects[0].held_out_after);
    assert!(
        (s.effects[1].params["value"] + 1.5).abs() < 0.15,
        "{:?}",
        s.effects[1].params
    );
}

#[test]
fn later_candidates_start_from_what_the_chosen_effects_leave() {
    // Offset 3 and drift −1.5: the first step's candidates are handed
    // the nominal residual (3 − 0.15 t plus noise: RMS sqrt(5.25 + 1) =
    // 2.5), the second step's what the offset leaves (a ramp of ±0.75
    // plus noise: RMS sqrt(0.19 + 1) = 1.09).
    let toy = Toy::new(&[(0, 3.0), (2, -1.5)], 11);
    let options = Options {
        max_effects: 2,
        ..Options::default()
    };
    let s = selection(&toy, &options);
    assert_eq!(s.steps.len(), 2);
    let hinted = toy.hinted.lock().unwrap().clone();
    // Three candidates at the first step, two at the second.
    assert_eq!(hinted.len(), 5, "{hinted:?}");
    assert!(hinted[..3].iter().all(|r| *r > 2.3), "{hinted:?}");
    assert!(hinted[3..].iter().all(|r| *r < 1.3), "{hinted:?}");
}

/// Options that ask an addition for half the gap.
fn half_the_gap() -> Options {
    Options {
        max_effects: 3,
        min_gain: 0.25,
        min_share: 0.5,
        ..Options::default()
    }
}

#[test]
fn two_effects_that_each_fall_short_of_the_share_are_added_together() {
    // Offset 3 and gain 3: a gap of about sqrt(9 + 4.5) = 3.7; the
    // offset alone leaves sqrt(4.5) = 2.1 (42 % of the gap: short of
    // half), the gain alone 3 (18 %); together they leave the noise.
    let toy = Toy::new(&[(0, 3.0), (1, 3.0)], 5);
    let s = selection(&toy, &half_the_gap());
    let added: Vec<&str> = s.effects.iter().map(|e| e.effect.as_str()).collect();
    assert_eq!(added, ["offset", "gain"]);
    let first = s.gap.before - s.effects[0].held_out_after;
    assert!(first < 0.5 * s.gap.before, "the offset alone: {first}");
    assert!(s.gap.shrink > 0.9, "{:?}", s.gap);
}

#[test]
fn an_addition_on_trial_that_nothing_confirms_is_taken_back() {
    // Offset 1.5 beside 4 sin 13t, which no candidate is: the best first
    // candidate trims about a tenth of the gap (the offset: sqrt 10.25 to
    // sqrt 8), enough to earn its parameter and the least gain, so it is
    // tried; nothing after it brings the share to half, so the answer
    // holds no effect and the step that tried it says it added none.
    let toy = Toy::new(&[(0, 1.5), (3, 4.0)], 5);
    let s = selection(&toy, &half_the_gap());
    assert!(s.effects.is_empty(), "{:?}", s.effects);
    assert_eq!(s.steps.len(), 1, "{:?}", s.steps);
    assert_eq!(s.steps[0].added, None);
    let tried = &s.steps[0].ranking[0];
    assert!(tried.criterion > 0.0, "{tried:?}");
    assert!(s.gap.before - tried.held_out_after >= 0.25, "{tried:?}");
    assert_eq!(s.gap.shrink, 0.0, "{:?}", s.gap);
}

#[test]
fn a_trial_is_not_confirmed_by_an_addition_of_unlike_size() {
    // Offset √12, gain 2 and 2√2 sin 13t (no candidate): a held-out gap
    // of 4.56 (seed 5). The offset alone leaves 2.44 (a 46 % shrink: on
    // trial), the gain after it 2.01 (the pair 56 %, past half) but
    // itself only 18 % of the 2.44 it joins: short of a quarter, so it
    // does not confirm the offset, and the answer holds no effect.
    let planted = [(0, 12f64.sqrt()), (1, 2.0), (3, 2.0 * 2f64.sqrt())];
    let toy = Toy::new(&planted, 5);
    let s = selection(&toy, &half_the_gap());
    assert!(s.effects.is_empty(), "{:?}", s.effects);
    assert_eq!(s.gap.shrink, 0.0, "{:?}", s.gap);
    // What the rule refused: with no share asked, the same two are
    // added, the pair past half of the gap, the gain under a quarter of
    // what the offset left.
    let free = Options {
        min_share: 0.0,
        max_effects: 2,
        ..half_the_gap()
    };
    let s = selection(&toy, &free);
    let added: Vec<&str> = s.effects.iter().map(|e| e.effect.as_str()).collect();
    assert_eq!(added, ["offset", "gain"]);
    let (first, pair) = (s.effects[0].held_out_after, s.effects[1].held_out_after);
    assert!(
        first > 0.5 * s.gap.before,
        "the offset alone: {first} of {}",
        s.gap.before
    );
    assert!(
        pair <= 0.5 * s.gap.before,
        "the pair: {pair} of {}",
        s.gap.before
    );
    assert!(first - pair < 0.25 * first, "the gain: {first} → {pair}");
}
