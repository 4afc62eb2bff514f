//! Running: every (case × engine) job in parallel, each with the settings its engine needs.
//!
//! This layer returns data (histories, what each run used and cost, failures) and writes
//! nothing; the report writes the files. The binary is a thin shell over it:
//!
//! ```no_run
//! use crosscheck::{case, run};
//! let cases = run::load_cases(&[], &case::cases_dir()).expect("valid cases");
//! let plan = run::Plan {
//!     cases,
//!     engines: run::registry::all(),
//!     settings: Default::default(),
//! };
//! let outcome = run::execute(&plan, false);
//! print!("{}", outcome.table());
//! ```
//!
//! - [`load`]: resolve and validate the cases (with the checks that need an engine);
//! - [`matching`]: what "matched settings" means: the settings one engine's job gets from
//!   another engine's rules (rapier's increment is the explicit engine's);
//! - [`refinement`]: a job's engine rerun at other increments and penalties (for the
//!   discrepancy budget the comparison takes);
//! - [`budget`]: each job's increments, rows and memory estimated and bounded before it runs;
//! - [`controls`]: a job rerun with one suspected cause of its discrepancy varied (for the
//!   comparison's attribution of causes);
//! - [`floor`]: the arithmetic floor of one increment, the simplest seed scene's recurrence
//!   written out by hand (for the benchmarks);
//! - [`schedule`]: tasks of unequal length on a few threads, longest first, their results in
//!   order (the jobs, and the studies' reruns);
//! - this module: the jobs, run in parallel, their results in plan order.

pub mod budget;
pub mod controls;

/// The engine trait, as the studies take engines: the comparison reaches engines only through
/// this layer.
pub use crate::engines::{Engine, RunSettings};
pub mod element_cost;
pub mod floor;
pub mod load;
pub mod matching;
pub mod on_request;
pub mod progress;
pub mod refinement;
pub mod registry;
pub mod scaling;
pub mod schedule;
pub mod stability;
pub mod sweep;

pub use load::{
    LoadError, UnknownEngine, check_increment, check_overrides, check_scene, check_scene_for,
    engine_names, load_cases, load_cases_for, select_among, select_engines,
};

use crate::contract::{self, History};
use crate::engines::{EngineError, RunInfo, RunOutput};
use crate::scene::{IncrementRule, Scene};
pub use progress::Progress;
use std::panic::{self, AssertUnwindSafe};
use std::time::Instant;

/// What to run: every case with every engine, under one set of setting overrides.
pub struct Plan {
    /// Validated cases, in report order.
    pub cases: Vec<Scene>,
    /// Engines, in report order.
    pub engines: Vec<Box<dyn Engine>>,
    /// Overrides applied to every job.
    pub settings: RunSettings,
}

impl Plan {
    /// Number of jobs (cases × engines).
    pub fn job_count(&self) -> usize {
        self.cases.len() * self.engines.len()
    }
}

/// A job that produced a history that meets the output contract.
#[derive(Debug, Clone)]
pub struct JobSuccess {
    /// What the run used and cost, as the engine reported it.
    pub info: RunInfo,
    /// The history (for the CSV, the comparison and the report).
    pub history: History,
}

/// The result of one (case, engine) job.
#[derive(Debug, Clone)]
pub struct JobResult {
    /// Case id.
    pub case: String,
    /// Engine name.
    pub engine: String,
    /// Wall-clock seconds of the whole job as the harness measured it (settings, engine run,
    /// contract check; available for failed jobs too).
    pub elapsed: f64,
    /// The run, or why there is none (the engine's words: the reason it does not apply, the
    /// evidence of its instability, or its failure).
    pub result: Result<JobSuccess, String>,
    /// How the run came out, typed: what every verdict reads (never the message).
    pub status: Status,
}

/// How a run came out, as the engine or the harness established it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// It produced a finite history that meets the output contract.
    Ok,
    /// The engine does not model what the scene asks for ([`EngineError::Unsupported`]): not
    /// a failure, and not counted as one.
    NotApplicable,
    /// Its state grew without bound: the engine stopped it as unstable
    /// ([`EngineError::Unstable`]), or its history holds a non-finite value.
    Unstable,
    /// Any other failure: an error mid-run, a panic, a history that breaks the contract.
    Failed,
}

impl Status {
    /// The status of an engine's error.
    pub fn of_error(e: &EngineError) -> Status {
        match e {
            EngineError::Unsupported(_) => Status::NotApplicable,
            EngineError::Unstable(_) => Status::Unstable,
            EngineError::UnstableIncrement { .. } | EngineError::Failed(_) => Status::Failed,
        }
    }

    /// Its name in the report's files.
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::NotApplicable => "not applicable",
            Status::Unstable => "unstable",
            Status::Failed => "failed",
        }
    }

    /// Whether the engine applies to the scene (it ran, or tried to).
    pub fn applicable(self) -> bool {
        self != Status::NotApplicable
    }
}

impl JobResult {
    /// Whether the job produced its history.
    pub fn is_ok(&self) -> bool {
        self.result.is_ok()
    }

    /// Whether the engine applies to the scene (its refusal is not a failure).
    pub fn applicable(&self) -> bool {
        self.status.applicable()
    }
}

/// Every job's result, ordered by case (plan order), then engine (plan order).
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// One entry per job.
    pub jobs: Vec<JobResult>,
}

