//! Time histories on disk: `DIR/data/<case-id>/<engine>.csv`.
//!
//! A CSV has a header row (the history's columns, `t` first) and one row per output time.
//! Numbers are written with `{:e}`, Rust's shortest representation that reads back to the same
//! `f64`, so a file is deterministic and [`read_history`] recovers the history bit for bit.
//! Files are written atomically: a temporary file in the same directory is renamed into place, so
//! an interrupted run leaves either the old file or the new one, never half of one.

use super::format::csv_value;
use crate::contract::History;
use std::fs::{self, File};
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A history that could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// A signal arrived: nothing more is written.
    #[error("interrupted")]
    Interrupted,
    /// Filesystem error.
    #[error("{path}: {source}")]
    Io {
        /// File or directory concerned.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// CSV error (malformed file, or rows of unequal length).
    #[error("{path}: {source}")]
    Csv {
        /// File concerned.
        path: PathBuf,
        /// Cause.
        source: csv::Error,
    },
    /// A field that is not a number.
    #[error("{path}:{line}: column `{column}`: `{value}` is not a number")]
    Number {
        /// File concerned.
        path: PathBuf,
        /// 1-based line in the file.
        line: u64,
        /// Column name.
        column: String,
        /// The offending text.
        value: String,
    },
    /// A history whose rows do not match its header.
    #[error("{path}: row {row} has {got} values but the header has {want} columns")]
    Shape {
        /// File concerned.
        path: PathBuf,
        /// 0-based row index.
        row: usize,
        /// Values in the row.
        got: usize,
        /// Columns in the header.
        want: usize,
    },
}

/// The path of a case's CSV for one engine: `out/data/<case_id>/<engine>.csv`.
pub fn csv_path(out: &Path, case_id: &str, engine: &str) -> PathBuf {
    let stem = crate::contract::file_stem(engine);
    out.join("data").join(case_id).join(format!("{stem}.csv"))
}

/// The path of a case's discrepancy budget for one engine:
/// `out/data/<case_id>/<engine>.budget.csv`.
pub fn budget_path(out: &Path, case_id: &str, engine: &str) -> PathBuf {
    out.join("data")
        .join(case_id)
        .join(format!("{}.budget.csv", crate::contract::file_stem(engine)))
}

/// Write `history` to `out/data/<case_id>/<engine>.csv` (creating directories as needed,
/// atomically replacing any previous file) and return the path written.
pub fn write_history(
    out: &Path,
    case_id: &str,
    engine: &str,
    history: &History,
) -> Result<PathBuf, DataError> {
    let path = csv_path(out, case_id, engine);
    write_history_to(&path, history)?;
    Ok(path)
}

