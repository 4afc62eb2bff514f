//! Invariance controls: a case parameter that does not enter the exact solution must not decide
//! a verdict. Where one does not, each judged cell is run again at both natural values of it,
//! and any engine whose verdict differs between them is named.
//!
//! - **The restitution of a contact that never strikes**: where the exact solution of the case
//!   has no impact (every pair that is closed stays closed, none that is open closes), the
//!   coefficient of restitution enters no exact history; its natural values are 0 (a contact
//!   that rests or slides) and 1 (elastic). The exact solution is run at both too, and must
//!   give the same history to round-off (that is what makes the parameter invariant here).
//! - **The penalty stiffness of a contact that never closes**: where the exact solution has no
//!   impact and every pair starts open, the penalty enters no exact history either; it is run
//!   at the case's and [`PENALTY_FACTOR`] times it (a penalty engine's stable increment falls
//!   with it, so that its time error can change).
//!
//! Each run is measured against the case's exact solution of the engine's own model, as the
//! cell is, and judged by the one rule ([`super::verdict`]).

use super::verdict::{meets, tolerance};
use super::{baseline, compare};
use crate::run::controls::{ControlKind, PENALTY_FACTOR};
use crate::run::{Engine, Outcome, Plan, RunSettings, Status, checked_run, matching};
use crate::scene::{ContactState, PenaltyRule, Scene};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Two histories of the exact solution agree to round-off within this fraction of the peak.
pub const ROUND_OFF: f64 = 1e-9;

/// One engine on one case at the two values of a parameter the exact solution ignores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pair {
    /// Engine.
    pub engine: String,
    /// Its worst error at each value (`None`: it failed, or nothing was compared).
    pub errors: [Option<f64>; 2],
    /// Its verdict at each value.
    pub met: [Option<bool>; 2],
}

impl Pair {
    /// Whether its verdict depends on the parameter.
    pub fn depends(&self) -> bool {
        self.met[0].is_some() && self.met[1].is_some() && self.met[0] != self.met[1]
    }
}

/// A parameter of a case that the exact solution ignores, at its two values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Invariance {
    /// Case id.
    pub case: String,
    /// What is varied, as a control's kind (restitution, penalty).
    pub kind: ControlKind,
    /// The parameter, in words ("restitution of every contact pair").
    pub parameter: String,
    /// The two values, in words ("e = 0", "e = 1").
    pub values: [String; 2],
    /// Which of the two the case states (`None`: neither, such as e = 0.5).
    pub stated: Option<usize>,
    /// The exact solution's largest change between the two values, over its peak (round-off
    /// where the parameter is truly ignored).
    pub exact_change: Option<f64>,
    /// Every judged engine at both values.
    pub engines: Vec<Pair>,
}

/// A parameter variant: its words and how a run is set up at each value.
struct Variant {
    kind: ControlKind,
    stated: Option<usize>,
    parameter: String,
    values: [String; 2],
    scenes: [Scene; 2],
    settings: [RunSettings; 2],
}

/// The parameters `scene` has that its exact solution ignores, given whether it `struck`.
fn variants(scene: &Scene, struck: bool) -> Vec<Variant> {
    if scene.contacts.is_empty() || struck {
        return Vec::new();
    }
    let restitution = |e: f64| {
        let mut s = scene.clone();
        for c in &mut s.contacts {
            c.restitution = e;
        }
        s
    };
    let all = |e: f64| scene.contacts.iter().all(|c| c.restitution == e);
    let mut out = vec![Variant {
        kind: ControlKind::Restitution,
        stated: [0.0, 1.0].iter().position(|e| all(*e)),
        parameter: "the restitution of every contact pair (none strikes)".into(),
        values: ["e = 0".into(), "e = 1".into()],
        scenes: [restitution(0.0), restitution(1.0)],
        settings: [RunSettings::default(); 2],
    }];
    if scene
        .contacts
        .iter()
        .all(|c| c.initially == ContactState::Open)
    {
        let k = scene.penalty_stiffness(scene.settings.penalty);
        let stiffer = RunSettings {
            penalty: Some(PenaltyRule::Stiffness(PENALTY_FACTOR * k)),
            ..RunSettings::default()
        };
        out.push(Variant {
            kind: ControlKind::Penalty,
            stated: Some(0),
            parameter: "the penalty stiffness (no pair closes)".into(),
            values: [
                format!("k_p = {k:.1e}"),
                format!("k_p = {:.1e}", PENALTY_FACTOR * k),
            ],
            scenes: [scene.clone(), scene.clone()],
            settings: [RunSettings::default(), stiffer],
        });
    }
    out
}

