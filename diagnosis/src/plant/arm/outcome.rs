//! The answer of `limb diagnose` (`shared/spec/cli.md`): the arm plant's
//! diagnosis of one log, built from the engine's [`Selection`].
//!
//! The log is split into alternating 1 s fit and held-out blocks
//! ([`HoldOut::default`]); effects are added by the engine's forward
//! selection while each earns its parameters on the held-out blocks (at
//! most [`MOST_EFFECTS`]), `none` when no candidate does. The arm
//! lengths are fitted with them unless given; the answer reports the arm
//! as corrected for the effects and what the effects leave unexplained.

use super::model::{ArmError, ArmModel, Lengths};
use crate::engine::{select, EngineError, Gap, Options, Problem, Progress, Ranked, Selection};
use crate::holdout::{HoldOut, TooShort};
use crate::locate::Location;
use limb_sim::effects::ShoulderHeight;
use limb_sim::log::Record;
use limb_sim::ArmBuild;
use serde::Serialize;
use thiserror::Error;

/// Why a log could not be diagnosed.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum DiagnoseError {
    /// The log cannot be compared with the sim.
    #[error(transparent)]
    Arm(#[from] ArmError),
    /// The log is too short to hold data out.
    #[error(transparent)]
    TooShort(#[from] TooShort),
    /// The engine failed.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// A self-check log could not be made.
    #[error("self-check: {0}")]
    SelfCheck(String),
}

/// Most effects one diagnosis adds.
pub const MOST_EFFECTS: usize = 3;
/// Least an added effect must lower the held-out gap by [σ of excess]:
/// an effect twice the noise on one of seven signals alone makes a gap of
/// about 0.76 σ, while the differences between limb-sim and the
/// independent plant of the shared logs, or a replayed 1 kHz session,
/// are worth a few hundredths to a tenth.
pub const MIN_GAIN: f64 = 0.25;
/// Least share of the current held-out gap an added effect must remove
/// (an effect outside the catalogue: the best candidate trims 4 %); one
/// short of it alone stays only when the next addition brings the two to
/// it (two effects of like size: see `Options::min_share`).
pub const MIN_SHARE: f64 = 0.2;
/// The answer when no effect is added but a gap beyond the noise remains:
/// neither `none` nor a catalogue effect.
pub const UNEXPLAINED: &str = "unexplained";

/// What the chosen effects leave of the held-out gap beyond the noise.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unexplained {
    /// Share of the held-out gap before (the nominal sim's) that remains:
    /// after / before.
    pub share: f64,
    /// Signals carrying what remains, strongest first.
    pub signals: Vec<String>,
    /// Start of the stretch holding it [s].
    pub t_start: Option<f64>,
    /// End of it [s].
    pub t_end: Option<f64>,
    /// Frequency band [Hz] when it is periodic.
    pub band_hz: Option<[f64; 2]>,
}

/// The arm, frame S: as given, or fitted and corrected for the effects.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Arm {
    /// Upper-arm length [m].
    pub l1: f64,
    /// Forearm length (elbow to grasp) [m].
    pub l2: f64,
    /// Shoulder at rest [m] (x, z): (l1 + l2, 0) with the arm straight
    /// at the grasp; on a person's build, where the fitted shoulder
    /// height puts it (`shoulder_height`: (l2 + l1 cos r, height), r =
    /// −asin(height / l1)).
    pub shoulder: [f64; 2],
    /// The lengths were given (held fixed), not fitted.
    pub given: bool,
    /// The body the lengths are on: `rod` (plant.md's dummy) or `person`
    /// ([`ArmBuild`]).
    pub build: &'static str,
    /// The kernel's estimate from the same log (`limb estimate`, auto),
    /// where the fit started, when fitted and the kernel had one.
    pub estimate: Option<[f64; 2]>,
    /// How finely the log tells l1 and l2 [m] (fitted lengths only): the
    /// change of each that, the arm's other parameters solved with it,
    /// raises the held-out gap by [`MIN_GAIN`], the least an effect must
    /// gain to be named ([`ArmModel::resolution`]); `null` for a length
    /// the log holds nothing of.
    pub resolution: Option<[Option<f64>; 2]>,
    /// The fitted lengths the log does not tell to [`RESOLVED`]: their
    /// value is the fit's, not the arm's (a lift that never raised the
    /// upper arm holds nothing of l1).
    pub unresolved: Vec<&'static str>,
}

impl Arm {
    /// How finely the log tells the fitted lengths, in words (`None`
    /// when the lengths were given): each length's resolution, and those
    /// the log does not tell named as such.
    pub fn resolution_text(&self) -> Option<String> {
        let told = |name: &str, r: Option<f64>| match r {
            Some(r) => format!("{name} to ±{:.1} mm", 1e3 * r),
            None => format!("nothing of {name}"),
        };
        let [l1, l2] = self.resolution?;
        let mut text = format!("the log tells {}, {}", told("l1", l1), told("l2", l2));
        if !self.unresolved.is_empty() {
            text += &format!(
                "; NOT RESOLVED (coarser than {:.0} mm): {} — its value, and the shoulder's that follows from it, are the fit's, not the arm's",
                1e3 * RESOLVED,
                self.unresolved.join(", ")
            );
        }
        Some(text)
    }
}

