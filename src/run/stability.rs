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
//!   [`ENERGY_GROWTH_LIMIT`] × what it may hold (its initial energy plus the work of the loads),
//!   times what a stable run of the engine's scheme at the ratio reads above its energy
//!   ([`crate::engines::Stepping::energy_reading`]; for central differences 1/(1 − r²) below
//!   1, 1 from 1 on);
//! - **failed**: the engine refused or failed for another reason;
//! - **accurate**: the largest error against the exact solution of the engine's own model is
//!   within the case's tolerance for the engine ([`tolerance`]);
//! - **inaccurate**: bounded, but outside that tolerance.

use crate::contract::History;
use crate::engines::explicit::ExplicitEngine;
use crate::engines::{self, Engine, RunSettings};
use crate::run::matching;
use crate::scene::{IncrementRule, Scene};
use rayon::prelude::*;

/// The ratios of the map.
pub const RATIOS: [f64; 10] = [0.25, 0.5, 0.75, 0.9, 0.98, 1.02, 1.1, 1.5, 2.0, 4.0];

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
    engines: &[&dyn Engine],
    ratios: &[f64],
    error_of: &(dyn Fn(&Scene, &str, &History) -> Option<f64> + Sync),
    tick: &(dyn Fn() + Sync),
) -> Vec<Point> {
    let jobs: Vec<(&Scene, &dyn Engine, f64)> = mapped(scenes)
        .into_iter()
        .flat_map(|s| {
            engines
                .iter()
                .flat_map(move |e| ratios.iter().map(move |r| (s, *e, *r)))
        })
        .collect();
    jobs.par_iter()
        .map(|(scene, engine, ratio)| {
            let point = map_point(scene, *engine, *ratio, error_of);
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
    engine: &dyn Engine,
    ratio: f64,
    error_of: &(dyn Fn(&Scene, &str, &History) -> Option<f64> + Sync),
) -> Point {
    let name = engine.name();
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
    let asked = RunSettings {
        increment: Some(IncrementRule::StableRatio(ratio)),
        ..RunSettings::default()
    };
    let settings = matching::job_settings(engine, scene, &asked);
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        engine.run(scene, &settings)
    }));
    match run {
        Ok(Ok(out)) => {
            point.increment = Some(out.info.increment);
            point.energy_growth = energy_growth(&out.history);
            point.error_max = error_of(scene, name, &out.history);
            let finite = out.history.rows.iter().flatten().all(|x| x.is_finite());
            let reading = engine.stepping().map_or(
                engines::central_difference_energy_reading as fn(f64) -> f64,
                |s| s.energy_reading,
            );
            let limit = ENERGY_GROWTH_LIMIT * reading(ratio);
            point.outcome = if !finite || point.energy_growth.is_some_and(|g| g > limit) {
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

/// A map: its grid runs and each (case, engine)'s critical increment.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Map {
    /// The grid's runs, in case, engine, ratio order.
    pub points: Vec<Point>,
    /// Per (case, engine), the largest increment that stays bounded.
    pub critical: Vec<Critical>,
}

/// Bisection stops when the bracket's two ratios are within this factor of each other (1 %).
pub const BISECTION_WIDTH: f64 = 1.01;

/// Ratios tried beyond the grid when an engine stayed bounded at all of its ratios: the
/// critical increment is then reported as at least the largest bounded one.
pub const BEYOND: [f64; 2] = [16.0, 64.0];

/// Ratios tried below the grid when an engine was unstable at its smallest ratio.
pub const BELOW: [f64; 2] = [0.125, 0.0625];

/// How the critical increment was bounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bound {
    /// Between a bounded and an unstable run within [`BISECTION_WIDTH`].
    Bisected,
    /// Bounded at every ratio tried, up to the largest ([`BEYOND`]): at least this.
    AtLeast,
    /// Unstable at every ratio tried, down to the smallest ([`BELOW`]): less than this.
    Below,
}

impl Bound {
    /// Name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Bound::Bisected => "bisected",
            Bound::AtLeast => "at_least",
            Bound::Below => "below",
        }
    }
    /// From the CSV name.
    pub fn parse(s: &str) -> Option<Bound> {
        [Bound::Bisected, Bound::AtLeast, Bound::Below]
            .into_iter()
            .find(|b| b.name() == s)
    }
}

