//! What accuracy costs: each engine's sweep ([`crate::run::sweep`]) measured against the exact
//! solution of its own model ([`super::baseline`]), its observed order of convergence, the
//! floor where it stops improving and why, and the cheapest setting that reaches an accuracy.
//!
//! - **Error of a point**: the worst contract column's largest error over its peak (and the
//!   largest RMS over peak), exactly as the verdicts measure it ([`super::compare`]).
//! - **Observed order**: the least-squares slope of log(error) against log(increment) over the
//!   path's *asymptotic range*: its ok points whose error is more than [`FLOOR_MARGIN`] times
//!   the path's floor (all of them when the path did not stall), less the coarse points whose
//!   local order is off the path's median local order by more than [`PRE_ASYMPTOTIC_ORDER`]
//!   (pre-asymptotic: a penalty so soft that its compliance is 1 % of the answer). For a penalty engine on a
//!   scene with contact the path is the *diagonal*: each penalty stiffness at 0.9 of its own
//!   stable increment (the increment and the compliance shrink together, h² ∝ 1/k_p), since at
//!   a fixed stiffness the compliance floor is reached at the first refinement. For rapier it
//!   is the increment path of its configuration.
//! - **Floor**: where a path stalled (twice in a row: the refinement no longer paid, see the
//!   sweep), its
//!   smallest error, with its cause named from the discrepancy budget's parts: penalty
//!   compliance (≈ k/k_p) for penalty paths, f32 round-off where the f64 twin goes lower on the
//!   same path, f64 round-off below 1e-10, and otherwise the solver settings the path holds
//!   fixed (a description, not a cause: the causes of a flagged cell are its controls').

use super::verdict::growth::{self, Verdict};
use super::{baseline, compare};
use crate::contract::History;
use crate::run::Engine;
use crate::run::sweep::{self, Grid, Measured, PathKind, Status, SweepPath};
use crate::run::{Outcome, Plan};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// The asymptotic range excludes points within this factor of the path's floor.
pub const FLOOR_MARGIN: f64 = 3.0;

/// A coarse point is pre-asymptotic when its local order differs from the median local order
/// of the path by more than this.
pub const PRE_ASYMPTOTIC_ORDER: f64 = 0.5;

/// Accuracies the time-to-accuracy table asks for (error over peak).
pub const TARGETS: [f64; 3] = [1e-2, 1e-4, 1e-6];

/// An observed order of convergence in the time increment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObservedOrder {
    /// The slope.
    pub value: f64,
    /// Which path it was fitted on.
    pub path: String,
    /// The coarsest increment of the range.
    pub coarsest: f64,
    /// The finest increment of the range.
    pub finest: f64,
    /// Points in the range.
    pub points: usize,
}

/// Where refinement stopped paying.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Floor {
    /// The smallest error the path reached (max over peak).
    pub value: f64,
    /// What limits it.
    pub cause: String,
    /// On which path.
    pub path: String,
}

/// One engine's order and floor on one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EngineFit {
    /// Engine name.
    pub engine: String,
    /// The observed order, where the sweep had an asymptotic range of at least two points.
    pub observed_order: Option<ObservedOrder>,
    /// The lowest floor of the engine's paths, where any stalled and no other path of the
    /// engine went below it.
    pub floor: Option<Floor>,
}

/// One case's sweep and what it shows.
#[derive(Debug, Clone)]
pub struct CaseSweep {
    /// Case id.
    pub case: String,
    /// Simulated seconds (the dynamic steps).
    pub duration: f64,
    /// Every path run.
    pub paths: Vec<SweepPath>,
    /// Per engine swept.
    pub fits: Vec<EngineFit>,
    /// The extrapolated costs checked by runs toward their accuracy ([`super::reach`]).
    pub checks: Vec<super::reach::Check>,
    /// The case this one is equivalent to (the same closed form, [`super::equivalence`]),
    /// where it is: its costs beyond its own sweep are that case's, checked there.
    pub same_as: Option<String>,
}

