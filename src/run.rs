//! Orchestration: load cases, run every (case × engine) job in parallel, write the CSVs.
//!
//! The binary is a thin shell over this module; tests and other tools can drive it directly:
//!
//! ```no_run
//! use crosscheck::{case, engines, run};
//! let cases = run::load_cases(&[], &case::cases_dir()).expect("valid cases");
//! let plan = run::Plan {
//!     cases,
//!     engines: engines::all(),
//!     settings: Default::default(),
//!     out: "report".into(),
//! };
//! let outcome = run::execute(&plan, false);
//! print!("{}", outcome.table());
//! ```

use crate::case::{self, CaseError};
use crate::engines::explicit::ExplicitEngine;
use crate::engines::{self, Engine, History, RunInfo, RunSettings};
use crate::report::data;
use crate::scene::{IncrementRule, Scene, SceneError};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to run: every case with every engine, under one set of setting overrides.
pub struct Plan {
    /// Validated cases, in report order.
    pub cases: Vec<Scene>,
    /// Engines, in report order.
    pub engines: Vec<Box<dyn Engine>>,
    /// Overrides applied to every job.
    pub settings: RunSettings,
    /// Output directory; CSVs go to `out/data/<case-id>/<engine>.csv`.
    pub out: PathBuf,
}

impl Plan {
    /// Number of jobs (cases × engines).
    pub fn job_count(&self) -> usize {
        self.cases.len() * self.engines.len()
    }
}

/// A job that produced a history and wrote it.
#[derive(Debug, Clone)]
pub struct JobSuccess {
    /// What the run used and cost, as the engine reported it.
    pub info: RunInfo,
    /// The CSV written.
    pub csv: PathBuf,
    /// The history itself (for the comparison and the report).
    pub history: History,
}

/// The result of one (case, engine) job.
#[derive(Debug, Clone)]
pub struct JobResult {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// Wall-clock seconds of the whole job as the harness measured it (engine run, checks and
    /// the CSV write; available for failed jobs too).
    pub elapsed: f64,
    /// The run and its CSV, or why there is none.
    pub result: Result<JobSuccess, String>,
}

impl JobResult {
    /// Whether the job produced and wrote its history.
    pub fn is_ok(&self) -> bool {
        self.result.is_ok()
    }
}

/// Every job's result, ordered by case (plan order), then engine (plan order).
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// One entry per job.
    pub jobs: Vec<JobResult>,
}

impl Outcome {
    /// Number of failed jobs.
    pub fn failures(&self) -> usize {
        self.jobs.iter().filter(|j| !j.is_ok()).count()
    }

    /// Whether every job succeeded.
    pub fn all_ok(&self) -> bool {
        self.failures() == 0
    }

    /// A plain-text table, one line per job: case, engine, increment, steps, wall time, status.
    pub fn table(&self) -> String {
        let header = ["case", "engine", "increment", "steps", "wall", "status"].map(String::from);
        let mut rows = vec![header];
        for j in &self.jobs {
            let row = match &j.result {
                Ok(s) => [
                    j.case.clone(),
                    j.engine.clone(),
                    format!("{:.4e}", s.info.increment),
                    s.info.steps.to_string(),
                    format!("{:.3} s", s.info.wall_seconds),
                    "ok".to_string(),
                ],
                Err(e) => [
                    j.case.clone(),
                    j.engine.clone(),
                    "-".to_string(),
                    "-".to_string(),
                    format!("{:.3} s", j.elapsed),
                    format!("FAILED: {e}"),
                ],
            };
            rows.push(row);
        }
        let mut widths = [0usize; 6];
        for r in &rows {
            for (w, cell) in widths.iter_mut().zip(r) {
                *w = (*w).max(cell.chars().count());
            }
        }
        let mut s = String::new();
        for r in &rows {
            let mut line = String::new();
            for (k, cell) in r.iter().enumerate() {
                if k > 0 {
                    line.push_str("  ");
                }
                // Numbers right-aligned, text left-aligned.
                let pad = widths[k] - cell.chars().count();
                if (2..=4).contains(&k) {
                    line.push_str(&" ".repeat(pad));
                    line.push_str(cell);
                } else {
                    line.push_str(cell);
                    line.push_str(&" ".repeat(pad));
                }
            }
            s.push_str(line.trim_end());
            s.push('\n');
        }
        s
    }
}

