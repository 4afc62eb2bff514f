//! Reports of shards (`crosscheck run --partition k/n`, each a whole report of its share of
//! the cases) merged into the report one run over all their cases writes: each case's files as
//! its shard wrote them, the study CSVs' rows in one run's order, the summaries joined, and
//! what is drawn or written from the whole (the family budgets, the rebounds, the stability
//! figures, the verdicts, the pages) made again from the joined data.

use super::data::DataError;
use super::{Previous, Timings};
use crate::comparison::summary::{SCHEMA_VERSION, Summary};
use std::path::{Path, PathBuf};

/// Why shards cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A directory that holds no report.
    #[error("{0}: not a crosscheck report (no readable summary.json)")]
    NotAReport(PathBuf),
    /// A report of another layout.
    #[error("{path}: summary.json has schema version {found}; this build reads {SCHEMA_VERSION}")]
    Schema {
        /// The shard.
        path: PathBuf,
        /// Its version.
        found: u32,
    },
    /// A case in two shards: they are not shards of one run (or one was written over a
    /// previous report).
    #[error(
        "case `{case}` is in both {first} and {second}: shards of one run hold disjoint cases \
         (write each shard into a directory of its own)"
    )]
    Overlap {
        /// The case.
        case: String,
        /// The first shard holding it.
        first: PathBuf,
        /// The second.
        second: PathBuf,
    },
    /// No shard given.
    #[error("no shard to merge")]
    Empty,
    /// Reports that are not the shards of one partitioned run, or not all of them.
    #[error("{0}")]
    NotShards(String),
    /// A file could not be copied or written.
    #[error(transparent)]
    Data(#[from] DataError),
}

/// Each shard's summary, checked: a report of this layout, no case in two shards.
fn summaries(shards: &[PathBuf]) -> Result<Vec<Summary>, MergeError> {
    let mut read: Vec<Summary> = Vec::new();
    for dir in shards {
        let summary: Summary = super::read_json(&super::summary_path(dir))
            .ok_or_else(|| MergeError::NotAReport(dir.clone()))?;
        if summary.schema_version != SCHEMA_VERSION {
            return Err(MergeError::Schema {
                path: dir.clone(),
                found: summary.schema_version,
            });
        }
        for (earlier, dir_before) in read.iter().zip(shards) {
            if let Some(case) = summary
                .cases
                .iter()
                .find(|c| earlier.cases.iter().any(|e| e.id == c.id))
            {
                return Err(MergeError::Overlap {
                    case: case.id.clone(),
                    first: dir_before.clone(),
                    second: dir.clone(),
                });
            }
        }
        read.push(summary);
    }
    whole(shards, &read)?;
    Ok(read)
}

/// Whether the shards make one partitioned run, whole: each says it is a shard, all of the
/// same run (the same shard count, cases and engines), and together they hold every case of
/// it (a shard with no case writes no report).
fn whole(shards: &[PathBuf], read: &[Summary]) -> Result<(), MergeError> {
    let mut first: Option<&crate::comparison::summary::Shard> = None;
    for (dir, summary) in shards.iter().zip(read) {
        let Some(shard) = &summary.shard else {
            return Err(MergeError::NotShards(format!(
                "{} is a whole run's report, not a shard of one (run --partition k/n)",
                dir.display()
            )));
        };
        match first {
            None => first = Some(shard),
            Some(f) if (f.n, &f.cases, &f.engines) != (shard.n, &shard.cases, &shard.engines) => {
                return Err(MergeError::NotShards(format!(
                    "{} is a shard of another run than {} (its shard count, cases or engines \
                     differ)",
                    dir.display(),
                    shards[0].display()
                )));
            }
            Some(_) => {}
        }
    }
    let Some(run) = first else {
        return Err(MergeError::Empty);
    };
    let held = |id: &String| read.iter().any(|s| s.cases.iter().any(|c| c.id == *id));
    let missing: Vec<&str> = run
        .cases
        .iter()
        .filter(|id| !held(id))
        .map(String::as_str)
        .collect();
    if !missing.is_empty() {
        return Err(MergeError::NotShards(format!(
            "{} of the run's {} cases are in no shard given (a shard is missing: {}{})",
            missing.len(),
            run.cases.len(),
            missing
                .iter()
                .take(5)
                .copied()
                .collect::<Vec<_>>()
                .join(", "),
            if missing.len() > 5 { ", …" } else { "" }
        )));
    }
    Ok(())
}

