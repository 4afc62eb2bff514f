//! `crosscheck run`, and what a finished run prints.

use super::cases::target_and_cases;
use super::studies::lock_and_stage;
use super::{RunArgs, Stdout, baseline, interrupted, stopped};
use crate::comparison::summary::Shard;
use crate::engines::Engine;
use crate::report::gate;
use crate::run::{self, Plan, budget};
use crate::scene::Scene;
use crate::{interrupt, pipeline, report};
use std::path::Path;
use std::process::ExitCode;

/// `crosscheck run`: check the options and load the cases, run them through the pipeline, and
/// print the jobs' table, the tolerance count and the stage times.
pub(super) fn run_command(args: RunArgs, dir: &Path, extra: Vec<Box<dyn Engine>>) -> ExitCode {
    let started = std::time::Instant::now();
    let names: Vec<String> = extra.iter().map(|e| e.name().to_string()).collect();
    let also: Vec<&str> = names.iter().map(String::as_str).collect();
    let available = crate::run::registry::all()
        .into_iter()
        .chain(extra)
        .collect();
    let (target, cases) = match target_and_cases(&args.out, &args.cases, dir, &also) {
        Ok(x) => x,
        Err(code) => return code,
    };
    note_missing_exact_solutions(&args.engines, &target, &cases);
    let engines = match run::select_among(available, &args.engines) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let (cases, shard) = match shard_of(&args, &target, cases, &engines) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let gated = match gated_engines(&args, &engines) {
        Ok(g) => g,
        Err(code) => return code,
    };
    if let Err(code) = baseline::check_exists(&args.baseline_dir, args.baseline.as_deref()) {
        return code;
    }
    let settings = args.settings();
    let refused = run::check_overrides(&cases, &settings);
    let plan = Plan {
        cases,
        engines,
        settings,
    };
    let refused = if refused.is_empty() {
        budget::check(&plan, &settings, &args.limits())
    } else {
        refused
    };
    if !refused.is_empty() {
        for r in &refused {
            eprintln!("error: {r}");
        }
        eprintln!("nothing was run");
        return ExitCode::from(2);
    }
    if interrupt::checkpoint("load").is_err() {
        return interrupted();
    }
    if let Some(s) = shard.as_ref().filter(|_| plan.cases.is_empty()) {
        eprintln!(
            "shard {}/{}: no case (the {} cases make fewer groups than shards); nothing to run",
            s.k,
            s.n,
            s.cases.len()
        );
        return ExitCode::SUCCESS;
    }
    let (_lock, staging) = match lock_and_stage(&target, !args.no_wait, &report::ENTRIES) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let studies = pipeline::Studies {
        sweep: args.sweep.then_some(args.repeat as usize),
        stability: args.stability,
        on_request: args.on_request,
        shard,
    };
    let finished = match pipeline::run(&plan, dir, &studies, staging, started, !args.quiet) {
        Ok(finished) => finished,
        Err(e) => return stopped("the report", e),
    };
    let code = print_run(&finished, &studies, &args.out);
    let gate = gate(&finished, args.junit.as_deref(), gated.as_deref());
    let mut out = Stdout::default();
    let (compare, save) = (args.baseline.as_deref(), args.save_baseline.as_deref());
    let baseline = baseline::after_run(&target, &args.baseline_dir, (compare, save), &mut out);
    let baseline = out.finish(baseline);
    [code, gate, baseline]
        .into_iter()
        .find(|c| *c != ExitCode::SUCCESS)
        .unwrap_or(ExitCode::SUCCESS)
}