/// Run every job of `plan` in parallel and write each successful history as CSV.
///
/// An engine error (or panic), a history that breaks the output contract, or a failed write
/// fails that job only; the others still run. A progress bar on stderr ticks once per job; it
/// is hidden when `progress` is false or stderr is not a terminal. Results come back in plan
/// order (case, then engine) whatever the thread scheduling.
pub fn execute(plan: &Plan, progress: bool) -> Outcome {
    let jobs: Vec<(&Scene, &dyn Engine)> = plan
        .cases
        .iter()
        .flat_map(|c| plan.engines.iter().map(move |e| (c, e.as_ref())))
        .collect();
    let bar = if progress && std::io::stderr().is_terminal() {
        ProgressBar::new(jobs.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("[{elapsed_precise}] {bar:30} {pos}/{len} {msg}")
            .expect("valid progress template")
            .progress_chars("=> "),
    );
    let results = jobs
        .par_iter()
        .map(|&(scene, engine)| {
            let result = run_job(scene, engine, &plan.settings, &plan.out);
            bar.set_message(format!("{}/{}", scene.id, engine.name()));
            bar.inc(1);
            result
        })
        .collect();
    bar.finish_and_clear();
    Outcome { jobs: results }
}

/// Run one job: the engine, the contract check, the CSV write.
fn run_job(scene: &Scene, engine: &dyn Engine, settings: &RunSettings, out: &Path) -> JobResult {
    let start = Instant::now();
    let name = engine.name().to_string();
    let result = panic::catch_unwind(AssertUnwindSafe(|| engine.run(scene, settings)))
        .map_err(|payload| format!("engine panicked: {}", panic_message(payload.as_ref())))
        .and_then(|r| r.map_err(|e| e.to_string()))
        .and_then(|output| {
            check_contract(scene, &output.history)
                .map_err(|e| format!("history breaks the output contract: {e}"))?;
            if crate::report::staging::interrupted() {
                return Err("interrupted before its CSV was written".to_string());
            }
            let csv = data::write_history(out, &scene.id, &name, &output.history)
                .map_err(|e| format!("cannot write the CSV: {e}"))?;
            Ok(JobSuccess {
                info: output.info,
                csv,
                history: output.history,
            })
        })
        .map_err(|e| {
            if data::csv_path(out, &scene.id, &name).exists() {
                format!("{e} (a CSV from an earlier run is still in place)")
            } else {
                e
            }
        });
    JobResult {
        case: scene.id.clone(),
        engine: name,
        elapsed: start.elapsed().as_secs_f64(),
        result,
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".to_string()
    }
}

/// Check a history against the output contract for `scene`: header `t` then the family's
/// contract columns; every row as long as the header; at least 200 rows sampling the duration
/// uniformly, first t = 0, last t = the duration.
pub fn check_contract(scene: &Scene, history: &History) -> Result<(), String> {
    let want: Vec<&str> = std::iter::once("t")
        .chain(scene.family.contract_columns().iter().copied())
        .collect();
    let got: Vec<&str> = history.columns.iter().map(String::as_str).collect();
    if !got.starts_with(&want) {
        return Err(format!(
            "columns must start with {}; got {}",
            want.join(","),
            got.join(",")
        ));
    }
    if let Some((i, r)) = history
        .rows
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != history.columns.len())
    {
        return Err(format!(
            "row {i} has {} values for {} columns",
            r.len(),
            history.columns.len()
        ));
    }
    let n = history.rows.len();
    if n < 200 {
        return Err(format!("{n} rows; at least 200 are needed"));
    }
    let duration = scene.duration();
    let tol = 1e-9 * duration;
    for (i, r) in history.rows.iter().enumerate() {
        let expected = duration * i as f64 / (n - 1) as f64;
        let on_grid = (r[0] - expected).abs() <= tol; // false for NaN too
        if !on_grid {
            return Err(format!(
                "row {i} has t = {:e}; uniform sampling of 0..{duration:e} over {n} rows needs {expected:e}",
                r[0]
            ));
        }
    }
    Ok(())
}

/// Checks that need the engines: tolerance names must be engine names, and a given increment
/// must not exceed the stable one.
pub fn check_scene(scene: &Scene) -> Result<(), SceneError> {
    let names = engine_names();
    for engine in scene.tolerances.keys() {
        if !names.contains(engine) {
            return Err(SceneError {
                field: format!("tolerances.{engine}"),
                message: format!(
                    "`{engine}` is not an engine; valid names: {}",
                    names.join(", ")
                ),
            });
        }
    }
    check_increment(scene)
}

/// A case's given time increment must not exceed the stable increment of either explicit
/// kinematics (finite rotation adds geometric stiffness, so the two can differ).
pub fn check_increment(scene: &Scene) -> Result<(), SceneError> {
    let IncrementRule::Given(h) = scene.settings.increment else {
        return Ok(());
    };
    let settings = RunSettings::default();
    let stable = [ExplicitEngine::finite(), ExplicitEngine::small()]
        .iter()
        .filter_map(|e| e.stable_increment(scene, &settings))
        .min_by(|a, b| a.increment.total_cmp(&b.increment));
    match stable {
        Some(s) if h > s.increment * (1.0 + 1e-12) => Err(SceneError {
            field: "time.increment".into(),
            message: format!(
                "{h:e} is above this scene's stable increment {:e} (highest frequency {:.4e} rad/s, penalty included); use at most that, or give `safety` instead",
                s.increment, s.omega_max
            ),
        }),
        _ => Ok(()),
    }
}

