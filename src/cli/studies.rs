//! The studies' commands: `scaling`, `sweep`, `stability`.

use super::cases::target_and_cases;
use super::{ScalingStudy, StabilityArgs, Stdout, StudyArgs, SweepArgs, interrupted, stopped};
use crate::case;
use crate::comparison::{self, work_precision};
use crate::engines::Engine;
use crate::report::{self, staging};
use crate::run::sweep;
use crate::{interrupt, pipeline};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub(super) fn scaling(
    study: ScalingStudy,
    max_n: usize,
    out: &Path,
    quiet: bool,
    dir: &Path,
) -> ExitCode {
    let target = match staging::resolve_output(out) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}; nothing was run");
            return ExitCode::from(2);
        }
    };
    let _lock = match staging::OutputLock::acquire(&target, true) {
        Ok(l) => l,
        Err(staging::OutputError::Interrupted) => return interrupted(),
        Err(e) => {
            eprintln!("error: cannot lock {}: {e}", target.display());
            return ExitCode::FAILURE;
        }
    };
    let mut stdout = Stdout::default();
    if study != ScalingStudy::Elements {
        let code = chain_study(max_n, &target, quiet, &mut stdout);
        if code != ExitCode::SUCCESS {
            return stdout.finish(code);
        }
    }
    if study != ScalingStudy::Chain {
        let code = element_study(&target, quiet, dir, &mut stdout);
        return stdout.finish(code);
    }
    stdout.finish(ExitCode::SUCCESS)
}

/// A progress bar of `len` steps on standard error (hidden when `quiet` or not a terminal).
pub(super) fn progress_bar(len: u64, quiet: bool, unit: &str) -> indicatif::ProgressBar {
    let bar = if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(len)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:30}} {{pos}}/{{len}} {unit}  {{msg}}"
        ))
        .expect("a valid template"),
    );
    bar
}

