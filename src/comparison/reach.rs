//! Costs measured where the sweep stopped short: an engine whose cost to an accuracy was
//! extrapolated along its observed order is run at the increment that extrapolation predicts,
//! and finer, until it reaches the accuracy, levels off, or would take more than
//! [`BUDGET`] × the sweep's budget of increments for one of its runs (about a minute of CPU for
//! rapier, a few seconds for the explicit engine). What was predicted and what the runs gave
//! are kept side by side ([`Check`]), so that an extrapolation is never taken on trust where
//! a run could check it.
//!
//! Each run after the first aims at [`AIM`] × the accuracy along the fitted order. Where the
//! local order from the coarsest earlier point at least [`SPAN`] × the run's increment (the
//! sweep's most accurate point, or an earlier run) falls below half the fitted one, the error
//! is levelling: the runs show a floor, and the accuracy is not extrapolated across it
//! ([`super::verdict::cost`]). Over a shorter span a local order is noise (a contact's event
//! times move the error by a few per cent either way), so none is read there. A case equivalent to
//! another (the same closed form, [`super::equivalence`]) is checked on that one only.

use super::verdict::cost::{self, Reached};
use super::work_precision::{CaseSweep, EngineFit};
use crate::run::sweep::{self, ErrorOf, Grid, PathKind, Status, SweepPath};
use crate::run::{Engine, Plan};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// A run toward an accuracy may take this many times the sweep's budget of increments for one
/// run of the engine ([`Grid::max_increments`] × its budget share): about a minute of CPU for
/// rapier's matched configuration (0.9 µs per substep measured on the pinned seed case).
pub const BUDGET: f64 = 300.0;

/// Most runs toward one accuracy.
pub const RUNS: usize = 3;

/// The accuracies checked: those the report's first screen answers (1e-6 stays extrapolated,
/// where no floor stops it).
pub const CHECKED: [f64; 2] = [1e-2, 1e-4];

/// After the run at the predicted increment, each run aims at this fraction of the accuracy,
/// so that one more run lands within it rather than approaching it from above.
pub const AIM: f64 = 0.7;

/// A local order is read only between increments at least this far apart.
pub const SPAN: f64 = 4.0;

/// How a reach ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ended {
    /// A run reached the accuracy.
    Reached,
    /// The error levelled: the local order fell below half the fitted one.
    Levelled,
    /// The next run would take more than the budget, or [`RUNS`] were made.
    Budget,
    /// A run failed or went unstable.
    Failed,
}

/// An extrapolated cost checked by runs: what was predicted, what the runs gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// Case id.
    pub case: String,
    /// Engine.
    pub engine: String,
    /// The accuracy aimed at.
    pub target: f64,
    /// The order it was extrapolated along.
    pub order: f64,
    /// The increment the extrapolation predicted, seconds.
    pub predicted_increment: f64,
    /// The CPU time the extrapolation predicted, seconds per simulated second.
    pub predicted_cpu: f64,
    /// The runs: (increment, error over the peak, CPU seconds per simulated second), the
    /// first at the predicted increment.
    pub runs: Vec<(f64, Option<f64>, f64)>,
    /// How it ended.
    pub ended: Ended,
}

/// One extrapolated cost to check: the case's sweep index, the engine, the target, the order
/// and the predicted increment and CPU time.
struct Task<'a> {
    sweep: usize,
    scene: &'a Scene,
    engine: &'a dyn Engine,
    target: f64,
    order: f64,
    from: (f64, f64),
    predicted: (f64, f64),
}

/// The extrapolated costs of `fit` on `sweep` that a run can check within the budget.
fn tasks<'a>(
    index: usize,
    sweep: &CaseSweep,
    fit: &EngineFit,
    scene: &'a Scene,
    engine: &'a dyn Engine,
    grid: &Grid,
) -> Vec<Task<'a>> {
    let Some(stepping) = engine.stepping() else {
        return Vec::new();
    };
    // Only along an increment path: the penalty diagonal varies two settings at once.
    let on_increments = sweep.paths.iter().any(|p| {
        p.engine == fit.engine
            && fit
                .observed_order
                .as_ref()
                .is_some_and(|o| o.path == p.label())
            && p.kind
                == (PathKind::Increment {
                    penalty_ratio: None,
                })
    });
    if !on_increments {
        return Vec::new();
    }
    let budget = BUDGET * grid.max_increments * stepping.budget_share;
    cost::costs(sweep, fit)
        .into_iter()
        .filter(|c| c.reached == Reached::Extrapolated && CHECKED.contains(&c.target))
        .filter_map(|c| {
            let (h, cpu, order) = (c.increment?, c.cpu_s_per_simulated_s?, c.order?);
            let e = c.error?;
            let from = (h * (e / c.target).powf(1.0 / order), e);
            (sweep::increments_at(scene, engine, h) <= budget).then_some(Task {
                sweep: index,
                scene,
                engine,
                target: c.target,
                order,
                from,
                predicted: (h, cpu),
            })
        })
        .collect()
}

