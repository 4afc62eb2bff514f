//! A run judged: every metric and verdict of a run, per case and engine, with what each run
//! used and cost, decided by [`super::verdict`]'s rules. The report writes it as
//! `summary.json` and renders REPORT.md from it, so their numbers agree; it decides nothing.

use crate::comparison::attribution::Attribution;
use crate::comparison::contact::{self, Impacts};
use crate::comparison::discrepancy::{ColumnBudget, JobBudget, PARTS};
use crate::comparison::equivalence::{self, Equivalence};
use crate::comparison::verdict::cost::CostToAccuracy;
use crate::comparison::work_precision::{CaseSweep, Floor, ObservedOrder};
use crate::comparison::{self, CLOSED_FORM, Comparison, ContactValidity, verdict};
use crate::contract::History;
use crate::run::{JobResult, Outcome, Plan, Status};
use crate::scene::{Dimension, Scene};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The whole run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The version of this file's layout ([`SCHEMA_VERSION`]; 0: written before it had one).
    #[serde(default)]
    pub schema_version: u32,
    /// `crosscheck <version>`.
    pub generator: String,
    /// Engines run, in report order.
    pub engines: Vec<String>,
    /// Per case, in report order.
    pub cases: Vec<CaseSummary>,
    /// Cases that are the same problem built another way, each measured against its
    /// equivalent in every engine ([`crate::comparison::equivalence`]).
    #[serde(default)]
    pub equivalences: Vec<Equivalence>,
    /// Parameters a case's exact solution ignores, each cell run at both of their values
    /// ([`crate::comparison::invariance`]).
    #[serde(default)]
    pub invariances: Vec<crate::comparison::invariance::Invariance>,
    /// Extrapolated costs checked by runs at the increment they predict
    /// ([`crate::comparison::reach`]).
    #[serde(default)]
    pub checks: Vec<crate::comparison::reach::Check>,
    /// The shard of a partitioned run this report is (`run --partition k/n`); absent in a
    /// whole run's report.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
}

/// What a shard of a partitioned run says of the whole it is part of, for the merge to check
/// that its shards make one run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, from 1.
    pub k: usize,
    /// How many shards.
    pub n: usize,
    /// Every case of the whole run, by id.
    pub cases: Vec<String>,
    /// The run's engines, in its order.
    pub engines: Vec<String>,
}

/// The layout of `summary.json` this build writes. 1: `schema_version`, `cost_to_accuracy`
/// and `critical_increment` on each run; 2: each run's typed `status`, the critical
/// increment's `own_step`, orientation compared as a rotation.
pub const SCHEMA_VERSION: u32 = 2;

/// Pairs of engines compared with each other, (candidate, reference):
/// - `explicit` against `explicit_small`: finite against small rotation, same integrator: the
///   model-form gap, free of solver error;
/// - `rapier_f64` against `explicit`: the independent engine against ours;
/// - `rapier_f32` against `rapier_f64`: single-precision round-off;
/// - `rapier_f64_default` against `rapier_f64`: what default settings cost.
pub const CROSS_CHECKS: [(&str, &str); 4] = [
    ("explicit", "explicit_small"),
    ("rapier_f64", "explicit"),
    ("rapier_f32", "rapier_f64"),
    ("rapier_f64_default", "rapier_f64"),
];

/// One engine measured against another on one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrossCheck {
    /// The engine measured.
    pub candidate: String,
    /// The engine it is measured against.
    pub reference: String,
    /// The metrics, relative to the reference's peaks.
    pub comparison: Comparison,
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
    /// Engines measured against each other (see [`CROSS_CHECKS`]).
    #[serde(default)]
    pub cross: Vec<CrossCheck>,
    /// Per engine, in report order.
    pub runs: Vec<EngineSummary>,
    /// The tolerance the run asked each engine for (accuracy on request: `--tolerance`, or
    /// `[time] tolerance` in the case file), where it asked one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub requested: Option<f64>,
    /// The scene's own scale in each output column's unit ([`comparison::scene_scales`]):
    /// what `crosscheck compare` reads a change of a column with a smaller peak against.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub scales: BTreeMap<String, f64>,
}

