//! Sweeps: each engine rerun on a case over a grid of settings, every point timed, so that the
//! comparison can say what accuracy costs (work–precision, `comparison::work_precision`).
//!
//! A sweep is a set of *paths*, each a sequence of settings that refine one thing, planned
//! from what each engine says of its stepping ([`Engine::stepping`]), never from its name:
//!
//! - the time increment, from the engine's coarsest ([`Coarsest`]) down by
//!   [`Grid::refinement`] per point. `explicit` and `explicit_small` start at 0.9 of their
//!   stable increment, the matched rapier engines at the output interval, the default ones at
//!   rapier's 1/60 s. An engine with penalty contact runs, on a scene with contact, one such
//!   path per penalty stiffness of [`Grid::penalty_ratios`] (× the largest spring stiffness
//!   `k`; on a scene without springs `k` is the case's own penalty stiffness over the grid's
//!   geometric middle ratio, so the middle path runs the case's own). A path that starts at
//!   the stable increment also runs once just above it (the shortest increment above it that
//!   divides the output interval, where there is one): that point must come back unstable.
//! - the substeps of an engine that has them ([`Engine::with_substeps`]: the matched rapier
//!   engines' `solver_iterations`, 1, 2, 4, …) at the output interval.
//!
//! A path stops when its error stalls twice in a row (two successive points each more than
//! [`Grid::stall`] of the point before: the refinement no longer pays; a single stall can be
//! a plateau, such as a small fast mode whose phase error has saturated before the step
//! resolves it; a stall that the budget leaves unconfirmed counts) or when the next point
//! would take more than
//! the engine's share of the grid's budget of increments ([`Grid::max_increments`] ×
//! [`Stepping::budget_share`], substeps counted).
//! Both rules depend only on the errors and the settings, never on timings, so the same inputs
//! run the same points. Each point runs [`Grid::repeat`] times; the CPU seconds of each run are
//! the running thread's own (`CLOCK_THREAD_CPUTIME_ID`), setup included.
//!
//! This layer measures and judges nothing: the caller hands in how a finished run is measured
//! ([`ErrorOf`]: its error against the exact solution, which the stall rule needs, and whether
//! its growth makes it unstable, the comparison's verdict). A point's status is otherwise the
//! engine's own, typed ([`crate::engines::EngineError`]).

use crate::contract::History;
use crate::engines::{Coarsest, Engine, RunInfo, RunSettings, Stepping};
use crate::scene::{IncrementRule, PenaltyRule, Scene};
use rayon::prelude::*;

/// The grid and its limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Runs per point (the CPU time is reported as min, median, max over them).
    pub repeat: usize,
    /// Increment ratio between successive points of a path (√10: two points per decade).
    pub refinement: f64,
    /// Penalty stiffnesses, as multiples of the scene's largest spring stiffness, one
    /// increment path each (scenes with penalty contact).
    pub penalty_ratios: Vec<f64>,
    /// Substep counts of the substeps path.
    pub substeps: Vec<usize>,
    /// A path stops after two successive points whose errors each exceed this fraction of the
    /// point before.
    pub stall: f64,
    /// Most increments one run of a point may take (substeps counted), of which an engine
    /// takes its [`Stepping::budget_share`] (rapier's: a fifth). About 0.1–0.3 s of CPU for the explicit
    /// engines and 0.3–1 s for rapier at the shipped speeds. Points above a tenth of it run
    /// once whatever [`Grid::repeat`] says (a long run's time varies little).
    pub max_increments: f64,
    /// Most points a path has (a bound whatever the errors do).
    pub max_points: usize,
}

impl Default for Grid {
    /// The compact grid the main command runs.
    fn default() -> Self {
        Grid {
            repeat: 3,
            refinement: 10f64.sqrt(),
            penalty_ratios: vec![1e2, 1e3, 1e4, 1e5, 1e6],
            substeps: vec![1, 2, 4, 8, 16, 32, 64],
            stall: 0.7,
            max_increments: 1.0e6,
            max_points: 12,
        }
    }
}

/// Errors (max over peak) at or above this are pre-asymptotic: a path does not stall there.
pub const PRE_ASYMPTOTIC: f64 = 0.5;