/// One point as the sweep CSV writes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// The path it is on ([`SweepPath::label`]).
    pub path: String,
    /// What the path varies: `h` (the increment) or `substeps`.
    pub varied: String,
    /// `f64` or `f32`.
    pub precision: String,
    /// Time increment taken.
    pub increment: f64,
    /// Penalty stiffness (empty when none).
    pub penalty_stiffness: Option<f64>,
    /// Rapier substeps (empty for other engines).
    pub iterations: Option<usize>,
    /// Increments taken.
    pub steps: u64,
    /// Max error over peak against the engine's own model (empty unless ok).
    pub error_max: Option<f64>,
    /// RMS error over peak (empty unless ok).
    pub error_rms: Option<f64>,
    /// CPU seconds per simulated second: minimum over the repeats.
    pub cpu_s_min: f64,
    /// Median.
    pub cpu_s_median: f64,
    /// Maximum.
    pub cpu_s_max: f64,
    /// `ok`, `unstable` or `failed`.
    pub status: String,
}

/// The CSV columns, in order (units: `increment_s` seconds, `penalty_n_per_m` N/m, errors
/// over the column's peak, CPU seconds per simulated second).
pub const COLUMNS: [&str; 15] = [
    "case",
    "engine",
    "precision",
    "path",
    "varied",
    "increment_s",
    "substeps",
    "penalty_n_per_m",
    "steps",
    "error",
    "error_rms",
    "cpu_s_per_simulated_s",
    "cpu_s_per_simulated_s_median",
    "cpu_s_per_simulated_s_max",
    "status",
];

impl CaseSweep {
    /// Every point as a CSV row, path by path.
    pub fn rows(&self) -> Vec<Row> {
        self.paths.iter().flat_map(|p| self.path_rows(p)).collect()
    }

    /// One path's points as CSV rows.
    pub fn path_rows(&self, path: &SweepPath) -> Vec<Row> {
        path.points
            .iter()
            .map(|pt| row(&self.case, path, pt, self.duration))
            .collect()
    }
}

fn row(case: &str, path: &SweepPath, p: &sweep::Point, duration: f64) -> Row {
    let mut cpu: Vec<f64> = p.cpu_seconds.iter().map(|c| c / duration).collect();
    cpu.sort_by(f64::total_cmp);
    let (min, max) = (
        cpu.first().copied().unwrap_or(0.0),
        cpu.last().copied().unwrap_or(0.0),
    );
    Row {
        case: case.to_string(),
        engine: path.engine.clone(),
        path: path.label(),
        varied: match path.kind {
            PathKind::Increment { .. } | PathKind::Reach { .. } => "h",
            PathKind::Substeps { .. } => "substeps",
        }
        .to_string(),
        precision: path.precision.to_string(),
        increment: p.increment,
        penalty_stiffness: p.penalty_stiffness,
        iterations: p.iterations,
        steps: p.steps,
        error_max: p.error.map(|e| e.0),
        error_rms: p.error.map(|e| e.1),
        cpu_s_min: min,
        cpu_s_median: cpu.get(cpu.len() / 2).copied().unwrap_or(0.0),
        cpu_s_max: max,
        status: p.status.name().to_string(),
    }
}

