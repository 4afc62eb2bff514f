//! Why a cell misses: each engine × case cell that needs a cause is rerun under control
//! experiments ([`crate::run::controls`]), and the cause is named from what they show.
//!
//! A cell needs a cause when its engine misses the case's tolerance, or when a rapier engine's
//! error is over [`FLAG_RATIO`] times `explicit`'s on the same case. Each control varies one
//! suspected cause, something the exact solution does not depend on (a restitution control is
//! left out where the exact solution strikes, since e enters it there), so the control's error
//! is measured against the same exact solution as the cell's.
//!
//! The rule that names the cause from what the controls show is the verdict module's
//! ([`super::verdict::cause`]): a control that brings the cell under its line, or a time step
//! ladder whose error falls along an order. Where no single control does, the penalty and the
//! engine's own controls are run again at the ladder's finest increment (combined with the
//! time step) before a cell is called *unexplained*; the controls tried are listed with their
//! errors all the same.

use super::invariance::Invariance;
use super::verdict::cause::{Cause, Explanation, Flag, Run, explain, flag};
use super::{EXACT_SOLUTIONS, baseline, compare};
use crate::contract::History;
use crate::run::controls::{self, ControlKind, Planned};
use crate::run::{JobSuccess, Outcome, Plan};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// One control experiment of a cell, measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlRun {
    /// What it varies.
    pub kind: ControlKind,
    /// The variation in words.
    pub change: String,
    /// The increment it ran at, seconds (a time step control's rung).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub increment: Option<f64>,
    /// The penalty stiffness it set (a penalty control's rung).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub penalty: Option<f64>,
    /// Its worst error against the cell's exact solution (`None`: it failed, see `failure`).
    pub error: Option<f64>,
    /// Why it failed, where it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Whether it is combined with the time step (run at the ladder's finest increment).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub combined: bool,
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
    /// The increment of the cell's own run, seconds.
    pub increment: f64,
    /// The penalty stiffness of the cell's own run, where it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub penalty: Option<f64>,
    /// The controls, in the order they were tried.
    pub controls: Vec<ControlRun>,
    /// The control that explains the error and how; `None`: unexplained.
    pub cause: Option<Cause>,
}