/// What happened at a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The run finished and its history meets the output contract.
    Ok,
    /// The run stopped on its instability guard, or its state turned non-finite.
    Unstable,
    /// Any other failure.
    Failed,
}

impl Status {
    /// `ok`, `unstable`, `failed`.
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Unstable => "unstable",
            Status::Failed => "failed",
        }
    }
}

/// One run setting and what it gave.
#[derive(Debug, Clone)]
pub struct Point {
    /// The increment taken (requested, where the run failed before choosing one).
    pub increment: f64,
    /// Penalty stiffness (engines with penalty contact on a scene with contact).
    pub penalty_stiffness: Option<f64>,
    /// Rapier substeps per increment.
    pub iterations: Option<usize>,
    /// Increments taken (0 for a failed run).
    pub steps: u64,
    /// The stable increment the engine computed (explicit engines, ok runs).
    pub stable_increment: Option<f64>,
    /// Error as the caller measures it: (max over peak, RMS over peak), for an ok run.
    pub error: Option<(f64, f64)>,
    /// CPU seconds of each repeat (one for a failed run).
    pub cpu_seconds: Vec<f64>,
    /// Outcome.
    pub status: Status,
    /// Why the run failed, if it did.
    pub message: Option<String>,
}

/// What a path refines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathKind {
    /// The time increment, at a fixed penalty stiffness (where the engine has one).
    Increment {
        /// Penalty stiffness ratio to the largest spring stiffness (penalty engines with
        /// contact).
        penalty_ratio: Option<f64>,
    },
    /// Rapier's substeps, at a fixed increment.
    Substeps {
        /// The increment.
        increment: f64,
    },
    /// Runs toward an accuracy the increment path did not reach: the increment its
    /// extrapolation predicts, then finer (the comparison's reach, `work_precision`).
    Reach {
        /// The accuracy aimed at (error over the peak).
        target: f64,
    },
}

/// One path of one engine.
#[derive(Debug, Clone)]
pub struct SweepPath {
    /// Engine name.
    pub engine: String,
    /// `f64` or `f32`.
    pub precision: &'static str,
    /// What it refines.
    pub kind: PathKind,
    /// Points, coarse to fine; an unstable probe, where there is one, first.
    pub points: Vec<Point>,
    /// Why the path ended: `stalled`, `budget`, `failed` or `points`.
    pub ended: &'static str,
}

impl SweepPath {
    /// A short label: the engine and what the path holds fixed.
    pub fn label(&self) -> String {
        match self.kind {
            PathKind::Increment {
                penalty_ratio: Some(r),
            } => format!("{}, k_p = {r:.0e} k", self.engine),
            PathKind::Increment {
                penalty_ratio: None,
            } => format!("{}, h", self.engine),
            PathKind::Substeps { .. } => format!("{}, substeps", self.engine),
            PathKind::Reach { target } => format!("{}, to {target:.0e}", self.engine),
        }
    }
}

/// What the caller measures of a finished run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// (max, RMS) over the peak against the exact solution (`None`: no baseline).
    pub error: Option<(f64, f64)>,
    /// Whether the run's energy kept growing: the comparison's verdict on its history.
    pub growing: bool,
}

/// How the caller measures a finished run: engine name, history and increments taken.
pub type ErrorOf<'a> = dyn Fn(&str, &History, u64) -> Measured + Sync + 'a;

/// How the caller measures a finished run on a scene (see [`ErrorOf`]).
pub type SceneErrorOf<'a> = dyn Fn(&Scene, &str, &History, u64) -> Measured + Sync + 'a;

/// The engines of `engines` a sweep can run: those that step in time ([`Engine::stepping`]).
pub fn steppers<'a>(engines: &[&'a dyn Engine]) -> Vec<&'a dyn Engine> {
    engines
        .iter()
        .copied()
        .filter(|e| e.stepping().is_some())
        .collect()
}