/// One engine on one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EngineSummary {
    /// Engine name.
    pub engine: String,
    /// How the run came out (typed): what every verdict reads.
    pub status: Status,
    /// Why the run did not finish, in the engine's words, if it did not.
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
    /// Quantities the engine measured about its own run (e.g. contact penetration).
    #[serde(default)]
    pub measures: BTreeMap<String, f64>,
    /// Errors against the closed form (the total error, model form included).
    pub against_analytic: Option<Comparison>,
    /// The exact solution this engine is judged against: its own model's
    /// ([`comparison::baseline`]), or the closed form where that did not run.
    #[serde(default)]
    pub baseline: Option<String>,
    /// Errors against the baseline.
    #[serde(default)]
    pub against_baseline: Option<Comparison>,
    /// The tolerance the case declares for this engine (on the error against its baseline).
    pub tolerance: Option<f64>,
    /// Whether `against_baseline.worst_max` ≤ `tolerance`.
    pub meets_tolerance: Option<bool>,
    /// The discrepancy budget's norms per contract column
    /// ([`comparison::discrepancy`]; the histories are in `data/<case>/<engine>.budget.csv`).
    #[serde(default)]
    pub budget: Option<Vec<ColumnBudget>>,
    /// Why this run has no budget, where it should have one.
    #[serde(default)]
    pub budget_error: Option<String>,
    /// The observed order of convergence in the time increment, from the sweep
    /// ([`crate::comparison::work_precision`]; None where the run had no sweep or the sweep no
    /// asymptotic range).
    #[serde(default)]
    pub observed_order: Option<f64>,
    /// How the order was fitted: the path, its range of increments and its points.
    #[serde(default)]
    pub order_fit: Option<ObservedOrder>,
    /// Where the sweep stopped improving (value and named cause), where it did.
    #[serde(default)]
    pub floor: Option<Floor>,
    /// Contact that opens and closes: impact times, energy per impact, first rebound
    /// ([`comparison::contact`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impacts: Option<Impacts>,
    /// A case with friction: when the node moves and rests, where it ends, how far it strays
    /// where the exact solution does not move, beside the exact solution's
    /// ([`comparison::friction`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<comparison::friction::FrictionEvents>,
    /// Why this cell misses its tolerance, or is far from `explicit`: its controls and the
    /// cause they show ([`crate::comparison::attribution`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attribution: Option<Attribution>,
    /// What reaching 1e-2, 1e-4 and 1e-6 of the peak costs, from the sweep (measured,
    /// extrapolated along the observed order, or the floor that stops it).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cost_to_accuracy: Vec<CostToAccuracy>,
    /// The largest increment that stays bounded, from the stability map, bisected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub critical_increment: Option<CriticalIncrement>,
    /// Where the stability map's runs stopped with an error: such a pair has no critical
    /// increment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stability_failure: Option<StabilityFailure>,
}

/// The stability map's runs of a pair that stopped with an error (not as unstable).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StabilityFailure {
    /// The lowest ratio to the explicit engine's stable increment at which a run failed.
    pub lowest_ratio: f64,
    /// That run's error, in the engine's words.
    pub error: Option<String>,
    /// Whether the map's run at the increment the engine's job ran at stayed bounded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounded_at_own_step: Option<bool>,
}

/// The largest increment at which a run stays bounded ([`super::stability::Critical`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CriticalIncrement {
    /// Seconds.
    pub seconds: f64,
    /// Over the explicit engine's computed stable increment.
    pub explicit_ratio: f64,
    /// `bisected` (to 1 %), `at_least` (bounded up to the largest ratio tried) or `below`
    /// (unstable down to the smallest).
    pub bound: super::stability::Bound,
    /// The largest increment the engine runs at anywhere in the report, seconds: an
    /// `at_least` bound below it says nothing of the engine's own runs.
    #[serde(default)]
    pub own_step: f64,
    /// Whether the map's run at the increment the engine's job ran at stayed bounded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounded_at_own_step: Option<bool>,
}

