//! The stability map's runs: one engine on one scene at an increment given as a ratio of the
//! explicit engine's computed stable increment, on a horizon long enough for the run's growth
//! to be judged. This layer runs; the comparison (`comparison::stability`) judges each run and
//! decides where to probe next.
//!
//! The explicit engines step at the ratio × their own computed stable increment; rapier, which
//! has none, at the ratio × the explicit engine's ([`crate::run::matching`]). Every increment is
//! taken exactly (rows between increments are interpolated), so a ratio of 1.02 is 1.02.
//!
//! **The horizon.** A run shorter than [`MIN_INCREMENTS`] increments cannot tell a growing
//! mode from a transient. Where a case is shorter than that at an increment, the run is made on
//! the case *continued in time* ([`continued`]): its last dynamic step lengthened by a whole
//! number of the case's durations, at the same output interval, so that its first rows are the
//! case's own (the accuracy is measured on them) and the rest show where the energy goes.

use crate::engines::explicit::ExplicitEngine;
use crate::engines::{Coarsest, Engine, RunOutput, RunSettings};
use crate::run::{Status, matching};
use crate::scene::{IncrementRule, Scene, StepKind};

/// The fewest increments a map run takes (see the module doc).
pub const MIN_INCREMENTS: f64 = 20.0;

/// The longest continuation: a case is run on at most this many times its duration.
pub const MAX_CONTINUATION: f64 = 1000.0;

/// The explicit engine's computed stable increment on a scene, the map's unit of increment
/// (`None`: a scene without stiffness, such as a free body's spin, has none).
pub fn explicit_stable(scene: &Scene) -> Option<f64> {
    ExplicitEngine::finite()
        .stable_increment(scene, &RunSettings::default())
        .map(|s| s.increment)
}

/// The scenes a map covers: those with a stable increment to take ratios of.
pub fn mapped<'a>(scenes: &[&'a Scene]) -> Vec<&'a Scene> {
    scenes
        .iter()
        .copied()
        .filter(|s| explicit_stable(s).is_some())
        .collect()
}

/// The largest increment `engine` runs at on `scene` anywhere in a report: its job's (`job`),
/// and its sweep's coarsest (for a sweep that starts at the engine's stable increment, the
/// probe just above it, under twice the explicit stable increment `stable`).
pub fn largest_step(scene: &Scene, engine: &dyn Engine, job: Option<f64>, stable: f64) -> f64 {
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    let sweep = match engine.stepping().map(|s| s.coarsest) {
        Some(Coarsest::Increment(h)) => h,
        Some(Coarsest::OutputInterval) => interval,
        Some(Coarsest::Stable { .. }) => 2.0 * stable,
        None => 0.0,
    };
    job.unwrap_or(0.0).max(sweep)
}

/// `scene` continued in time: its last dynamic step lengthened so that the whole lasts
/// `times` × its duration (`times` a whole number, at least 1), with as many more output rows
/// at the same output interval. The first rows sample the same times as the case's own.
pub fn continued(scene: &Scene, times: usize) -> Scene {
    let mut longer = scene.clone();
    if times <= 1 {
        return longer;
    }
    let extra = scene.duration() * (times - 1) as f64;
    if let Some(step) = longer
        .steps
        .iter_mut()
        .rev()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        && let StepKind::Dynamic { duration } = &mut step.kind
    {
        *duration += extra;
        longer.output_rows = (scene.output_rows - 1) * times + 1;
    }
    longer
}

/// How many times its duration a case must last for a run at `increment` to take at least
/// [`MIN_INCREMENTS`] increments (1 where it already does; `None` beyond
/// [`MAX_CONTINUATION`]).
pub fn continuation(scene: &Scene, increment: f64) -> Option<usize> {
    let times = (MIN_INCREMENTS * increment / scene.duration())
        .ceil()
        .max(1.0);
    (times <= MAX_CONTINUATION).then_some(times as usize)
}

/// One run of the map: how it came out (typed), its output where it finished, the engine's
/// message where it did not, the increment and the horizon it ran on.
pub struct MapRun {
    /// Typed outcome of the run.
    pub status: Status,
    /// The engine's output (a history that meets the contract) where it finished.
    pub output: Option<RunOutput>,
    /// Why it did not finish, in the engine's words.
    pub message: Option<String>,
    /// The increment used (the one asked for where the engine refused before choosing).
    pub increment: Option<f64>,
    /// How many times the case's duration it ran over (`None`: it did not run, the case
    /// being too short for [`MIN_INCREMENTS`] increments even continued [`MAX_CONTINUATION`]
    /// times).
    pub continued: Option<usize>,
}

/// Run `engine` on `scene` at `ratio` × the explicit stable increment, continued in time where
/// the case is too short for [`MIN_INCREMENTS`] increments at that increment.
pub fn run_at(scene: &Scene, engine: &dyn Engine, ratio: f64) -> MapRun {
    run_on(scene, engine, ratio, 1)
}

/// [`run_at`] on a horizon at least `longer` times the one [`run_at`] chooses (the
/// confirmation of a run that was still growing at its end).
pub fn run_on(scene: &Scene, engine: &dyn Engine, ratio: f64, longer: usize) -> MapRun {
    let asked = RunSettings {
        increment: Some(IncrementRule::StableRatio(ratio)),
        ..RunSettings::default()
    };
    let settings = matching::job_settings(engine, scene, &asked);
    let planned = engine
        .increments(scene, &settings)
        .map(|n| scene.duration() / n)
        .or_else(|| explicit_stable(scene).map(|s| ratio * s));
    let times = match planned.map(|h| continuation(scene, h)) {
        Some(Some(k)) => k * longer.max(1),
        Some(None) => {
            return MapRun {
                status: Status::Ok,
                output: None,
                message: Some(format!(
                    "the case would have to last over {MAX_CONTINUATION} times its duration for \
                     {MIN_INCREMENTS} increments"
                )),
                increment: planned,
                continued: None,
            };
        }
        None => longer.max(1),
    };
    let scene = continued(scene, times);
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        engine.run(&scene, &settings)
    }));
    let (result, status) = crate::run::checked_run(&scene, run);
    match result {
        Ok(success) => MapRun {
            status,
            increment: Some(success.info.increment),
            output: Some(RunOutput {
                engine: engine.name().to_string(),
                history: success.history,
                info: success.info,
            }),
            message: None,
            continued: Some(times),
        },
        Err(message) => MapRun {
            status,
            output: None,
            message: Some(message),
            increment: planned,
            continued: Some(times),
        },
    }
}
