//! Writing results: the files other tools and people read. The report reads what a run
//! returned ([`crate::run::Outcome`]); it never drives a run.
//!
//! - [`data`]: the time histories, one CSV per case and engine (the spec's output contract);
//! - `summary.json`: every metric and verdict per case and engine, as the comparison judged
//!   them ([`crate::comparison::summary`]; deterministic: the same inputs give the same bytes);
//! - [`gate`]: `verdicts.json`, each judged cell's error, tolerance, verdict and cause, and the
//!   same as JUnit XML for a pipeline;
//! - [`merge`]: the reports of a partitioned run's shards as one run's;
//! - `timings.json`: wall-clock seconds per case and engine (the one thing that varies);
//! - [`figures`]: `figures/<case>.svg`, each case's histories drawn, and its errors over time;
//! - [`sketch`]: `figures/<case>.sketch.svg`, each scene drawn from the `Scene` itself;
//! - [`work_precision`]: `sweep.csv` and `figures/<case>.work-precision.svg`, what
//!   each accuracy costs;
//! - [`stability`]: `stability.csv` and `figures/stability-<engine>.svg`, where each
//!   engine stays stable and accurate;
//! - [`contact`]: the report's section on contact that opens and closes;
//! - [`markdown`]: `REPORT.md`, rendered from the summary and the timings;
//! - [`format`]: how every number in the report is written (pages, figures, CSVs);
//! - [`provenance`]: what was run (version, commit, compiler, rapier, machine, date);
//! - [`staging`]: how a report is assembled beside its target and swapped into place.

pub mod contact;
pub mod data;
pub mod element_cost;
pub mod figures;
pub mod first_screen;
pub mod format;
pub mod friction;
pub mod gate;
pub mod judge;
pub mod markdown;
pub mod merge;
pub mod on_request;
#[cfg(feature = "figures")]
pub mod palette;
pub mod provenance;
#[cfg(feature = "figures")]
pub mod rebound;
pub mod regression;
pub mod results;
pub mod scaling;
#[cfg(feature = "figures")]
pub mod sketch;
pub mod stability;
pub mod staging;
pub mod verdicts;
pub mod versions;
pub mod work_precision;

use crate::comparison::discrepancy::JobBudget;
use crate::comparison::summary::Summary;
use crate::comparison::work_precision::CaseSweep;
use crate::run::{Outcome, Plan};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The report's own entries in its directory; nothing else there is the report's.
pub const ENTRIES: [&str; 15] = [
    "README.md",
    "cases",
    "accuracy.md",
    "cost.md",
    "stability.md",
    "results.csv",
    "data",
    "figures",
    "sweep.csv",
    "stability.csv",
    "on_request.csv",
    "summary.json",
    "verdicts.json",
    "timings.json",
    "REPORT.md",
];

/// What a run measured beyond its jobs, for the report.
#[derive(Debug)]
pub struct Study<'a> {
    /// Each job's discrepancy budget.
    pub budgets: &'a [JobBudget],
    /// The cells that needed a cause, with their controls.
    pub attributions: &'a [crate::comparison::attribution::Attribution],
    /// The invariance controls: parameters the exact solution ignores, at both values.
    pub invariances: &'a [crate::comparison::invariance::Invariance],
    /// Each case's sweep (what accuracy costs).
    pub sweeps: &'a [CaseSweep],
    /// The stability map (empty when it did not run).
    pub stability: &'a crate::comparison::stability::Map,
    /// Accuracy on request's runs (empty when it did not run).
    pub requests: &'a [crate::run::on_request::Request],
    /// How long each part of the run took (name, wall seconds), in order.
    pub parts: Vec<(&'static str, f64)>,
    /// The shard this run is of a partitioned run, where it is one.
    pub shard: Option<&'a crate::comparison::summary::Shard>,
}

/// A map that did not run.
static NO_MAP: crate::comparison::stability::Map = crate::comparison::stability::Map {
    points: Vec::new(),
    critical: Vec::new(),
};

impl Default for Study<'_> {
    fn default() -> Self {
        Study {
            budgets: &[],
            attributions: &[],
            invariances: &[],
            sweeps: &[],
            stability: &NO_MAP,
            requests: &[],
            parts: Vec::new(),
            shard: None,
        }
    }
}

/// Wall-clock seconds per case and engine.
pub type Timings = BTreeMap<String, BTreeMap<String, f64>>;

