//! Judging a history from another code (Abaqus, Chrono, one's own solver) against a case's
//! exact solution, with the same comparison and verdict an engine gets.
//!
//! Their CSV has a header row and one row per output time; a time column (`t` unless named)
//! that increases strictly; a column for each of the case's contract columns (the same name
//! unless mapped, `OURS=THEIRS`), each optionally multiplied by a factor to convert its unit.
//! Their rows are interpolated linearly onto the case's output times: each of our times lies
//! between two of their rows (or on one), and a time before their first row or after their
//! last is refused, never extrapolated.

use crate::contract::{self, History};
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::path::Path;

/// What can be wrong with their CSV or the options; every message names the file, and the line
/// and column where there is one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JudgeError {
    /// The file cannot be read or is not CSV.
    #[error("{file}: {message}")]
    Unreadable {
        /// The file.
        file: String,
        /// Why.
        message: String,
    },
    /// A column the judgement needs is not in the header.
    #[error("{file}:1: no column `{column}` (needed for `{needed_for}`; the header has: {header})")]
    MissingColumn {
        /// The file.
        file: String,
        /// Their column name looked for.
        column: String,
        /// Ours it stands for (`t` for the time).
        needed_for: String,
        /// Their header.
        header: String,
    },
    /// A cell that is not a finite number.
    #[error("{file}:{line}: column `{column}`: `{cell}` is not a finite number")]
    Cell {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// Their column name.
        column: String,
        /// The cell's text.
        cell: String,
    },
    /// Time does not increase strictly.
    #[error(
        "{file}:{line}: column `{column}`: time {time:e} does not increase (previous row: {previous:e})"
    )]
    Time {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// Their time column.
        column: String,
        /// The time on this line.
        time: f64,
        /// The time on the line before.
        previous: f64,
    },
    /// One of the case's output times lies outside their rows.
    #[error(
        "{file}: the case's output time {time:e} s lies outside their rows ({first:e} s to {last:e} s): refusing to extrapolate"
    )]
    Outside {
        /// The file.
        file: String,
        /// Our time.
        time: f64,
        /// Their first time.
        first: f64,
        /// Their last time.
        last: f64,
    },
    /// An option names a column the case does not have.
    #[error("--{option}: `{column}` is not a contract column of {case} (its columns: {columns})")]
    UnknownColumn {
        /// The option.
        option: String,
        /// The column named.
        column: String,
        /// The case.
        case: String,
        /// Its contract columns.
        columns: String,
    },
}

/// How their CSV maps onto the case.
#[derive(Debug, Clone, Default)]
pub struct Mapping {
    /// Their time column (default `t`).
    pub time: Option<String>,
    /// Ours → theirs, where the names differ.
    pub columns: BTreeMap<String, String>,
    /// Ours → the factor that converts theirs to our unit.
    pub scales: BTreeMap<String, f64>,
}

/// Their history, read: the times and, per contract column of ours, their values (already
/// scaled), with the names they came from.
#[derive(Debug, Clone)]
pub struct External {
    /// Their times, strictly increasing.
    pub times: Vec<f64>,
    /// Per contract column: (our name, their name, the factor applied, the values).
    pub columns: Vec<(String, String, f64, Vec<f64>)>,
}

/// Where the case's output times fell among their rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Resampling {
    /// Their rows used (1-based data rows, the header not counted): the first and last.
    pub rows_used: (usize, usize),
    /// Output times that fell exactly on one of their rows.
    pub on_a_row: usize,
    /// Output times interpolated linearly between two of their rows.
    pub interpolated: usize,
}

fn contract_columns(scene: &Scene) -> Vec<String> {
    contract::columns(scene.family)
        .iter()
        .filter(|c| scene.columns.iter().any(|k| k.name == **c))
        .map(|c| c.to_string())
        .collect()
}

/// Check that every column an option names is one of the case's contract columns.
pub fn check_options(scene: &Scene, mapping: &Mapping) -> Result<(), JudgeError> {
    let ours = contract_columns(scene);
    let named = mapping
        .columns
        .keys()
        .map(|c| ("column", c))
        .chain(mapping.scales.keys().map(|c| ("scale", c)));
    for (option, column) in named {
        if !ours.contains(column) {
            return Err(JudgeError::UnknownColumn {
                option: option.to_string(),
                column: column.clone(),
                case: scene.id.clone(),
                columns: ours.join(", "),
            });
        }
    }
    Ok(())
}