/// An engine name that matches no engine.
#[derive(Debug, Clone, thiserror::Error)]
#[error("unknown engine `{name}`; valid engines: {}", .valid.join(", "))]
pub struct UnknownEngine {
    /// The name given.
    pub name: String,
    /// Every valid name, in report order.
    pub valid: Vec<String>,
}

/// Every engine name, in report order.
pub fn engine_names() -> Vec<String> {
    engines::all()
        .iter()
        .map(|e| e.name().to_string())
        .collect()
}

/// Engines by name, in the order given (duplicates dropped); every engine when `names` is empty.
pub fn select_engines(names: &[String]) -> Result<Vec<Box<dyn Engine>>, UnknownEngine> {
    if names.is_empty() {
        return Ok(engines::all());
    }
    let mut out: Vec<Box<dyn Engine>> = Vec::new();
    for name in names {
        let name = name.trim();
        if out.iter().any(|e| e.name() == name) {
            continue;
        }
        match engines::named(name) {
            Some(e) => out.push(e),
            None => {
                return Err(UnknownEngine {
                    name: name.to_string(),
                    valid: engine_names(),
                });
            }
        }
    }
    Ok(out)
}

/// Why the cases of a run could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// A case argument that is not a case, or a case file that is not valid.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// The case directory could not be listed.
    #[error("{path}: cannot list cases: {source}")]
    Directory {
        /// The directory.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// Two different files with the same case id (their CSVs would collide).
    #[error("case id `{id}` is given by both {first} and {second}")]
    DuplicateId {
        /// The id.
        id: String,
        /// The first file.
        first: PathBuf,
        /// The second file.
        second: PathBuf,
    },
    /// No case to run.
    #[error("no case files (*.toml) in {0}")]
    NoCases(PathBuf),
}

