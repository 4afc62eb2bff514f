//! The stability map: every engine that steps in time on every case with a stable increment,
//! at increments that are ratios of the explicit engine's computed stable increment, each run
//! judged by the growth rule ([`verdict::growth`]) and against the exact solution of its
//! engine's own model; then each pair's critical increment, the largest at which it stays
//! bounded, bisected.
//!
//! - **The grid**: [`RATIOS`], the same for every engine (0.25 … 4×).
//! - **Its own step**: each engine also runs at the increment its job ran at (rapier's default
//!   configuration: 1/60 s), so that the map and the verdicts speak of the same runs.
//! - **Its operating range**: an engine bounded on the whole grid is run on, × [`LADDER`] at a
//!   time, up to its *ceiling*: [`CEILING`] × the largest increment it runs at anywhere in the
//!   report (its job, the coarsest point of its sweep; for an engine whose sweep starts at its
//!   stable increment, the probe just above it, under twice it), and at least the grid's last
//!   ratio × [`LADDER`]². A bound "at least X" is only ever as large as that ceiling.
//! - **Below the grid**: an engine unstable at its smallest ratio is tried at [`BELOW`].
//!
//! Every run takes at least [`crate::run::stability::MIN_INCREMENTS`] increments (the case is
//! continued in time where it is shorter); a run still growing at its end is confirmed on a
//! horizon [`growth::CONFIRM`] times longer before it is called unstable.

use super::against_own_model;
use super::verdict::growth::{self, Growth, Outcome, Verdict};
use super::verdict::tolerance;
use crate::run::stability::{self as runs, MapRun};
use crate::run::{Engine, Plan, Status};
use crate::scene::Scene;
use rayon::prelude::*;

/// The grid's ratios.
pub const RATIOS: [f64; 10] = [0.25, 0.5, 0.75, 0.9, 0.98, 1.02, 1.1, 1.5, 2.0, 4.0];

/// Beyond the grid, each ratio tried is this many times the one before.
pub const LADDER: f64 = 4.0;

/// The map reaches this many times the largest increment an engine runs at in the report.
pub const CEILING: f64 = 4.0;

/// Ratios tried below the grid when an engine was unstable at its smallest ratio.
pub const BELOW: [f64; 2] = [0.125, 0.0625];

/// Bisection stops when the bracket's two ratios are within this factor of each other (1 %).
pub const BISECTION_WIDTH: f64 = 1.01;

/// Which search a run belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Search {
    /// A ratio of [`RATIOS`].
    Grid,
    /// The increment the engine's job ran at.
    OwnStep,
    /// Beyond the grid, up to the ceiling.
    Beyond,
    /// Below the grid.
    Below,
    /// Between a bounded and an unstable run.
    Bisection,
}

impl Search {
    /// Every search, in the CSV's order.
    pub const ALL: [Search; 5] = [
        Search::Grid,
        Search::OwnStep,
        Search::Beyond,
        Search::Below,
        Search::Bisection,
    ];

    /// Name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Search::Grid => "grid",
            Search::OwnStep => "own step",
            Search::Beyond => "beyond",
            Search::Below => "below",
            Search::Bisection => "bisection",
        }
    }

    /// From the CSV name.
    pub fn parse(s: &str) -> Option<Search> {
        Search::ALL.into_iter().find(|x| x.name() == s)
    }
}

/// One run of the map, judged.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// Which search it belongs to.
    pub search: Search,
    /// Ratio asked for (of the explicit engine's stable increment).
    pub ratio: f64,
    /// Increment used.
    pub increment: Option<f64>,
    /// How many times the case's duration it ran over (1: the case as it is).
    pub continued: Option<usize>,
    /// How it came out.
    pub outcome: Outcome,
    /// Largest error over the peak against the engine's own model's exact solution (over the
    /// case's own rows).
    pub error_max: Option<f64>,
    /// Its growth: the verdict of the rule and the transient amplification (`None` for a run
    /// that did not finish).
    pub growth: Option<Growth>,
    /// The engine's message, for a run that did not finish.
    pub message: Option<String>,
}

/// How a critical increment was bounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// Between a bounded and an unstable run within [`BISECTION_WIDTH`].
    Bisected,
    /// Bounded at every ratio tried, up to the engine's ceiling: at least this.
    AtLeast,
    /// Unstable at every ratio tried, down to the smallest ([`BELOW`]): less than this.
    Below,
}

impl Bound {
    /// Name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Bound::Bisected => "bisected",
            Bound::AtLeast => "at_least",
            Bound::Below => "below",
        }
    }
    /// From the CSV name.
    pub fn parse(s: &str) -> Option<Bound> {
        [Bound::Bisected, Bound::AtLeast, Bound::Below]
            .into_iter()
            .find(|b| b.name() == s)
    }
}

