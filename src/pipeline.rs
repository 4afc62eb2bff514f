//! A run from end to end, in the order of the data flow: the jobs, the studies that measure
//! them against the exact solutions, and the files written into a staging directory and
//! swapped into place. The command line chooses what runs and prints what it returns; this
//! module is the last in the flow (it uses the modules before it, and none of them uses it).

use crate::comparison::stability::Map;
use crate::comparison::summary::Summary;
use crate::comparison::{self, discrepancy, work_precision};
use crate::engines::{Engine, RunSettings};
use crate::interrupt;
use crate::report::data::DataError;
use crate::report::staging::Staging;
use crate::report::{self, Study};
use crate::run::on_request::Request;
use crate::run::refinement::Depth;
use crate::run::{self, Outcome, Plan, sweep};
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// The studies a run makes beyond the jobs, their discrepancy budgets and their causes.
#[derive(Debug, Clone)]
pub struct Studies {
    /// The sweep (what accuracy costs), each setting timed `repeat` times; `None`: not run.
    pub sweep: Option<usize>,
    /// The stability map.
    pub stability: bool,
    /// Accuracy on request.
    pub on_request: bool,
    /// The shard this run is, where it is one of a partitioned run (`run --partition k/n`).
    pub shard: Option<crate::comparison::summary::Shard>,
}

/// When each stage of a run ended, seconds after it started.
#[derive(Debug, Clone, Copy, Default)]
pub struct StageTimes {
    /// The cases loaded and checked, the output locked and staged.
    pub loaded: f64,
    /// The jobs.
    pub ran: f64,
    /// The discrepancy budgets.
    pub budgeted: f64,
    /// The invariance controls.
    pub invariant: f64,
    /// The control experiments.
    pub attributed: f64,
    /// The sweep.
    pub swept: f64,
    /// The runs that check the sweep's extrapolated costs.
    pub reached: f64,
    /// The stability map.
    pub mapped: f64,
    /// Accuracy on request.
    pub requested: f64,
    /// The report written into the staging directory.
    pub written: f64,
    /// The report swapped into place.
    pub swapped: f64,
}

/// Why a run stopped before its files were in place (the previous ones are unchanged).
#[derive(Debug)]
pub enum Stopped {
    /// A signal asked it to stop.
    Interrupted,
    /// The files could not be written.
    Write(DataError),
    /// The files could not be swapped into place.
    Swap(std::io::Error),
}

/// A run whose report is in place: the jobs' outcome, the report's summary, the stage times.
pub struct Finished {
    /// What the jobs returned.
    pub outcome: Outcome,
    /// The report's summary.
    pub summary: Summary,
    /// When each stage ended.
    pub times: StageTimes,
}

/// What the optional studies measured (each empty when it did not run).
struct Measured {
    sweeps: Vec<comparison::work_precision::CaseSweep>,
    maps: Map,
    requests: Vec<Request>,
}

/// Run `plan`'s jobs and `studies`, write the report into `staging` and swap it into place.
/// `cases_dir` says which cases are seeds (accuracy on request covers those, the sweep those
/// and the cases that ask for it); `started` is when the run began (its loading included).
pub fn run(
    plan: &Plan,
    cases_dir: &Path,
    studies: &Studies,
    staging: Staging,
    started: Instant,
    progress: bool,
) -> Result<Finished, Stopped> {
    let mut times = StageTimes {
        loaded: seconds_since(started),
        ..StageTimes::default()
    };
    let lines = progress && !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let lap = |stage: &str, previous: f64| lap(started, stage, previous, lines);
    let outcome = run::execute(plan, progress);
    times.ran = lap("jobs", times.loaded);
    stop_if_interrupted()?;
    let budgets = discrepancy::measure(plan, &outcome, Depth::Basic, progress);
    times.budgeted = lap("discrepancy budget", times.ran);
    stop_if_interrupted()?;
    let invariances = comparison::invariance::measure(plan, &outcome, progress);
    times.invariant = lap("invariance controls", times.budgeted);
    stop_if_interrupted()?;
    let attributions = comparison::attribution::measure(plan, &outcome, &invariances, progress);
    times.attributed = lap("controls", times.invariant);
    stop_if_interrupted()?;
    let measured = measure(
        plan, &outcome, cases_dir, studies, progress, &lap, &mut times,
    )?;
    let study = Study {
        shard: studies.shard.as_ref(),
        budgets: &budgets,
        attributions: &attributions,
        invariances: &invariances,
        sweeps: &measured.sweeps,
        stability: &measured.maps,
        requests: &measured.requests,
        parts: times.parts(studies),
    };
    let summary = report::write(staging.path(), plan, &outcome, &study, staging.target())
        .map_err(written_or_interrupted)?;
    if interrupt::checkpoint("swap").is_err() {
        return Err(Stopped::Interrupted);
    }
    times.written = lap("report written", times.requested);
    staging.commit().map_err(Stopped::Swap)?;
    times.swapped = lap("report in place", times.written);
    Ok(Finished {
        outcome,
        summary,
        times,
    })
}