/// Link (or copy) a shard's files of one case into `out`: its histories and budgets, and its
/// figures (`figures/<case>.*`). Its page is written again from the joined summary.
fn case_files(shard: &Path, case: &str, out: &Path) -> std::io::Result<()> {
    let data = shard.join("data").join(case);
    if data.is_dir() {
        std::fs::create_dir_all(out.join("data"))?;
        super::staging::link_tree(&data, &out.join("data").join(case))?;
    }
    let prefix = format!("{case}.");
    let Ok(figures) = std::fs::read_dir(shard.join("figures")) else {
        return Ok(());
    };
    std::fs::create_dir_all(out.join("figures"))?;
    for entry in figures.flatten() {
        let name = entry.file_name();
        if name.to_string_lossy().starts_with(&prefix) {
            super::staging::link_tree(&entry.path(), &out.join("figures").join(&name))?;
        }
    }
    Ok(())
}

/// The study CSVs of the shards as one run writes them: `sweep.csv` and `on_request.csv` by
/// case (each case's rows as its shard wrote them), `stability.csv` by engine then case.
fn study_files(shards: &[PathBuf], out: &Path) -> Result<(), DataError> {
    use super::{on_request, stability, work_precision};
    let mut sweep: Vec<crate::comparison::work_precision::Row> = shards
        .iter()
        .flat_map(|d| work_precision::read(&work_precision::csv_path(d)).unwrap_or_default())
        .collect();
    sweep.sort_by(|a, b| a.case.cmp(&b.case));
    if !sweep.is_empty() {
        super::data::write_atomic(
            &work_precision::csv_path(out),
            work_precision::csv(&sweep).as_bytes(),
        )?;
    }
    let mut requests: Vec<_> = shards.iter().flat_map(|d| on_request::read(d)).collect();
    requests.sort_by(|a, b| a.case.cmp(&b.case));
    if !requests.is_empty() {
        super::data::write_atomic(
            &on_request::csv_path(out),
            on_request::csv(&requests).as_bytes(),
        )?;
    }
    let maps = shards.iter().map(|d| stability::read_all(d)).collect();
    stability::write_whole(out, &stability::merged(maps))
}

/// Merge the reports in `shards` into `out` (a staging directory, empty of report entries);
/// `previous` is the report it will replace (for "since the previous report"). Returns the
/// joined summary.
pub fn merge(shards: &[PathBuf], out: &Path, previous: &Path) -> Result<Summary, MergeError> {
    let read = summaries(shards)?;
    for (shard, held) in shards.iter().zip(&read) {
        for case in &held.cases {
            case_files(shard, &case.id, out).map_err(|source| DataError::Io {
                path: shard.join("data").join(&case.id),
                source,
            })?;
        }
    }
    let mut read = read.into_iter();
    let mut summary = read.next().ok_or(MergeError::Empty)?;
    let engines = summary.shard.take().map(|s| s.engines).unwrap_or_default();
    for other in read {
        summary.merge_previous(other);
    }
    // As one run writes them: the sweep's cost checks case by case, the engines in the run's
    // order (that of `--engines`).
    summary.checks.sort_by(|a, b| a.case.cmp(&b.case));
    let order = |e: &str| engines.iter().position(|x| x == e).unwrap_or(engines.len());
    summary.engines.sort_by_key(|e| order(e));
    for case in &mut summary.cases {
        case.runs.sort_by_key(|r| order(&r.engine));
    }
    study_files(shards, out)?;
    let mut timings = Timings::new();
    for shard in shards {
        let t: Timings = super::read_json(&super::timings_path(shard)).unwrap_or_default();
        timings.extend(t);
    }
    #[cfg(feature = "figures")]
    super::write_summary_figures(out, &summary)?;
    let settings = crate::engines::RunSettings::default();
    let previous = Previous {
        dir: previous,
        settings: &settings,
        parts: &[],
    };
    super::publish(out, &summary, &timings, &previous)?;
    Ok(summary)
}
