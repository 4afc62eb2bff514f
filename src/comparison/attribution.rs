//! Why a cell misses: each engine × case cell that needs a cause is rerun under control
//! experiments ([`crate::run::controls`]), and the cause is named from what they show.
//!
//! A cell needs a cause when its engine misses the case's tolerance, or when a rapier engine's
//! error is over [`FLAG_RATIO`] times `explicit`'s on the same case. Each control varies one
//! suspected cause, something the exact solution does not depend on (a restitution control is
//! left out where the exact solution strikes, since e enters it there), so the control's error
//! is measured against the same exact solution as the cell's.
//!
//! The cause is the control with the smallest error, if that divides the cell's error by
//! [`EXPLAINS`] or more, or meets the tolerance the cell misses; otherwise the cell is
//! *unexplained*, and the controls tried are listed with their errors all the same.

use super::{EXACT_SOLUTIONS, baseline, compare, judged_tolerance};
use crate::contract::{History, IMPACTS_COLUMN};
use crate::run::controls::{self, ControlKind, Planned};
use crate::run::{JobSuccess, Outcome, Plan};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// A rapier cell needs a cause when its error is over this many times `explicit`'s.
pub const FLAG_RATIO: f64 = 10.0;

/// A control explains a discrepancy when it divides the error by at least this much (or meets
/// the tolerance the cell misses).
pub const EXPLAINS: f64 = 2.0;

/// Why a cell needs a cause.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "value")]
pub enum Flag {
    /// It misses the case's tolerance (the tolerance).
    MissesTolerance(f64),
    /// A rapier error over [`FLAG_RATIO`] × `explicit`'s (the explicit engine's error).
    OverExplicit(f64),
}

/// One control experiment of a cell, measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlRun {
    /// What it varies.
    pub kind: ControlKind,
    /// The variation in words.
    pub change: String,
    /// Its worst error against the cell's exact solution (`None`: it failed, see `failure`).
    pub error: Option<f64>,
    /// Why it failed, where it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// A cell that needs a cause, with its controls and the cause they show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attribution {
    /// Case id.
    pub case: String,
    /// Engine.
    pub engine: String,
    /// The cell's worst error against its exact solution.
    pub error: f64,
    /// Why it needs a cause.
    pub flag: Flag,
    /// The controls, in the order they were tried.
    pub controls: Vec<ControlRun>,
    /// The control that explains the error (index into `controls`); `None`: unexplained.
    pub cause: Option<usize>,
}

impl Attribution {
    /// The control that explains the cell, where one does.
    pub fn explaining(&self) -> Option<&ControlRun> {
        self.controls.get(self.cause?)
    }
}

/// A cell to attribute: its case, job, exact solution, error and why.
struct Cell<'a> {
    scene: &'a Scene,
    engine: &'a str,
    job: &'a JobSuccess,
    exact: &'a History,
    error: f64,
    flag: Flag,
}

/// The cells of `outcome` that need a cause.
fn cells<'a>(plan: &'a Plan, outcome: &'a Outcome) -> Vec<Cell<'a>> {
    let mut out = Vec::new();
    for job in &outcome.jobs {
        if EXACT_SOLUTIONS.contains(&job.engine.as_str()) {
            continue;
        }
        let (Ok(success), Some(scene)) =
            (&job.result, plan.cases.iter().find(|s| s.id == job.case))
        else {
            continue;
        };
        let Some(exact) = baseline(&job.engine).and_then(|b| outcome.history(&job.case, b)) else {
            continue;
        };
        let Some(error) = compare(scene, exact, &success.history).worst_max else {
            continue;
        };
        let explicit = outcome
            .history(&scene.id, "explicit")
            .and_then(|h| super::against_own_model(outcome, scene, "explicit", h));
        let flag = match (judged_tolerance(scene, &job.engine), explicit) {
            (Some(t), _) if error > t => Flag::MissesTolerance(t),
            (_, Some(x))
                if job.engine.starts_with("rapier")
                    && !crate::contract::on_older_release(&job.engine)
                    && error > FLAG_RATIO * x =>
            {
                Flag::OverExplicit(x)
            }
            _ => continue,
        };
        out.push(Cell {
            scene,
            engine: &job.engine,
            job: success,
            exact,
            error,
            flag,
        });
    }
    out
}

/// The controls of one cell (none where its engine is not in the plan). A restitution
/// control needs an exact solution without impacts: e must not enter it.
fn controls_of<'a>(plan: &'a Plan, cell: &Cell<'a>) -> Vec<Planned<'a>> {
    let Some(engine) = plan.engines.iter().find(|e| e.name() == cell.engine) else {
        return Vec::new();
    };
    let strikes = cell
        .exact
        .column(IMPACTS_COLUMN)
        .is_some_and(|i| i.iter().any(|x| *x > 0.0));
    controls::plan(cell.scene, engine.as_ref(), &plan.settings, cell.job)
        .into_iter()
        .filter(|c| !(c.kind() == ControlKind::Restitution && strikes))
        .collect()
}

/// Run one control and measure it against the cell's exact solution.
fn run_control(cell: &Cell, planned: &Planned) -> ControlRun {
    let result = planned.run().and_then(|h| {
        compare(cell.scene, cell.exact, &h)
            .worst_max
            .ok_or_else(|| "no column with a peak compared".to_string())
    });
    ControlRun {
        kind: planned.kind(),
        change: planned.control.change.clone(),
        error: result.as_ref().ok().copied(),
        failure: result.err(),
    }
}

/// The index of the control that explains `error` (see the module doc).
pub fn cause(error: f64, flag: Flag, controls: &[ControlRun]) -> Option<usize> {
    let (k, best) = controls
        .iter()
        .enumerate()
        .filter_map(|(k, c)| Some((k, c.error?)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let within = matches!(flag, Flag::MissesTolerance(t) if best <= t);
    (best * EXPLAINS <= error || within).then_some(k)
}

/// Attribute every cell of `outcome` that needs a cause (in outcome order), running the
/// controls in parallel. A progress bar on stderr when `progress` is set.
pub fn measure(plan: &Plan, outcome: &Outcome, progress: bool) -> Vec<Attribution> {
    use rayon::prelude::*;
    let cells = cells(plan, outcome);
    let work: Vec<(usize, Planned)> = cells
        .iter()
        .enumerate()
        .flat_map(|(i, c)| controls_of(plan, c).into_iter().map(move |k| (i, k)))
        .collect();
    let bar = crate::run::progress_bar(work.len(), progress);
    let runs: Vec<(usize, ControlRun)> = work
        .par_iter()
        .map(|(i, planned)| {
            let run = if crate::interrupt::requested() {
                ControlRun {
                    kind: planned.kind(),
                    change: planned.control.change.clone(),
                    error: None,
                    failure: Some("interrupted before it ran".into()),
                }
            } else {
                run_control(&cells[*i], planned)
            };
            bar.set_message(format!(
                "control {}/{}",
                cells[*i].scene.id, cells[*i].engine
            ));
            bar.inc(1);
            (*i, run)
        })
        .collect();
    bar.finish_and_clear();
    cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let controls: Vec<ControlRun> = runs
                .iter()
                .filter(|(j, _)| *j == i)
                .map(|(_, r)| r.clone())
                .collect();
            Attribution {
                case: c.scene.id.clone(),
                engine: c.engine.to_string(),
                error: c.error,
                flag: c.flag,
                cause: cause(c.error, c.flag, &controls),
                controls,
            }
        })
        .collect()
}