/// The paths of `engines` on `scene`, before they run: per engine, one increment path (one
/// per penalty stiffness of the grid where it has penalty contact and the scene has contact),
/// and a substeps path at the output interval where it has substeps.
fn plan<'a>(
    scene: &Scene,
    engines: &[&'a dyn Engine],
    grid: &Grid,
) -> Vec<(&'a dyn Engine, PathKind)> {
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    let mut paths = Vec::new();
    for &e in engines {
        let Some(stepping) = e.stepping() else {
            continue;
        };
        if stepping.penalty && !scene.contacts.is_empty() {
            for r in &grid.penalty_ratios {
                let penalty_ratio = Some(*r);
                paths.push((e, PathKind::Increment { penalty_ratio }));
            }
        } else {
            let penalty_ratio = None;
            paths.push((e, PathKind::Increment { penalty_ratio }));
        }
        if e.with_substeps(1).is_some() {
            let increment = interval;
            paths.push((e, PathKind::Substeps { increment }));
        }
    }
    paths
}

/// The contact softness (Hz) of the matched rapier engine named `name`.
#[cfg(feature = "rapier")]
pub fn matched_contact_frequency(name: &str) -> f64 {
    crate::engines::rapier::matched_contact_frequency(name)
}

/// How many paths [`run`] runs on `scene` (for a progress bar).
pub fn plan_len(scene: &Scene, engines: &[&dyn Engine], grid: &Grid) -> usize {
    plan(scene, engines, grid).len()
}

/// Run every path of every case in `scenes`, each with the engines given beside it (those
/// that do not step in time are skipped), in parallel; `tick` is called once per finished
/// path. Paths come back per case in the order of `scenes`, each case's in engine order.
pub fn run(
    scenes: &[(&Scene, Vec<&dyn Engine>)],
    grid: &Grid,
    error_of: &SceneErrorOf,
    tick: &(dyn Fn(&str) + Sync),
) -> Vec<Vec<SweepPath>> {
    let jobs: Vec<(usize, &Scene, &dyn Engine, PathKind)> = scenes
        .iter()
        .enumerate()
        .flat_map(|(i, (s, engines))| {
            plan(s, engines, grid)
                .into_iter()
                .map(move |(e, k)| (i, *s, e, k))
        })
        .collect();
    let done: Vec<(usize, SweepPath)> = jobs
        .par_iter()
        .map(|(i, scene, engine, kind)| {
            let error = |e: &str, h: &History, steps: u64| error_of(scene, e, h, steps);
            let path = run_path(scene, *engine, *kind, grid, &error);
            tick(&format!("{}/{}", scene.id, path.label()));
            (*i, path)
        })
        .collect();
    let mut out = vec![Vec::new(); scenes.len()];
    for (i, p) in done {
        out[i].push(p);
    }
    out
}

/// CPU seconds this thread has used.
pub fn thread_cpu_seconds() -> f64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// One run of `engine` on `scene` at `increment` (forced) with its own substeps, timed: a
/// point of a path toward an accuracy ([`PathKind::Reach`]).
pub fn run_at(scene: &Scene, engine: &dyn Engine, increment: f64, error: &ErrorOf) -> Point {
    let settings = RunSettings {
        increment: Some(IncrementRule::Forced(increment)),
        ..RunSettings::default()
    };
    let iterations = engine.stepping().and_then(|s| s.substeps);
    run_point(scene, engine, &settings, iterations, 1, error)
}

/// The increments (substeps counted) a run of `engine` on `scene` at `increment` takes.
pub fn increments_at(scene: &Scene, engine: &dyn Engine, increment: f64) -> f64 {
    let settings = RunSettings {
        increment: Some(IncrementRule::Forced(increment)),
        ..RunSettings::default()
    };
    let substeps = engine.stepping().and_then(|s| s.substeps).unwrap_or(1) as f64;
    engine
        .increments(scene, &settings)
        .unwrap_or(scene.duration() / increment)
        * substeps
}

