//! Case files: finding them, reading them, and turning them into validated scenes.

pub mod file;

use crate::scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

/// A case file that could not be read or is not a valid scene.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (toml reports line, column and key).
    #[error("{path}: {message}")]
    Syntax {
        /// File.
        path: PathBuf,
        /// The parser's message, with line and column.
        message: String,
    },
    /// The file parses but is not a valid scene.
    #[error("{path}:{line}: {source}")]
    Invalid {
        /// File.
        path: PathBuf,
        /// 1-based line of the offending field (best effort: the line of its table or key).
        line: usize,
        /// Field and message.
        source: SceneError,
    },
    /// A case id or path that matches no file.
    #[error("no case `{0}`: give an id from cases/ or a path to a .toml file")]
    NotFound(String),
}

/// The directory holding the shipped cases.
pub fn cases_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases")
}

/// Every case file in a directory, sorted by id.
pub fn discover(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    Ok(v)
}

/// Resolve a CASE argument: an id from `dir`, or a path to a TOML file.
pub fn resolve(arg: &str, dir: &Path) -> Result<PathBuf, CaseError> {
    let as_path = PathBuf::from(arg);
    if as_path.extension().is_some_and(|x| x == "toml") && as_path.is_file() {
        return Ok(as_path);
    }
    let in_dir = dir.join(format!("{arg}.toml"));
    if in_dir.is_file() {
        return Ok(in_dir);
    }
    Err(CaseError::NotFound(arg.to_string()))
}

/// Read and validate a case file.
pub fn load(path: &Path) -> Result<Scene, CaseError> {
    let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Validate case text (as if read from `path`).
pub fn parse(text: &str, path: &Path) -> Result<Scene, CaseError> {
    let case: file::CaseFile = toml::from_str(text).map_err(|e| CaseError::Syntax {
        path: path.to_path_buf(),
        message: e.to_string().trim_end().to_string(),
    })?;
    let stem = path.file_stem().and_then(|s| s.to_str());
    Scene::from_case(&case, stem).map_err(|source| CaseError::Invalid {
        path: path.to_path_buf(),
        line: line_of(text, &source.field),
        source,
    })
}

/// Best-effort line of a key path such as `springs[2].stiffness`: the line of the
/// (n+1)-th `[[springs]]` header, then of the key within that table.
fn line_of(text: &str, field: &str) -> usize {
    let lines: Vec<&str> = text.lines().collect();
    let mut start = 0usize;
    let mut end = lines.len();
    let mut key = field;
    // First path component, possibly indexed.
    let head = field.split('.').next().unwrap_or(field);
    if let Some((table, rest)) = head.split_once('[') {
        let idx: usize = rest.trim_end_matches(']').parse().unwrap_or(0);
        let header = format!("[[{table}]]");
        let mut seen = 0;
        for (i, l) in lines.iter().enumerate() {
            if l.trim() == header {
                if seen == idx {
                    start = i;
                    end = lines[i + 1..]
                        .iter()
                        .position(|l| l.trim_start().starts_with('['))
                        .map_or(lines.len(), |p| i + 1 + p);
                    break;
                }
                seen += 1;
            }
        }
        key = field.split('.').nth(1).unwrap_or("");
    } else if let Some((table, k)) = field.split_once('.') {
        let header = format!("[{table}]");
        if let Some(i) = lines.iter().position(|l| l.trim() == header) {
            start = i;
        }
        key = k;
    }
    let key = key.split('[').next().unwrap_or(key);
    if !key.is_empty() {
        for (i, l) in lines.iter().enumerate().take(end).skip(start) {
            let t = l.trim_start();
            if t.starts_with(key) && t[key.len()..].trim_start().starts_with('=') {
                return i + 1;
            }
        }
    }
    start + 1
}
