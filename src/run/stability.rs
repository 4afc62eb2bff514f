//! The stability map: every stepping engine on every case at a grid of increments, each a
//! ratio of the explicit engine's computed stable increment, each run classified as accurate,
//! inaccurate, unstable or failed.
//!
//! The explicit engines step at the ratio × their own computed stable increment; rapier, which
//! has none, at the ratio × the explicit engine's ([`crate::run::matching`]). Every increment is
//! taken exactly (rows between increments are interpolated), so a ratio of 1.02 is 1.02.
//!
//! - **unstable**: the engine stopped the run as unstable (its state turned non-finite, or
//!   `explicit`'s energy guard tripped), or the run's kinetic plus elastic energy rose above
//!   [`ENERGY_GROWTH_LIMIT`] × what it may hold (its initial energy plus the work of the loads);
//! - **failed**: the engine refused or failed for another reason;
//! - **accurate**: the largest error against the exact solution of the engine's own model is
//!   within the case's tolerance for the engine ([`tolerance`]);
//! - **inaccurate**: bounded, but outside that tolerance.

use crate::contract::History;
use crate::engines::explicit::ExplicitEngine;
use crate::engines::{self, RunSettings};
use crate::run::matching;
use crate::scene::{IncrementRule, Scene};
use rayon::prelude::*;

/// The ratios of the map.
pub const RATIOS: [f64; 10] = [0.25, 0.5, 0.75, 0.9, 0.98, 1.02, 1.1, 1.5, 2.0, 4.0];

/// The engines mapped (every engine that steps in time, as the sweep's).
pub const ENGINES: [&str; 6] = crate::run::sweep::ENGINES;

/// A run is unstable when its energy rose above this multiple of what it may hold: the
/// explicit engine's own guard ([`crate::engines::explicit::integrate::ENERGY_GUARD`]), applied
/// to every engine from the energy columns it writes.
pub const ENERGY_GROWTH_LIMIT: f64 = crate::engines::explicit::integrate::ENERGY_GUARD;

/// How a run came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Outcome {
    /// Within tolerance.
    Accurate,
    /// Bounded, outside tolerance.
    Inaccurate,
    /// Energy grew past the limit, or the engine stopped the run as unstable.
    Unstable,
    /// Failed for another reason (an error mid-run, a panic, an unknown engine).
    Failed,
    /// The engine does not model the case (it says why), at any increment.
    NotApplicable,
}

impl Outcome {
    /// Name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Accurate => "accurate",
            Outcome::Inaccurate => "inaccurate",
            Outcome::Unstable => "unstable",
            Outcome::Failed => "failed",
            Outcome::NotApplicable => "not applicable",
        }
    }
    /// From the CSV name.
    pub fn parse(s: &str) -> Option<Outcome> {
        [
            Outcome::Accurate,
            Outcome::Inaccurate,
            Outcome::Unstable,
            Outcome::Failed,
            Outcome::NotApplicable,
        ]
        .into_iter()
        .find(|o| o.name() == s)
    }
}

/// One run of the map.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// Ratio asked for.
    pub ratio: f64,
    /// Increment used (`None` when the engine refused before choosing one).
    pub increment: Option<f64>,
    /// How it came out.
    pub outcome: Outcome,
    /// Largest error over the peak against the engine's own model's exact solution.
    pub error_max: Option<f64>,
    /// Largest kinetic plus elastic energy over the largest initial energy plus work.
    pub energy_growth: Option<f64>,
    /// The engine's message, for a run that did not finish.
    pub message: Option<String>,
}

/// The tolerance a case sets an engine: its own; for a rapier engine without one, the
/// case's `rapier_f64` tolerance (the same solver); else the tightest the case declares.
pub fn tolerance(scene: &Scene, engine: &str) -> Option<f64> {
    let own = scene.tolerances.get(engine).copied();
    let rapier = || {
        engine
            .starts_with("rapier")
            .then(|| scene.tolerances.get("rapier_f64").copied())
            .flatten()
    };
    own.or_else(rapier)
        .or_else(|| scene.tolerances.values().copied().reduce(f64::min))
}