impl Attribution {
    /// The control that explains the cell, where one does.
    pub fn explaining(&self) -> Option<&ControlRun> {
        self.controls.get(self.cause?.control)
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
        let tolerance = super::verdict::tolerance(scene, &job.engine);
        let Some(flag) = flag(&job.engine, error, tolerance, explicit) else {
            continue;
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
    let strikes = super::strikes(cell.exact);
    controls::plan(cell.scene, engine.as_ref(), &plan.settings, cell.job)
        .into_iter()
        .filter(|c| !(c.kind() == ControlKind::Restitution && strikes))
        .collect()
}

/// Run one control and measure it against the cell's exact solution.
fn run_control(cell: &Cell, planned: &Planned, combined: bool) -> ControlRun {
    let result = if crate::interrupt::requested() {
        Err("interrupted before it ran".to_string())
    } else {
        planned.run().and_then(|h| {
            compare(cell.scene, cell.exact, &h)
                .worst_max
                .ok_or_else(|| "no column with a peak compared".to_string())
        })
    };
    ControlRun {
        kind: planned.kind(),
        change: planned.control.change.clone(),
        increment: planned.increment(),
        penalty: planned.penalty(),
        error: result.as_ref().ok().copied(),
        failure: result.err(),
        combined,
    }
}

/// Run every control of `work` (cell index, control) in parallel, longest first, ticking `bar`.
fn run_all(
    cells: &[Cell],
    work: &[(usize, Planned)],
    combined: bool,
    bar: &crate::run::progress::Progress,
) -> Vec<(usize, ControlRun)> {
    // Longest first, so that a long control does not start last and run alone.
    crate::run::schedule::longest_first(
        work,
        |(_, planned)| planned.estimated_cost(),
        |(i, planned)| {
            let run = run_control(&cells[*i], planned, combined);
            bar.set_message(format!(
                "control {}/{}",
                cells[*i].scene.id, cells[*i].engine
            ));
            bar.inc(1);
            (*i, run)
        },
    )
}

/// Attribute every cell of `outcome` that needs a cause (in outcome order), running the
/// controls in parallel; then, for each cell no single control explains, the controls
/// combined with the time step ladder's finest increment. The invariance controls already run
/// ([`super::invariance`]) count among a cell's controls: its engine at the other value of a
/// parameter the exact solution ignores. A progress bar on stderr when `progress` is set.
pub fn measure(
    plan: &Plan,
    outcome: &Outcome,
    invariances: &[Invariance],
    progress: bool,
) -> Vec<Attribution> {
    let cells = cells(plan, outcome);
    let work: Vec<(usize, Planned)> = cells
        .iter()
        .enumerate()
        .flat_map(|(i, c)| controls_of(plan, c).into_iter().map(move |k| (i, k)))
        .collect();
    let bar = crate::run::progress_bar(work.len(), progress);
    let mut runs = run_all(&cells, &work, false, &bar);
    let controls_of_cell = |runs: &[(usize, ControlRun)], i: usize| -> Vec<ControlRun> {
        runs.iter()
            .filter(|(j, _)| *j == i)
            .map(|(_, r)| r.clone())
            .collect()
    };
    // The invariance controls already run, where the engine has none of their kind of its own.
    for (i, cell) in cells.iter().enumerate() {
        let own = controls_of_cell(&runs, i);
        let offered = invariant(cell, invariances).into_iter().filter(|c| {
            !own.iter()
                .any(|o| o.kind == c.kind && o.increment.is_none())
        });
        runs.extend(offered.map(|c| (i, c)));
    }
    // Cells no single control explains: their controls at the ladder's finest increment.
    let combined: Vec<(usize, Planned)> = cells
        .iter()
        .enumerate()
        .filter(|(i, c)| {
            let found = explain(&own_run(c), c.flag, &controls_of_cell(&runs, *i));
            !found.is_some_and(|k| !matches!(k.explanation, Explanation::InPart { .. }))
        })
        .flat_map(|(i, c)| {
            combinations(plan, c, &controls_of_cell(&runs, i))
                .into_iter()
                .map(move |k| (i, k))
        })
        .collect();
    bar.inc_length(combined.len() as u64);
    runs.extend(run_all(&cells, &combined, true, &bar));
    bar.finish_and_clear();
    cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let controls = controls_of_cell(&runs, i);
            Attribution {
                case: c.scene.id.clone(),
                engine: c.engine.to_string(),
                error: c.error,
                flag: c.flag,
                increment: c.job.info.increment,
                penalty: c.job.info.penalty_stiffness,
                cause: explain(&own_run(c), c.flag, &controls),
                controls,
            }
        })
        .collect()
}

/// The cell's engine at the other values of each parameter its case's exact solution ignores
/// (from the invariance controls), as controls: the values the case does not state.
fn invariant(cell: &Cell, invariances: &[Invariance]) -> Vec<ControlRun> {
    invariances
        .iter()
        .filter(|i| i.case == cell.scene.id)
        .filter_map(|i| {
            let pair = i.engines.iter().find(|p| p.engine == cell.engine)?;
            Some((0..2).filter(|&k| i.stated != Some(k)).map(move |k| {
                ControlRun {
                    kind: i.kind,
                    change: format!("{}: {} instead of the case's", i.parameter, i.values[k]),
                    increment: None,
                    penalty: None,
                    error: pair.errors[k],
                    failure: pair.errors[k]
                        .is_none()
                        .then(|| "failed or compared nothing".to_string()),
                    combined: false,
                }
            }))
        })
        .flatten()
        .collect()
}

/// The cell's own run, as the first point of its ladders.
fn own_run(cell: &Cell) -> Run {
    Run {
        error: cell.error,
        increment: cell.job.info.increment,
        penalty: cell.job.info.penalty_stiffness,
    }
}

/// The combinations of a cell's controls with its time step ladder's finest increment (none
/// where it has no ladder, or no control to combine).
fn combinations<'a>(plan: &'a Plan, cell: &Cell<'a>, controls: &[ControlRun]) -> Vec<Planned<'a>> {
    let finest = controls
        .iter()
        .filter(|c| c.kind == ControlKind::TimeStep)
        .filter_map(|c| c.increment)
        .reduce(f64::min);
    let (Some(h), Some(engine)) = (
        finest,
        plan.engines.iter().find(|e| e.name() == cell.engine),
    ) else {
        return Vec::new();
    };
    let strikes = super::strikes(cell.exact);
    controls::combined(cell.scene, engine.as_ref(), &plan.settings, cell.job, h)
        .into_iter()
        .filter(|c| !(c.kind() == ControlKind::Restitution && strikes))
        .collect()
}