impl CriticalIncrement {
    /// Whether it answers the question for the engine's own runs (see
    /// [`super::stability::Critical::covers_own_step`]).
    pub fn covers_own_step(&self) -> bool {
        super::stability::covers(self.bound, self.seconds, self.own_step)
    }
}

impl CaseSummary {
    /// The run of `engine` on this case, where it ran.
    pub fn run(&self, engine: &str) -> Option<&EngineSummary> {
        self.runs.iter().find(|r| r.engine == engine)
    }
}

impl EngineSummary {
    /// The budget's worst column (largest total) and its dominant part (name, norm): the source
    /// that explains most of the discrepancy.
    pub fn dominant_source(&self) -> Option<(&ColumnBudget, &'static str, f64)> {
        let worst = self
            .budget
            .as_ref()?
            .iter()
            .filter(|c| c.relative)
            .max_by(|a, b| a.total.total_cmp(&b.total))?;
        let (k, norm) = worst
            .parts()
            .into_iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        Some((worst, PARTS[k + 1], norm))
    }
}

impl Summary {
    /// Build from a run's plan and outcome.
    ///
    /// Histories of engines this run did not include come from `earlier` (the report's CSVs
    /// from an earlier run: a run of some engines still compares against the analytic answer on
    /// disk); a failed job whose history from an earlier run is still there says so.
    pub fn build(
        plan: &Plan,
        outcome: &Outcome,
        earlier: &dyn Fn(&str, &str) -> Option<History>,
    ) -> Summary {
        let history = |case: &str, engine: &str| -> Option<History> {
            match outcome
                .jobs
                .iter()
                .find(|j| j.case == case && j.engine == engine)
            {
                Some(j) => j.result.as_ref().ok().map(|s| s.history.clone()),
                None => earlier(case, engine),
            }
        };
        let cases = plan
            .cases
            .iter()
            .map(|scene| {
                let reference = history(&scene.id, CLOSED_FORM);
                let reference = reference.as_ref();
                let runs = outcome
                    .jobs
                    .iter()
                    .filter(|j| j.case == scene.id)
                    .map(|j| {
                        let stale = !j.is_ok() && earlier(&j.case, &j.engine).is_some();
                        // The engine's own model's exact solution, or the closed form where
                        // that is missing (the reference refused the scene, or did not run).
                        let baseline = comparison::baseline(&j.engine).and_then(|b| {
                            if b == CLOSED_FORM {
                                reference.map(|h| (b, h.clone()))
                            } else {
                                history(&scene.id, b)
                                    .map(|h| (b, h))
                                    .or_else(|| reference.map(|h| (CLOSED_FORM, h.clone())))
                            }
                        });
                        engine_summary(scene, j, reference, baseline.as_ref(), stale)
                    })
                    .collect();
                let requested = match plan.settings.increment.unwrap_or(scene.settings.increment) {
                    crate::scene::IncrementRule::Tolerance(eps) => Some(eps),
                    _ => None,
                };
                CaseSummary {
                    requested,
                    scales: comparison::scene_scales(scene),
                    id: scene.id.clone(),
                    title: scene.title.clone(),
                    family: scene.family.name().to_string(),
                    dimension: match scene.dimension {
                        Dimension::Two => 2,
                        Dimension::Three => 3,
                    },
                    duration: scene.duration(),
                    contact: reference.and_then(comparison::contact_validity),
                    cross: CROSS_CHECKS
                        .iter()
                        .filter_map(|(candidate, reference)| {
                            let c = history(&scene.id, candidate)?;
                            let r = history(&scene.id, reference)?;
                            Some(CrossCheck {
                                candidate: candidate.to_string(),
                                reference: reference.to_string(),
                                comparison: comparison::compare(scene, &r, &c),
                            })
                        })
                        .collect(),
                    runs,
                }
            })
            .collect();
        let engines: Vec<String> = plan.engines.iter().map(|e| e.name().to_string()).collect();
        Summary {
            schema_version: SCHEMA_VERSION,
            generator: format!("crosscheck {}", env!("CARGO_PKG_VERSION")),
            equivalences: equivalence::measure(&plan.cases, &engines, history),
            invariances: Vec::new(),
            checks: Vec::new(),
            shard: None,
            engines,
            cases,
        }
    }