/// The largest increment at which an engine stays bounded on a case.
#[derive(Debug, Clone, PartialEq)]
pub struct Critical {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// The largest bounded run's increment, seconds (for [`Bound::Below`], the smallest
    /// increment tried).
    pub increment: f64,
    /// The explicit engine's computed stable increment on the case, seconds.
    pub explicit_stable: f64,
    /// How it was bounded.
    pub bound: Bound,
    /// The largest increment the engine runs at anywhere in the report, seconds: a bound
    /// "at least" below it says nothing of the engine's own runs.
    pub own_step: f64,
}

impl Critical {
    /// The critical increment over the explicit engine's computed stable increment.
    pub fn explicit_ratio(&self) -> f64 {
        self.increment / self.explicit_stable
    }

    /// Whether it answers the question for the engine's own runs ([`covers`]).
    pub fn covers_own_step(&self) -> bool {
        covers(self.bound, self.increment, self.own_step)
    }
}

/// Whether a critical `increment` bounded so answers the question for an engine whose largest
/// increment anywhere in the report is `own_step`: bisected, below, or at least an increment no
/// smaller than that (a bound "at least" below it is no answer: the map stopped short of it).
pub fn covers(bound: Bound, increment: f64, own_step: f64) -> bool {
    bound != Bound::AtLeast || increment >= own_step * (1.0 - 1e-9)
}

/// A map: its runs and each (case, engine)'s critical increment.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Map {
    /// Every run, in case, engine, search, ratio order.
    pub points: Vec<Point>,
    /// Per (case, engine), the largest increment that stays bounded.
    pub critical: Vec<Critical>,
}

/// How a history's error against its own model's exact solution is measured.
type ErrorOf<'a> = dyn Fn(&Scene, &str, &crate::contract::History) -> Option<f64> + Sync + 'a;

/// Judge one run: its outcome from its typed status, its growth and its error.
fn judge(
    scene: &Scene,
    engine: &str,
    ratio: f64,
    search: Search,
    run: MapRun,
    error_of: &ErrorOf,
) -> Point {
    let (growth, error_max) = match &run.output {
        Some(out) => (
            growth::judge(&out.history, out.info.steps as f64),
            error_of(scene, engine, &out.history),
        ),
        None => (None, None),
    };
    let outcome = match (run.continued, run.status) {
        (None, _) => Outcome::TooShort,
        (_, status) => {
            growth::outcome(status, growth.as_ref(), error_max, tolerance(scene, engine))
        }
    };
    Point {
        case: scene.id.clone(),
        engine: engine.to_string(),
        search,
        ratio,
        increment: run.increment,
        continued: run.continued,
        outcome,
        error_max,
        growth,
        message: run.message,
    }
}

/// Run and judge `engine` on `scene` at `ratio`; a run still growing at its end is run again
/// on a horizon [`growth::CONFIRM`] times longer, whose growth decides (its accuracy stays the
/// first run's: the case's own rows are the same).
fn point(
    scene: &Scene,
    engine: &dyn Engine,
    ratio: f64,
    search: Search,
    error_of: &ErrorOf,
) -> Point {
    let name = engine.name();
    let first = judge(
        scene,
        name,
        ratio,
        search,
        runs::run_at(scene, engine, ratio),
        error_of,
    );
    if first.growth.is_none_or(|g| g.verdict != Verdict::Growing)
        || first.outcome != Outcome::Unstable
    {
        return first;
    }
    let longer = runs::run_on(scene, engine, ratio, growth::CONFIRM);
    let confirmed = judge(scene, name, ratio, search, longer, error_of);
    // Only a longer run that is bounded undoes the verdict; one that fails or is still growing
    // confirms it.
    if !confirmed.outcome.bounded() {
        return Point {
            continued: confirmed.continued.or(first.continued),
            growth: confirmed.growth.or(first.growth),
            ..first
        };
    }
    let outcome = growth::outcome(
        Status::Ok,
        confirmed.growth.as_ref(),
        first.error_max,
        tolerance(scene, name),
    );
    Point {
        outcome,
        continued: confirmed.continued,
        growth: confirmed.growth,
        ..first
    }
}

