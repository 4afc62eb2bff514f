//! Bounded runs: before anything runs, each job's increments, output rows and memory are
//! estimated and checked against [`Limits`]; a plan above them is refused with the figures.
//!
//! No engine keeps per-step data, so a job's memory is its output history (rows × columns ×
//! 8 bytes, kept until the report is written, plus as much again while its CSV is formatted)
//! and a small, step-independent working set; its time is proportional to its increments.

use super::{Plan, matching};
use crate::contract;
use crate::engines::RunSettings;

/// Resource limits of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Increments of one job.
    pub max_increments: f64,
    /// Output rows of one case.
    pub max_rows: usize,
    /// Bytes of output histories held by the whole run.
    pub max_memory_bytes: f64,
}

impl Default for Limits {
    /// 1e9 increments per job (minutes of work for the explicit engine, hours for rapier),
    /// 1e6 rows per case, 1 GiB of histories.
    fn default() -> Self {
        Limits {
            max_increments: 1e9,
            max_rows: 1_000_000,
            max_memory_bytes: (1u64 << 30) as f64,
        }
    }
}

/// Columns an engine may add after the contract's (energies, validity).
const ADDED_COLUMNS: usize = contract::ENERGY_COLUMNS.len() + 1;

/// The estimated bytes a history of `rows` rows and `columns` columns needs while it is held and
/// written.
pub fn history_bytes(rows: usize, columns: usize) -> f64 {
    2.0 * rows as f64 * (columns + 1 + ADDED_COLUMNS) as f64 * 8.0
}

/// Check every job of `plan` against `limits`; one message per refusal, with the figures and
/// the option that raises the limit.
pub fn check(plan: &Plan, settings: &RunSettings, limits: &Limits) -> Vec<String> {
    let mut refusals = Vec::new();
    let mut memory = 0.0;
    for scene in &plan.cases {
        if scene.output_rows > limits.max_rows {
            refusals.push(format!(
                "case {}: {} output rows exceed the limit of {} (--max-rows)",
                scene.id, scene.output_rows, limits.max_rows
            ));
            continue;
        }
        memory += history_bytes(scene.output_rows, scene.columns.len()) * plan.engines.len() as f64;
        for engine in &plan.engines {
            let job = matching::job_settings(engine.as_ref(), scene, settings);
            let Some(n) = engine.increments(scene, &job) else {
                continue;
            };
            if n.is_nan() || n > limits.max_increments {
                refusals.push(format!(
                    "case {} / {}: {n:.3e} increments (duration {:e} s) exceed the limit of {:.0e} (--max-increments)",
                    scene.id,
                    engine.name(),
                    scene.duration(),
                    limits.max_increments
                ));
            }
        }
    }
    if memory > limits.max_memory_bytes {
        refusals.push(format!(
            "the run's histories need about {:.3e} bytes, above the limit of {:.3e} (--max-memory; fewer cases, engines or rows)",
            memory, limits.max_memory_bytes
        ));
    }
    refusals
}