/// With `--partition k/n`: this shard's share of `cases` and what it says of the whole run;
/// refused (exit 2) with overrides of the cases' settings (the merged report states the
/// cases' own) or into a directory that holds files (a shard's report must be its cases'
/// alone, not joined with a report already there).
fn shard_of(
    args: &RunArgs,
    target: &Path,
    cases: Vec<crate::scene::Scene>,
    engines: &[Box<dyn Engine>],
) -> Result<(Vec<crate::scene::Scene>, Option<Shard>), ExitCode> {
    let Some(part) = args.partition else {
        return Ok((cases, None));
    };
    let settings = args.settings();
    let overridden = settings.increment.is_some()
        || settings.penalty.is_some()
        || settings.damping.is_some()
        || settings.contact_start.is_some();
    if overridden {
        eprintln!(
            "error: --partition runs each case with its own settings: drop --increment, \
             --penalty, --tolerance, --increment-ratio, --damping and --contact-start; nothing \
             was run"
        );
        return Err(ExitCode::from(2));
    }
    if std::fs::read_dir(target).is_ok_and(|mut d| d.next().is_some()) {
        eprintln!(
            "error: --partition writes each shard into a directory of its own, and {} holds \
             files (remove them, or give another --out); nothing was run",
            target.display()
        );
        return Err(ExitCode::from(2));
    }
    let shard = Shard {
        k: part.k,
        n: part.n,
        cases: cases.iter().map(|s| s.id.clone()).collect(),
        engines: engines.iter().map(|e| e.name().to_string()).collect(),
    };
    Ok((pipeline::partition(cases, part), Some(shard)))
}

/// Say which exact solutions the named engines are judged against that neither run nor lie in
/// `target` for every case (a run of some engines is judged against the exact solutions on
/// disk; a new directory, or a report kept without its histories, holds none): the cells of
/// those cases get no verdict. The closed form judges every engine but itself; the reference,
/// the engines judged against it.
fn note_missing_exact_solutions(named: &[String], target: &Path, cases: &[Scene]) {
    use crate::comparison::{CLOSED_FORM, EXACT_SOLUTIONS, baseline};
    let named: Vec<&str> = named.iter().map(|n| n.trim()).collect();
    let needed = |exact: &str| {
        !named.contains(&exact)
            && named
                .iter()
                .any(|n| *n != exact && (exact == CLOSED_FORM || baseline(n) == Some(exact)))
    };
    let missing = |exact: &str| {
        let cases = cases.iter();
        cases
            .filter(|c| !report::data::csv_path(target, &c.id, exact).is_file())
            .count()
    };
    for exact in EXACT_SOLUTIONS
        .iter()
        .filter(|e| !named.is_empty() && needed(e))
    {
        let n = missing(exact);
        if n > 0 {
            eprintln!(
                "note: `{exact}` is not in --engines and {} holds its history for {} of the {} \
                 cases: their cells that are judged against it get no verdict (add it to \
                 --engines)",
                target.display(),
                cases.len() - n,
                cases.len()
            );
        }
    }
}

/// The engines `--fail-on-miss` gates on (every engine of the run where it names none), or
/// exit 2 where it names one the run does not have.
fn gated_engines(
    args: &RunArgs,
    engines: &[Box<dyn Engine>],
) -> Result<Option<Vec<String>>, ExitCode> {
    let Some(named) = &args.fail_on_miss else {
        return Ok(None);
    };
    let named: Vec<String> = named
        .iter()
        .map(|n| n.trim().to_string())
        .filter(|n| !n.is_empty())
        .collect();
    let running: Vec<&str> = engines.iter().map(|e| e.name()).collect();
    if !running
        .iter()
        .any(|e| crate::comparison::EXACT_SOLUTIONS.contains(e))
    {
        eprintln!(
            "error: --fail-on-miss judges errors against the exact solutions ({}), and this \
             run has neither: add them to --engines; nothing was run",
            crate::comparison::EXACT_SOLUTIONS.join(", ")
        );
        return Err(ExitCode::from(2));
    }
    if let Some(unknown) = named.iter().find(|n| !running.contains(&n.as_str())) {
        eprintln!(
            "error: --fail-on-miss: `{unknown}` is not an engine of this run{}; its engines: {}",
            crate::case::diagnostic::did_you_mean(unknown, &running),
            running.join(", ")
        );
        return Err(ExitCode::from(2));
    }
    Ok(Some(named))
}