/// Largest (kinetic + elastic) energy over the largest (initial energy + |work|), from a
/// history's energy columns.
pub fn energy_growth(history: &History) -> Option<f64> {
    let col = |name: &str| history.columns.iter().position(|c| c == name);
    let (k, e, w) = (col("e_kinetic")?, col("e_elastic")?, col("w_external")?);
    let first = history.rows.first()?;
    let e0 = first[k] + first[e];
    let held = history
        .rows
        .iter()
        .map(|r| r[k] + r[e])
        .fold(0.0f64, f64::max);
    let budget = history
        .rows
        .iter()
        .map(|r| e0 + r[w].abs())
        .fold(0.0f64, f64::max);
    (budget > 0.0).then_some(held / budget)
}

/// Run the map: every (case, engine, ratio), in parallel; `error_of` measures a history against
/// the engine's own model's exact solution (`None` when that did not run). Points come back in
/// case, engine, ratio order.
pub fn run(
    scenes: &[&Scene],
    engines: &[&str],
    ratios: &[f64],
    error_of: &(dyn Fn(&Scene, &str, &History) -> Option<f64> + Sync),
    tick: &(dyn Fn() + Sync),
) -> Vec<Point> {
    let jobs: Vec<(&Scene, &str, f64)> = mapped(scenes)
        .into_iter()
        .flat_map(|s| {
            engines
                .iter()
                .flat_map(move |e| ratios.iter().map(move |r| (s, *e, *r)))
        })
        .collect();
    jobs.par_iter()
        .map(|(scene, name, ratio)| {
            let point = map_point(scene, name, *ratio, error_of);
            tick();
            point
        })
        .collect()
}

/// The scenes a map covers: those with a stable increment (a scene without stiffness, such as
/// a free body's spin, has none to take a ratio of).
pub fn mapped<'a>(scenes: &[&'a Scene]) -> Vec<&'a Scene> {
    scenes
        .iter()
        .copied()
        .filter(|s| {
            ExplicitEngine::finite()
                .stable_increment(s, &RunSettings::default())
                .is_some()
        })
        .collect()
}

/// Points a run of the map takes.
pub fn len(scenes: usize, engines: usize, ratios: usize) -> usize {
    scenes * engines * ratios
}

fn map_point(
    scene: &Scene,
    name: &str,
    ratio: f64,
    error_of: &(dyn Fn(&Scene, &str, &History) -> Option<f64> + Sync),
) -> Point {
    let mut point = Point {
        case: scene.id.clone(),
        engine: name.to_string(),
        ratio,
        increment: None,
        outcome: Outcome::Failed,
        error_max: None,
        energy_growth: None,
        message: None,
    };
    let Some(engine) = engines::named(name) else {
        point.message = Some(format!("no engine named {name}"));
        return point;
    };
    let asked = RunSettings {
        increment: Some(IncrementRule::StableRatio(ratio)),
        ..RunSettings::default()
    };
    let settings = matching::job_settings(engine.as_ref(), scene, &asked);
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        engine.run(scene, &settings)
    }));
    match run {
        Ok(Ok(out)) => {
            point.increment = Some(out.info.increment);
            point.energy_growth = energy_growth(&out.history);
            point.error_max = error_of(scene, name, &out.history);
            let finite = out.history.rows.iter().flatten().all(|x| x.is_finite());
            point.outcome =
                if !finite || point.energy_growth.is_some_and(|g| g > ENERGY_GROWTH_LIMIT) {
                    Outcome::Unstable
                } else {
                    match (point.error_max, tolerance(scene, name)) {
                        (Some(e), Some(t)) if e <= t => Outcome::Accurate,
                        _ => Outcome::Inaccurate,
                    }
                };
        }
        Ok(Err(e)) => {
            let message = e.to_string();
            point.increment = engine
                .increments(scene, &settings)
                .map(|n| scene.duration() / n);
            point.outcome = if matches!(e, engines::EngineError::Unsupported(_)) {
                Outcome::NotApplicable
            } else if message.contains("unstable") || message.contains("non-finite") {
                Outcome::Unstable
            } else {
                Outcome::Failed
            };
            point.message = Some(message);
        }
        Err(_) => point.message = Some("the engine panicked".into()),
    }
    point
}
