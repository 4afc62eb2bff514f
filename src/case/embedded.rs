//! The shipped cases, compiled into the binary: an installed `crosscheck` run anywhere finds
//! them without a checkout.
//!
//! Where the cases come from ([`case_dir`]): `--cases DIR`, else the `CROSSCHECK_CASES`
//! environment variable, else `cases/` in the working directory where it holds case files,
//! else the shipped cases, written out once per content under the user's cache directory
//! (`$XDG_CACHE_HOME/crosscheck/`, `~/.cache/crosscheck/`, or the temporary directory), so
//! that every message names a file the user can open.

use std::io;
use std::path::{Path, PathBuf};

include!(concat!(env!("OUT_DIR"), "/embedded_cases.rs"));

/// The environment variable that names the case directory when `--cases` is not given.
pub const ENV: &str = "CROSSCHECK_CASES";

/// Where a command reads its cases from, and why there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CaseSource {
    /// `--cases DIR`.
    Option(PathBuf),
    /// `CROSSCHECK_CASES`.
    Environment(PathBuf),
    /// `cases/` in the working directory.
    WorkingDirectory(PathBuf),
    /// The shipped cases, written out here.
    Shipped(PathBuf),
}

impl CaseSource {
    /// The directory.
    pub fn dir(&self) -> &Path {
        match self {
            CaseSource::Option(p)
            | CaseSource::Environment(p)
            | CaseSource::WorkingDirectory(p)
            | CaseSource::Shipped(p) => p,
        }
    }
}

/// The case directory for `given` (`--cases`), in the order the module docs state. Only the
/// shipped cases can fail to be found: their directory could not be written.
pub fn case_dir(given: Option<PathBuf>) -> io::Result<CaseSource> {
    if let Some(dir) = given {
        return Ok(CaseSource::Option(dir));
    }
    if let Some(dir) = std::env::var_os(ENV).filter(|v| !v.is_empty()) {
        return Ok(CaseSource::Environment(PathBuf::from(dir)));
    }
    // A directory of case files: a report's `cases/` (its pages) is not one.
    let here = super::cases_dir();
    if super::discover(&here).is_ok_and(|found| !found.is_empty()) {
        return Ok(CaseSource::WorkingDirectory(here));
    }
    write_out(&cache_root()).map(CaseSource::Shipped)
}

/// `$XDG_CACHE_HOME/crosscheck`, `$HOME/.cache/crosscheck`, or `crosscheck` in the temporary
/// directory.
fn cache_root() -> PathBuf {
    let var = |name: &str| {
        std::env::var_os(name)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    var("XDG_CACHE_HOME")
        .or_else(|| var("HOME").map(|h| h.join(".cache")))
        .unwrap_or_else(std::env::temp_dir)
        .join("crosscheck")
}

/// FNV-1a (64 bits) of every file's name and text: the written directory's name, so that two
/// builds with different cases never share one.
fn fingerprint() -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for (name, text) in FILES {
        for byte in name.bytes().chain([0]).chain(text.bytes()).chain([0]) {
            hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    hash
}

/// Whether `dir` holds exactly the shipped files with their texts (an edited or half-written
/// directory does not).
fn holds_shipped(dir: &Path) -> bool {
    FILES.iter().all(|(name, text)| {
        std::fs::read_to_string(dir.join(name)).is_ok_and(|on_disk| on_disk == *text)
    }) && super::discover_suite(dir).is_ok_and(|found| found.len() == FILES.len())
}

/// The shipped cases written under `root` as `cases-<fingerprint>/` (and its families'
/// folders): made
/// in a directory of its own and renamed into place, so that a run never reads a half-written
/// one; rewritten where it was edited.
pub fn write_out(root: &Path) -> io::Result<PathBuf> {
    let dir = root.join(format!("cases-{:016x}", fingerprint()));
    if holds_shipped(&dir) {
        return Ok(dir);
    }
    std::fs::create_dir_all(root)?;
    let fresh = root.join(format!(
        ".cases-{:016x}-{}",
        fingerprint(),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&fresh);
    for (name, text) in FILES {
        let path = fresh.join(name);
        std::fs::create_dir_all(path.parent().unwrap_or(&fresh))?;
        std::fs::write(&path, text)?;
    }
    if holds_shipped(&dir) {
        // Another run put its copy in place meanwhile.
        let _ = std::fs::remove_dir_all(&fresh);
        return Ok(dir);
    }
    if dir.exists() {
        // Edited or incomplete: set aside, then removed once the fresh copy is in place.
        let old = root.join(format!(
            ".old-{:016x}-{}",
            fingerprint(),
            std::process::id()
        ));
        std::fs::rename(&dir, &old)?;
        let placed = std::fs::rename(&fresh, &dir);
        let _ = std::fs::remove_dir_all(&old);
        placed?;
    } else if let Err(e) = std::fs::rename(&fresh, &dir) {
        // Another run put its copy in place first; it holds the same files.
        let _ = std::fs::remove_dir_all(&fresh);
        if !holds_shipped(&dir) {
            return Err(e);
        }
    }
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped files are the repository's `cases/` and its families' folders, one for one.
    #[test]
    fn every_shipped_case_is_embedded() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
        let on_disk = super::super::discover_suite(&dir).unwrap();
        assert_eq!(FILES.len(), on_disk.len());
        for path in on_disk {
            let name = path
                .strip_prefix(&dir)
                .unwrap()
                .to_string_lossy()
                .into_owned();
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(FILES.contains(&(name.as_str(), text.as_str())), "{name}");
        }
    }

    /// Written once, found again; an edited copy is put back as shipped.
    #[test]
    fn written_out_and_restored_when_edited() {
        let root = tempfile::tempdir().unwrap();
        let dir = write_out(root.path()).unwrap();
        assert_eq!(
            super::super::discover_suite(&dir).unwrap().len(),
            FILES.len()
        );
        assert_eq!(write_out(root.path()).unwrap(), dir);
        let (name, text) = FILES[0];
        std::fs::write(dir.join(name), "edited").unwrap();
        assert_eq!(write_out(root.path()).unwrap(), dir);
        assert_eq!(std::fs::read_to_string(dir.join(name)).unwrap(), text);
        // Nothing left beside it.
        assert_eq!(std::fs::read_dir(root.path()).unwrap().count(), 1);
    }
}
