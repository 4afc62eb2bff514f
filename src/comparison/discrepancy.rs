//! The discrepancy budget: an engine's error against the closed form, split into histories
//! that add up to it at every row.
//!
//! With y the engine's history (increment h, penalty k₀), a the closed form, r the converged
//! solution of the engine's own model (`reference` for the finite-rotation engines; the closed
//! form itself for `explicit_small`), Y the engine extrapolated to h → 0 at k₀ and Z that
//! extrapolated further to k_p → ∞:
//!
//! - `model_form` = r − a (zero where the engine's model is the closed form's);
//! - `time_step` = y − Y;
//! - `penalty` = Y − Z (zero for an engine without penalty: Z = Y);
//! - `solver` = Z − r, what remains against the engine's own model: round-off and the
//!   extrapolations' own error for the explicit engines, contact softness, joint and motor
//!   formulation and precision for rapier;
//!
//! and `total` = y − a = model_form + time_step + penalty + solver, exactly but for the
//! round-off of the subtractions.
//!
//! Each extrapolation is Richardson's, per column and row, with the order the three runs
//! themselves show ([`Extrapolation`]): for parameters s_f < s_m < s_c (increments, or 1/k_p)
//! and runs y_f, y_m, y_c, the order p solves
//! max|y_m − y_c| / max|y_f − y_m| = (s_c^p − s_m^p)/(s_m^p − s_f^p), and
//! y(0) = y_f − (y_m − y_f) s_f^p/(s_m^p − s_f^p). A column whose runs differ by no more than
//! round-off (1e-12 of its scale) is converged in that parameter; one whose differences do not
//! shrink with the parameter has no order, is left at its finest run and flagged.

use super::{first_compared_row, peak as max_abs, valid_rows};
use crate::contract::History;
use crate::run::refinement::{Direction, Ladder, PenaltyLevel};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// The parts, in the order they are written.
pub const PARTS: [&str; 5] = ["total", "model_form", "time_step", "penalty", "solver"];

/// Below this fraction of a column's scale, differences between runs are round-off.
pub const ROUND_OFF: f64 = 1e-12;

/// A Richardson extrapolation of one column.
#[derive(Debug, Clone, PartialEq)]
pub struct Extrapolation {
    /// The extrapolated values, row by row.
    pub values: Vec<f64>,
    /// What the runs showed.
    pub order: Order,
}

/// The order of convergence three runs show in one column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "value")]
pub enum Order {
    /// Observed order p.
    Observed(f64),
    /// The runs agree to round-off: nothing to extrapolate.
    Converged,
    /// The differences do not shrink as the parameter does (or not like a power of it): no
    /// extrapolation; the finest run stands for the limit.
    NotAsymptotic,
}

/// Extrapolate three runs `(s, values)` of one column to s → 0 (`scale`: the column's size, for
/// the round-off test). The order is observed on the rows from `first` on (the rows the
/// comparison measures) and applied to every row.
pub fn extrapolate(runs: [(f64, &[f64]); 3], scale: f64, first: usize) -> Extrapolation {
    let mut runs = runs;
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let [(sf, yf), (sm, ym), (sc, yc)] = runs;
    let diff = |a: &[f64], b: &[f64]| {
        let from = first.min(a.len());
        a[from..]
            .iter()
            .zip(&b[from..])
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    };
    let (d_fm, d_mc) = (diff(yf, ym), diff(ym, yc));
    let finest = |order| Extrapolation {
        values: yf.to_vec(),
        order,
    };
    if d_fm.max(d_mc) <= ROUND_OFF * scale.max(f64::MIN_POSITIVE) {
        return finest(Order::Converged);
    }
    // ratio(p) = (s_c^p − s_m^p)/(s_m^p − s_f^p) grows with p; bisect for the observed one.
    let ratio = |p: f64| (sc.powf(p) - sm.powf(p)) / (sm.powf(p) - sf.powf(p));
    let target = d_mc / d_fm;
    let (mut lo, mut hi) = (0.25, 12.0);
    if !(d_fm > 0.0 && target > ratio(lo) && target < ratio(hi)) {
        return finest(Order::NotAsymptotic);
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if ratio(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let w = sf.powf(p) / (sm.powf(p) - sf.powf(p));
    Extrapolation {
        values: yf.iter().zip(ym).map(|(f, m)| f - (m - f) * w).collect(),
        order: Order::Observed(p),
    }
}

/// Which three levels of a ladder an extrapolation uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// The job's own increment (penalty) and the next two.
    Basic,
    /// One level further: the coarsest of the basic three dropped, the extra one taken.
    Extra,
}

/// The budget of one column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColumnBudget {
    /// Column name.
    pub column: String,
    /// Peak |value| of the closed form's column (the norms' scale).
    pub peak: f64,
    /// Whether the norms are relative to the peak (false: absolute, the peak being 0).
    pub relative: bool,
    /// Largest |total| over the rows, over the peak.
    pub total: f64,
    /// Largest |model_form|, over the peak.
    pub model_form: f64,
    /// Largest |time_step|, over the peak.
    pub time_step: f64,
    /// Largest |penalty|, over the peak.
    pub penalty: f64,
    /// Largest |solver|, over the peak.
    pub solver: f64,
    /// Largest |total − (model_form + time_step + penalty + solver)|, over the peak: round-off.
    pub residual: f64,
    /// Order of convergence in the increment.
    pub time_order: Order,
    /// Order of convergence in 1/k_p (`None`: no penalty).
    pub penalty_order: Option<Order>,
}