/// Map every case of `plan` for the `engines` that step in time ([`Engine::stepping`]),
/// measuring errors against the exact solutions in `outcome` (which also holds each job's
/// increment), and bisect each pair's critical increment.
pub fn measure(
    plan: &Plan,
    outcome: &crate::run::Outcome,
    engines: &[&dyn Engine],
    progress: bool,
) -> Map {
    let error_of = |scene: &Scene, engine: &str, h: &crate::contract::History| {
        against_own_model(outcome, scene, engine, h)
    };
    let chosen = crate::run::sweep::steppers(engines);
    let all: Vec<&Scene> = plan.cases.iter().collect();
    let scenes = runs::mapped(&all);
    let job_step = |case: &str, engine: &str| {
        outcome
            .jobs
            .iter()
            .find(|j| j.case == case && j.engine == engine)
            .and_then(|j| j.result.as_ref().ok())
            .map(|s| s.info.increment)
    };
    let pairs: Vec<Pair> = scenes
        .iter()
        .flat_map(|s| chosen.iter().map(move |e| (*s, *e)))
        .filter_map(|(scene, engine)| {
            let stable = runs::explicit_stable(scene)?;
            let job = job_step(&scene.id, engine.name());
            Some(Pair {
                scene,
                engine,
                stable,
                own: runs::largest_step(scene, engine, job, stable),
                job,
            })
        })
        .collect();
    let bar = crate::run::progress_bar(pairs.len(), progress);
    bar.set_message("stability map");
    let maps: Vec<(Vec<Point>, Option<Critical>)> = pairs
        .par_iter()
        .map(|pair| {
            let m = map_pair(pair, &error_of);
            bar.inc(1);
            m
        })
        .collect();
    bar.finish_and_clear();
    let mut map = Map::default();
    for (points, critical) in maps {
        map.points.extend(points);
        map.critical.extend(critical);
    }
    map
}

/// One (case, engine) of the map, with what it needs to know.
struct Pair<'a> {
    scene: &'a Scene,
    engine: &'a dyn Engine,
    /// The explicit engine's stable increment on the case.
    stable: f64,
    /// The largest increment the engine runs at in the report.
    own: f64,
    /// The increment its job ran at.
    job: Option<f64>,
}

/// One pair's runs (grid, own step, beyond, below, bisection, in the order run) and its
/// critical increment.
fn map_pair(pair: &Pair, error_of: &ErrorOf) -> (Vec<Point>, Option<Critical>) {
    let Pair {
        scene,
        engine,
        stable,
        own,
        job,
    } = *pair;
    let run = |r: f64, search: Search| point(scene, engine, r, search, error_of);
    let mut points: Vec<Point> = RATIOS.iter().map(|r| run(*r, Search::Grid)).collect();
    if let Some(h) = job {
        points.push(run(h / stable, Search::OwnStep));
    }
    // A pair with a failed or inapplicable run has no critical increment.
    if points
        .iter()
        .any(|p| matches!(p.outcome, Outcome::Failed | Outcome::NotApplicable))
    {
        return (points, None);
    }
    let ceiling = (CEILING * own / stable).max(RATIOS[RATIOS.len() - 1] * LADDER * LADDER);
    let critical = search(ceiling, &mut points, &run).and_then(|(at, bound)| {
        Some(Critical {
            case: scene.id.clone(),
            engine: engine.name().to_string(),
            increment: at.increment?,
            explicit_stable: stable,
            bound,
            own_step: own,
        })
    });
    (points, critical)
}

/// The run at a pair's critical increment and how it is bounded, from its runs so far, running
/// the ones it needs: the bracket the grid (and the own step) gives, then beyond it up to
/// `ceiling` or below it, then bisected.
fn search(
    ceiling: f64,
    points: &mut Vec<Point>,
    run: &dyn Fn(f64, Search) -> Point,
) -> Option<(Point, Bound)> {
    let (mut low, mut high) = bracket(points);
    if high.is_none() {
        (low, high) = beyond(low, ceiling, points, run);
    }
    if low.is_none() {
        (low, high) = below(high, points, run);
    }
    let mut bound = match (&low, &high) {
        (Some(_), Some(_)) => Bound::Bisected,
        (Some(_), None) => Bound::AtLeast,
        (None, _) => Bound::Below,
    };
    if let (Some(l), Some(h)) = (&mut low, &mut high) {
        while h.ratio / l.ratio > BISECTION_WIDTH {
            let p = run((l.ratio * h.ratio).sqrt(), Search::Bisection);
            points.push(p.clone());
            match p.outcome {
                o if o.bounded() => *l = p,
                Outcome::Unstable => *h = p,
                // A run that neither stays bounded nor grows leaves the bracket open: the
                // largest bounded run is only a lower bound.
                _ => {
                    bound = Bound::AtLeast;
                    break;
                }
            }
        }
    }
    Some((low.or(high)?, bound))
}

/// The first bracket from the grid and the own step, by ratio: (the largest bounded run below
/// the first unstable one, the first unstable one).
fn bracket(points: &[Point]) -> (Option<Point>, Option<Point>) {
    let mut grid: Vec<&Point> = points
        .iter()
        .filter(|p| matches!(p.search, Search::Grid | Search::OwnStep))
        .collect();
    grid.sort_by(|a, b| a.ratio.total_cmp(&b.ratio));
    let first_unstable = grid.iter().position(|p| p.outcome == Outcome::Unstable);
    let bounded_below = |i: usize| grid[..i].iter().rev().find(|p| p.outcome.bounded());
    match first_unstable {
        Some(i) => (
            bounded_below(i).map(|p| (*p).clone()),
            Some(grid[i].clone()),
        ),
        None => (bounded_below(grid.len()).map(|p| (*p).clone()), None),
    }
}

