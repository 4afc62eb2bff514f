//! Case files: finding them, reading them, and turning them into validated scenes.

pub mod build;
pub mod chain;
pub mod diagnostic;
pub mod embedded;
pub mod family;
pub mod file;

use crate::scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

/// A case file that could not be read or is not a valid scene.
///
/// `Display` gives one line, `file:line:column: key: message`; [`CaseError::render`] adds the
/// offending text of the file, underlined.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (unknown key, wrong type, missing field).
    #[error("{}:{line}:{column}: {}: {message}", path.display(), key.as_deref().unwrap_or("syntax"))]
    Syntax {
        /// File.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// Key path where the parser stopped, when it is inside a key.
        key: Option<String>,
        /// The parser's message.
        message: String,
        /// The message with the offending text.
        rendered: String,
    },
    /// The file parses but is not a valid scene.
    #[error("{}:{line}:{column}: {key}: {message}", path.display())]
    Invalid {
        /// File.
        path: PathBuf,
        /// 1-based line of the offending field.
        line: usize,
        /// 1-based column of the offending field.
        column: usize,
        /// Key path of the offending field, e.g. `springs[2].stiffness`.
        key: String,
        /// What is wrong and what would be valid.
        message: String,
        /// The message with the offending text.
        rendered: String,
    },
    /// Not a regular file (a directory, FIFO, device, ...), or larger than [`MAX_FILE_BYTES`].
    #[error("{}: cannot read: {reason}", path.display())]
    Unreadable {
        /// File.
        path: PathBuf,
        /// Why it is not read.
        reason: String,
    },
    /// A byte sequence that is not UTF-8.
    #[error("{}:{line}:{column}: the file is not valid UTF-8 (byte offset {offset})", path.display())]
    NotUtf8 {
        /// File.
        path: PathBuf,
        /// 1-based line of the first invalid byte.
        line: usize,
        /// 1-based column (in characters) of the first invalid byte.
        column: usize,
        /// Byte offset of the first invalid byte.
        offset: usize,
    },
    /// A case id or path that matches no file.
    #[error("no case `{arg}`{hint}: give an id from {dir} or a path to a .toml file")]
    NotFound {
        /// The argument given.
        arg: String,
        /// ", did you mean `id`?" where a case's id is near it; empty otherwise.
        hint: String,
        /// The case directory searched.
        dir: String,
    },
}

impl CaseError {
    /// The error with the offending text of the file shown and underlined.
    pub fn render(&self) -> String {
        match self {
            CaseError::Syntax { rendered, .. } | CaseError::Invalid { rendered, .. } => {
                format!("error: {self}\n{rendered}")
            }
            _ => format!("error: {self}\n"),
        }
    }

    /// The key path the error is about, if any.
    pub fn key(&self) -> Option<&str> {
        match self {
            CaseError::Syntax { key, .. } => key.as_deref(),
            CaseError::Invalid { key, .. } => Some(key),
            _ => None,
        }
    }
}

/// The directory the cases are read from by default: `cases/` in the working directory.
pub fn cases_dir() -> PathBuf {
    PathBuf::from("cases")
}

