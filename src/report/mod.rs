//! Writing results: the files other tools and people read.
//!
//! - [`data`]: the time histories, one CSV per case and engine (the spec's output contract);
//! - [`summary`]: `summary.json`, every metric per case and engine;
//! - [`markdown`]: `REPORT.md`, rendered from the same summary.

pub mod data;
pub mod markdown;
pub mod summary;

use crate::run::{Outcome, Plan};
use std::path::{Path, PathBuf};
use summary::Summary;

/// Write `summary.json` and `REPORT.md` for a run into `plan.out`; returns the summary.
pub fn write(plan: &Plan, outcome: &Outcome) -> Result<Summary, data::DataError> {
    let summary = Summary::build(plan, outcome);
    data::write_atomic(&summary_path(&plan.out), summary.to_json().as_bytes())?;
    data::write_atomic(
        &report_path(&plan.out),
        markdown::render(&summary).as_bytes(),
    )?;
    Ok(summary)
}

/// `out/summary.json`.
pub fn summary_path(out: &Path) -> PathBuf {
    out.join("summary.json")
}

/// `out/REPORT.md`.
pub fn report_path(out: &Path) -> PathBuf {
    out.join("REPORT.md")
}
