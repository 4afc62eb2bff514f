//! Your own engine in every study: `cargo run --release --example own_engine [-- OUT]`.
//!
//! Runs every case of `cases/` (seeds and stress family) with the built-in engines and
//! [`engine::SemiImplicitEuler`], a user's engine written against the public [`Engine`] trait
//! (`engine.rs`), through the same jobs, exact solutions, discrepancy budgets, sweep, stability
//! map and report as the main command, and writes the report to OUT (default
//! `target/own_engine`). The engine's row is in every table of engines that step in time;
//! accuracy on request asks only engines that choose their own increment, which this one does
//! not.

mod engine;

use crosscheck::engines::{self, Engine, RunSettings};
use crosscheck::pipeline::{self, Studies};
use crosscheck::report::{self, staging};
use crosscheck::run::{self, Plan};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    let started = std::time::Instant::now();
    let out = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from("target/own_engine"), PathBuf::from);
    match report_with_own_engine(&out, started) {
        Ok(summary) => {
            println!("{summary}; report: {}", out.join("REPORT.md").display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The whole run, as `crosscheck run` does it, with one more engine in the plan.
fn report_with_own_engine(out: &Path, started: std::time::Instant) -> Result<String, String> {
    let cases_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    // Case files may declare a tolerance for the engine by its name (none of the shipped do).
    let name = [engine::SemiImplicitEuler.name()];
    let cases = run::load_cases_for(&[], &cases_dir, &name).map_err(|e| format!("{e:?}"))?;
    let stress = cases_dir.join("stress");
    let stress_cases = run::load_cases_for(&[], &stress, &name).map_err(|e| format!("{e:?}"))?;
    let mut engines: Vec<Box<dyn Engine>> = engines::all();
    engines.push(Box::new(engine::SemiImplicitEuler));
    let plan = Plan {
        cases: cases.into_iter().chain(stress_cases).collect(),
        engines,
        settings: RunSettings::default(),
    };
    let target = staging::resolve_output(out).map_err(|e| e.to_string())?;
    let _lock = staging::OutputLock::acquire(&target, true).map_err(|e| e.to_string())?;
    let staging = staging::Staging::begin(&target, &report::ENTRIES).map_err(|e| e.to_string())?;
    let studies = Studies {
        sweep: Some(3),
        stability: true,
        on_request: true,
    };
    let finished = pipeline::run(&plan, &cases_dir, &studies, staging, started, true)
        .map_err(|e| format!("{e:?}"))?;
    let checks = finished.summary.tolerance_checks();
    let mine: Vec<_> = checks
        .iter()
        .filter(|c| c.engine == engine::SemiImplicitEuler.name())
        .collect();
    let worst = mine
        .iter()
        .filter_map(|c| c.measured)
        .fold(0.0f64, f64::max);
    let declared = mine.iter().filter(|c| c.tolerance.is_some()).count();
    Ok(format!(
        "{} jobs; semi_implicit_euler judged on {} cases (worst error {worst:.2e} of the peak), \
         {} of them with a tolerance declared, {} met",
        finished.outcome.jobs.len(),
        mine.len(),
        declared,
        mine.iter().filter(|c| c.met()).count()
    ))
}
