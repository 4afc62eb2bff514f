//! `summary.json`: every metric of a run, per case and engine, with what each run used and
//! cost. REPORT.md is rendered from the same [`Summary`], so their numbers agree.

use crate::comparison::{self, Comparison, ContactValidity, REFERENCE_ENGINE};
use crate::engines::History;
use crate::report::data::{csv_path, read_history};
use crate::run::{Outcome, Plan};
use crate::scene::{Dimension, Scene};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The whole run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// `crosscheck <version>`.
    pub generator: String,
    /// Engines run, in report order.
    pub engines: Vec<String>,
    /// Per case, in report order.
    pub cases: Vec<CaseSummary>,
}

/// One case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseSummary {
    /// Case id.
    pub id: String,
    /// One-line description.
    pub title: String,
    /// Output family.
    pub family: String,
    /// 2 or 3.
    pub dimension: u8,
    /// Duration of the dynamic steps.
    pub duration: f64,
    /// What the closed form says about contact (rigid-contact cases).
    pub contact: Option<ContactValidity>,
    /// `explicit` (finite rotation) measured against `explicit_small` (the closed form's
    /// small-rotation model, same integrator): the model-form gap, free of solver error.
    pub finite_vs_small: Option<Comparison>,
    /// Per engine, in report order.
    pub runs: Vec<EngineSummary>,
}

/// One engine on one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EngineSummary {
    /// Engine name.
    pub engine: String,
    /// Why the run failed, if it did.
    pub error: Option<String>,
    /// Time increment used (0 for closed forms).
    pub increment: Option<f64>,
    /// Increments taken.
    pub steps: Option<u64>,
    /// Stable increment the engine computed.
    pub stable_increment: Option<f64>,
    /// Penalty stiffness used.
    pub penalty_stiffness: Option<f64>,
    /// Work counters.
    pub counters: BTreeMap<String, u64>,
    /// Errors against the closed form.
    pub against_analytic: Option<Comparison>,
    /// The tolerance the case declares for this engine.
    pub tolerance: Option<f64>,
    /// Whether `against_analytic.worst_max` ≤ `tolerance`.
    pub meets_tolerance: Option<bool>,
}

impl Summary {
    /// Build from a run's plan and outcome.
    ///
    /// Histories of engines this run did not include are read from the CSVs already in
    /// `plan.out` (a run of some engines still compares against the analytic answer on disk).
    pub fn build(plan: &Plan, outcome: &Outcome) -> Summary {
        let history = |case: &str, engine: &str| -> Option<History> {
            match outcome
                .jobs
                .iter()
                .find(|j| j.case == case && j.engine == engine)
            {
                Some(j) => j.result.as_ref().ok().map(|s| s.history.clone()),
                None => read_history(&csv_path(&plan.out, case, engine)).ok(),
            }
        };
        let cases = plan
            .cases
            .iter()
            .map(|scene| {
                let reference = history(&scene.id, REFERENCE_ENGINE);
                let reference = reference.as_ref();
                let runs = outcome
                    .jobs
                    .iter()
                    .filter(|j| j.case == scene.id)
                    .map(|j| engine_summary(scene, j, reference))
                    .collect();
                CaseSummary {
                    id: scene.id.clone(),
                    title: scene.title.clone(),
                    family: scene.family.name().to_string(),
                    dimension: match scene.dimension {
                        Dimension::Two => 2,
                        Dimension::Three => 3,
                    },
                    duration: scene.duration(),
                    contact: reference.and_then(comparison::contact_validity),
                    finite_vs_small: match (
                        history(&scene.id, "explicit_small"),
                        history(&scene.id, "explicit"),
                    ) {
                        (Some(small), Some(finite)) => {
                            Some(comparison::compare(scene, &small, &finite))
                        }
                        _ => None,
                    },
                    runs,
                }
            })
            .collect();
        Summary {
            generator: format!("crosscheck {}", env!("CARGO_PKG_VERSION")),
            engines: plan.engines.iter().map(|e| e.name().to_string()).collect(),
            cases,
        }
    }

    /// Keep what `previous` had for cases and engines this summary lacks (a run of some cases or
    /// engines must not lose the others' results).
    pub fn merge_previous(&mut self, previous: Summary) {
        for old_case in previous.cases {
            match self.cases.iter_mut().find(|c| c.id == old_case.id) {
                None => self.cases.push(old_case),
                Some(case) => {
                    for old_run in old_case.runs {
                        if !case.runs.iter().any(|r| r.engine == old_run.engine) {
                            case.runs.push(old_run);
                        }
                    }
                    if case.finite_vs_small.is_none() {
                        case.finite_vs_small = old_case.finite_vs_small;
                    }
                }
            }
        }
        for e in previous.engines {
            if !self.engines.contains(&e) {
                self.engines.push(e);
            }
        }
        // Report order: cases by id, engines as `engines::all()` lists them.
        let canonical: Vec<String> = crate::engines::all()
            .iter()
            .map(|e| e.name().to_string())
            .collect();
        let order = |name: &str| {
            canonical
                .iter()
                .position(|e| e == name)
                .unwrap_or(usize::MAX)
        };
        self.engines.sort_by_key(|e| order(e));
        self.cases.sort_by(|a, b| a.id.cmp(&b.id));
        for c in &mut self.cases {
            c.runs.sort_by_key(|r| order(&r.engine));
        }
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a summary serialises") + "\n"
    }

    /// Every (case, engine, tolerance, measured) check, and whether it passed.
    pub fn tolerance_checks(&self) -> Vec<(&str, &str, f64, f64, bool)> {
        self.cases
            .iter()
            .flat_map(|c| {
                c.runs.iter().filter_map(move |r| {
                    let measured = r.against_analytic.as_ref()?.worst_max;
                    Some((
                        c.id.as_str(),
                        r.engine.as_str(),
                        r.tolerance?,
                        measured,
                        r.meets_tolerance?,
                    ))
                })
            })
            .collect()
    }
}

fn engine_summary(
    scene: &Scene,
    job: &crate::run::JobResult,
    reference: Option<&History>,
) -> EngineSummary {
    let tolerance = comparison::tolerance(scene, &job.engine);
    match &job.result {
        Err(e) => EngineSummary {
            engine: job.engine.clone(),
            error: Some(e.clone()),
            increment: None,
            steps: None,
            stable_increment: None,
            penalty_stiffness: None,
            counters: BTreeMap::new(),
            against_analytic: None,
            tolerance,
            meets_tolerance: tolerance.map(|_| false),
        },
        Ok(s) => {
            let against = (job.engine != REFERENCE_ENGINE)
                .then(|| reference.map(|r| comparison::compare(scene, r, &s.history)))
                .flatten();
            let meets = match (&against, tolerance) {
                (Some(c), Some(t)) => Some(c.worst_max <= t),
                _ => None,
            };
            EngineSummary {
                engine: job.engine.clone(),
                error: None,
                increment: Some(s.info.increment),
                steps: Some(s.info.steps),
                stable_increment: s.info.stable_increment,
                penalty_stiffness: s.info.penalty_stiffness,
                counters: s.info.counters.clone(),
                against_analytic: against,
                tolerance,
                meets_tolerance: meets,
            }
        }
    }
}