/// The optional studies, in order (sweep, stability map, accuracy on request), each stage's
/// end noted in `times`.
fn measure(
    plan: &Plan,
    outcome: &Outcome,
    cases_dir: &Path,
    studies: &Studies,
    progress: bool,
    lap: &dyn Fn(&str, f64) -> f64,
    times: &mut StageTimes,
) -> Result<Measured, Stopped> {
    let engines: Vec<&dyn Engine> = plan.engines.iter().map(|e| e.as_ref()).collect();
    let seeds = crate::case::discover(cases_dir).unwrap_or_default();
    let is_seed = |s: &Scene| {
        seeds
            .iter()
            .any(|p| p.file_stem().is_some_and(|f| *f == *s.id))
    };
    let subplan = |keep: &dyn Fn(&Scene) -> bool| Plan {
        cases: plan.cases.iter().filter(|s| keep(s)).cloned().collect(),
        engines: Vec::new(),
        settings: plan.settings,
    };
    let seed_plan = subplan(&is_seed);
    let sweep_plan = subplan(&|s: &Scene| is_seed(s) || s.sweep);
    let grid = sweep::Grid {
        repeat: studies.sweep.unwrap_or(1),
        ..sweep::Grid::default()
    };
    let mut sweeps = match studies.sweep {
        Some(_) => work_precision::measure(&sweep_plan, outcome, &engines, &grid, progress),
        None => Vec::new(),
    };
    times.swept = if studies.sweep.is_some() {
        lap("sweep", times.attributed)
    } else {
        lap("", times.attributed)
    };
    stop_if_interrupted()?;
    work_precision::reach(&sweep_plan, outcome, &engines, &mut sweeps, &grid, progress);
    times.reached = lap(
        if studies.sweep.is_some() {
            "time to accuracy checked"
        } else {
            ""
        },
        times.swept,
    );
    stop_if_interrupted()?;
    let maps = if studies.stability {
        comparison::stability::measure(plan, outcome, &engines, progress)
    } else {
        Default::default()
    };
    times.mapped = lap(
        if studies.stability {
            "stability map"
        } else {
            ""
        },
        times.reached,
    );
    stop_if_interrupted()?;
    let requests = if studies.on_request {
        comparison::on_request::measure(&seed_plan, outcome, &engines, progress)
    } else {
        Vec::new()
    };
    times.requested = lap(
        if studies.on_request {
            "accuracy on request"
        } else {
            ""
        },
        times.mapped,
    );
    stop_if_interrupted()?;
    Ok(Measured {
        sweeps,
        maps,
        requests,
    })
}

/// Seconds since `started`; with `lines` (progress asked for, standard error not a terminal,
/// so no bar shows), a line on standard error naming the `stage` that just ended (none where
/// it is empty: a study that did not run) and how long it took since `previous`.
fn lap(started: Instant, stage: &str, previous: f64, lines: bool) -> f64 {
    let now = seconds_since(started);
    if lines && !stage.is_empty() {
        let _ = std::io::Write::write_fmt(
            &mut std::io::stderr(),
            format_args!(
                "crosscheck: {stage}: {:.1} s (at {now:.1} s)\n",
                now - previous
            ),
        );
    }
    now
}