impl Outcome {
    /// The history a job produced, where it succeeded.
    pub fn history(&self, case: &str, engine: &str) -> Option<&History> {
        self.jobs
            .iter()
            .find(|j| j.case == case && j.engine == engine)?
            .result
            .as_ref()
            .ok()
            .map(|s| &s.history)
    }

    /// Number of failed jobs (an engine that does not apply to a scene has not failed).
    pub fn failures(&self) -> usize {
        self.jobs
            .iter()
            .filter(|j| !j.is_ok() && j.applicable())
            .count()
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
                    match j.status {
                        Status::NotApplicable => format!("not applicable: {e}"),
                        Status::Unstable => format!("UNSTABLE: {e}"),
                        _ => format!("FAILED: {e}"),
                    },
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

/// Run every job of `plan` in parallel.
///
/// Each job gets the plan's overrides completed with what its engine needs
/// ([`matching::job_settings`]). An engine error (or panic), or a history that breaks the
/// output contract, fails that job only; the others still run. A progress bar on stderr ticks once per job; it
/// is hidden when `progress` is false or stderr is not a terminal. Results come back in plan
/// order (case, then engine) whatever the thread scheduling.
pub fn execute(plan: &Plan, progress: bool) -> Outcome {
    let jobs: Vec<(&Scene, &dyn Engine)> = plan
        .cases
        .iter()
        .flat_map(|c| plan.engines.iter().map(move |e| (c, e.as_ref())))
        .collect();
    let bar = progress_bar(jobs.len(), progress);
    // Longest first, so that a long job does not start last and run alone.
    let results = schedule::longest_first(
        &jobs,
        |&(scene, engine)| estimated_cost(scene, engine, &plan.settings),
        |&(scene, engine)| {
            let result = run_job(scene, engine, &plan.settings);
            bar.set_message(format!("{}/{}", scene.id, engine.name()));
            bar.inc(1);
            result
        },
    );
    bar.finish_and_clear();
    Outcome { jobs: results }
}

/// A job's relative cost for scheduling only ([`schedule::longest_first`]): the increments it will take (from its increment
/// rule; the output rows where the engine chooses), weighted by 40 for an engine stepped at the
/// explicit engine's increment (rapier: a few substeps of a constraint solver per increment,
/// 26–62× the explicit step measured). A job whose settings cannot be worked out here (they
/// panic) goes first, at infinite cost: its own run reports the failure.
pub fn estimated_cost(scene: &Scene, engine: &dyn Engine, settings: &RunSettings) -> f64 {
    let job = match panic::catch_unwind(AssertUnwindSafe(|| {
        matching::job_settings(engine, scene, settings)
    })) {
        Ok(job) => job,
        Err(_) => return f64::INFINITY,
    };
    let h = match job.increment.unwrap_or(scene.settings.increment) {
        IncrementRule::Given(h) | IncrementRule::Forced(h) | IncrementRule::Exact(h) => h,
        _ => scene.duration() / scene.output_rows.max(2) as f64,
    };
    let weight = match engine.needs() {
        crate::engines::Needs::MatchedIncrement => 40.0,
        _ => 1.0,
    };
    weight * scene.duration() / h.max(f64::MIN_POSITIVE)
}

/// A progress bar on stderr for `len` tasks, hidden unless `progress` is set and stderr is a
/// terminal (and drawn only with the `cli` feature).
pub fn progress_bar(len: usize, progress: bool) -> Progress {
    Progress::new(len, progress)
}

/// Run one job: its settings, the engine, the contract check.
fn run_job(scene: &Scene, engine: &dyn Engine, settings: &RunSettings) -> JobResult {
    let start = Instant::now();
    let name = engine.name().to_string();
    if crate::interrupt::checkpoint("run").is_err() {
        return JobResult {
            case: scene.id.clone(),
            engine: name,
            elapsed: 0.0,
            result: Err("interrupted before it ran".to_string()),
            status: Status::Failed,
        };
    }
    let result = panic::catch_unwind(AssertUnwindSafe(|| {
        let settings = matching::job_settings(engine, scene, settings);
        engine.run(scene, &settings)
    }));
    let (result, status) = checked_run(scene, result);
    JobResult {
        case: scene.id.clone(),
        engine: name,
        elapsed: start.elapsed().as_secs_f64(),
        result,
        status,
    }
}

/// An engine's run (or its panic) as a job's result and typed status: the history checked
/// against the output contract (a non-finite value is instability, another breach a failure).
pub fn checked_run(
    scene: &Scene,
    run: std::thread::Result<Result<RunOutput, EngineError>>,
) -> (Result<JobSuccess, String>, Status) {
    let output = match run {
        Err(payload) => {
            let message = format!("engine panicked: {}", panic_message(payload.as_ref()));
            return (Err(message), Status::Failed);
        }
        Ok(Err(e)) => return (Err(e.to_string()), Status::of_error(&e)),
        Ok(Ok(output)) => output,
    };
    if let Err(e) = contract::check(scene, &output.history) {
        let message = format!("history breaks the output contract: {e}");
        return (Err(message), Status::Failed);
    }
    if let Err(e) = contract::check_finite(&output.history) {
        return (Err(e), Status::Unstable);
    }
    let success = JobSuccess {
        info: output.info,
        history: output.history,
    };
    (Ok(success), Status::Ok)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case;
    use crate::engines::{EngineError, RunOutput};
    use std::collections::BTreeMap;
    use std::path::Path;

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
            match j.engine.as_str() {
                "good" => assert_eq!(j.result.as_ref().unwrap().history.rows.len(), 201),
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