/// Run one task: at the predicted increment, then along the local order, until it ends.
fn reach(task: &Task, grid: &Grid, error: &ErrorOf) -> (Check, SweepPath) {
    let stepping = task.engine.stepping();
    let budget = BUDGET * grid.max_increments * stepping.map_or(1.0, |s| s.budget_share);
    let duration = task.scene.duration();
    let mut points = Vec::new();
    let mut runs = Vec::new();
    let mut h = task.predicted.0;
    let mut earlier = vec![task.from];
    let mut ended = Ended::Budget;
    for _ in 0..RUNS {
        if sweep::increments_at(task.scene, task.engine, h) > budget {
            break;
        }
        let p = sweep::run_at(task.scene, task.engine, h, error);
        let cpu = p.cpu_seconds.iter().copied().fold(f64::INFINITY, f64::min) / duration;
        let e = p.error.map(|e| e.0);
        runs.push((p.increment, e, cpu));
        let status = p.status;
        points.push(p);
        let Some(e) = e.filter(|_| status == Status::Ok) else {
            ended = Ended::Failed;
            break;
        };
        if super::verdict::within(e, task.target) {
            ended = Ended::Reached;
            break;
        }
        let span = earlier
            .iter()
            .filter(|p| p.0 >= SPAN * h)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let falls = |(hp, ep): (f64, f64)| (ep / e).ln() / (hp / h).ln() >= task.order / 2.0;
        if span.is_some_and(|p| !falls(*p)) {
            ended = Ended::Levelled;
            break;
        }
        earlier.push((h, e));
        h *= (AIM * task.target / e).powf(1.0 / task.order);
    }
    let check = Check {
        case: task.scene.id.clone(),
        engine: task.engine.name().to_string(),
        target: task.target,
        order: task.order,
        predicted_increment: task.predicted.0,
        predicted_cpu: task.predicted.1,
        runs,
        ended,
    };
    let path = SweepPath {
        engine: task.engine.name().to_string(),
        precision: stepping.map_or("f64", |s| s.precision),
        kind: PathKind::Reach {
            target: task.target,
        },
        points,
        ended: match ended {
            Ended::Reached => "reached",
            Ended::Levelled => "levelled",
            Ended::Budget => "budget",
            Ended::Failed => "failed",
        },
    };
    (check, path)
}

/// Check every extrapolated cost of `sweeps` that a run can check within the budget (in
/// parallel), adding each reach's runs to its case's sweep as a path and its [`Check`] to its
/// case's checks. `error_of` measures a run as the sweep does.
pub fn measure(
    plan: &Plan,
    engines: &[&dyn Engine],
    sweeps: &mut [CaseSweep],
    grid: &Grid,
    error_of: &sweep::SceneErrorOf,
    progress: bool,
) {
    let work: Vec<Task> = sweeps
        .iter()
        .enumerate()
        .filter(|(_, s)| s.same_as.is_none())
        .filter_map(|(i, s)| Some((i, s, plan.cases.iter().find(|c| c.id == s.case)?)))
        .flat_map(|(i, s, scene)| {
            s.fits.iter().flat_map(move |fit| {
                engines
                    .iter()
                    .find(|e| e.name() == fit.engine)
                    .map(|e| tasks(i, s, fit, scene, *e, grid))
                    .unwrap_or_default()
            })
        })
        .collect();
    let bar = crate::run::progress_bar(work.len(), progress);
    bar.set_message("time to accuracy");
    // Longest first: the first run's CPU time as extrapolated (later runs are finer still).
    let done = crate::run::schedule::longest_first(
        &work,
        |task| task.predicted.1 * task.scene.duration(),
        |task| {
            let error = |e: &str, h: &crate::contract::History, steps: u64| {
                error_of(task.scene, e, h, steps)
            };
            let (check, path) = reach(task, grid, &error);
            bar.inc(1);
            (task.sweep, check, path)
        },
    );
    bar.finish_and_clear();
    for (i, check, path) in done {
        sweeps[i].paths.push(path);
        sweeps[i].checks.push(check);
    }
}