    /// Keep what `previous` had for cases and engines this summary lacks (a run of some cases or
    /// engines must not lose the others' results).
    pub fn merge_previous(&mut self, previous: Summary) {
        let ran: Vec<String> = self.cases.iter().map(|c| c.id.clone()).collect();
        for old_case in previous.cases {
            match self.cases.iter_mut().find(|c| c.id == old_case.id) {
                None => self.cases.push(old_case),
                Some(case) => {
                    for old_run in old_case.runs {
                        if !case.runs.iter().any(|r| r.engine == old_run.engine) {
                            case.runs.push(old_run);
                        }
                    }
                    for old in old_case.cross {
                        if !case
                            .cross
                            .iter()
                            .any(|c| c.candidate == old.candidate && c.reference == old.reference)
                        {
                            case.cross.push(old);
                        }
                    }
                }
            }
        }
        self.checks.extend(
            previous
                .checks
                .into_iter()
                .filter(|c| !ran.contains(&c.case)),
        );
        for old in previous.invariances {
            if !self
                .invariances
                .iter()
                .any(|i| i.case == old.case && i.parameter == old.parameter)
            {
                self.invariances.push(old);
            }
        }
        for old in previous.equivalences {
            if !self
                .equivalences
                .iter()
                .any(|e| e.case == old.case && e.same_as == old.same_as)
            {
                self.equivalences.push(old);
            }
        }
        for e in previous.engines {
            if !self.engines.contains(&e) {
                self.engines.push(e);
            }
        }
        // Report order: cases by id, engines as `crate::run::registry::all()` lists them.
        let canonical: Vec<String> = crate::run::engine_names();
        let order = |name: &str| {
            canonical
                .iter()
                .position(|e| e == name)
                .unwrap_or(usize::MAX)
        };
        self.engines.sort_by_key(|e| order(e));
        self.cases.sort_by(|a, b| a.id.cmp(&b.id));
        self.equivalences
            .sort_by(|a, b| (&a.same_as, &a.case).cmp(&(&b.same_as, &b.case)));
        self.invariances
            .sort_by(|a, b| (&a.case, &a.parameter).cmp(&(&b.case, &b.parameter)));
        for c in &mut self.cases {
            c.runs.sort_by_key(|r| order(&r.engine));
        }
    }

    /// The run entry of `engine` on `case`, where there is one.
    fn run_mut(&mut self, case: &str, engine: &str) -> Option<&mut EngineSummary> {
        self.cases
            .iter_mut()
            .filter(|c| c.id == case)
            .flat_map(|c| c.runs.iter_mut())
            .find(|r| r.engine == engine)
    }

    /// Put each job's budget norms (or why it has none) on its run entry.
    pub fn attach_budgets(&mut self, budgets: &[JobBudget]) {
        for b in budgets {
            if let Some(run) = self.run_mut(&b.case, &b.engine) {
                match &b.result {
                    Ok((basic, _)) => run.budget = Some(basic.columns.clone()),
                    Err(e) => run.budget_error = Some(e.clone()),
                }
            }
        }
    }

    /// Put each attributed cell's controls and cause on its run entry.
    pub fn attach_attributions(&mut self, attributions: &[Attribution]) {
        for a in attributions {
            if let Some(run) = self.run_mut(&a.case, &a.engine) {
                run.attribution = Some(a.clone());
            }
        }
    }

