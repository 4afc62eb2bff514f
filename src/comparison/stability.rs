//! The stability map measured: each run of [`crate::run::stability`] judged against the exact
//! solution of its engine's own model (`reference` or `analytic`, as in the tolerance table).

use crate::comparison::against_own_model;
use crate::contract::History;
use crate::run::Engine;
use crate::run::stability::{self, Map};
use crate::run::{Outcome, Plan};
use crate::scene::Scene;

/// Map every case of `plan` for the `engines` that step in time ([`Engine::stepping`]),
/// measuring errors against the exact solutions in `outcome`, and bisect each pair's critical
/// increment ([`stability::critical`]).
pub fn measure(plan: &Plan, outcome: &Outcome, engines: &[&dyn Engine], progress: bool) -> Map {
    let error_of =
        |scene: &Scene, engine: &str, h: &History| against_own_model(outcome, scene, engine, h);
    let chosen = crate::run::sweep::steppers(engines);
    let all: Vec<&Scene> = plan.cases.iter().collect();
    let scenes = stability::mapped(&all);
    let bar = crate::run::progress_bar(
        stability::len(scenes.len(), chosen.len(), stability::RATIOS.len()),
        progress,
    );
    bar.set_message("stability map");
    let points = stability::run(&scenes, &chosen, &stability::RATIOS, &error_of, &|| {
        bar.inc(1)
    });
    bar.set_message("critical increments");
    let critical = stability::critical(&scenes, &chosen, &points, &error_of);
    bar.finish_and_clear();
    Map { points, critical }
}