/// Sweep every case of `plan` with the engines of `engines` that step in time, each point's
/// error measured against its own model's exact solution from `outcome` (engines whose
/// baseline did not run are skipped). A progress bar when `progress` is set.
pub fn measure(
    plan: &Plan,
    outcome: &Outcome,
    engines: &[&dyn Engine],
    grid: &Grid,
    progress: bool,
) -> Vec<CaseSweep> {
    let history = |case: &str, engine: &str| outcome.history(case, engine);
    let error_of = |scene: &Scene, engine: &str, h: &History, steps: u64| {
        measured(outcome, scene, engine, h, steps)
    };
    // Per case, the engines asked for whose own model's exact solution ran.
    let scenes: Vec<(&Scene, Vec<&dyn Engine>)> = plan
        .cases
        .iter()
        .map(|s| {
            let chosen = sweep::steppers(engines)
                .into_iter()
                .filter(|e| baseline(e.name()).is_some_and(|b| history(&s.id, b).is_some()))
                .collect();
            (s, chosen)
        })
        .collect();
    let paths = scenes
        .iter()
        .map(|(s, e)| sweep::plan_len(s, e, grid))
        .sum();
    let bar = crate::run::progress_bar(paths, progress);
    let swept = sweep::run(&scenes, grid, &error_of, &|label| {
        bar.set_message(format!("sweep {label}"));
        bar.inc(1);
    });
    bar.finish_and_clear();
    scenes
        .iter()
        .zip(swept)
        .map(|((scene, engines), paths)| {
            let fits = engines
                .iter()
                .filter(|e| paths.iter().any(|p| p.engine == e.name()))
                .map(|e| fit(e.name(), &paths, !scene.contacts.is_empty()))
                .collect();
            CaseSweep {
                case: scene.id.clone(),
                duration: scene.duration(),
                paths,
                fits,
                checks: Vec::new(),
                same_as: None,
            }
        })
        .collect()
}

/// A sweep point's run measured: its error (max and RMS over the peak, worst column) against
/// its engine's own model's exact solution in `outcome`, and whether its growth makes it
/// unstable ([`growth`]).
fn measured(outcome: &Outcome, scene: &Scene, engine: &str, h: &History, steps: u64) -> Measured {
    let error = || {
        let own = outcome.history(&scene.id, baseline(engine)?)?;
        let c = compare(scene, own, h);
        let rms = c
            .columns
            .iter()
            .filter(|c| c.relative)
            .fold(0.0f64, |m, c| m.max(c.rms));
        Some((c.worst_max?, rms))
    };
    Measured {
        error: error(),
        growing: growth::judge(h, steps as f64).is_some_and(|g| g.verdict == Verdict::Growing),
    }
}

/// Check the extrapolated costs of `sweeps` by runs toward their accuracy ([`super::reach`]),
/// measured as the sweep's points are.
pub fn reach(
    plan: &Plan,
    outcome: &Outcome,
    engines: &[&dyn Engine],
    sweeps: &mut [CaseSweep],
    grid: &Grid,
    progress: bool,
) {
    let error_of = |scene: &Scene, engine: &str, h: &History, steps: u64| {
        measured(outcome, scene, engine, h, steps)
    };
    // A case equivalent to another (the same closed form) is checked on that one only.
    let closed = |case: &str, engine: &str| outcome.history(case, engine).cloned();
    for e in super::equivalence::measure(&plan.cases, &[], closed) {
        if let Some(s) = sweeps.iter_mut().find(|s| s.case == e.case) {
            s.same_as = Some(e.same_as);
        }
    }
    super::reach::measure(plan, engines, sweeps, grid, &error_of, progress);
}

/// The ok points of a path as (increment, error), coarse to fine: those at or below the
/// engine's stable increment, where it has one (a bounded run above it, the probe, is not on
/// the refinement path).
fn ok_points(path: &SweepPath) -> Vec<(f64, f64)> {
    path.points
        .iter()
        .filter(|p| p.status == Status::Ok)
        .filter(|p| {
            p.stable_increment
                .is_none_or(|s| p.increment <= s * (1.0 + 1e-9))
        })
        .filter_map(|p| Some((p.increment, p.error?.0)))
        .collect()
}

/// A path's floor value, if it stalled: its smallest error.
fn floor_value(path: &SweepPath) -> Option<f64> {
    (path.ended == "stalled").then(|| {
        ok_points(path)
            .iter()
            .fold(f64::INFINITY, |m, p| m.min(p.1))
    })
}