impl StageTimes {
    /// How long each part of the run took, seconds, in order, for the report: the parts that
    /// ran.
    pub fn parts(&self, studies: &Studies) -> Vec<(&'static str, f64)> {
        let mut parts = vec![
            ("load and check", self.loaded),
            ("jobs", self.ran - self.loaded),
            ("discrepancy budget", self.budgeted - self.ran),
            ("invariance controls", self.invariant - self.budgeted),
            ("controls", self.attributed - self.invariant),
        ];
        if studies.sweep.is_some() {
            parts.push(("sweep", self.swept - self.attributed));
            parts.push(("time to accuracy checked", self.reached - self.swept));
        }
        if studies.stability {
            parts.push(("stability map", self.mapped - self.reached));
        }
        if studies.on_request {
            parts.push(("accuracy on request", self.requested - self.mapped));
        }
        parts
    }
}

/// The exact solutions (`analytic`, `reference`) of `cases`, which every study's runs are
/// measured against.
pub fn exact_solutions(cases: Vec<Scene>) -> (Plan, Outcome) {
    let plan = Plan {
        cases,
        engines: ["analytic", "reference"]
            .iter()
            .filter_map(|n| crate::run::registry::named(n))
            .collect(),
        settings: RunSettings::default(),
    };
    let outcome = run::execute(&plan, false);
    (plan, outcome)
}

/// A study on its own (`crosscheck sweep`, `crosscheck stability`): the exact solutions of
/// `cases`, the study's runs measured against them (`measure`), its files written into
/// `staging` (`write`) and swapped into place. Stops (the previous files unchanged) when a
/// signal asks it to or a file cannot be written.
pub fn study<T>(
    cases: Vec<Scene>,
    staging: Staging,
    measure: impl FnOnce(&Plan, &Outcome) -> T,
    write: impl FnOnce(&Path, &Plan, &T) -> Result<(), DataError>,
) -> Result<T, Stopped> {
    let (plan, outcome) = exact_solutions(cases);
    stop_if_interrupted()?;
    let measured = measure(&plan, &outcome);
    stop_if_interrupted()?;
    put_in_place(staging, |dir| write(dir, &plan, &measured))?;
    Ok(measured)
}

/// Write a study's files into the staging directory with `write`, then swap them into place;
/// on failure the previous files stay.
pub fn put_in_place(
    staging: Staging,
    write: impl FnOnce(&Path) -> Result<(), DataError>,
) -> Result<(), Stopped> {
    write(staging.path()).map_err(written_or_interrupted)?;
    if interrupt::checkpoint("swap").is_err() {
        return Err(Stopped::Interrupted);
    }
    staging.commit().map_err(Stopped::Swap)
}

/// A write that failed because a signal asked it to stop is an interruption.
fn written_or_interrupted(e: DataError) -> Stopped {
    match e {
        DataError::Interrupted => Stopped::Interrupted,
        e => Stopped::Write(e),
    }
}

/// `Err(Interrupted)` once a signal has asked the run to stop.
fn stop_if_interrupted() -> Result<(), Stopped> {
    if interrupt::requested() {
        Err(Stopped::Interrupted)
    } else {
        Ok(())
    }
}

/// Seconds since `started`.
fn seconds_since(started: Instant) -> f64 {
    started.elapsed().as_secs_f64()
}

/// What `crosscheck judge` was given.
#[derive(Debug, Clone)]
pub struct JudgeRequest {
    /// Case id or path.
    pub case: String,
    /// Their CSV.
    pub file: std::path::PathBuf,
    /// `OURS=THEIRS` column maps.
    pub columns: Vec<String>,
    /// Their time column.
    pub time: String,
    /// `COLUMN=FACTOR` conversions.
    pub scales: Vec<String>,
    /// The exact solution's engine: `reference` or `analytic`.
    pub against: &'static str,
    /// Largest error over the peak (`None`: the tightest the case declares).
    pub tolerance: Option<f64>,
}

/// `OURS=THEIRS` pairs into a map; `what` names the option in an error.
fn pairs(items: &[String], what: &str) -> Result<BTreeMap<String, String>, String> {
    items
        .iter()
        .map(|item| match item.split_once('=') {
            Some((a, b)) if !a.trim().is_empty() && !b.trim().is_empty() => {
                Ok((a.trim().to_string(), b.trim().to_string()))
            }
            _ => Err(format!("--{what} {item}: expected NAME=VALUE")),
        })
        .collect()
}