impl ColumnBudget {
    /// The norms of the four parts, in [`PARTS`] order after `total`.
    pub fn parts(&self) -> [f64; 4] {
        [self.model_form, self.time_step, self.penalty, self.solver]
    }
}

/// The budget of one engine on one case.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    /// `t`, then `c:total`, `c:model_form`, `c:time_step`, `c:penalty`, `c:solver` for every
    /// contract column `c`, over the rows where the closed form (and the reference) is valid.
    pub history: History,
    /// Norms per column.
    pub columns: Vec<ColumnBudget>,
}

fn column(h: &History, name: &str, n: usize) -> Result<Vec<f64>, String> {
    let mut v = h
        .column(name)
        .ok_or_else(|| format!("no column `{name}`"))?;
    if v.len() < n {
        return Err(format!("column `{name}` has {} rows, {n} needed", v.len()));
    }
    v.truncate(n);
    Ok(v)
}

/// The three rungs of one penalty level that `level` uses, as (increment, values).
fn time_runs(
    p: &PenaltyLevel,
    direction: Direction,
    level: Level,
    name: &str,
    n: usize,
) -> Result<[(f64, Vec<f64>); 3], String> {
    let pick: [usize; 3] = match (direction, level) {
        // Rungs: base, then away from it (h/2, h/4, h/8 or 2h, 4h, h/2).
        (_, Level::Basic) => [0, 1, 2],
        (Direction::Refine, Level::Extra) => [1, 2, 3],
        (Direction::Coarsen, Level::Extra) => [3, 0, 1],
    };
    let get = |i: usize| -> Result<(f64, Vec<f64>), String> {
        let r = p
            .rungs
            .get(i)
            .ok_or("the ladder lacks the extra level".to_string())?;
        Ok((r.increment, column(&r.history, name, n)?))
    };
    Ok([get(pick[0])?, get(pick[1])?, get(pick[2])?])
}

/// The budget of `engine_history` (the job's run, rung 0 of `ladder`) against the closed form
/// `analytic`, with `own_model` the converged solution of the engine's model (`reference`, or
/// the closed form itself for a small-rotation engine).
pub fn budget(
    scene: &Scene,
    analytic: &History,
    own_model: &History,
    ladder: &Ladder,
    level: Level,
) -> Result<Budget, String> {
    let run = &ladder.levels[0].rungs[0].history;
    let n = valid_rows(analytic)
        .min(valid_rows(own_model))
        .min(run.rows.len());
    let t = column(analytic, "t", n)?;
    let mut columns = vec!["t".to_string()];
    let mut data: Vec<Vec<f64>> = vec![t];
    let mut norms = Vec::new();
    for name in crate::contract::columns(scene.family) {
        let a = column(analytic, name, n)?;
        let r = column(own_model, name, n)?;
        let y = column(run, name, n)?;
        let peak = max_abs(&a);
        let relative = peak > 0.0 && peak >= 1e-6 * max_abs(&y);
        let scale = if relative { peak } else { 1.0 };
        let round_off = peak.max(max_abs(&y));
        // Norms and observed orders over the rows the comparison measures (a contact force
        // from the first increment on); the histories keep every row.
        let first = first_compared_row(scene, name).min(n);
        // h → 0 at each penalty level.
        let mut limits = Vec::new();
        let mut time_order = Order::Converged;
        for (j, p) in ladder.levels.iter().enumerate() {
            let [f, m, c] = time_runs(p, ladder.direction, level, name, n)?;
            let e = extrapolate([(f.0, &f.1), (m.0, &m.1), (c.0, &c.1)], round_off, first);
            if j == 0 {
                time_order = e.order;
            }
            limits.push((p.stiffness, e.values));
        }
        // k_p → ∞ from three penalty levels (in 1/k_p).
        let (z, penalty_order) = match limits.as_slice() {
            [(None, y0)] => (y0.clone(), None),
            levels if levels.len() >= 3 => {
                let pick = if level == Level::Basic { 0 } else { 1 };
                let three: Vec<(f64, &[f64])> = levels[pick..pick + 3]
                    .iter()
                    .map(|(k, v)| (1.0 / k.unwrap_or(f64::INFINITY), v.as_slice()))
                    .collect();
                let e = extrapolate([three[0], three[1], three[2]], round_off, first);
                (e.values, Some(e.order))
            }
            _ => return Err("a penalty ladder needs three stiffnesses".into()),
        };
        let y0 = &limits[0].1;
        let parts: [Vec<f64>; 5] = [
            y.iter().zip(&a).map(|(y, a)| y - a).collect(),
            r.iter().zip(&a).map(|(r, a)| r - a).collect(),
            y.iter().zip(y0).map(|(y, y0)| y - y0).collect(),
            y0.iter().zip(&z).map(|(y0, z)| y0 - z).collect(),
            z.iter().zip(&r).map(|(z, r)| z - r).collect(),
        ];
        let residual = (0..n)
            .map(|i| (parts[0][i] - (parts[1][i] + parts[2][i] + parts[3][i] + parts[4][i])).abs())
            .fold(0.0f64, f64::max);
        let norm = |v: &[f64]| max_abs(&v[first..]) / scale;
        norms.push(ColumnBudget {
            column: name.to_string(),
            peak,
            relative,
            total: norm(&parts[0]),
            model_form: norm(&parts[1]),
            time_step: norm(&parts[2]),
            penalty: norm(&parts[3]),
            solver: norm(&parts[4]),
            residual: residual / scale,
            time_order,
            penalty_order,
        });
        for (part, values) in PARTS.iter().zip(parts) {
            columns.push(format!("{name}:{part}"));
            data.push(values);
        }
    }
    let rows = (0..n)
        .map(|i| data.iter().map(|c| c[i]).collect())
        .collect();
    Ok(Budget {
        history: History { columns, rows },
        columns: norms,
    })
}