/// One setting run `repeat` times.
fn run_point(
    scene: &Scene,
    engine: &dyn Engine,
    settings: &RunSettings,
    iterations: Option<usize>,
    repeat: usize,
    error: &ErrorOf,
) -> Point {
    let requested = match settings.increment {
        Some(IncrementRule::Forced(h) | IncrementRule::Given(h)) => h,
        _ => 0.0,
    };
    let mut cpu = Vec::new();
    type Finished = (RunInfo, Measured);
    let mut first: Option<Result<Finished, (Status, String)>> = None;
    for _ in 0..repeat.max(1) {
        if crate::interrupt::checkpoint("sweep").is_err() {
            first.get_or_insert(Err((Status::Failed, "interrupted".into())));
            break;
        }
        let start = thread_cpu_seconds();
        let run =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| engine.run(scene, settings)));
        let (checked, status) = crate::run::checked_run(scene, run);
        cpu.push(thread_cpu_seconds() - start);
        let failed = checked.is_err();
        if first.is_none() {
            first = Some(match checked {
                Ok(o) => {
                    let measured = error(engine.name(), &o.history, o.info.steps);
                    Ok((o.info, measured))
                }
                Err(message) => Err((status.into(), message)),
            });
        }
        if failed {
            break;
        }
    }
    match first.expect("at least one run") {
        Ok((info, measured)) => Point {
            increment: info.increment,
            penalty_stiffness: info.penalty_stiffness,
            iterations,
            steps: info.steps,
            stable_increment: info.stable_increment,
            error: measured.error,
            cpu_seconds: cpu,
            status: if measured.growing {
                Status::Unstable
            } else {
                Status::Ok
            },
            message: measured
                .growing
                .then(|| "its energy kept growing to the end of the run".to_string()),
        },
        Err((status, message)) => Point {
            increment: requested,
            penalty_stiffness: None,
            iterations,
            steps: 0,
            stable_increment: None,
            error: None,
            cpu_seconds: cpu,
            status,
            message: Some(message),
        },
    }
}

impl From<crate::run::Status> for Status {
    fn from(s: crate::run::Status) -> Status {
        match s {
            crate::run::Status::Ok => Status::Ok,
            crate::run::Status::Unstable => Status::Unstable,
            crate::run::Status::NotApplicable | crate::run::Status::Failed => Status::Failed,
        }
    }
}

/// Run one path until it stalls, fails, or the next point exceeds the budget.
fn run_path(
    scene: &Scene,
    engine: &dyn Engine,
    kind: PathKind,
    grid: &Grid,
    error: &ErrorOf,
) -> SweepPath {
    let stepping = engine.stepping().unwrap_or(UNSTEPPED);
    let penalty = match kind {
        PathKind::Increment {
            penalty_ratio: Some(r),
        } => Some(penalty_rule(scene, r, grid)),
        _ => None,
    };
    let budget = grid.max_increments * stepping.budget_share;
    let mut points: Vec<Point> = Vec::new();
    let mut ended = "points";
    let count = match kind {
        PathKind::Substeps { .. } => grid.substeps.len().min(grid.max_points),
        PathKind::Increment { .. } => grid.max_points,
        PathKind::Reach { .. } => 0,
    };
    let mut probe: Option<Point> = None;
    let mut stalls = 0;
    for k in 0..count {
        let at = PathPoint {
            k,
            penalty,
            first: points.first(),
        };
        let (settings, substeps) = point_setting(scene, &stepping, kind, grid, &at);
        let varied = substeps.and_then(|n| engine.with_substeps(n));
        let engine = varied.as_deref().unwrap_or(engine);
        let iterations = substeps.or(stepping.substeps);
        // An engine that cannot tell is counted from the increment it is given.
        let given = match settings.increment {
            Some(IncrementRule::Forced(h)) if h > 0.0 => Some(scene.duration() / h),
            _ => None,
        };
        let increments = engine.increments(scene, &settings).or(given).unwrap_or(0.0)
            * iterations.unwrap_or(1) as f64;
        if increments > budget * (1.0 + 1e-9) {
            // A stall the budget left unconfirmed still ends the path as stalled.
            ended = if stalls > 0 { "stalled" } else { "budget" };
            break;
        }
        let repeat = if increments > budget / 10.0 {
            1
        } else {
            grid.repeat
        };
        let point = run_point(scene, engine, &settings, iterations, repeat, error);
        let status = point.status;
        let this = point.error.map(|e| e.0);
        let previous = points.last().and_then(|p| p.error.map(|e| e.0));
        let from_stable = matches!(stepping.coarsest, Coarsest::Stable { .. })
            && matches!(kind, PathKind::Increment { .. });
        if k == 0 && from_stable && status == Status::Ok {
            let interval = scene.duration() / (scene.output_rows - 1) as f64;
            probe = unstable_probe(scene, engine, &settings, &point, interval, error);
        }
        points.push(point);
        if status != Status::Ok {
            ended = "failed";
            break;
        }
        // An error of the order of the answer itself is pre-asymptotic (it saturates, it
        // does not stall): only smaller errors can stall.
        let stalled = matches!((this, previous), (Some(e), Some(p))
            if e > grid.stall * p && p < PRE_ASYMPTOTIC);
        stalls = if stalled { stalls + 1 } else { 0 };
        if stalls == 2 {
            ended = "stalled";
            break;
        }
    }
    if let Some(p) = probe {
        points.insert(0, p);
    }
    SweepPath {
        engine: engine.name().to_string(),
        precision: stepping.precision,
        kind,
        points,
        ended,
    }
}