/// The judgement's inputs from the request: the case, the mapping of their CSV, the tolerance.
fn judge_inputs(
    request: &JudgeRequest,
    dir: &Path,
) -> Result<(Scene, comparison::judge::Mapping, f64), String> {
    let path = crate::case::resolve(&request.case, dir).map_err(|e| e.to_string())?;
    let scene = crate::case::load_checked(&path, &run::check_scene).map_err(|e| e.render())?;
    let mut scales = BTreeMap::new();
    for (column, factor) in pairs(&request.scales, "scale")? {
        let f: f64 = factor
            .parse()
            .ok()
            .filter(|f: &f64| f.is_finite() && *f != 0.0)
            .ok_or_else(|| format!("--scale {column}={factor}: not a finite, non-zero number"))?;
        scales.insert(column, f);
    }
    let mapping = comparison::judge::Mapping {
        time: Some(request.time.clone()),
        columns: pairs(&request.columns, "column")?,
        scales,
    };
    comparison::judge::check_options(&scene, &mapping).map_err(|e| e.to_string())?;
    let tolerance = match request.tolerance {
        Some(t) if t.is_finite() && t > 0.0 => t,
        Some(t) => return Err(format!("--tolerance {t}: not a positive number")),
        None => comparison::verdict::tightest(&scene)
            .ok_or_else(|| format!("{} declares no tolerance: give --tolerance", scene.id))?,
    };
    Ok((scene, mapping, tolerance))
}

/// Judge their history against the case's exact solution: the markdown to print and whether
/// it passed; `Err` when the input is unusable (the message says why and where).
pub fn judge(request: &JudgeRequest, dir: &Path) -> Result<(String, bool), String> {
    use comparison::judge;
    let (scene, mapping, tolerance) = judge_inputs(request, dir)?;
    let file = &request.file;
    let text = std::fs::read_to_string(file)
        .map_err(|e| format!("{}: cannot read: {e}", file.display()))?;
    let external = judge::read(&scene, &text, file, &mapping).map_err(|e| e.to_string())?;
    let engine = crate::run::registry::named(request.against)
        .ok_or_else(|| format!("no exact solution named {}", request.against))?;
    let exact = engine
        .run(&scene, &RunSettings::default())
        .map_err(|e| format!("{} cannot solve {}: {e}", request.against, scene.id))?
        .history;
    let (candidate, resampling) =
        judge::resample(&external, &exact, file).map_err(|e| e.to_string())?;
    let comparison = comparison::compare(&scene, &exact, &candidate);
    let text = report::judge::render(
        &scene.id,
        request.against,
        &external,
        &resampling,
        &comparison,
        tolerance,
    );
    let pass = comparison::verdict::meets(
        crate::run::Status::Ok,
        comparison.worst_max,
        Some(tolerance),
    );
    Ok((text, pass == Some(true)))
}

/// Compare the reports `base` and `new` ([`report::regression`]): the markdown to print and
/// whether a tier failed (the machine tier not counted when `physics_only`), the JUnit XML
/// written to `junit` when given; `Err` when they cannot be compared.
pub fn compare(
    base: &Path,
    new: &Path,
    threshold: f64,
    physics_only: bool,
    junit: Option<&Path>,
) -> Result<(String, bool), String> {
    use report::regression;
    let (a, b) = (
        regression::read(base).map_err(|e| e.to_string())?,
        regression::read(new).map_err(|e| e.to_string())?,
    );
    let compared = regression::compare(&a, &b).map_err(|e| e.to_string())?;
    if let Some(why) = compared.machine_tier_missing().filter(|_| !physics_only) {
        return Err(format!(
            "{why}; `crosscheck compare --physics-only` compares the verdicts alone"
        ));
    }
    let judged = compared.changes.iter().any(|c| c.physics.is_some());
    if physics_only && !judged && compared.broken.is_empty() {
        return Err(
            "--physics-only: no cell has a verdict in both reports (no exact solution \
                    judged it), so nothing was compared"
                .to_string(),
        );
    }
    if let Some(path) = junit {
        let xml = regression::junit(&compared, threshold, physics_only);
        report::data::write_atomic(path, xml.as_bytes()).map_err(|e| e.to_string())?;
    }
    let drifted = compared.changes.iter().any(|c| c.drifted(threshold));
    let failed = compared
        .changes
        .iter()
        .any(regression::Change::newly_failing)
        || !compared.broken.is_empty()
        || (!physics_only && (drifted || !compared.incomparable.is_empty()));
    Ok((
        regression::markdown(base, new, &compared, threshold),
        failed,
    ))
}

