//! What "matched settings" means: a decision of the comparison, made when jobs are planned.
//!
//! An engine never borrows another engine's rules. An engine that is to be compared step for
//! step with the explicit engine says so ([`Needs::MatchedIncrement`]); this module asks the
//! explicit engine which increment it would take on the scene under the run's overrides and
//! hands that over as a plain, forced increment in [`RunSettings`]. Everything else an engine
//! decides for itself (rapier's solver sweeps and contact softness are its own configuration).

use crate::engines::explicit::ExplicitEngine;
use crate::engines::{Engine, Needs, RunSettings};
use crate::scene::{IncrementRule, Scene};

/// The settings one job runs with: the run's overrides, completed with what `engine` needs.
pub fn job_settings(engine: &dyn Engine, scene: &Scene, settings: &RunSettings) -> RunSettings {
    let on_request = matches!(
        settings.increment.unwrap_or(scene.settings.increment),
        IncrementRule::Tolerance(_)
    );
    let ratio = match settings.increment.unwrap_or(scene.settings.increment) {
        IncrementRule::StableRatio(r) => Some(r),
        _ => None,
    };
    match engine.needs() {
        // Accuracy on request: every engine chooses its own increment for the tolerance.
        _ if on_request => *settings,
        // A stability study: the ratio is of the explicit engine's stable increment, taken
        // exactly (rapier has no stable increment of its own).
        Needs::MatchedIncrement | Needs::StudyIncrement if ratio.is_some() => RunSettings {
            increment: ratio.and_then(|r| {
                ExplicitEngine::finite()
                    .stable_increment(scene, settings)
                    .map(|s| IncrementRule::Exact(r * s.increment))
            }),
            ..*settings
        },
        Needs::Nothing | Needs::StudyIncrement => *settings,
        Needs::MatchedIncrement => RunSettings {
            increment: Some(IncrementRule::Forced(matched_increment(scene, settings))),
            ..*settings
        },
    }
}

/// The increment the explicit engine (finite rotation, the scene's own model) takes on `scene`
/// under `settings`, by its own rule. A given increment is taken as it is even above the
/// explicit stable one (the matched engine is implicit and has no such limit); when the
/// explicit engine cannot choose one (no stable increment), the output interval.
pub fn matched_increment(scene: &Scene, settings: &RunSettings) -> f64 {
    let rule = match settings.increment.unwrap_or(scene.settings.increment) {
        IncrementRule::Given(h) => IncrementRule::Forced(h),
        other => other,
    };
    let settings = RunSettings {
        increment: Some(rule),
        ..*settings
    };
    ExplicitEngine::finite()
        .increment(scene, &settings)
        .unwrap_or_else(|_| scene.duration() / (scene.output_rows - 1) as f64)
}
