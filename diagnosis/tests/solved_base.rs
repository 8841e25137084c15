//! A base the model solves itself is not searched: a toy plant whose
//! nominal level is solved by least squares (as the arm plant solves its
//! lengths, `Model::solves`). Searching the level as well gives the
//! simplex directions along which the cost cannot change; on the arm
//! plant that stopped slips in mid-lift at half their shift
//! (`arm_slip.rs`).

use limb_diagnosis::model::{grid, Applied, Candidate, Data, Hints, Parameter, Series, Signal};
use limb_diagnosis::{select, HoldOut, Model, ModelError, Options, Problem};
use limb_sim::noise::Gaussian;

/// The base candidate, the only one: the nominal level.
const LEVEL: usize = 0;

struct Level {
    data: Data,
    solves: bool,
}

impl Level {
    /// Unit noise over sin t + `level`, t in [0, 10) s; `solves`: what
    /// [`Model::solves`] says of the level.
    fn new(level: f64, seed: u64, solves: bool) -> Self {
        let times: Vec<f64> = (0..1000).map(|i| f64::from(i) * 0.01).collect();
        let mut noise = Gaussian::new(seed);
        let mut observed = Series::with_capacity(1, times.len());
        for t in &times {
            let y = t.sin() + level + noise.sample(1.0);
            observed.push(&[y]).unwrap();
        }
        Self {
            data: Data {
                signals: vec![Signal {
                    name: "y",
                    unit: "1",
                }],
                scales: vec![1.0],
                times,
                observed,
                candidates: vec![Candidate {
                    name: "level",
                    parameters: vec![Parameter::new("value", "1", -10.0, 10.0, "level")],
                }],
            },
            solves,
        }
    }
}

impl Model for Level {
    fn data(&self) -> &Data {
        &self.data
    }
    fn noise_floor(&self) -> f64 {
        1.0
    }
    fn gap_metric(&self) -> &'static str {
        "excess_rms"
    }
    fn base(&self) -> Option<usize> {
        Some(LEVEL)
    }
    fn predict(&self, effects: &[Applied]) -> Result<Series, ModelError> {
        let level: f64 = effects
            .iter()
            .filter(|a| a.candidate == LEVEL)
            .map(|a| a.values[0])
            .sum();
        let mut out = Series::with_capacity(1, self.times().len());
        for t in self.times() {
            out.push(&[level + t.sin()])?;
        }
        Ok(out)
    }
    /// The level is the mean of observed − sin t on the masked samples.
    fn polish(&self, _effects: &[Applied], mask: &[bool]) -> Option<Vec<Applied>> {
        let (mut sum, mut count) = (0.0, 0.0);
        for (i, t) in self.times().iter().enumerate() {
            if mask[i] {
                sum += self.data.observed.row(i)[0] - t.sin();
                count += 1.0;
            }
        }
        Some(vec![Applied {
            candidate: LEVEL,
            values: vec![sum / count],
        }])
    }
    fn solves(&self, candidate: usize) -> bool {
        self.solves && candidate == LEVEL
    }
    fn starts(&self, candidate: usize, _hints: &Hints) -> Vec<Vec<f64>> {
        grid(self.data.candidates[candidate].parameters.len(), 3)
    }
}

#[test]
fn a_solved_base_alone_costs_one_evaluation() {
    // The nominal fit of the level has nothing to search: one cost
    // evaluation (and the engine's own nominal prediction), where a
    // searched level spends the start grid and the simplex's iterations.
    let solved = Level::new(2.0, 4, true);
    let searched = Level::new(2.0, 4, false);
    let options = Options {
        max_effects: 0,
        ..Options::default()
    };
    let run = |toy: &Level| {
        let problem = Problem::split(toy, HoldOut::default()).unwrap();
        select(&problem, &options, &|_| {}).unwrap()
    };
    let (a, b) = (run(&solved), run(&searched));
    assert_eq!(a.nominal, b.nominal);
    assert!(
        a.evaluations + 40 <= b.evaluations,
        "{} vs {}",
        a.evaluations,
        b.evaluations
    );
}
