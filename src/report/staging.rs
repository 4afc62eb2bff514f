//! A report is assembled in a staging directory and swapped into place in one step, so a
//! failed or interrupted run leaves the previous report whole; one run at a time writes to an
//! output ([`OutputLock`]).
//!
//! The target (`--out`) must be a directory or not exist. Two ways to swap, chosen from what
//! the target holds:
//!
//! - **Whole directory** (the target does not exist, or holds nothing but report entries): the
//!   staging directory `.<name>.staging-<pid>` is created beside the target and exchanged with it
//!   in one `renameat2(RENAME_EXCHANGE)` (two renames where that is unavailable).
//! - **Entry by entry** (the target holds files that are not the report's, for example
//!   `--out .`): the staging directory `.crosscheck.staging-<pid>` is created inside the target,
//!   and each report entry (`data/`, `figures/`, `summary.json`, `timings.json`, `REPORT.md`
//!   last) is exchanged with its counterpart, each in one step. Nothing else in the target is
//!   touched. Signals are deferred during the swap; only a SIGKILL in the microseconds between
//!   two exchanges could leave some entries new and others old (never a half-written file).
//!
//! The staging directory starts with hard links to the report entries the target already has
//! (a run of some cases keeps the others' data). Dropping an uncommitted staging removes it; a
//! starting run removes staging directories whose owning process is dead (after a SIGKILL), and
//! never another live run's.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How a staged report replaces the target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SwapMode {
    /// The whole target directory is exchanged with the staging directory.
    WholeDirectory,
    /// Each report entry is exchanged on its own; the target's other files stay.
    EntryByEntry,
}

/// A report being assembled.
#[derive(Debug)]
pub struct Staging {
    target: PathBuf,
    dir: PathBuf,
    mode: SwapMode,
    entries: Vec<String>,
    committed: bool,
}

const INNER_PREFIX: &str = ".crosscheck.staging-";

fn file_name(target: &Path) -> String {
    target
        .file_name()
        .map_or_else(|| "report".into(), |n| n.to_string_lossy().into_owned())
}

fn outer_prefix(target: &Path) -> String {
    format!(".{}.staging-", file_name(target))
}

fn parent(target: &Path) -> PathBuf {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Why an output directory cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path exists and is not a directory.
    #[error("{}: --out must be a directory or not exist; this is a {kind}", path.display())]
    NotADirectory {
        /// The path given.
        path: PathBuf,
        /// What it is.
        kind: &'static str,
    },
    /// A parent of the path exists and is not a directory.
    #[error("{}: --out cannot be created: {} is not a directory", path.display(), blocker.display())]
    ParentNotADirectory {
        /// The path given.
        path: PathBuf,
        /// The component that is not a directory.
        blocker: PathBuf,
    },
    /// Another run holds the output (and waiting was not allowed).
    #[error("{}: another crosscheck run is writing this report{}; not waiting (--no-wait)", path.display(), holder.map(|p| format!(" (pid {p})")).unwrap_or_default())]
    Busy {
        /// The target.
        path: PathBuf,
        /// The process holding it, if it said.
        holder: Option<u32>,
    },
    /// Interrupted while waiting for another run.
    #[error("interrupted while waiting for another run")]
    Interrupted,
    /// Filesystem error.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path concerned.
        path: PathBuf,
        /// Cause.
        source: io::Error,
    },
}

fn kind_of(meta: &fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_file() {
        "regular file"
    } else if t.is_fifo() {
        "FIFO"
    } else if t.is_socket() {
        "socket"
    } else if t.is_block_device() || t.is_char_device() {
        "device"
    } else {
        "special file"
    }
}

/// Check an output path before anything runs: it must be a directory or not exist, and then
/// every existing ancestor must be a directory. Returns the path to use (symbolic links and `.`
/// resolved, so the swap acts on the real directory).
pub fn resolve_output(out: &Path) -> Result<PathBuf, OutputError> {
    let io = |source| OutputError::Io {
        path: out.to_path_buf(),
        source,
    };
    match fs::metadata(out) {
        Ok(meta) if meta.is_dir() => return out.canonicalize().map_err(io),
        Ok(meta) => {
            return Err(OutputError::NotADirectory {
                path: out.to_path_buf(),
                kind: kind_of(&meta),
            });
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) if e.kind() == io::ErrorKind::NotADirectory => {}
        Err(e) => return Err(io(e)),
    }
    // It does not exist: find the nearest existing ancestor; it must be a directory.
    let absolute = if out.is_absolute() {
        out.to_path_buf()
    } else {
        std::env::current_dir().map_err(io)?.join(out)
    };
    let mut ancestor = absolute.parent();
    while let Some(a) = ancestor {
        match fs::metadata(a) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) => {
                return Err(OutputError::ParentNotADirectory {
                    path: out.to_path_buf(),
                    blocker: a.to_path_buf(),
                });
            }
            Err(_) => ancestor = a.parent(),
        }
    }
    Ok(absolute)
}