/// Bounded on the grid: × [`LADDER`] at a time from the grid's last ratio up to `ceiling`,
/// until a run is unstable (the bracket) or neither bounded nor unstable (the search stops).
fn beyond(
    mut low: Option<Point>,
    ceiling: f64,
    points: &mut Vec<Point>,
    run: &dyn Fn(f64, Search) -> Point,
) -> (Option<Point>, Option<Point>) {
    let mut r = RATIOS[RATIOS.len() - 1];
    while r < ceiling * (1.0 - 1e-9) {
        r = (r * LADDER).min(ceiling);
        let p = run(r, Search::Beyond);
        points.push(p.clone());
        match p.outcome {
            o if o.bounded() => {
                if low.as_ref().is_none_or(|l| l.ratio < p.ratio) {
                    low = Some(p);
                }
            }
            Outcome::Unstable => return (low, Some(p)),
            _ => break,
        }
    }
    (low, None)
}

/// Unstable at the grid's smallest ratio: the ratios of [`BELOW`], until one is bounded.
fn below(
    mut high: Option<Point>,
    points: &mut Vec<Point>,
    run: &dyn Fn(f64, Search) -> Point,
) -> (Option<Point>, Option<Point>) {
    for r in BELOW {
        let p = run(r, Search::Below);
        points.push(p.clone());
        match p.outcome {
            o if o.bounded() => return (Some(p), high),
            Outcome::Unstable => high = Some(p),
            _ => break,
        }
    }
    (None, high)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run at `ratio` whose outcome `at` gives (increment = ratio).
    fn run_with(at: impl Fn(f64) -> Outcome) -> impl Fn(f64, Search) -> Point {
        move |ratio, search| Point {
            case: "synthetic".into(),
            engine: "synthetic".into(),
            search,
            ratio,
            increment: Some(ratio),
            continued: Some(1),
            outcome: at(ratio),
            error_max: None,
            growth: None,
            message: None,
        }
    }

    fn grid(run: &dyn Fn(f64, Search) -> Point) -> Vec<Point> {
        RATIOS.iter().map(|r| run(*r, Search::Grid)).collect()
    }

    /// Bounded up to 1.3, unstable above, but bounded again at 2 (a chattering contact): the
    /// bracket is the first unstable run and the largest bounded one below it, bisected to 1 %.
    #[test]
    fn a_non_monotone_map_is_bisected_below_its_first_unstable_run() {
        let run = run_with(|r| match r {
            r if r <= 1.3 => Outcome::Accurate,
            r if (1.9..2.1).contains(&r) => Outcome::Inaccurate,
            _ => Outcome::Unstable,
        });
        let mut points = grid(&run);
        let (at, bound) = search(64.0, &mut points, &run).unwrap();
        assert_eq!(bound, Bound::Bisected);
        assert!(
            at.ratio <= 1.3 && at.ratio * BISECTION_WIDTH > 1.3,
            "{}",
            at.ratio
        );
    }

    /// Bounded on the whole grid: × 4 from the grid's last ratio up to the ceiling, each run
    /// there; bounded at all of them is "at least" the ceiling.
    #[test]
    fn a_map_bounded_on_its_grid_goes_on_to_its_ceiling() {
        let run = run_with(|_| Outcome::Inaccurate);
        let mut points = grid(&run);
        let (at, bound) = search(1000.0, &mut points, &run).unwrap();
        assert_eq!((at.ratio, bound), (1000.0, Bound::AtLeast));
        let beyond: Vec<f64> = points
            .iter()
            .filter(|p| p.search == Search::Beyond)
            .map(|p| p.ratio)
            .collect();
        assert_eq!(beyond, [16.0, 64.0, 256.0, 1000.0]);
    }

    /// A run that fails inside the bracket leaves it open: the largest bounded run is a lower
    /// bound, not a bisected limit.
    #[test]
    fn a_failed_run_inside_the_bracket_leaves_a_lower_bound() {
        let run = run_with(|r| match r {
            r if r <= 1.0 => Outcome::Accurate,
            r if r < 1.1 => Outcome::Failed,
            _ => Outcome::Unstable,
        });
        let mut points = grid(&run);
        let (at, bound) = search(64.0, &mut points, &run).unwrap();
        assert_eq!((at.ratio, bound), (0.98, Bound::AtLeast));
    }
}