/// Resolve and validate the cases named by `args` (ids from `dir` or paths to `.toml` files),
/// or every case in `dir` when `args` is empty. Every case is loaded before returning, so the
/// caller sees every problem at once; a case given twice is kept once. The scenes come back
/// sorted by id (the report order).
pub fn load_cases(args: &[String], dir: &Path) -> Result<Vec<Scene>, Vec<LoadError>> {
    let paths: Vec<Result<PathBuf, LoadError>> = if args.is_empty() {
        match case::discover(dir) {
            Ok(v) if v.is_empty() => return Err(vec![LoadError::NoCases(dir.to_path_buf())]),
            Ok(v) => v.into_iter().map(Ok).collect(),
            Err(source) => {
                return Err(vec![LoadError::Directory {
                    path: dir.to_path_buf(),
                    source,
                }]);
            }
        }
    } else {
        args.iter()
            .map(|a| case::resolve(a, dir).map_err(LoadError::from))
            .collect()
    };
    let mut scenes: Vec<(PathBuf, Scene)> = Vec::new();
    let mut errors = Vec::new();
    for p in paths {
        let path = match p {
            Ok(p) => p,
            Err(e) => {
                errors.push(e);
                continue;
            }
        };
        let scene = match case::load_checked(&path, &check_scene) {
            Ok(s) => s,
            Err(e) => {
                errors.push(e.into());
                continue;
            }
        };
        let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
        match scenes.iter().find(|(_, s)| s.id == scene.id) {
            Some((first, _)) if *first == canonical => {}
            Some((first, _)) => errors.push(LoadError::DuplicateId {
                id: scene.id.clone(),
                first: first.clone(),
                second: canonical,
            }),
            None => scenes.push((canonical, scene)),
        }
    }
    if errors.is_empty() {
        scenes.sort_by(|a, b| a.1.id.cmp(&b.1.id));
        Ok(scenes.into_iter().map(|(_, s)| s).collect())
    } else {
        Err(errors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::{EngineError, RunOutput};
    use std::collections::BTreeMap;

    const CASE: &str = r#"
id = "tiny"
title = "a grounded spring-mass oscillator"
family = "springs"
dimension = 2

[time]
increment = 1.0e-3

[output]
rows = 201
columns = [
  { name = "u_end", displacement = "end", direction = [1.0, 0.0] },
  { name = "u_mid", zero = "no middle mass" },
  { name = "v_end", velocity = "end", direction = [1.0, 0.0] },
  { name = "v_mid", zero = "no middle mass" },
]

[[nodes]]
id = "end"
at = [0.0, 0.0]

[[masses]]
node = "end"
mass = 1.0

[[springs]]
kind = "grounded"
nodes = ["end"]
dof = "ux"
stiffness = 1.0

[[steps]]
kind = "dynamic"
duration = 1.0
hold = [{ node = "end", dofs = ["uy"] }]
"#;

    fn scene(id: &str) -> Scene {
        let text = CASE.replace("\"tiny\"", &format!("\"{id}\""));
        case::parse(&text, Path::new(&format!("{id}.toml"))).unwrap()
    }

    /// Writes a cosine for `u_end`; fails, panics or breaks the contract on request.
    struct Fake {
        name: &'static str,
        mode: &'static str,
    }

    impl Engine for Fake {
        fn name(&self) -> &str {
            self.name
        }
        fn run(&self, scene: &Scene, _: &RunSettings) -> Result<RunOutput, EngineError> {
            match self.mode {
                "error" => return Err(EngineError::Failed("boom".into())),
                "panic" => panic!("kaboom"),
                _ => {}
            }
            let mut times = scene.output_times();
            if self.mode == "short" {
                times.truncate(10);
            }
            let columns = ["t", "u_end", "u_mid", "v_end", "v_mid"].map(String::from);
            let rows = times
                .iter()
                .map(|&t| vec![t, t.cos(), 0.0, -t.sin(), 0.0])
                .collect();
            Ok(RunOutput {
                engine: self.name.into(),
                history: History {
                    columns: columns.to_vec(),
                    rows,
                },
                info: RunInfo {
                    increment: 1e-3,
                    steps: 1000,
                    stable_increment: Some(2.0),
                    penalty_stiffness: None,
                    wall_seconds: 0.0,
                    counters: BTreeMap::new(),
                    measures: BTreeMap::new(),
                },
            })
        }
    }

    #[test]
    fn failures_are_isolated_and_order_is_deterministic() {
        let out = tempfile::tempdir().unwrap();
        let plan = Plan {
            cases: vec![scene("b_case"), scene("a_case")],
            engines: vec![
                Box::new(Fake {
                    name: "good",
                    mode: "ok",
                }),
                Box::new(Fake {
                    name: "bad",
                    mode: "error",
                }),
                Box::new(Fake {
                    name: "wild",
                    mode: "panic",
                }),
                Box::new(Fake {
                    name: "short",
                    mode: "short",
                }),
            ],
            settings: RunSettings::default(),
            out: out.path().to_path_buf(),
        };
        let outcome = execute(&plan, false);
        let order: Vec<(&str, &str)> = outcome
            .jobs
            .iter()
            .map(|j| (j.case.as_str(), j.engine.as_str()))
            .collect();
        let expected: Vec<(&str, &str)> = ["b_case", "a_case"]
            .iter()
            .flat_map(|c| ["good", "bad", "wild", "short"].map(|e| (*c, e)))
            .collect();
        assert_eq!(order, expected);
        assert_eq!(outcome.failures(), 6);
        for j in &outcome.jobs {
            let csv = data::csv_path(out.path(), &j.case, &j.engine);
            assert_eq!(csv.exists(), j.engine == "good", "{j:?}");
            match j.engine.as_str() {
                "good" => {
                    let h = data::read_history(&csv).unwrap();
                    assert_eq!(h.rows.len(), 201);
                    assert_eq!(j.result.as_ref().unwrap().csv, csv);
                }
                "bad" => assert_eq!(j.result.as_ref().unwrap_err(), "boom"),
                "wild" => assert!(j.result.as_ref().unwrap_err().contains("kaboom")),
                _ => assert!(j.result.as_ref().unwrap_err().contains("10 rows")),
            }
        }
        let table = outcome.table();
        assert_eq!(table.lines().count(), 9);
        assert!(table.contains("FAILED: boom"), "{table}");
    }

    #[test]
    fn unknown_engine_lists_valid_names() {
        let err = select_engines(&["nope".into()]).err().unwrap().to_string();
        for name in engine_names() {
            assert!(err.contains(&name), "{err}");
        }
        let two = select_engines(&["explicit".into(), "explicit".into()]).unwrap();
        assert_eq!(two.len(), 1);
    }

    #[test]
    fn load_cases_reports_every_problem() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("tiny.toml"), CASE).unwrap();
        std::fs::write(
            dir.path().join("broken.toml"),
            CASE.replace("\"tiny\"", "\"broken\"")
                .replace("stiffness = 1.0", "stiffness = -1.0"),
        )
        .unwrap();
        let args: Vec<String> = ["tiny", "broken", "missing", "tiny"]
            .map(String::from)
            .into();
        let errors = load_cases(&args, dir.path()).unwrap_err();
        assert_eq!(errors.len(), 2, "{errors:?}");
        assert!(errors[0].to_string().contains("springs[0].stiffness"));
        assert!(errors[1].to_string().contains("no case `missing`"));
        let ok = load_cases(&["tiny".into(), "tiny".into()], dir.path()).unwrap();
        assert_eq!(ok.len(), 1);
    }
}