/// This run's judged cells (not those a previous report holds for other cases) written as
/// JUnit XML to `junit`, and the gate: exit 1, naming the cells, when one of the `gated`
/// engines' misses its tolerance; 1 as well when the XML cannot be written.
fn gate(finished: &pipeline::Finished, junit: Option<&Path>, gated: Option<&[String]>) -> ExitCode {
    let ran = |c: &gate::Cell| {
        finished
            .outcome
            .jobs
            .iter()
            .any(|j| j.case == c.case && j.engine == c.engine)
    };
    let cells: Vec<gate::Cell> = gate::cells(&finished.summary)
        .into_iter()
        .filter(|c| ran(c))
        .collect();
    let mut code = ExitCode::SUCCESS;
    if let Some(path) = junit {
        let seconds = |case: &str, engine: &str| {
            let job = finished.outcome.jobs.iter();
            job.filter(|j| j.case == case && j.engine == engine)
                .map(|j| j.elapsed)
                .next()
        };
        let xml = gate::junit(&cells, &seconds);
        match report::data::write_atomic(path, xml.as_bytes()) {
            Ok(()) => eprintln!("JUnit: {} ({} cells)", path.display(), cells.len()),
            Err(e) => {
                eprintln!("error: cannot write the JUnit file: {e}");
                code = ExitCode::FAILURE;
            }
        }
    }
    let Some(engines) = gated else {
        return code;
    };
    let judged = cells
        .iter()
        .filter(|c| engines.is_empty() || engines.contains(&c.engine))
        .filter(|c| c.tolerance.is_some() && c.verdict != gate::Verdict::Unjudged)
        .count();
    if judged == 0 {
        eprintln!(
            "--fail-on-miss: no cell of {} was judged against a tolerance; the gate looked at \
             nothing",
            if engines.is_empty() {
                "any engine".to_string()
            } else {
                engines.join(", ")
            }
        );
        return ExitCode::FAILURE;
    }
    let failing: Vec<&gate::Cell> = cells
        .iter()
        .filter(|c| gate::fails_gate(c, engines))
        .collect();
    if failing.is_empty() {
        return code;
    }
    eprintln!(
        "--fail-on-miss: {} judged cell(s) miss their tolerance:",
        failing.len()
    );
    for c in failing {
        let error = c
            .error
            .map_or_else(|| "failed".to_string(), report::format::sci);
        let tolerance = c
            .tolerance
            .map_or_else(|| "–".to_string(), report::format::sci);
        let cause = c
            .cause
            .as_ref()
            .map_or_else(String::new, |cause| format!("; cause: {cause}"));
        eprintln!(
            "  {} / {}: {error} (tolerance {tolerance}{cause})",
            c.case, c.engine
        );
    }
    ExitCode::FAILURE
}

/// What a finished run prints: the jobs' table, the tolerance count, the stage times; exit 1
/// when a job failed.
pub(super) fn print_run(
    finished: &pipeline::Finished,
    studies: &pipeline::Studies,
    out_dir: &Path,
) -> ExitCode {
    let (outcome, t) = (&finished.outcome, &finished.times);
    let mut out = Stdout::default();
    out.print(&outcome.table());
    let checks = finished.summary.tolerance_checks();
    out.print(&format!(
        "{} job(s), {} failed; report: {} ({} of {} cells meet their tolerance)\n",
        outcome.jobs.len(),
        outcome.failures(),
        report::report_path(out_dir).display(),
        checks.iter().filter(|c| c.met()).count(),
        checks.len()
    ));
    let parts: Vec<String> = t
        .parts(studies)
        .iter()
        .map(|(name, seconds)| format!("{name} {seconds:.2} s"))
        .collect();
    out.print(&format!(
        "time: {}, report {:.2} s, swap {:.2} s; total {:.2} s\n",
        parts.join(", "),
        t.written - t.requested,
        t.swapped - t.written,
        t.swapped
    ));
    if interrupt::requested() {
        eprintln!("interrupted after the new report was put in place");
        return ExitCode::from(interrupt::EXIT_CODE);
    }
    out.finish(if outcome.all_ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