/// The largest case file read, in bytes (the shipped ones are under 10 KiB).
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// Read a case file: a regular file of at most [`MAX_FILE_BYTES`], in UTF-8. Never blocks on a
/// FIFO or reads a device.
pub fn read_text(path: &Path) -> Result<String, CaseError> {
    use std::io::Read;
    let io = |source| CaseError::Io {
        path: path.to_path_buf(),
        source,
    };
    let unreadable = |reason: String| CaseError::Unreadable {
        path: path.to_path_buf(),
        reason,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(unreadable(
            "not a regular file (a case is a .toml file)".to_string(),
        ));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(unreadable(format!(
            "{} bytes; a case file may have at most {MAX_FILE_BYTES}",
            meta.len()
        )));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    // The size may change between the check and the read: read one byte past the limit.
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(unreadable(format!(
            "more than {MAX_FILE_BYTES} bytes; a case file may have at most that"
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let valid = std::str::from_utf8(&e.as_bytes()[..offset]).unwrap_or_default();
        let line = valid.matches('\n').count() + 1;
        let column = valid.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        CaseError::NotUtf8 {
            path: path.to_path_buf(),
            line,
            column,
            offset,
        }
    })
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

/// The folders of the case families beside the seed cases: the stress family and the
/// friction family.
pub const FAMILY_FOLDERS: [&str; 2] = ["stress", "friction"];

/// The directory of the stress family beside the seed cases: `dir/stress`.
pub fn stress_dir(dir: &Path) -> PathBuf {
    dir.join("stress")
}

/// The directory of the friction family beside the seed cases: `dir/friction`.
pub fn friction_dir(dir: &Path) -> PathBuf {
    dir.join("friction")
}

/// The seed cases of `dir` and those of each family folder that exists
/// ([`FAMILY_FOLDERS`]): what a run with no case named runs.
pub fn discover_suite(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut v = discover(dir)?;
    for folder in FAMILY_FOLDERS {
        let family = dir.join(folder);
        if family.is_dir() {
            v.extend(discover(&family)?);
        }
    }
    Ok(v)
}

/// Resolve a CASE argument: an id from `dir` (or from a family folder of it), or a path to a
/// TOML file.
pub fn resolve(arg: &str, dir: &Path) -> Result<PathBuf, CaseError> {
    let as_path = PathBuf::from(arg);
    if as_path.extension().is_some_and(|x| x == "toml") && as_path.is_file() {
        return Ok(as_path);
    }
    let folders = FAMILY_FOLDERS.iter().map(|f| dir.join(f));
    for d in std::iter::once(dir.to_path_buf()).chain(folders) {
        let in_dir = d.join(format!("{arg}.toml"));
        if in_dir.is_file() {
            return Ok(in_dir);
        }
    }
    let ids: Vec<String> = discover_suite(dir)
        .unwrap_or_default()
        .iter()
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    Err(CaseError::NotFound {
        arg: arg.to_string(),
        hint: diagnostic::did_you_mean(arg, &ids),
        dir: format!("{}/", dir.display()),
    })
}

/// Read and validate a case file.
pub fn load(path: &Path) -> Result<Scene, CaseError> {
    load_checked(path, &|_| Ok(()))
}

/// Read and validate a case file, then apply a further check (for example one that needs an
/// engine, such as the stable increment); its error is located in the file like the others.
pub fn load_checked(
    path: &Path,
    check: &dyn Fn(&Scene) -> Result<(), SceneError>,
) -> Result<Scene, CaseError> {
    let text = read_text(path)?;
    let scene = parse(&text, path)?;
    check(&scene).map_err(|e| invalid(&text, path, e))?;
    Ok(scene)
}

/// Validate case text (as if read from `path`).
pub fn parse(text: &str, path: &Path) -> Result<Scene, CaseError> {
    let name = path.display().to_string();
    let case: file::CaseFile = toml::from_str(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        let (line, column) = diagnostic::line_column(text, span.start);
        let key = diagnostic::key_at(text, span.start).or_else(|| {
            e.message()
                .starts_with("missing field")
                .then(|| "(top level)".to_string())
        });
        let message = e
            .message()
            .trim_end()
            .replace("expected f64", "expected a number")
            .replace("expected usize", "expected a whole number ≥ 0")
            .replace("expected u8", "expected a whole number");
        CaseError::Syntax {
            rendered: diagnostic::render(&name, text, span, &message, "here", None),
            path: path.to_path_buf(),
            line,
            column,
            key,
            message,
        }
    })?;
    let stem = path.file_stem().and_then(|s| s.to_str());
    build::scene(&case, stem).map_err(|e| invalid(text, path, e))
}

/// A scene error located in the text of its case file.
pub fn invalid(text: &str, path: &Path, e: SceneError) -> CaseError {
    let span = diagnostic::span_of(text, &e.field).unwrap_or(0..0);
    let (line, column) = diagnostic::line_column(text, span.start);
    CaseError::Invalid {
        rendered: diagnostic::render(
            &path.display().to_string(),
            text,
            span,
            &e.message,
            &e.field,
            None,
        ),
        path: path.to_path_buf(),
        line,
        column,
        key: e.field,
        message: e.message,
    }
}