/// Coarsest resolution [m] at which a fitted length is reported as told
/// by the log (see [`Arm::unresolved`]).
pub const RESOLVED: f64 = 0.01;

/// The diagnosis of one arm log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnosis {
    /// The first effect added; `none` when none is and only noise
    /// remains; [`UNEXPLAINED`] when none is but a gap remains.
    pub effect: String,
    /// The effects added, in order, each with its parameters refitted
    /// with all of them and the held-out gap after it was added.
    pub effects: Vec<Ranked>,
    /// Every candidate, best held-out criterion first.
    pub ranking: Vec<Ranked>,
    /// Where the nominal sim's gap lies.
    #[serde(rename = "where")]
    pub location: Location,
    /// The held-out gap before and after adding the chosen effect.
    pub gap: Gap,
    /// Where what the chosen effect leaves lies (empty signals: nothing
    /// beyond noise).
    pub remaining: Location,
    /// What the effects leave beyond the noise (`null`: only noise).
    pub unexplained: Option<Unexplained>,
    /// The arm corrected for the effects.
    pub arm: Arm,
    /// How the data were held out.
    pub held_out: String,
    /// Simulations and cost evaluations spent.
    pub evaluations: usize,
}

impl Diagnosis {
    fn from_selection(
        selection: &Selection,
        hold_out: HoldOut,
        model: &ArmModel,
        resolution: Option<[Option<f64>; 2]>,
    ) -> Self {
        let r = &selection.remaining;
        let gap = &selection.gap;
        // What remains is named when it is located beyond the noise and
        // at least as large as an addition must gain: the independent
        // plant's clean log leaves 0.22 σ in x, which is no finding.
        let remains = !r.signals.is_empty() && gap.before > 0.0 && gap.after >= MIN_GAIN;
        let unexplained = remains.then(|| Unexplained {
            share: (gap.after / gap.before).clamp(0.0, 1.0),
            signals: r.signals.clone(),
            t_start: r.t_start,
            t_end: r.t_end,
            band_hz: r.band_hz,
        });
        let effect = match (selection.effects.first(), &unexplained) {
            (Some(e), _) => e.effect.clone(),
            (None, Some(_)) => UNEXPLAINED.to_string(),
            (None, None) => "none".to_string(),
        };
        let (l1, l2, height) = match model.lengths() {
            Lengths::Given(l1, l2) => (l1, l2, 0.0),
            Lengths::Fitted => {
                let get = |k: &str| selection.corrected.get(k).copied();
                let length = |k: &str| get(k).unwrap_or(f64::NAN);
                (length("l1"), length("l2"), get("height").unwrap_or(0.0))
            }
        };
        let shoulder = match (ShoulderHeight { height }).rest(l1) {
            Some(rest) => [l1 + l2 + rest.shift[0], rest.shift[1]],
            None => [l1 + l2, f64::NAN],
        };
        let arm = Arm {
            l1,
            l2,
            shoulder,
            given: matches!(model.lengths(), Lengths::Given(..)),
            build: model.build().name(),
            estimate: model.start().map(|(a, b)| [a, b]),
            resolution,
            unresolved: resolution.map_or_else(Vec::new, |r| {
                ["l1", "l2"]
                    .into_iter()
                    .zip(r)
                    .filter(|(_, r)| r.is_none_or(|r| r > RESOLVED))
                    .map(|(name, _)| name)
                    .collect()
            }),
        };
        Self {
            effect,
            effects: selection.effects.clone(),
            unexplained,
            arm,
            ranking: selection
                .steps
                .first()
                .map(|s| s.ranking.clone())
                .unwrap_or_default(),
            location: selection.location.clone(),
            gap: selection.gap.clone(),
            remaining: selection.remaining.clone(),
            held_out: format!(
                "alternating {} s blocks: even blocks fit, odd blocks score",
                hold_out.block
            ),
            evaluations: selection.evaluations,
        }
    }
}

/// The model, the engine's selection and the answer, for callers that
/// also plot (the report).
pub struct Diagnosed {
    /// The sim compared with the log.
    pub model: ArmModel,
    /// The engine's full output (predictions included).
    pub selection: Selection,
    /// The answer.
    pub diagnosis: Diagnosis,
}

/// Diagnoses `records` against the reference plant driven by their
/// commanded set-point, with the arm `lengths` given or fitted, put on
/// `build` (plant.md's dummy, or a person's segments).
/// Ground-truth columns are not read.
///
/// # Errors
/// See [`DiagnoseError`].
pub fn diagnose(
    lengths: Lengths,
    build: ArmBuild,
    records: &[Record],
    threads: usize,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Diagnosed, DiagnoseError> {
    let model = ArmModel::new(lengths, build, records)?;
    let hold_out = HoldOut::default();
    let (selection, resolution) = {
        let problem = Problem::split(&model, hold_out)?;
        let options = Options {
            threads,
            max_effects: MOST_EFFECTS,
            min_gain: MIN_GAIN,
            min_share: MIN_SHARE,
            ..Options::default()
        };
        let selection = select(&problem, &options, progress)?;
        let resolution = model.resolution(
            &selection.chosen,
            &problem.held.mask,
            selection.gap.after,
            MIN_GAIN,
        );
        (selection, resolution)
    };
    let diagnosis = Diagnosis::from_selection(&selection, hold_out, &model, resolution);
    Ok(Diagnosed {
        model,
        selection,
        diagnosis,
    })
}