/// One shard of a run split across machines: `run --partition k/n` (nextest's convention:
/// shard `k` of `n`, from 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Partition {
    /// This shard, 1 ≤ k ≤ n.
    pub k: usize,
    /// How many shards.
    pub n: usize,
}

impl std::str::FromStr for Partition {
    type Err = String;

    /// `k/n` (or nextest's `count:k/n`), 1 ≤ k ≤ n.
    fn from_str(s: &str) -> Result<Self, String> {
        let text = s.strip_prefix("count:").unwrap_or(s);
        let parsed = text
            .split_once('/')
            .and_then(|(k, n)| Some((k.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((k, n)) if 1 <= k && k <= n => Ok(Partition { k, n }),
            _ => Err(format!("`{s}`: expected k/n with 1 ≤ k ≤ n (e.g. 2/4)")),
        }
    }
}

/// The share of `cases` (sorted by id) that shard `part` runs. Cases the report measures
/// together stay together: equivalent cases (the same closed form) form a group, since the
/// sweep checks a group's cost on its first case only and the summary measures each member
/// against that one. The groups, in the order of their first case, are dealt out round-robin;
/// the closed forms that find them are computed here (they are cheap), whatever the shard.
pub fn partition(cases: Vec<Scene>, part: Partition) -> Vec<Scene> {
    let plan = Plan {
        cases,
        engines: run::registry::named(comparison::CLOSED_FORM)
            .into_iter()
            .collect(),
        settings: RunSettings::default(),
    };
    let outcome = run::execute(&plan, false);
    let closed = |case: &str, engine: &str| outcome.history(case, engine).cloned();
    let pairs = comparison::equivalence::measure(&plan.cases, &[], closed);
    let index = |id: &str| plan.cases.iter().position(|s| s.id == id);
    // Each case's group: the first case (by id) it is joined to through the pairs.
    let mut group: Vec<usize> = (0..plan.cases.len()).collect();
    let root = |group: &[usize], mut i: usize| {
        while group[i] != i {
            i = group[i];
        }
        i
    };
    for e in &pairs {
        if let (Some(a), Some(b)) = (index(&e.case), index(&e.same_as)) {
            let (ra, rb) = (root(&group, a), root(&group, b));
            group[ra.max(rb)] = ra.min(rb);
        }
    }
    let roots: Vec<usize> = (0..plan.cases.len()).map(|i| root(&group, i)).collect();
    let mut firsts: Vec<usize> = roots.clone();
    firsts.sort_unstable();
    firsts.dedup();
    let shard_of = |i: usize| {
        let g = firsts.iter().position(|f| *f == roots[i]).unwrap_or(0);
        g % part.n + 1
    };
    plan.cases
        .into_iter()
        .enumerate()
        .filter(|(i, _)| shard_of(*i) == part.k)
        .map(|(_, s)| s)
        .collect()
}

/// Merge the shards' reports into `staging` (its carried entries removed first: the merged
/// report is the shards' alone) and put it in place.
pub fn merge(
    shards: &[std::path::PathBuf],
    staging: Staging,
) -> Result<Summary, report::merge::MergeError> {
    use report::merge::MergeError;
    for entry in report::ENTRIES {
        let path = staging.path().join(entry);
        let removed = match std::fs::symlink_metadata(&path) {
            Ok(m) if m.is_dir() => std::fs::remove_dir_all(&path),
            Ok(_) => std::fs::remove_file(&path),
            Err(_) => Ok(()),
        };
        removed.map_err(|source| DataError::Io { path, source })?;
    }
    let summary = report::merge::merge(shards, staging.path(), staging.target())?;
    if interrupt::checkpoint("swap").is_err() {
        return Err(MergeError::Data(DataError::Interrupted));
    }
    let target = staging.target().to_path_buf();
    staging.commit().map_err(|source| DataError::Io {
        path: target,
        source,
    })?;
    Ok(summary)
}
