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
//!   same path, f64 round-off below 1e-10, and otherwise the engine's solver (rapier's contact
//!   softness and projected Gauss–Seidel sweeps).

use super::{baseline, compare};
use crate::contract::History;
use crate::run::Engine;
use crate::run::sweep::{self, Grid, PathKind, Status, SweepPath};
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
            PathKind::Increment { .. } => "h",
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
    let error_of = |scene: &Scene, engine: &str, h: &History| {
        let own = history(&scene.id, baseline(engine)?)?;
        let c = compare(scene, own, h);
        let rms = c
            .columns
            .iter()
            .filter(|c| c.relative)
            .fold(0.0f64, |m, c| m.max(c.rms));
        Some((c.worst_max?, rms))
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
            }
        })
        .collect()
}

/// The ok points of a path as (increment, error), coarse to fine.
fn ok_points(path: &SweepPath) -> Vec<(f64, f64)> {
    path.points
        .iter()
        .filter(|p| p.status == Status::Ok)
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
        (true, _) => "solver: rapier's default contact softness and one PGS sweep".to_string(),
        (false, PathKind::Substeps { increment }) if contact => format!(
            "contact points found once per increment ({increment:.1e} s): substeps reuse them"
        ),
        (false, PathKind::Substeps { increment }) => {
            format!("solver at the fixed increment {increment:.1e} s")
        }
        #[cfg(feature = "rapier")]
        (false, _) if path.engine.starts_with("rapier") => {
            format!(
                "solver: rapier's contact softness ({} kHz) and PGS sweeps",
                sweep::matched_contact_frequency(&path.engine) / 1e3
            )
        }
        _ => "solver".to_string(),
    }
}

/// One engine's order and floor on a case (`contact`: the scene has contact pairs).
fn fit(engine: &str, paths: &[SweepPath], contact: bool) -> EngineFit {
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

/// How an engine fares against an accuracy target.
#[derive(Debug, Clone, PartialEq)]
pub enum Reach<'a> {
    /// The cheapest ok point (least minimum CPU time) whose error is within the target.
    Reached(&'a Row),
    /// Not reached; the smallest error the engine attains (None: no ok point).
    NotReached(Option<f64>),
}

/// The cheapest row of `engine` within `target`.
pub fn cheapest<'a>(rows: &'a [Row], engine: &str, target: f64) -> Reach<'a> {
    let own = rows
        .iter()
        .filter(|r| r.engine == engine && r.status == "ok");
    let mut best: Option<&Row> = None;
    let mut smallest: Option<f64> = None;
    for r in own {
        let Some(e) = r.error_max else { continue };
        smallest = Some(smallest.map_or(e, |s: f64| s.min(e)));
        if e <= target && best.is_none_or(|b| r.cpu_s_min < b.cpu_s_min) {
            best = Some(r);
        }
    }
    best.map_or(Reach::NotReached(smallest), Reach::Reached)
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

/// How a time to accuracy was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reached {
    /// A swept point within the target: the cheapest such.
    Measured,
    /// Beyond the sweep, along the observed order from its most accurate point.
    Extrapolated,
    /// Refinement stopped paying above the target (the floor is named).
    Floor,
    /// Neither reached nor extrapolable (no asymptotic range).
    NotReached,
}

/// What reaching an accuracy costs an engine on a case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CostToAccuracy {
    /// The accuracy asked for: largest error over the peak, worst column.
    pub target: f64,
    /// How it was found.
    pub reached: Reached,
    /// CPU seconds per simulated second (measured or extrapolated).
    pub cpu_s_per_simulated_s: Option<f64>,
    /// The order it was extrapolated along (error ∝ hᵖ, CPU time ∝ 1/h).
    pub order: Option<f64>,
    /// The error of the point it was measured at or extrapolated from; for a floor, the floor.
    pub error: Option<f64>,
    /// For a floor, what limits it.
    pub cause: Option<String>,
}