/// Write a run's report into `out` (the staging directory): each successful job's history as
/// CSV, the figures, `summary.json`, `timings.json` and `REPORT.md`, keeping what the
/// `previous` report had for cases and engines this run did not include. Returns the summary.
///
/// Checks for an interruption before every file ([`crate::interrupt::checkpoint`], phases
/// `csv`, `figures`, `summary`, `report`) and stops with [`data::DataError::Interrupted`].
pub fn write(
    out: &Path,
    plan: &Plan,
    outcome: &Outcome,
    study: &Study,
    previous: &Path,
) -> Result<Summary, data::DataError> {
    write_histories(out, outcome)?;
    write_budgets(out, study.budgets)?;
    work_precision::write(out, study.sweeps, &plan.cases)?;
    stability::write(out, study.stability)?;
    on_request::write(out, study.requests)?;
    checkpoint("summary")?;
    let earlier =
        |case: &str, engine: &str| data::read_history(&data::csv_path(out, case, engine)).ok();
    let mut summary = Summary::build(plan, outcome, &earlier);
    summary.attach_budgets(study.budgets);
    summary.attach_attributions(study.attributions);
    summary.invariances = study.invariances.to_vec();
    summary.attach_sweeps(study.sweeps);
    summary.attach_critical(study.stability);
    summary.attach_stability_failures(study.stability);
    let mut timings: Timings = read_json(&timings_path(previous)).unwrap_or_default();
    let old = read_json::<Summary>(&summary_path(previous));
    if let Some(old) = &old {
        summary.merge_previous(old.clone());
    }
    summary.shard = study.shard.cloned();
    for job in &outcome.jobs {
        if let Ok(s) = &job.result {
            timings
                .entry(job.case.clone())
                .or_default()
                .insert(job.engine.clone(), s.info.wall_seconds);
        }
    }
    #[cfg(feature = "figures")]
    write_case_figures(out, plan, &summary)?;
    #[cfg(feature = "figures")]
    write_summary_figures(out, &summary)?;
    let previous = Previous {
        dir: previous,
        settings: &plan.settings,
        parts: &study.parts,
    };
    publish(out, &summary, &timings, &previous)?;
    Ok(summary)
}

/// What the pages say of how the report came to be: the report it replaces (for "since the
/// previous report"), the settings it was run with, and how long each stage took.
pub struct Previous<'a> {
    /// The directory of the report being replaced.
    pub dir: &'a Path,
    /// The run's settings.
    pub settings: &'a crate::engines::RunSettings,
    /// Seconds per stage, in order (empty where unknown: a merge of shards).
    pub parts: &'a [(&'static str, f64)],
}

/// The files written from the judged summary, by a run and by a merge alike:
/// `summary.json`, `verdicts.json`, `results.csv`, `timings.json` and the pages (which also
/// read the study CSVs already in `out`).
pub fn publish(
    out: &Path,
    summary: &Summary,
    timings: &Timings,
    previous: &Previous,
) -> Result<(), data::DataError> {
    data::write_atomic(&summary_path(out), summary.to_json().as_bytes())?;
    let verdicts = gate::json(&gate::cells(summary));
    data::write_atomic(&gate::json_path(out), verdicts.as_bytes())?;
    data::write_atomic(&results::csv_path(out), results::csv(summary).as_bytes())?;
    let json = serde_json::to_string_pretty(timings).expect("timings serialise") + "\n";
    data::write_atomic(&timings_path(out), json.as_bytes())?;
    checkpoint("report")?;
    // Both tiers of `crosscheck compare`, this report's files against the previous report's.
    let since = regression::since_dirs(previous.dir, out);
    let pages = markdown::render(
        summary,
        &markdown::Inputs {
            timings,
            provenance: &provenance::Provenance::gather(previous.settings),
            sweeps: &work_precision::read_all(out),
            maps: &stability::read_all(out),
            requests: &on_request::read(out),
            parts: previous.parts,
            since: since.as_ref(),
        },
    );
    let mut pages = pages;
    versions::section(&mut pages.report, summary, out);
    write_pages(out, &pages)
}

/// The figures of a run's cases: per case its histories, its sketch and its errors.
#[cfg(feature = "figures")]
fn write_case_figures(out: &Path, plan: &Plan, summary: &Summary) -> Result<(), data::DataError> {
    use crate::contract::{self, History};
    for case in &summary.cases {
        // An older release of rapier is drawn nowhere: its tables are the versions section.
        let histories: Vec<(&str, History)> = summary
            .engines
            .iter()
            .filter(|e| !contract::on_older_release(e))
            .filter_map(|e| {
                let h = data::read_history(&data::csv_path(out, &case.id, e)).ok()?;
                Some((e.as_str(), h))
            })
            .collect();
        let Some(scene) = plan.cases.iter().find(|s| s.id == case.id) else {
            continue; // a case this run did not include keeps its previous figure
        };
        // The contract's columns, then the case's contact gaps.
        let panels: Vec<(&str, &str)> = contract::columns(scene.family)
            .iter()
            .map(|c| (*c, figures::unit(c)))
            .chain(
                scene
                    .columns
                    .iter()
                    .filter(|c| matches!(c.probe, crate::scene::Probe::Gap { .. }))
                    .map(|c| (c.name.as_str(), "m")),
            )
            .collect();
        if let Some(svg) = figures::render(&case.id, &panels, &histories) {
            checkpoint("figures")?;
            data::write_atomic(&figures::figure_path(out, &case.id), svg.as_bytes())?;
        }
        if let Some(svg) = sketch::render(scene) {
            checkpoint("figures")?;
            data::write_atomic(&figures::sketch_path(out, &case.id), svg.as_bytes())?;
        }
        if let Some(svg) = figures::render_errors(scene, &histories) {
            checkpoint("figures")?;
            data::write_atomic(&figures::errors_figure_path(out, &case.id), svg.as_bytes())?;
        }
    }
    Ok(())
}