    /// Put each engine's observed order and floor from the sweeps on its run entry.
    pub fn attach_sweeps(&mut self, sweeps: &[CaseSweep]) {
        for sweep in sweeps {
            self.checks.retain(|c| c.case != sweep.case);
            self.checks.extend(sweep.checks.iter().cloned());
            for fit in &sweep.fits {
                if let Some(run) = self.run_mut(&sweep.case, &fit.engine) {
                    run.observed_order = fit.observed_order.as_ref().map(|o| o.value);
                    run.order_fit = fit.observed_order.clone();
                    run.floor = fit.floor.clone();
                    run.cost_to_accuracy = verdict::cost::costs(sweep, fit);
                }
            }
        }
    }

    /// Put each pair's critical increment, and whether its run at its own step stayed bounded,
    /// on its run.
    pub fn attach_critical(&mut self, map: &super::stability::Map) {
        for c in &map.critical {
            let own = map.points.iter().find(|p| {
                p.case == c.case
                    && p.engine == c.engine
                    && p.search == super::stability::Search::OwnStep
            });
            if let Some(run) = self.run_mut(&c.case, &c.engine) {
                run.critical_increment = Some(CriticalIncrement {
                    seconds: c.increment,
                    explicit_ratio: c.explicit_ratio(),
                    bound: c.bound,
                    own_step: c.own_step,
                    bounded_at_own_step: own.map(|p| p.outcome.bounded()),
                });
            }
        }
    }

    /// Put on each pair whose map runs stopped with an error the lowest ratio at which one did,
    /// and whether its run at its own step stayed bounded.
    pub fn attach_stability_failures(&mut self, map: &super::stability::Map) {
        use super::stability::Search;
        use super::verdict::growth::Outcome;
        for p in map.points.iter().filter(|p| p.outcome == Outcome::Failed) {
            let own = map
                .points
                .iter()
                .find(|o| o.case == p.case && o.engine == p.engine && o.search == Search::OwnStep);
            let Some(run) = self.run_mut(&p.case, &p.engine) else {
                continue;
            };
            let failure = run.stability_failure.get_or_insert(StabilityFailure {
                lowest_ratio: p.ratio,
                error: p.message.clone(),
                bounded_at_own_step: own.map(|o| o.outcome.bounded()),
            });
            if p.ratio < failure.lowest_ratio {
                failure.lowest_ratio = p.ratio;
                failure.error = p.message.clone();
            }
        }
    }

    /// A case's cross-check of `candidate` against `reference`, if both ran.
    pub fn cross<'a>(
        case: &'a CaseSummary,
        candidate: &str,
        reference: &str,
    ) -> Option<&'a Comparison> {
        case.cross
            .iter()
            .find(|c| c.candidate == candidate && c.reference == reference)
            .map(|c| &c.comparison)
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a summary serialises") + "\n"
    }

    /// Every cell that is judged, checked against its tolerance: each engine that is not an
    /// exact solution ([`comparison::EXACT_SOLUTIONS`]) on each case where it applies, i.e.
    /// where it ran and rows were compared against its baseline, or where it failed. A cell
    /// whose case declares no tolerance for the engine is counted too, as such. An engine on an
    /// older release of a third-party code (`rapier_f64@0.34`) is not: the report's versions
    /// section judges it against its current release's tolerance.
    pub fn tolerance_checks(&self) -> Vec<ToleranceCheck<'_>> {
        self.cases
            .iter()
            .flat_map(|c| {
                c.runs.iter().filter_map(move |r| {
                    // An engine on an older release is judged in the versions section.
                    if comparison::EXACT_SOLUTIONS.contains(&r.engine.as_str())
                        || crate::contract::on_older_release(&r.engine)
                    {
                        return None;
                    }
                    // Compared over no row: the engine does not apply there. A cell compared
                    // over rows but with no column with a peak is counted, unjudged.
                    let rows = r.against_baseline.as_ref().map(|a| a.rows);
                    if !verdict::is_cell(r.status, rows) {
                        return None;
                    }
                    let measured = r.against_baseline.as_ref().and_then(|a| a.worst_max);
                    Some(ToleranceCheck {
                        case: &c.id,
                        engine: &r.engine,
                        baseline: r.baseline.as_deref()?,
                        tolerance: r.tolerance,
                        measured,
                        met: r.meets_tolerance,
                    })
                })
            })
            .collect()
    }
}