/// An exclusive lock on an output: one writer at a time. Held until dropped; dropping it
/// removes the lock file (a lock taken on a file that was meanwhile removed is retried, so two
/// runs never both hold one).
#[derive(Debug)]
pub struct OutputLock {
    file: Option<File>,
    path: PathBuf,
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Unlink while still locked, then unlock by closing.
        let _ = fs::remove_file(&self.path);
        self.file.take();
    }
}

/// Whether the open `file` is still the one at `path` (not removed and re-created).
fn is_current(file: &File, path: &Path) -> io::Result<bool> {
    use std::os::unix::fs::MetadataExt;
    let open = file.metadata()?;
    Ok(match fs::metadata(path) {
        Ok(now) => now.dev() == open.dev() && now.ino() == open.ino(),
        Err(_) => false,
    })
}

impl OutputLock {
    /// The lock file of a target: `.<name>.lock` beside it.
    pub fn path_for(target: &Path) -> PathBuf {
        parent(target).join(format!(".{}.lock", file_name(target)))
    }

    /// Take the lock of `target`. When another run holds it: with `wait`, say so once on
    /// stderr and wait (polling, so a signal still stops the wait); without, fail with
    /// [`OutputError::Busy`].
    pub fn acquire(target: &Path, wait: bool) -> Result<OutputLock, OutputError> {
        let path = Self::path_for(target);
        let io = |source| OutputError::Io {
            path: path.clone(),
            source,
        };
        fs::create_dir_all(parent(target)).map_err(io)?;
        let mut said = false;
        let mut file = loop {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(io)?;
            if try_lock(&file).map_err(io)? {
                if is_current(&file, &path).map_err(io)? {
                    break file;
                }
                continue; // its holder removed it as we locked it: take the new one
            }
            let holder = read_pid(&mut file);
            if !wait {
                return Err(OutputError::Busy {
                    path: target.to_path_buf(),
                    holder,
                });
            }
            if !said {
                let _ = writeln!(
                    std::io::stderr(),
                    "waiting: another crosscheck run{} is writing {}",
                    holder.map(|p| format!(" (pid {p})")).unwrap_or_default(),
                    target.display()
                );
                said = true;
            }
            if crate::interrupt::requested() {
                return Err(OutputError::Interrupted);
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        file.set_len(0).map_err(io)?;
        writeln!(file, "{}", std::process::id()).map_err(io)?;
        Ok(OutputLock {
            file: Some(file),
            path,
        })
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// An exclusive lock on `file` if no other process holds one (`flock` on Linux).
fn try_lock(file: &File) -> io::Result<bool> {
    match file.try_lock() {
        Ok(()) => Ok(true),
        Err(fs::TryLockError::WouldBlock) => Ok(false),
        Err(fs::TryLockError::Error(e)) => Err(e),
    }
}

fn read_pid(file: &mut File) -> Option<u32> {
    use std::io::Seek;
    let mut s = String::new();
    file.seek(io::SeekFrom::Start(0)).ok()?;
    file.take(32).read_to_string(&mut s).ok()?;
    s.trim().parse().ok()
}

/// Whether process `pid` is provably gone (signal 0: only checks that it exists).
fn is_dead(pid: u32) -> bool {
    let Some(pid) = i32::try_from(pid)
        .ok()
        .and_then(rustix::process::Pid::from_raw)
    else {
        return false;
    };
    rustix::process::test_kill_process(pid) == Err(rustix::io::Errno::SRCH)
}

/// Remove the staging directories in `dir` named `<prefix><pid>` whose process is dead.
fn remove_stale(dir: &Path, prefix: &str) -> io::Result<()> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix(prefix)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && is_dead(pid) && entry.file_type()?.is_dir() {
            fs::remove_dir_all(entry.path())?;
        }
    }
    Ok(())
}

/// Hard-link (or copy, across devices) every file under `from` into `to`.
pub(crate) fn link_tree(from: &Path, to: &Path) -> io::Result<()> {
    if !fs::symlink_metadata(from)?.is_dir() {
        if fs::hard_link(from, to).is_err() {
            fs::copy(from, to)?;
        }
        return Ok(());
    }
    fs::create_dir_all(to)?;
    for entry in fs::read_dir(from)? {
        let entry = entry?;
        link_tree(&entry.path(), &to.join(entry.file_name()))?;
    }
    Ok(())
}

/// Put a copy of the report in `source` (its `entries`) in place of `target`'s, through a
/// staging directory and the swap, so that `target` holds the old report or the new one, never
/// a mixture; the files are hard-linked where the two share a device (a report's files are
/// only ever replaced, never written in place). The caller holds `target`'s lock.
pub fn replace_report(source: &Path, target: &Path, entries: &[&str]) -> io::Result<()> {
    let staging = Staging::begin(target, entries)?;
    for e in entries {
        let (from, to) = (source.join(e), staging.dir.join(e));
        match fs::symlink_metadata(&to) {
            Ok(m) if m.is_dir() => fs::remove_dir_all(&to)?,
            Ok(_) => fs::remove_file(&to)?,
            Err(_) => {}
        }
        if fs::symlink_metadata(&from).is_ok() {
            link_tree(&from, &to)?;
        }
    }
    let entry_by_entry = staging.mode() == SwapMode::EntryByEntry;
    staging.commit()?;
    // Put in entry by entry (the target holds other files), the swap leaves an entry the
    // source has not got: remove it, so that the target holds the source's report alone.
    if entry_by_entry {
        for e in entries {
            let (from, left) = (source.join(e), target.join(e));
            if fs::symlink_metadata(&from).is_err() {
                match fs::symlink_metadata(&left) {
                    Ok(m) if m.is_dir() => fs::remove_dir_all(&left)?,
                    Ok(_) => fs::remove_file(&left)?,
                    Err(_) => {}
                }
            }
        }
    }
    Ok(())
}

impl Staging {
    /// Start a report for `target` (a path from [`resolve_output`], locked by the caller)
    /// whose own entries are `entries`: remove staging directories of dead runs, create this
    /// one, and carry over the report entries the target has.
    pub fn begin(target: &Path, entries: &[&str]) -> io::Result<Staging> {
        let parent = parent(target);
        fs::create_dir_all(&parent)?;
        remove_stale(&parent, &outer_prefix(target))?;
        remove_stale(target, INNER_PREFIX)?;
        let foreign = match fs::read_dir(target) {
            Ok(list) => list.filter_map(Result::ok).any(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                !entries.contains(&name.as_str()) && !name.starts_with(INNER_PREFIX)
            }),
            Err(_) => false,
        };
        let (mode, dir) = if foreign {
            (
                SwapMode::EntryByEntry,
                target.join(format!("{INNER_PREFIX}{}", std::process::id())),
            )
        } else {
            (
                SwapMode::WholeDirectory,
                parent.join(format!("{}{}", outer_prefix(target), std::process::id())),
            )
        };
        if dir.exists() {
            fs::remove_dir_all(&dir)?;
        }
        fs::create_dir_all(&dir)?;
        let staging = Staging {
            target: target.to_path_buf(),
            dir,
            mode,
            entries: entries.iter().map(|s| s.to_string()).collect(),
            committed: false,
        };
        for e in entries {
            let from = target.join(e);
            if fs::symlink_metadata(&from).is_ok() {
                link_tree(&from, &staging.dir.join(e))?;
            }
        }
        Ok(staging)
    }

    /// Where the run writes.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The report being replaced.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// How the report will be put in place.
    pub fn mode(&self) -> SwapMode {
        self.mode
    }

    /// Put the staged report in place of the target (see the module docs), then remove the
    /// previous one.
    pub fn commit(mut self) -> io::Result<()> {
        match self.mode {
            SwapMode::WholeDirectory => {
                if self.target.exists() {
                    exchange(&self.dir, &self.target)?;
                } else {
                    fs::rename(&self.dir, &self.target)?;
                }
            }
            SwapMode::EntryByEntry => {
                // REPORT.md last: it is what a reader opens first.
                let mut order: Vec<&String> = self.entries.iter().collect();
                order.sort_by_key(|e| e.as_str() == "REPORT.md");
                for e in order {
                    let (staged, live) = (self.dir.join(e), self.target.join(e));
                    if fs::symlink_metadata(&staged).is_err() {
                        continue;
                    }
                    if fs::symlink_metadata(&live).is_ok() {
                        exchange(&staged, &live)?;
                    } else {
                        fs::rename(&staged, &live)?;
                    }
                }
            }
        }
        self.committed = true;
        // The staging path now holds the previous report (or nothing).
        if self.dir.exists() {
            fs::remove_dir_all(&self.dir)?;
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.dir);
        }
    }
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    use rustix::io::Errno;
    match renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE) {
        Ok(()) => Ok(()),
        Err(Errno::NOSYS | Errno::INVAL) => exchange_by_renames(a, b),
        Err(e) => Err(e.into()),
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    exchange_by_renames(a, b)
}