/// The observed order over a sequence of (increment, error) points with `floor` (if any):
/// the slope over the points more than [`FLOOR_MARGIN`] × floor.
pub fn order(points: &[(f64, f64)], floor: Option<f64>, path: &str) -> Option<ObservedOrder> {
    let mut range: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(_, e)| floor.is_none_or(|f| *e > FLOOR_MARGIN * f))
        .collect();
    // Pre-asymptotic coarse points: while the coarsest pair's local order is more than
    // `PRE_ASYMPTOTIC_ORDER` from the median local order, drop its coarse point.
    let local = |r: &[(f64, f64)]| -> Vec<f64> {
        r.windows(2)
            .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
            .collect()
    };
    while range.len() > 3 {
        let mut orders = local(&range);
        let first = orders[0];
        orders.sort_by(f64::total_cmp);
        if (first - orders[orders.len() / 2]).abs() <= PRE_ASYMPTOTIC_ORDER {
            break;
        }
        range.remove(0);
    }
    let (slope, _) = crate::run::scaling::fitted_exponent(&range)?;
    Some(ObservedOrder {
        value: slope,
        path: path.to_string(),
        coarsest: range.iter().fold(0.0f64, |m, p| m.max(p.0)),
        finest: range.iter().fold(f64::INFINITY, |m, p| m.min(p.0)),
        points: range.len(),
    })
}

/// A penalty path's first point is on the diagonal when its increment is at least this
/// fraction of its stable one.
pub const DIAGONAL_SHARE: f64 = 0.5;

/// The diagonal of a penalty engine: each penalty path's first ok point, stiffest last.
pub fn diagonal<'a>(paths: impl Iterator<Item = &'a SweepPath>) -> Vec<(f64, f64)> {
    let mut firsts: Vec<(f64, f64, f64)> = paths
        .filter_map(|p| {
            let ratio = match p.kind {
                PathKind::Increment {
                    penalty_ratio: Some(r),
                } => r,
                _ => return None,
            };
            // The first ok point, where its increment is set by stability (at least half the
            // stable one: not cut short to the output interval by a soft penalty).
            let first = p.points.iter().find(|q| q.status == Status::Ok)?;
            if first
                .stable_increment
                .is_none_or(|s| first.increment < DIAGONAL_SHARE * s)
            {
                return None;
            }
            Some((ratio, first.increment, first.error?.0))
        })
        .collect();
    firsts.sort_by(|a, b| a.0.total_cmp(&b.0));
    firsts.into_iter().map(|(_, h, e)| (h, e)).collect()
}

/// Name what limits a stalled path.
fn floor_cause(path: &SweepPath, value: f64, twin: Option<&SweepPath>, contact: bool) -> String {
    if let PathKind::Increment {
        penalty_ratio: Some(r),
    } = path.kind
    {
        return format!("penalty compliance (k/k_p = {:.0e})", 1.0 / r);
    }
    // f32 round-off: where the f32 path stalled, its f64 twin at the same setting is at least
    // twice as accurate.
    let stalled_at = path
        .points
        .last()
        .and_then(|p| Some((p.increment, p.iterations, p.error?.0)));
    let twin_better = |t: &SweepPath| {
        stalled_at.is_some_and(|(h, n, e)| {
            t.points.iter().any(|q| {
                (q.increment / h - 1.0).abs() < 1e-9
                    && q.iterations == n
                    && q.error.is_some_and(|f| f.0 < e / 2.0)
            })
        })
    };
    if path.precision == "f32" && twin.is_some_and(twin_better) {
        return "f32 round-off".to_string();
    }
    if value < 1e-10 {
        return format!("{} round-off", path.precision);
    }
    match (path.engine.ends_with("default"), path.kind) {
        // What the increment path holds fixed, not a cause: the controls name causes.
        (true, _) => "levels at the default solver settings (its causes: accuracy.md)".to_string(),
        (false, PathKind::Substeps { increment }) if contact => format!(
            "contact points found once per increment ({increment:.1e} s): substeps reuse them"
        ),
        (false, PathKind::Substeps { increment }) => {
            format!("solver at the fixed increment {increment:.1e} s")
        }
        #[cfg(feature = "rapier")]
        (false, _) if path.engine.starts_with("rapier") => {
            format!(
                "levels at the matched solver settings (contact softness {} kHz)",
                sweep::matched_contact_frequency(&path.engine) / 1e3
            )
        }
        _ => "solver".to_string(),
    }
}