/// One job's budget, or why it has none.
#[derive(Debug, Clone)]
pub struct JobBudget {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// The budget at the basic level, and at one level further when it was asked for.
    pub result: Result<(Budget, Option<Budget>), String>,
}

/// The budget of every successful job of `plan` whose engine steps in time and is studied
/// ([`Engine::stepping`](crate::run::Engine::stepping): not the closed form, the reference or
/// an older release of rapier), each from its own refinement ladder (`depth`; with
/// [`Depth::Extra`](crate::run::refinement::Depth::Extra) also the budget one level further).
/// Ladders run in parallel and are dropped once their budget is taken, so memory stays at a
/// few histories per thread. A progress bar on stderr, as for the jobs, when `progress` is set.
pub fn measure(
    plan: &crate::run::Plan,
    outcome: &crate::run::Outcome,
    depth: crate::run::refinement::Depth,
    progress: bool,
) -> Vec<JobBudget> {
    use crate::run::refinement::{self, Depth};
    use rayon::prelude::*;
    let history = |case: &str, engine: &str| {
        outcome
            .jobs
            .iter()
            .find(|j| j.case == case && j.engine == engine)
            .and_then(|j| j.result.as_ref().ok())
            .map(|s| &s.history)
    };
    let jobs: Vec<_> = outcome
        .jobs
        .iter()
        .filter(|j| j.is_ok())
        .filter_map(|j| {
            let baseline = super::baseline(&j.engine)?;
            if j.engine == super::FINITE_ROTATION_REFERENCE {
                return None;
            }
            let scene = plan.cases.iter().find(|s| s.id == j.case)?;
            let engine = plan.engines.iter().find(|e| e.name() == j.engine)?;
            // An engine the studies leave alone (an older release of rapier) has no budget.
            engine.stepping()?;
            Some((j, scene, engine, baseline))
        })
        .collect();
    let bar = crate::run::progress_bar(jobs.len(), progress);
    let budgets = jobs
        .par_iter()
        .map(|&(job, scene, engine, baseline)| {
            let result = (|| {
                let success = job.result.as_ref().map_err(|e| e.clone())?;
                let analytic = history(&job.case, super::CLOSED_FORM)
                    .ok_or("no closed-form history in this run")?;
                let own = history(&job.case, baseline)
                    .ok_or(format!("no `{baseline}` history in this run"))?;
                let ladder =
                    refinement::ladder(scene, engine.as_ref(), &plan.settings, success, depth)?
                        .ok_or("the engine does not step in time")?;
                let basic = budget(scene, analytic, own, &ladder, Level::Basic)?;
                let extra = match depth {
                    Depth::Basic => None,
                    Depth::Extra => Some(budget(scene, analytic, own, &ladder, Level::Extra)?),
                };
                Ok((basic, extra))
            })();
            bar.set_message(format!("budget {}/{}", job.case, job.engine));
            bar.inc(1);
            JobBudget {
                case: job.case.clone(),
                engine: job.engine.clone(),
                result,
            }
        })
        .collect();
    bar.finish_and_clear();
    budgets
}