/// One judged cell, checked against its tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToleranceCheck<'a> {
    /// Case id.
    pub case: &'a str,
    /// Engine.
    pub engine: &'a str,
    /// The exact solution the error is measured against.
    pub baseline: &'a str,
    /// Declared tolerance (max error over the peak), if the case declares one.
    pub tolerance: Option<f64>,
    /// Measured worst max error over the peak (`None`: the run failed, or no column compared
    /// has a peak).
    pub measured: Option<f64>,
    /// Whether measured ≤ tolerance (`None`: no tolerance declared).
    pub met: Option<bool>,
}

impl ToleranceCheck<'_> {
    /// Whether the cell meets a declared tolerance.
    pub fn met(&self) -> bool {
        self.met == Some(true)
    }
}

fn engine_summary(
    scene: &Scene,
    job: &JobResult,
    reference: Option<&History>,
    baseline: Option<&(&str, History)>,
    stale_csv: bool,
) -> EngineSummary {
    let tolerance = verdict::tolerance(scene, &job.engine);
    match &job.result {
        Err(e) => EngineSummary {
            engine: job.engine.clone(),
            status: job.status,
            error: Some(if stale_csv {
                format!("{e} (a CSV from an earlier run is still in place)")
            } else {
                e.clone()
            }),
            increment: None,
            steps: None,
            stable_increment: None,
            penalty_stiffness: None,
            counters: BTreeMap::new(),
            measures: BTreeMap::new(),
            against_analytic: None,
            baseline: baseline.map(|b| b.0.to_string()),
            against_baseline: None,
            tolerance,
            meets_tolerance: verdict::meets(job.status, None, tolerance),
            budget: None,
            budget_error: None,
            observed_order: None,
            order_fit: None,
            floor: None,
            impacts: None,
            friction: None,
            attribution: None,
            cost_to_accuracy: Vec::new(),
            critical_increment: None,
            stability_failure: None,
        },
        Ok(s) => {
            let against = (job.engine != CLOSED_FORM)
                .then(|| reference.map(|r| comparison::compare(scene, r, &s.history)))
                .flatten();
            let judged = baseline.map(|(_, b)| comparison::compare(scene, b, &s.history));
            let worst = judged.as_ref().and_then(|c| c.worst_max);
            let meets = verdict::meets(job.status, worst, tolerance);
            EngineSummary {
                engine: job.engine.clone(),
                status: job.status,
                error: None,
                increment: Some(s.info.increment),
                steps: Some(s.info.steps),
                stable_increment: s.info.stable_increment,
                penalty_stiffness: s.info.penalty_stiffness,
                counters: s.info.counters.clone(),
                measures: s.info.measures.clone(),
                against_analytic: against,
                baseline: baseline.map(|b| b.0.to_string()),
                against_baseline: judged,
                tolerance,
                meets_tolerance: meets,
                budget: None,
                budget_error: None,
                observed_order: None,
                order_fit: None,
                floor: None,
                impacts: contact::measure(scene, &s.history, &s.info.measures, s.info.increment),
                friction: baseline
                    .and_then(|(_, b)| comparison::friction::measure(scene, b, &s.history)),
                attribution: None,
                cost_to_accuracy: Vec::new(),
                critical_increment: None,
                stability_failure: None,
            }
        }
    }
}