/// Fallback: b → aside, a → b, aside → a (not atomic: a crash between the renames leaves the
/// previous report under the aside name).
fn exchange_by_renames(a: &Path, b: &Path) -> io::Result<()> {
    let mut name = a.file_name().unwrap_or_default().to_os_string();
    name.push("-previous");
    let aside = a.with_file_name(name);
    fs::rename(b, &aside)?;
    fs::rename(a, b)?;
    fs::rename(&aside, a)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ENTRIES: [&str; 3] = ["data", "summary.json", "REPORT.md"];

    #[test]
    fn whole_directory_swap_keeps_nothing_stale() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("report");
        fs::create_dir_all(target.join("data")).unwrap();
        fs::write(target.join("data/a.csv"), "old").unwrap();
        fs::write(target.join("REPORT.md"), "old").unwrap();
        let s = Staging::begin(&target, &ENTRIES).unwrap();
        assert_eq!(s.mode(), SwapMode::WholeDirectory);
        // Carried over as links.
        assert_eq!(
            fs::read_to_string(s.path().join("data/a.csv")).unwrap(),
            "old"
        );
        fs::write(s.path().join("REPORT.md"), "new").unwrap();
        s.commit().unwrap();
        assert_eq!(fs::read_to_string(target.join("REPORT.md")).unwrap(), "new");
        assert_eq!(
            fs::read_to_string(target.join("data/a.csv")).unwrap(),
            "old"
        );
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 1);
    }

    #[test]
    fn entry_swap_leaves_the_users_files_alone() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path();
        fs::write(target.join("notes.txt"), "mine").unwrap();
        fs::write(target.join("REPORT.md"), "old").unwrap();
        let s = Staging::begin(target, &ENTRIES).unwrap();
        assert_eq!(s.mode(), SwapMode::EntryByEntry);
        assert!(s.path().starts_with(target));
        fs::write(s.path().join("REPORT.md"), "new").unwrap();
        fs::create_dir_all(s.path().join("data")).unwrap();
        fs::write(s.path().join("data/x.csv"), "x").unwrap();
        s.commit().unwrap();
        assert_eq!(fs::read_to_string(target.join("REPORT.md")).unwrap(), "new");
        assert_eq!(
            fs::read_to_string(target.join("notes.txt")).unwrap(),
            "mine"
        );
        assert_eq!(fs::read_to_string(target.join("data/x.csv")).unwrap(), "x");
        let mut names: Vec<String> = fs::read_dir(target)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["REPORT.md", "data", "notes.txt"]);
    }

    #[test]
    fn a_live_runs_staging_is_kept_and_a_dead_ones_removed() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("report");
        // pid 1 is alive (init); a pid above the kernel's limit is dead.
        let live = root.path().join(".report.staging-1");
        let dead = root.path().join(".report.staging-2147483646");
        fs::create_dir_all(&live).unwrap();
        fs::create_dir_all(&dead).unwrap();
        let s = Staging::begin(&target, &ENTRIES).unwrap();
        assert!(live.exists());
        assert!(!dead.exists());
        drop(s);
    }

    #[test]
    fn output_must_be_a_directory() {
        let root = tempfile::tempdir().unwrap();
        let file = root.path().join("f");
        fs::write(&file, "user data").unwrap();
        assert!(matches!(
            resolve_output(&file),
            Err(OutputError::NotADirectory { .. })
        ));
        assert!(matches!(
            resolve_output(&file.join("sub")),
            Err(OutputError::ParentNotADirectory { .. })
        ));
        assert_eq!(fs::read_to_string(&file).unwrap(), "user data");
        let fresh = root.path().join("a/b");
        assert_eq!(resolve_output(&fresh).unwrap(), fresh);
    }

    #[test]
    fn a_second_lock_is_refused_without_waiting() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("report");
        let first = OutputLock::acquire(&target, false).unwrap();
        let err = OutputLock::acquire(&target, false).unwrap_err();
        assert!(
            err.to_string()
                .contains(&format!("pid {}", std::process::id())),
            "{err}"
        );
        drop(first);
        OutputLock::acquire(&target, false).unwrap();
    }
}
