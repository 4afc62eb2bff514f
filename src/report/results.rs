//! `results.csv`: the verdicts as tidy data, one row per case, engine and contract column:
//! each engine's largest error against the exact solution of its own model, with its unit, the
//! column's peak, the rows compared and the case's tolerance. Read with any CSV tool; the
//! columns and units are documented in the report directory's `README.md`.

use crate::comparison::summary::Summary;
use crate::comparison::verdict;
use crate::report::format::csv_finite as number;
use std::path::{Path, PathBuf};

/// The header.
pub const COLUMNS: [&str; 11] = [
    "case",
    "engine",
    "column",
    "unit",
    "against",
    "error",
    "relative",
    "peak",
    "rows_compared",
    "tolerance",
    "pass",
];

/// `out/results.csv`.
pub fn csv_path(out: &Path) -> PathBuf {
    out.join("results.csv")
}

/// The summary's comparisons as CSV text. `error` is the largest error over the column's
/// `peak` where `relative` is true, in the column's `unit` where it is false (a column whose
/// exact solution is zero over the compared rows); `tolerance` and `pass` apply to relative
/// columns of engines judged by a tolerance (empty otherwise, and for the exact solutions
/// compared with each other: the model-form gap, no engine's error).
pub fn csv(s: &Summary) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(COLUMNS);
    for c in &s.cases {
        for r in &c.runs {
            let (Some(a), Some(against)) = (&r.against_baseline, &r.baseline) else {
                continue;
            };
            let judged = !crate::comparison::EXACT_SOLUTIONS.contains(&r.engine.as_str());
            for col in &a.columns {
                let tolerance = r.tolerance.filter(|_| judged && col.relative);
                let _ = w.write_record([
                    c.id.as_str(),
                    &r.engine,
                    &col.column,
                    &col.unit,
                    against,
                    &number(col.max),
                    if col.relative { "true" } else { "false" },
                    &if col.relative {
                        number(col.peak)
                    } else {
                        String::new()
                    },
                    &a.rows.to_string(),
                    &tolerance.map_or(String::new(), number),
                    tolerance.map_or("", |t| {
                        if verdict::within(col.max, t) {
                            "true"
                        } else {
                            "false"
                        }
                    }),
                ]);
            }
        }
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}