/// Read their CSV `text` (named `path` in errors) for the case's contract columns.
pub fn read(
    scene: &Scene,
    text: &str,
    path: &Path,
    mapping: &Mapping,
) -> Result<External, JudgeError> {
    let file = path.display().to_string();
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| JudgeError::Unreadable {
            file: file.clone(),
            message: e.to_string(),
        })?
        .iter()
        .map(str::to_string)
        .collect();
    let find = |theirs: &str, ours: &str| {
        header
            .iter()
            .position(|h| h == theirs)
            .ok_or_else(|| JudgeError::MissingColumn {
                file: file.clone(),
                column: theirs.to_string(),
                needed_for: ours.to_string(),
                header: header.join(", "),
            })
    };
    let time_name = mapping.time.clone().unwrap_or_else(|| "t".to_string());
    let time_index = find(&time_name, "t")?;
    let mut wanted = Vec::new();
    for ours in contract_columns(scene) {
        let theirs = mapping
            .columns
            .get(&ours)
            .cloned()
            .unwrap_or_else(|| ours.clone());
        let index = find(&theirs, &ours)?;
        let scale = mapping.scales.get(&ours).copied().unwrap_or(1.0);
        wanted.push((ours, theirs, scale, index));
    }
    let mut times: Vec<f64> = Vec::new();
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); wanted.len()];
    for (k, record) in reader.records().enumerate() {
        let record = record.map_err(|e| JudgeError::Unreadable {
            file: file.clone(),
            message: match e.position() {
                Some(p) => format!("line {}: {e}", p.line()),
                None => format!("record {}: {e}", k + 1),
            },
        })?;
        // The line the record starts on in the file (blank lines are skipped, not counted
        // as records).
        let line = record.position().map_or(k + 2, |p| p.line() as usize);
        let cell = |index: usize, column: &str| -> Result<f64, JudgeError> {
            let text = record.get(index).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| JudgeError::Cell {
                    file: file.clone(),
                    line,
                    column: column.to_string(),
                    cell: text.to_string(),
                })
        };
        let t = cell(time_index, &time_name)?;
        if let Some(&previous) = times.last()
            && t <= previous
        {
            return Err(JudgeError::Time {
                file: file.clone(),
                line,
                column: time_name.clone(),
                time: t,
                previous,
            });
        }
        times.push(t);
        for (j, (_, theirs, scale, index)) in wanted.iter().enumerate() {
            values[j].push(scale * cell(*index, theirs)?);
        }
    }
    Ok(External {
        times,
        columns: wanted
            .into_iter()
            .zip(values)
            .map(|((ours, theirs, scale, _), v)| (ours, theirs, scale, v))
            .collect(),
    })
}

/// Their history on the times of `reference` (the case's output times), linearly
/// interpolated, as a [`History`] with our column names; refuses any time outside their rows.
pub fn resample(
    external: &External,
    reference: &History,
    path: &Path,
) -> Result<(History, Resampling), JudgeError> {
    let times = reference.column("t").unwrap_or_default();
    let (first, last) = match (external.times.first(), external.times.last()) {
        (Some(a), Some(b)) => (*a, *b),
        _ => (f64::NAN, f64::NAN),
    };
    // Round-off in their printed times: a relative 1e-9 of the span counts as on the end row.
    let slack = 1e-9 * (last - first).abs().max(f64::MIN_POSITIVE);
    let mut rows = Vec::with_capacity(times.len());
    let mut used = (usize::MAX, 0);
    let (mut on_a_row, mut interpolated) = (0, 0);
    for &t in &times {
        if !(t >= first - slack && t <= last + slack) {
            return Err(JudgeError::Outside {
                file: path.display().to_string(),
                time: t,
                first,
                last,
            });
        }
        let t = t.clamp(first, last);
        // The first of their rows at or after t.
        let j = external.times.partition_point(|x| *x < t);
        let mut row = vec![t];
        if external.times[j] == t {
            on_a_row += 1;
            used = (used.0.min(j), used.1.max(j));
            row.extend(external.columns.iter().map(|c| c.3[j]));
        } else {
            interpolated += 1;
            used = (used.0.min(j - 1), used.1.max(j));
            let (t0, t1) = (external.times[j - 1], external.times[j]);
            let w = (t - t0) / (t1 - t0);
            row.extend(
                external
                    .columns
                    .iter()
                    .map(|c| c.3[j - 1] + w * (c.3[j] - c.3[j - 1])),
            );
        }
        rows.push(row);
    }
    let mut columns = vec!["t".to_string()];
    columns.extend(external.columns.iter().map(|c| c.0.clone()));
    Ok((
        History { columns, rows },
        Resampling {
            rows_used: (used.0 + 1, used.1 + 1),
            on_a_row,
            interpolated,
        },
    ))
}