/// What each of [`TARGETS`] costs `fit`'s engine on `sweep`'s case: the cheapest swept point
/// within it; else, where a floor above the target stopped the sweep, that floor; else, along
/// the observed order p from the engine's most accurate point on the path the order was fitted
/// on (CPU time × (error / target)^(1/p): CPU time ∝ 1/h, error ∝ hᵖ); else not reached.
pub fn costs(sweep: &CaseSweep, fit: &EngineFit) -> Vec<CostToAccuracy> {
    let rows: Vec<Row> = sweep
        .paths
        .iter()
        .filter(|p| p.engine == fit.engine)
        .flat_map(|p| sweep.path_rows(p))
        .collect();
    // The points to extrapolate from: the fitted path's (every path of the engine for the
    // penalty diagonal, which is not one path).
    let along: Vec<Row> = match &fit.observed_order {
        Some(o) => {
            let path: Vec<Row> = sweep
                .paths
                .iter()
                .filter(|p| p.engine == fit.engine && p.label() == o.path)
                .flat_map(|p| sweep.path_rows(p))
                .collect();
            if path.is_empty() { rows.clone() } else { path }
        }
        None => Vec::new(),
    };
    let best = along
        .iter()
        .filter(|r| r.status == "ok")
        .filter_map(|r| Some((r.error_max?, r.cpu_s_min)))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    TARGETS
        .iter()
        .map(|&target| {
            let mut cost = CostToAccuracy {
                target,
                reached: Reached::NotReached,
                cpu_s_per_simulated_s: None,
                order: None,
                error: None,
                cause: None,
            };
            match cheapest(&rows, &fit.engine, target) {
                Reach::Reached(r) => {
                    cost.reached = Reached::Measured;
                    cost.cpu_s_per_simulated_s = Some(r.cpu_s_min);
                    cost.error = r.error_max;
                }
                Reach::NotReached(smallest) => {
                    let order = fit.observed_order.as_ref().map(|o| o.value);
                    match (&fit.floor, order, best) {
                        (Some(f), _, _) if f.value > target => {
                            cost.reached = Reached::Floor;
                            cost.error = Some(f.value);
                            cost.cause = Some(f.cause.clone());
                        }
                        (_, Some(p), Some((e, cpu))) if p >= MIN_EXTRAPOLATED_ORDER => {
                            cost.reached = Reached::Extrapolated;
                            cost.cpu_s_per_simulated_s = Some(cpu * (e / target).powf(1.0 / p));
                            cost.order = Some(p);
                            cost.error = Some(e);
                        }
                        _ => cost.error = smallest,
                    }
                }
            }
            cost
        })
        .collect()
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

/// Below this observed order a time to accuracy is not extrapolated (a slope that shallow is
/// not an asymptotic range).
pub const MIN_EXTRAPOLATED_ORDER: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;

    /// A first-order engine whose CPU time per simulated second is 1/h: error h, so the time to
    /// an error ε is 1/ε, measured or not.
    fn first_order(finest: i32) -> CaseSweep {
        let points = (0..=finest)
            .map(|k| {
                let h = 10f64.powi(-k);
                sweep::Point {
                    increment: h,
                    penalty_stiffness: None,
                    iterations: None,
                    steps: (1.0 / h) as u64,
                    stable_increment: None,
                    error: Some((h, h)),
                    cpu_seconds: vec![1.0 / h],
                    status: Status::Ok,
                    message: None,
                }
            })
            .collect();
        let path = SweepPath {
            engine: "rapier_f64".into(),
            precision: "f64",
            kind: PathKind::Increment {
                penalty_ratio: None,
            },
            points,
            ended: "budget",
        };
        let fits = vec![fit("rapier_f64", std::slice::from_ref(&path), false)];
        CaseSweep {
            case: "synthetic".into(),
            duration: 1.0,
            paths: vec![path],
            fits,
        }
    }

    #[test]
    fn a_cost_beyond_the_sweep_is_extrapolated_along_the_observed_order() {
        let sweep = first_order(2); // errors 1, 0.1, 0.01
        let found = costs(&sweep, &sweep.fits[0]);
        let at = |t: f64| found.iter().find(|c| c.target == t).unwrap();
        assert_eq!(at(1e-2).reached, Reached::Measured);
        assert_eq!(at(1e-2).cpu_s_per_simulated_s, Some(100.0));
        // 1e-4 and 1e-6: along order 1 from the finest point, 1/ε (to round-off).
        for t in [1e-4, 1e-6] {
            let c = at(t);
            assert_eq!(c.reached, Reached::Extrapolated);
            assert!((c.order.unwrap() - 1.0).abs() < 1e-12);
            let cpu = c.cpu_s_per_simulated_s.unwrap();
            assert!((cpu * t - 1.0).abs() < 1e-9, "{t}: {cpu}");
        }
        // Swept further, the same figure is measured.
        let further = first_order(4);
        let measured = costs(&further, &further.fits[0]);
        assert_eq!(measured[1].reached, Reached::Measured);
        assert!((measured[1].cpu_s_per_simulated_s.unwrap() * 1e-4 - 1.0).abs() < 1e-9);
    }
}