/// What [`run_path`] assumes of an engine that does not say how it steps (none is planned).
const UNSTEPPED: Stepping = Stepping {
    coarsest: Coarsest::OutputInterval,
    penalty: false,
    substeps: None,
    budget_share: 1.0,
    precision: "f64",
    on_request: false,
};

/// Where a path is: the point's index, the path's penalty rule, and its first point (whose
/// increment a stable-increment start chose).
struct PathPoint<'a> {
    k: usize,
    penalty: Option<PenaltyRule>,
    first: Option<&'a Point>,
}

/// The run settings of a path's point and its substeps (substeps paths only): a substeps path
/// at its fixed increment; an increment path from the engine's coarsest increment down by the
/// grid's refinement.
fn point_setting(
    scene: &Scene,
    stepping: &Stepping,
    kind: PathKind,
    grid: &Grid,
    at: &PathPoint,
) -> (RunSettings, Option<usize>) {
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    let refined = |h: f64| IncrementRule::Forced(h / grid.refinement.powi(at.k as i32));
    let (increment, substeps) = match (kind, stepping.coarsest) {
        (PathKind::Substeps { increment }, _) => (
            IncrementRule::Forced(increment),
            grid.substeps.get(at.k).copied(),
        ),
        (_, Coarsest::Stable { safety }) if at.k == 0 => (IncrementRule::Stable { safety }, None),
        (_, Coarsest::Stable { .. }) => (refined(at.first.map_or(0.0, |p| p.increment)), None),
        (_, Coarsest::OutputInterval) => (refined(interval), None),
        (_, Coarsest::Increment(h)) => (refined(h), None),
    };
    let settings = RunSettings {
        increment: Some(increment),
        penalty: at.penalty,
        ..RunSettings::default()
    };
    (settings, substeps)
}

/// A penalty path's stiffness: `ratio` × the scene's largest spring stiffness `k`. A scene
/// without springs has no `k`: there the grid's geometric middle ratio stands for the case's
/// own penalty stiffness (`k` = the case's k_p over that middle ratio).
fn penalty_rule(scene: &Scene, ratio: f64, grid: &Grid) -> PenaltyRule {
    let ratios = &grid.penalty_ratios;
    match (ratios.first(), ratios.last()) {
        (Some(first), Some(last)) if scene.largest_stiffness() <= 0.0 => {
            let own = scene.penalty_stiffness(scene.settings.penalty);
            PenaltyRule::Stiffness(ratio / (first * last).sqrt() * own)
        }
        _ => PenaltyRule::Ratio(ratio),
    }
}

/// The run just above the stable increment of a path's first point: the shortest increment
/// above it that divides the output interval (so that the engine takes it as it is), when that
/// is less than twice the stable one.
fn unstable_probe(
    scene: &Scene,
    engine: &dyn Engine,
    settings: &RunSettings,
    first: &Point,
    interval: f64,
    error: &ErrorOf,
) -> Option<Point> {
    let stable = first.stable_increment?;
    let n = (interval / stable).floor();
    if n < 1.0 {
        return None;
    }
    let h = interval / n;
    if !(h > 1.001 * stable && h < 2.0 * stable) {
        return None;
    }
    let forced = RunSettings {
        increment: Some(IncrementRule::Forced(h)),
        ..*settings
    };
    let mut point = run_point(scene, engine, &forced, None, 1, error);
    point.penalty_stiffness = point.penalty_stiffness.or(first.penalty_stiffness);
    Some(point)
}
