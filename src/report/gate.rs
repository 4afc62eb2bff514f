//! The verdicts as a pipeline reads them: one cell per case and judged engine, with its error,
//! tolerance, verdict and cause: `verdicts.json` beside `summary.json`, JUnit XML (a test case
//! per cell), and the cells that make `run --fail-on-miss` exit 1.

use crate::comparison::summary::Summary;
use crate::report::format::sci;
use crate::report::verdicts::cause_name;
use crate::run::Status;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// How a judged cell came out against its tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Its worst error is within the tolerance the case declares.
    Met,
    /// Its worst error is above the tolerance.
    Missed,
    /// The run failed or went unstable: no error to judge, and the tolerance not met.
    Failed,
    /// The case declares no tolerance for the engine: measured, not judged.
    NoTolerance,
    /// A tolerance is declared, but no column has a peak to measure the error against.
    Unjudged,
}

/// One judged cell.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Cell {
    /// Case id.
    pub case: String,
    /// Engine.
    pub engine: String,
    /// The exact solution the error is measured against.
    pub against: String,
    /// Worst error over the columns' peaks (`None`: failed, or no column with a peak).
    pub error: Option<f64>,
    /// The tolerance the case declares for the engine.
    pub tolerance: Option<f64>,
    /// The verdict.
    pub verdict: Verdict,
    /// Why a flagged cell is off, as its controls showed ("time step", "unexplained"); `None`
    /// where no control ran.
    pub cause: Option<String>,
    /// Why the run failed, where it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// `out/verdicts.json`.
pub fn json_path(out: &Path) -> PathBuf {
    out.join("verdicts.json")
}

/// Every judged cell of the summary, in report order.
pub fn cells(summary: &Summary) -> Vec<Cell> {
    summary
        .tolerance_checks()
        .into_iter()
        .map(|c| {
            let run = summary
                .cases
                .iter()
                .find(|s| s.id == c.case)
                .and_then(|s| s.runs.iter().find(|r| r.engine == c.engine));
            let status = run.map_or(Status::Ok, |r| r.status);
            let verdict = match (c.tolerance, c.met, status) {
                (_, _, Status::Failed | Status::Unstable) => Verdict::Failed,
                (None, _, _) => Verdict::NoTolerance,
                (Some(_), None, _) => Verdict::Unjudged,
                (Some(_), Some(true), _) => Verdict::Met,
                (Some(_), Some(false), _) => Verdict::Missed,
            };
            let cause = run
                .and_then(|r| r.attribution.as_ref())
                .map(|a| cause_name(a).unwrap_or_else(|| "unexplained".to_string()));
            Cell {
                case: c.case.to_string(),
                engine: c.engine.to_string(),
                against: c.baseline.to_string(),
                error: c.measured,
                tolerance: c.tolerance,
                verdict,
                cause,
                failure: run
                    .filter(|_| verdict == Verdict::Failed)
                    .and_then(|r| r.error.clone()),
            }
        })
        .collect()
}

/// `verdicts.json`: the counts and every cell.
pub fn json(cells: &[Cell]) -> String {
    let count = |v: Verdict| cells.iter().filter(|c| c.verdict == v).count();
    let counts: BTreeMap<&str, usize> = [
        ("met", count(Verdict::Met)),
        ("missed", count(Verdict::Missed)),
        ("failed", count(Verdict::Failed)),
        ("no_tolerance", count(Verdict::NoTolerance)),
        ("unjudged", count(Verdict::Unjudged)),
    ]
    .into_iter()
    .collect();
    let value = serde_json::json!({ "counts": counts, "cells": cells });
    serde_json::to_string_pretty(&value).expect("verdicts serialise") + "\n"
}

/// Whether a cell fails a pipeline gated on `engines` (every engine where empty): its
/// tolerance missed, or its run failed where it had one to meet.
pub fn fails_gate(cell: &Cell, engines: &[String]) -> bool {
    let gated = engines.is_empty() || engines.contains(&cell.engine);
    let missed = match cell.verdict {
        Verdict::Missed => true,
        Verdict::Failed => cell.tolerance.is_some(),
        Verdict::Met | Verdict::NoTolerance | Verdict::Unjudged => false,
    };
    gated && missed
}

