//! Accuracy on request measured: each run of [`crate::run::on_request`] judged against the
//! exact solution of its engine's own model (`reference` or `analytic`, as in the tolerance
//! table).

use crate::comparison::against_own_model;
use crate::contract::History;
use crate::run::Engine;
use crate::run::on_request::{self, Request};
use crate::run::{Outcome, Plan};
use crate::scene::Scene;

/// Ask the `engines` the study asks (`Stepping::on_request`) for every tolerance of
/// [`on_request::TOLERANCES`] on every case of `plan`, measuring errors against the exact
/// solutions in `outcome`.
pub fn measure(
    plan: &Plan,
    outcome: &Outcome,
    engines: &[&dyn Engine],
    progress: bool,
) -> Vec<Request> {
    let error_of =
        |scene: &Scene, engine: &str, h: &History| against_own_model(outcome, scene, engine, h);
    let chosen: Vec<&dyn Engine> = engines
        .iter()
        .copied()
        .filter(|e| e.stepping().is_some_and(|s| s.on_request))
        .collect();
    let scenes: Vec<&Scene> = plan.cases.iter().collect();
    let bar = crate::run::progress_bar(
        scenes.len() * chosen.len() * on_request::TOLERANCES.len(),
        progress,
    );
    bar.set_message("accuracy on request");
    let requests = on_request::run(
        &scenes,
        &chosen,
        &on_request::TOLERANCES,
        &error_of,
        &|| bar.inc(1),
    );
    bar.finish_and_clear();
    requests
}