/// The figures drawn from the whole summary: the discrepancy budget per family, the rebounds.
#[cfg(feature = "figures")]
pub fn write_summary_figures(out: &Path, summary: &Summary) -> Result<(), data::DataError> {
    use crate::scene::Family;
    for family in [Family::RigidBody, Family::Springs] {
        let bars: Vec<figures::BudgetBar> = summary
            .cases
            .iter()
            .filter(|c| c.family == family.name())
            .flat_map(|c| c.runs.iter().map(move |r| (c, r)))
            .filter_map(|(c, r)| {
                let (worst, _, _) = r.dominant_source()?;
                Some(figures::BudgetBar {
                    label: format!("{} / {} ({})", c.id, r.engine, worst.column),
                    parts: worst.parts(),
                    total: worst.total,
                })
            })
            .collect();
        if let Some(svg) = figures::render_budget(family.name(), &bars) {
            checkpoint("figures")?;
            data::write_atomic(
                &figures::budget_figure_path(out, family.name()),
                svg.as_bytes(),
            )?;
        }
    }
    if let Some(svg) = rebound::render(&rebound::points(summary)) {
        checkpoint("figures")?;
        data::write_atomic(&rebound::figure_path(out), svg.as_bytes())?;
    }
    Ok(())
}

/// Write the report's pages: each case's, then the question pages, `REPORT.md` last.
fn write_pages(out: &Path, pages: &markdown::Pages) -> Result<(), data::DataError> {
    for (case, page) in &pages.cases {
        data::write_atomic(&case_page_path(out, case), page.as_bytes())?;
    }
    for (name, page) in [
        ("accuracy.md", &pages.accuracy),
        ("cost.md", &pages.cost),
        ("stability.md", &pages.stability),
    ] {
        data::write_atomic(&out.join(name), page.as_bytes())?;
    }
    data::write_atomic(&out.join("README.md"), DATA_DICTIONARY.as_bytes())?;
    data::write_atomic(&report_path(out), pages.report.as_bytes())
}

/// The report directory's `README.md`: its pages, data files, columns and units.
pub const DATA_DICTIONARY: &str = include_str!("README.md");

/// `out/cases/<case>.md`.
pub fn case_page_path(out: &Path, case: &str) -> PathBuf {
    out.join("cases").join(format!("{case}.md"))
}

/// Write each job's discrepancy budget to `out/data/<case>/<engine>.budget.csv`.
pub fn write_budgets(out: &Path, budgets: &[JobBudget]) -> Result<(), data::DataError> {
    budgets
        .par_iter()
        .filter_map(|b| Some((b, &b.result.as_ref().ok()?.0)))
        .try_for_each(|(b, budget)| {
            checkpoint("csv")?;
            data::write_history_to(&data::budget_path(out, &b.case, &b.engine), &budget.history)
        })
}

/// Write each successful job's history to `out/data/<case>/<engine>.csv` (in parallel; each
/// file atomically).
pub fn write_histories(out: &Path, outcome: &Outcome) -> Result<(), data::DataError> {
    outcome
        .jobs
        .par_iter()
        .filter_map(|job| Some((job, job.result.as_ref().ok()?)))
        .try_for_each(|(job, s)| {
            checkpoint("csv")?;
            data::write_history(out, &job.case, &job.engine, &s.history).map(|_| ())
        })
}

/// Engine names, each once, in the order met: the run's order, a user's engine after the
/// registry's.
pub(crate) fn in_order_met<'a>(names: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut engines: Vec<&str> = Vec::new();
    for n in names {
        if !engines.contains(&n) {
            engines.push(n);
        }
    }
    engines
}

fn checkpoint(phase: &str) -> Result<(), data::DataError> {
    crate::interrupt::checkpoint(phase).map_err(|_| data::DataError::Interrupted)
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Option<T> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// `out/summary.json`.
pub fn summary_path(out: &Path) -> PathBuf {
    out.join("summary.json")
}

/// `out/timings.json`.
pub fn timings_path(out: &Path) -> PathBuf {
    out.join("timings.json")
}

/// `out/REPORT.md`.
pub fn report_path(out: &Path) -> PathBuf {
    out.join("REPORT.md")
}