/// The cells as JUnit XML: one suite, a test case per cell (the case its class, the engine its
/// name; `seconds` the job's wall-clock time where known), a failure where the tolerance is
/// missed, an error where the run failed, skipped where no tolerance is declared; the error,
/// tolerance and cause as properties.
pub fn junit(cells: &[Cell], seconds: &dyn Fn(&str, &str) -> Option<f64>) -> String {
    use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};
    let number = |x: Option<f64>| x.map_or_else(|| "–".to_string(), sci);
    let mut suite = TestSuite::new("crosscheck");
    for c in cells {
        let said = format!(
            "error {} against {}, tolerance {}{}",
            number(c.error),
            c.against,
            number(c.tolerance),
            c.cause
                .as_ref()
                .map_or_else(String::new, |cause| format!("; cause: {cause}"))
        );
        let mut status = match c.verdict {
            Verdict::Met => TestCaseStatus::success(),
            Verdict::NoTolerance | Verdict::Unjudged => TestCaseStatus::skipped(),
            Verdict::Missed => TestCaseStatus::non_success(NonSuccessKind::Failure),
            Verdict::Failed => TestCaseStatus::non_success(NonSuccessKind::Error),
        };
        match c.verdict {
            Verdict::Met => {}
            Verdict::NoTolerance => {
                status.set_message(format!("no tolerance declared; {said}"));
            }
            Verdict::Unjudged => {
                status.set_message(format!("no column with a peak to judge; {said}"));
            }
            Verdict::Missed => {
                status.set_message(said.clone());
            }
            Verdict::Failed => {
                let why = c.failure.as_deref().unwrap_or("the run failed");
                status.set_message(format!("{why}; {said}"));
            }
        }
        let mut case = TestCase::new(c.engine.as_str(), status);
        case.set_classname(c.case.as_str());
        if let Some(s) = seconds(&c.case, &c.engine) {
            case.set_time(std::time::Duration::from_secs_f64(s.max(0.0)));
        }
        case.add_property(("against", c.against.as_str()));
        case.add_property(("error", number(c.error).as_str()));
        case.add_property(("tolerance", number(c.tolerance).as_str()));
        if let Some(cause) = &c.cause {
            case.add_property(("cause", cause.as_str()));
        }
        suite.add_test_case(case);
    }
    let mut report = Report::new("crosscheck run");
    report.add_test_suite(suite);
    report.to_string().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(engine: &str, verdict: Verdict, tolerance: Option<f64>) -> Cell {
        Cell {
            case: "springs_grounded_a".into(),
            engine: engine.into(),
            against: "analytic".into(),
            error: Some(2e-3),
            tolerance,
            verdict,
            cause: Some("time step & <penalty>".into()),
            failure: None,
        }
    }

    /// The gate: a miss or a failed judged run fails it for its engine, nothing else does.
    #[test]
    fn the_gate_fails_on_misses_of_the_engines_named() {
        let missed = cell("rapier_f64", Verdict::Missed, Some(1e-3));
        let met = cell("explicit", Verdict::Met, Some(1e-2));
        let free = cell("explicit", Verdict::NoTolerance, None);
        let broke = cell("explicit", Verdict::Failed, Some(1e-2));
        assert!(fails_gate(&missed, &[]));
        assert!(fails_gate(&missed, &["rapier_f64".into()]));
        assert!(!fails_gate(&missed, &["explicit".into()]));
        assert!(!fails_gate(&met, &[]));
        assert!(!fails_gate(&free, &[]));
        assert!(fails_gate(&broke, &["explicit".into()]));
    }

    /// The XML parses, holds one test case per cell with the verdict's element, and escapes
    /// what XML forbids in text.
    #[test]
    fn junit_has_a_test_case_per_cell() {
        let cells = [
            cell("explicit", Verdict::Met, Some(1e-2)),
            cell("rapier_f64", Verdict::Missed, Some(1e-3)),
            cell("rapier_f32", Verdict::NoTolerance, None),
        ];
        let xml = junit(&cells, &|_, e| (e == "explicit").then_some(0.25));
        let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
        let cases: Vec<_> = doc
            .descendants()
            .filter(|n| n.has_tag_name("testcase"))
            .collect();
        assert_eq!(cases.len(), 3);
        assert_eq!(cases[0].attribute("time"), Some("0.250"));
        assert!(cases[1].children().any(|n| n.has_tag_name("failure")));
        assert!(cases[2].children().any(|n| n.has_tag_name("skipped")));
        let message = cases[1]
            .children()
            .find(|n| n.has_tag_name("failure"))
            .and_then(|n| n.attribute("message"))
            .unwrap();
        assert!(
            message.contains("tolerance 1.00e-3; cause: time step & <penalty>"),
            "{message}"
        );
    }
}