/// A study's result, or the exit code of its failure: interrupted, or an error said on
/// standard error.
pub(super) fn finished<T>(study: Result<T, String>) -> Result<T, ExitCode> {
    study.map_err(|e| {
        if interrupt::requested() {
            interrupted()
        } else {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    })
}

/// Print a study's `text`, write its CSV (path, text), the commit it was measured at (the
/// CSV's path with `.provenance`) and, where given, its figure (path, SVG), and say where.
pub(super) fn publish(
    stdout: &mut Stdout,
    text: &str,
    (path, csv): (PathBuf, String),
    figure: Option<(PathBuf, String)>,
) -> ExitCode {
    stdout.print(text);
    let written = report::data::write_atomic(&path, csv.as_bytes())
        .and_then(|_| report::data::write_provenance(&path))
        .and_then(|_| match figure {
            Some((path, svg)) => report::data::write_atomic(&path, svg.as_bytes()),
            None => Ok(()),
        });
    if let Err(e) = written {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    stdout.print(&format!("written: {}\n", path.display()));
    ExitCode::SUCCESS
}

/// The element-cost study: run, print the model and how well it predicts, write the files.
pub(super) fn element_study(
    target: &Path,
    quiet: bool,
    dir: &Path,
    stdout: &mut Stdout,
) -> ExitCode {
    use crate::report::element_cost as written;
    use crate::run::element_cost;
    let seeds = match case::discover(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))
        .and_then(|paths| {
            paths
                .iter()
                .map(|p| case::load(p).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()
        }) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let bar = progress_bar(
        (element_cost::family().len() + seeds.len()) as u64,
        quiet,
        "scenes",
    );
    let study = element_cost::study(&seeds, |id| {
        bar.set_message(id.to_string());
        bar.inc(1);
    });
    bar.finish_and_clear();
    let study = match finished(study) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let text = format!(
        "explicit, ns per increment = sum of coefficient × count:\n\n{}",
        written::summary(&study)
    );
    #[cfg(feature = "figures")]
    let figure = written::render(&study).map(|svg| (written::figure_path(target), svg));
    #[cfg(not(feature = "figures"))]
    let figure = None;
    let csv = (written::csv_path(target), written::csv(&study));
    publish(stdout, &text, csv, figure)
}

/// The chain study: run, print, write the files.
pub(super) fn chain_study(
    max_n: usize,
    target: &Path,
    quiet: bool,
    stdout: &mut Stdout,
) -> ExitCode {
    use crate::report::scaling as written;
    use crate::run::scaling;
    let bar = progress_bar(2 * scaling::sizes(max_n).len() as u64, quiet, "points");
    let lines = !quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr()); // bar hidden
    let started = std::time::Instant::now();
    let study = scaling::study(max_n, |engine, n| {
        bar.set_message(format!("{engine}, N = {n}"));
        bar.inc(1);
        lines.then(|| eprintln!("scaling: {engine}, N = {n} (at {:.1?})", started.elapsed()));
    });
    bar.finish_and_clear();
    let study = match finished(study) {
        Ok(s) => s,
        Err(code) => return code,
    };
    #[cfg(feature = "figures")]
    let figure = written::render(&study).map(|svg| (written::figure_path(target), svg));
    #[cfg(not(feature = "figures"))]
    let figure = None;
    let csv = (written::csv_path(target), written::csv(&study));
    publish(stdout, &written::table(&study), csv, figure)
}

/// Take the output's lock (waiting unless `wait` is false: then a busy output is exit 2) and
/// start a staging directory for `entries`.
pub(super) fn lock_and_stage(
    target: &Path,
    wait: bool,
    entries: &[&str],
) -> Result<(staging::OutputLock, staging::Staging), ExitCode> {
    let lock = match staging::OutputLock::acquire(target, wait) {
        Ok(l) => l,
        Err(staging::OutputError::Interrupted) => return Err(interrupted()),
        Err(e @ staging::OutputError::Busy { .. }) => {
            eprintln!("error: {e}");
            return Err(ExitCode::from(2));
        }
        Err(e) => {
            eprintln!("error: cannot lock the report: {e}");
            return Err(ExitCode::FAILURE);
        }
    };
    match staging::Staging::begin(target, entries) {
        Ok(s) => Ok((lock, s)),
        Err(e) => {
            eprintln!(
                "error: cannot prepare the report in {}: {e}",
                target.display()
            );
            Err(ExitCode::FAILURE)
        }
    }
}

/// What `sweep` and `stability` start from: the engines asked for among those that step in
/// time, the cases, and the output locked and staged for the study's `entries`.
struct Prepared {
    engines: Vec<Box<dyn Engine>>,
    cases: Vec<crate::scene::Scene>,
    _lock: staging::OutputLock,
    staging: staging::Staging,
}

/// [`Prepared`] for a study of `refusal` (what an engine that does not step cannot do), or
/// the exit code of why not (said on standard error).
fn prepare(
    args: &StudyArgs,
    refusal: &str,
    extra: Vec<Box<dyn Engine>>,
    dir: &Path,
    entries: &[&str],
) -> Result<Prepared, ExitCode> {
    let engines = chosen_engines(&args.engines, refusal, extra)?;
    let names: Vec<String> = engines.iter().map(|e| e.name().to_string()).collect();
    let also: Vec<&str> = names.iter().map(String::as_str).collect();
    let (target, cases) = target_and_cases(&args.out, &args.cases, dir, &also)?;
    let (lock, staging) = lock_and_stage(&target, !args.no_wait, entries)?;
    Ok(Prepared {
        engines,
        cases,
        _lock: lock,
        staging,
    })
}

pub(super) fn sweep_command(args: SweepArgs, dir: &Path, extra: Vec<Box<dyn Engine>>) -> ExitCode {
    use crate::report::work_precision as written;
    let entries = ["sweep.csv", "figures"];
    let Prepared {
        engines,
        cases,
        _lock,
        staging,
    } = match prepare(&args.study, "cannot be swept", extra, dir, &entries) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let grid = sweep::Grid {
        repeat: args.repeat as usize,
        max_increments: args.max_increments,
        ..sweep::Grid::default()
    };
    let engines: Vec<&dyn Engine> = engines.iter().map(|e| e.as_ref()).collect();
    let progress = !args.study.quiet;
    let sweeps = pipeline::study(
        cases,
        staging,
        |plan, outcome| work_precision::measure(plan, outcome, &engines, &grid, progress),
        |dir, plan, sweeps| written::write(dir, sweeps, &plan.cases),
    );
    let sweeps = match sweeps {
        Ok(s) => s,
        Err(e) => return stopped("the sweep", e),
    };
    let out_dir = &args.study.out;
    let mut out = Stdout::default();
    out.print(&written::text(&sweeps));
    out.print(&format!(
        "written: {} and {}\n",
        out_dir.join("sweep.csv").display(),
        out_dir.join("figures").display()
    ));
    out.finish(ExitCode::SUCCESS)
}

pub(super) fn stability_command(
    args: StabilityArgs,
    dir: &Path,
    extra: Vec<Box<dyn Engine>>,
) -> ExitCode {
    use crate::report::stability as written;
    let entries = ["stability.csv", "figures"];
    let Prepared {
        engines,
        cases,
        _lock,
        staging,
    } = match prepare(&args.study, "has no stability map", extra, dir, &entries) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let engines: Vec<&dyn Engine> = engines.iter().map(|e| e.as_ref()).collect();
    let progress = !args.study.quiet;
    let map = pipeline::study(
        cases,
        staging,
        |plan, outcome| comparison::stability::measure(plan, outcome, &engines, progress),
        |dir, _, map| written::write(dir, map),
    );
    if let Err(e) = map {
        return stopped("the stability map", e);
    }
    let mut out = Stdout::default();
    let mut text = String::new();
    written::overview(&mut text, &written::read_all(&args.study.out));
    out.print(&text);
    out.finish(ExitCode::SUCCESS)
}

/// The engines named in `asked` among those that step in time (all of them when none is
/// named); another is an error (exit 2) saying `refusal` and listing those that step.
pub(super) fn chosen_engines(
    asked: &[String],
    refusal: &str,
    extra: Vec<Box<dyn Engine>>,
) -> Result<Vec<Box<dyn Engine>>, ExitCode> {
    let allowed: Vec<Box<dyn Engine>> = crate::run::registry::all()
        .into_iter()
        .chain(extra)
        .filter(|e| e.stepping().is_some())
        .collect();
    if asked.is_empty() {
        return Ok(allowed);
    }
    let names: Vec<&str> = allowed.iter().map(|e| e.name()).collect();
    if let Some(name) = asked.iter().find(|n| !names.contains(&n.trim())) {
        eprintln!(
            "error: `{}` {refusal}; engines that step in time: {}",
            name.trim(),
            names.join(", ")
        );
        return Err(ExitCode::from(2));
    }
    // Each once, in report order.
    Ok(allowed
        .into_iter()
        .filter(|e| asked.iter().any(|n| n.trim() == e.name()))
        .collect())
}