/// The largest increment at which an engine stays bounded on a case, found from the map's
/// grid and refined by bisection.
#[derive(Debug, Clone, PartialEq)]
pub struct Critical {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// The largest bounded run's increment, seconds (for [`Bound::Below`], the smallest
    /// increment tried).
    pub increment: f64,
    /// The explicit engine's computed stable increment on the case, seconds.
    pub explicit_stable: f64,
    /// How it was bounded.
    pub bound: Bound,
    /// The runs beyond the grid (bisection, extension above or below), in the order run.
    pub probes: Vec<Point>,
}

impl Critical {
    /// The critical increment over the explicit engine's computed stable increment.
    pub fn explicit_ratio(&self) -> f64 {
        self.increment / self.explicit_stable
    }
}

fn bounded(o: Outcome) -> bool {
    matches!(o, Outcome::Accurate | Outcome::Inaccurate)
}

/// Each (case, engine)'s critical increment from its grid `points` (as [`run`] returns them),
/// running the extra ratios it needs; in parallel. A pair whose grid has a failed or not
/// applicable run, or whose case has no explicit stable increment, has none.
pub fn critical(
    scenes: &[&Scene],
    engines: &[&dyn Engine],
    points: &[Point],
    error_of: &(dyn Fn(&Scene, &str, &History) -> Option<f64> + Sync),
) -> Vec<Critical> {
    let mut pairs: Vec<(&Scene, &dyn Engine)> = Vec::new();
    for p in points {
        if let Some(s) = scenes.iter().find(|s| s.id == p.case)
            && let Some(e) = engines.iter().find(|e| e.name() == p.engine)
            && !pairs
                .iter()
                .any(|(c, e)| c.id == p.case && e.name() == p.engine)
        {
            pairs.push((s, *e));
        }
    }
    pairs
        .par_iter()
        .filter_map(|(scene, engine)| {
            let mut grid: Vec<&Point> = points
                .iter()
                .filter(|p| p.case == scene.id && p.engine == engine.name())
                .collect();
            grid.sort_by(|a, b| a.ratio.total_cmp(&b.ratio));
            bisect(scene, *engine, &grid, error_of)
        })
        .collect()
}

/// One pair's critical increment (see [`critical`]).
fn bisect(
    scene: &Scene,
    engine: &dyn Engine,
    grid: &[&Point],
    error_of: &(dyn Fn(&Scene, &str, &History) -> Option<f64> + Sync),
) -> Option<Critical> {
    if grid
        .iter()
        .any(|p| !bounded(p.outcome) && p.outcome != Outcome::Unstable)
    {
        return None;
    }
    let explicit_stable = ExplicitEngine::finite()
        .stable_increment(scene, &RunSettings::default())?
        .increment;
    let mut probes: Vec<Point> = Vec::new();
    let run = |ratio: f64, probes: &mut Vec<Point>| -> Point {
        let p = map_point(scene, engine, ratio, error_of);
        probes.push(p.clone());
        p
    };
    let first_unstable = grid.iter().position(|p| p.outcome == Outcome::Unstable);
    // The bracket: (largest bounded run, smallest unstable run above it).
    let (mut low, mut high): (Option<Point>, Option<Point>) = match first_unstable {
        Some(0) => (None, Some(grid[0].clone())),
        Some(i) => (Some(grid[i - 1].clone()), Some(grid[i].clone())),
        None => (grid.last().map(|p| (*p).clone()), None),
    };
    if high.is_none() {
        for r in BEYOND {
            let p = run(r, &mut probes);
            match p.outcome {
                o if bounded(o) => low = Some(p),
                Outcome::Unstable => {
                    high = Some(p);
                    break;
                }
                _ => break,
            }
        }
    }
    if low.is_none() {
        for r in BELOW {
            let p = run(r, &mut probes);
            match p.outcome {
                o if bounded(o) => {
                    low = Some(p);
                    break;
                }
                Outcome::Unstable => high = Some(p),
                _ => break,
            }
        }
    }
    let bound = match (&low, &high) {
        (Some(_), Some(_)) => Bound::Bisected,
        (Some(_), None) => Bound::AtLeast,
        (None, _) => Bound::Below,
    };
    if let (Some(l), Some(h)) = (&mut low, &mut high) {
        while h.ratio / l.ratio > BISECTION_WIDTH {
            let p = run((l.ratio * h.ratio).sqrt(), &mut probes);
            match p.outcome {
                o if bounded(o) => *l = p,
                Outcome::Unstable => *h = p,
                _ => break,
            }
        }
    }
    let at = low.or(high)?;
    Some(Critical {
        case: scene.id.clone(),
        engine: engine.name().to_string(),
        increment: at.increment?,
        explicit_stable,
        bound,
        probes,
    })
}