/// Write `history` as CSV to `path`, atomically: the data go to a temporary file in the same
/// directory, which is flushed, synced and renamed over `path`. On error the temporary file is
/// removed and any previous `path` is left untouched.
pub fn write_history_to(path: &Path, history: &History) -> Result<(), DataError> {
    for (row, values) in history.rows.iter().enumerate() {
        if values.len() != history.columns.len() {
            return Err(DataError::Shape {
                path: path.to_path_buf(),
                row,
                got: values.len(),
                want: history.columns.len(),
            });
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&dir).map_err(|source| DataError::Io {
        path: dir.clone(),
        source,
    })?;
    let tmp = temporary_sibling(path, &dir);
    let result = write_csv(&tmp, history).and_then(|()| {
        fs::rename(&tmp, path).map_err(|source| DataError::Io {
            path: path.to_path_buf(),
            source,
        })
    });
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Write the commit this build was made from beside a study's file (`path` with the extension
/// `provenance`): a speed figure is only as current as the engine it measured
/// (tests/figures_current.rs).
pub fn write_provenance(path: &Path) -> Result<(), DataError> {
    let text = format!("{}\n", env!("CROSSCHECK_COMMIT"));
    write_atomic(&path.with_extension("provenance"), text.as_bytes())
}

/// Write `contents` to `path` atomically (temporary sibling, synced, renamed into place),
/// creating the parent directory. On error any previous `path` is left untouched.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), DataError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| DataError::Io { path: p, source }
    };
    fs::create_dir_all(&dir).map_err(io(&dir))?;
    let tmp = temporary_sibling(path, &dir);
    let result = (|| {
        let mut f = File::create(&tmp).map_err(io(&tmp))?;
        std::io::Write::write_all(&mut f, contents).map_err(io(&tmp))?;
        f.sync_all().map_err(io(&tmp))?;
        fs::rename(&tmp, path).map_err(io(path))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// A fresh name for a temporary file next to `path` (unique per process and call).
fn temporary_sibling(path: &Path, dir: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let stem = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "history".into());
    dir.join(format!(".{stem}.{}.{n}.tmp", std::process::id()))
}

fn write_csv(tmp: &Path, history: &History) -> Result<(), DataError> {
    let io = |source| DataError::Io {
        path: tmp.to_path_buf(),
        source,
    };
    let csv_err = |source| DataError::Csv {
        path: tmp.to_path_buf(),
        source,
    };
    let file = File::create(tmp).map_err(io)?;
    let mut w = csv::Writer::from_writer(BufWriter::new(file));
    w.write_record(&history.columns).map_err(csv_err)?;
    let mut fields = Vec::with_capacity(history.columns.len());
    for row in &history.rows {
        fields.clear();
        fields.extend(row.iter().map(|x| csv_value(*x)));
        w.write_record(&fields).map_err(csv_err)?;
    }
    let buffered = w
        .into_inner()
        .map_err(|e| io(std::io::Error::other(e.to_string())))?;
    let file = buffered.into_inner().map_err(|e| io(e.into_error()))?;
    file.sync_all().map_err(io)?;
    Ok(())
}

/// Read a CSV written by [`write_history`] back into a [`History`].
pub fn read_history(path: &Path) -> Result<History, DataError> {
    let csv_err = |source| DataError::Csv {
        path: path.to_path_buf(),
        source,
    };
    let mut r = csv::Reader::from_path(path).map_err(csv_err)?;
    let columns: Vec<String> = r
        .headers()
        .map_err(csv_err)?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for record in r.records() {
        let record = record.map_err(csv_err)?;
        let line = record.position().map_or(0, |p| p.line());
        let row = record
            .iter()
            .zip(&columns)
            .map(|(field, column)| {
                field.trim().parse::<f64>().map_err(|_| DataError::Number {
                    path: path.to_path_buf(),
                    line,
                    column: column.clone(),
                    value: field.to_string(),
                })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        rows.push(row);
    }
    Ok(History { columns, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> History {
        History {
            columns: vec!["t".into(), "u_end".into(), "v_end".into()],
            rows: vec![
                vec![0.0, 1.0, -0.0],
                vec![0.1 + 0.2, 1e-300, -123456.789e10],
                vec![1.0 / 3.0, f64::MIN_POSITIVE / 4.0, f64::MAX],
                vec![2.0, f64::INFINITY, f64::NEG_INFINITY],
            ],
        }
    }

    fn bits(h: &History) -> Vec<Vec<u64>> {
        h.rows
            .iter()
            .map(|r| r.iter().map(|x| x.to_bits()).collect())
            .collect()
    }

    #[test]
    fn round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let h = sample();
        let path = write_history(dir.path(), "case_a", "explicit", &h).unwrap();
        assert_eq!(path, dir.path().join("data/case_a/explicit.csv"));
        let back = read_history(&path).unwrap();
        assert_eq!(back.columns, h.columns);
        assert_eq!(bits(&back), bits(&h));
        let text = fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("t,u_end,v_end\n0e0,1e0,-0e0\n"), "{text}");
    }

    #[test]
    fn nan_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let h = History {
            columns: vec!["t".into(), "x".into()],
            rows: vec![vec![0.0, f64::NAN]],
        };
        let path = write_history(dir.path(), "c", "e", &h).unwrap();
        assert!(read_history(&path).unwrap().rows[0][1].is_nan());
    }

    #[test]
    fn rewrite_replaces_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let mut h = sample();
        write_history(dir.path(), "c", "e", &h).unwrap();
        h.rows.truncate(1);
        let path = write_history(dir.path(), "c", "e", &h).unwrap();
        assert_eq!(read_history(&path).unwrap().rows.len(), 1);
        let names: Vec<_> = fs::read_dir(path.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("e.csv")]);
    }

    #[test]
    fn ragged_history_is_refused_and_old_file_kept() {
        let dir = tempfile::tempdir().unwrap();
        let good = sample();
        let path = write_history(dir.path(), "c", "e", &good).unwrap();
        let bad = History {
            columns: vec!["t".into(), "x".into()],
            rows: vec![vec![0.0]],
        };
        let err = write_history(dir.path(), "c", "e", &bad).unwrap_err();
        assert!(matches!(err, DataError::Shape { row: 0, .. }), "{err}");
        assert_eq!(bits(&read_history(&path).unwrap()), bits(&good));
        assert_eq!(fs::read_dir(path.parent().unwrap()).unwrap().count(), 1);
    }

    #[test]
    fn bad_number_names_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.csv");
        fs::write(&path, "t,u\n0e0,1e0\n1e0,oops\n").unwrap();
        let err = read_history(&path).unwrap_err().to_string();
        assert!(
            err.contains(":3:") && err.contains("`u`") && err.contains("oops"),
            "{err}"
        );
    }
}