/// One engine's order and floor on a case (`contact`: the scene has contact pairs).
pub(crate) fn fit(engine: &str, paths: &[SweepPath], contact: bool) -> EngineFit {
    let own: Vec<&SweepPath> = paths.iter().filter(|p| p.engine == engine).collect();
    let penalty = own.iter().any(|p| {
        matches!(
            p.kind,
            PathKind::Increment {
                penalty_ratio: Some(_)
            }
        )
    });
    let observed_order = if penalty {
        let d = diagonal(own.iter().copied());
        order(
            &d,
            None,
            &format!("{engine}, k_p with h = 0.9 × its stable increment"),
        )
    } else {
        own.iter()
            .find(|p| matches!(p.kind, PathKind::Increment { .. }))
            .and_then(|p| {
                let mut points = ok_points(p);
                if p.ended == "stalled" {
                    // The two points that stalled are not in the asymptotic range.
                    points.truncate(points.len().saturating_sub(2));
                }
                order(&points, floor_value(p), &p.label())
            })
    };
    let twin_name = engine.replace("f32", "f64");
    let floor = own
        .iter()
        .filter_map(|p| {
            let value = floor_value(p)?;
            let twin = paths
                .iter()
                .find(|t| t.engine == twin_name && t.kind == p.kind && t.engine != p.engine);
            Some(Floor {
                value,
                cause: floor_cause(p, value, twin, contact),
                path: p.label(),
            })
        })
        .min_by(|a, b| a.value.total_cmp(&b.value))
        // A floor is the engine's only if none of its other paths went below it.
        .filter(|f| {
            own.iter()
                .flat_map(|p| ok_points(p))
                .all(|(_, e)| e >= f.value * (1.0 - 1e-12))
        })
        .or_else(|| round_off(paths, engine));
    EngineFit {
        engine: engine.to_string(),
        observed_order,
        floor,
    }
}

/// Indices of the rows on the Pareto front (ok rows no other ok row beats in both error and
/// minimum CPU time), cheapest first.
pub fn pareto(rows: &[Row]) -> Vec<usize> {
    let mut ok: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].status == "ok" && rows[i].error_max.is_some())
        .collect();
    ok.sort_by(|&a, &b| {
        rows[a].cpu_s_min.total_cmp(&rows[b].cpu_s_min).then(
            rows[a]
                .error_max
                .unwrap_or(f64::INFINITY)
                .total_cmp(&rows[b].error_max.unwrap_or(f64::INFINITY)),
        )
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in ok {
        let e = rows[i].error_max.unwrap_or(f64::INFINITY);
        if e < best {
            best = e;
            front.push(i);
        }
    }
    front
}

/// An f32 engine's floor where its f64 twin is at least twice as accurate at the most refined
/// setting of one of its paths (the f32 run is held by round-off there, however the sweep
/// ended): the smallest error it reached.
fn round_off(paths: &[SweepPath], engine: &str) -> Option<Floor> {
    if !engine.contains("f32") {
        return None;
    }
    let twin = engine.replace("f32", "f64");
    let finest = |name: &str| -> Vec<(String, f64, Option<usize>, f64)> {
        paths
            .iter()
            .filter(|p| p.engine == name)
            .flat_map(|p| {
                ok_points(p).last().map(|&(h, e)| {
                    let n = p.points.iter().rev().find_map(|q| q.iterations);
                    (p.label().replace(&twin, engine), h, n, e)
                })
            })
            .collect()
    };
    let theirs = finest(&twin);
    let held = finest(engine).into_iter().find(|(label, h, n, e)| {
        theirs.iter().any(|(l, th, tn, te)| {
            l == label && (th / h - 1.0).abs() < 1e-9 && tn == n && *te < e / 2.0
        })
    })?;
    // The floor is the smallest error the engine reached on any path.
    let value = paths
        .iter()
        .filter(|p| p.engine == engine)
        .flat_map(ok_points)
        .fold(f64::INFINITY, |m, (_, e)| m.min(e));
    Some(Floor {
        value,
        cause: "f32 round-off".into(),
        path: held.0,
    })
}