/// The worst error of `engine` on `scene` with `settings` (completed as its job's are), against
/// `exact`, and its verdict under `judged`'s tolerance.
fn judged_run(
    engine: &dyn Engine,
    scene: &Scene,
    settings: &RunSettings,
    plan: &Plan,
    exact: &crate::contract::History,
    judged: &Scene,
) -> (Option<f64>, Option<bool>) {
    let merged = RunSettings {
        penalty: settings.penalty.or(plan.settings.penalty),
        ..plan.settings
    };
    let job = matching::job_settings(engine, scene, &merged);
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| engine.run(scene, &job)));
    let (result, status) = checked_run(scene, run);
    let error = result
        .ok()
        .and_then(|s| compare(judged, exact, &s.history).worst_max);
    let status = if status == Status::Ok && error.is_none() {
        Status::NotApplicable
    } else {
        status
    };
    (
        error,
        meets(status, error, tolerance(judged, engine.name())),
    )
}

/// Every invariance control of `plan`'s cases, for the judged engines of the plan, in parallel.
pub fn measure(plan: &Plan, outcome: &Outcome, progress: bool) -> Vec<Invariance> {
    let work: Vec<(&Scene, Variant)> = plan
        .cases
        .iter()
        .filter_map(|s| {
            let exact = outcome.history(&s.id, super::FINITE_ROTATION_REFERENCE)?;
            Some(
                variants(s, super::strikes(exact))
                    .into_iter()
                    .map(move |v| (s, v)),
            )
        })
        .flatten()
        .collect();
    let bar = crate::run::progress_bar(work.len(), progress);
    bar.set_message("invariance controls");
    let found = work
        .par_iter()
        .map(|(scene, v)| {
            let i = invariance(plan, outcome, scene, v);
            bar.inc(1);
            i
        })
        .collect();
    bar.finish_and_clear();
    found
}

/// One parameter of one case: the exact solution at both values, then every judged engine.
fn invariance(plan: &Plan, outcome: &Outcome, scene: &Scene, v: &Variant) -> Invariance {
    let reference = plan
        .engines
        .iter()
        .find(|e| e.name() == super::FINITE_ROTATION_REFERENCE);
    let exact_change = reference.and_then(|r| {
        let at = |k: usize| r.run(&v.scenes[k], &v.settings[k]).ok().map(|o| o.history);
        let (a, b) = (at(0)?, at(1)?);
        compare(scene, &a, &b).worst_max
    });
    // A parameter the exact solution turns out to depend on judges no engine.
    let ignored = exact_change.is_some_and(|c| c <= ROUND_OFF);
    let engines = plan
        .engines
        .iter()
        .filter(|e| !super::EXACT_SOLUTIONS.contains(&e.name()))
        .filter(|e| !crate::contract::on_older_release(e.name()))
        .filter(|_| ignored)
        .filter_map(|e| {
            let exact = outcome.history(&scene.id, baseline(e.name())?)?;
            let applies = outcome
                .jobs
                .iter()
                .any(|j| j.case == scene.id && j.engine == e.name() && j.applicable());
            if !applies {
                return None;
            }
            let at =
                |k: usize| judged_run(e.as_ref(), &v.scenes[k], &v.settings[k], plan, exact, scene);
            let (first, second) = (at(0), at(1));
            Some(Pair {
                engine: e.name().to_string(),
                errors: [first.0, second.0],
                met: [first.1, second.1],
            })
        })
        .collect();
    Invariance {
        case: scene.id.clone(),
        kind: v.kind,
        stated: v.stated,
        parameter: v.parameter.clone(),
        values: v.values.clone(),
        exact_change,
        engines,
    }
}
