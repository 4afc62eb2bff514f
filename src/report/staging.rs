//! A report is assembled in a staging directory beside its target and swapped into place in
//! one step, so a failed or interrupted run leaves the previous report whole.
//!
//! The staging directory starts with hard links to the target's existing CSVs (a run of some
//! cases keeps the others' data); the run writes into it; [`Staging::commit`] exchanges it with
//! the target atomically (`renameat2(RENAME_EXCHANGE)` on Linux; two renames elsewhere) and
//! removes the old report. Dropping an uncommitted staging removes it; SIGINT and SIGTERM
//! remove it too (see [`install_signal_cleanup`]); after a SIGKILL the next run removes it.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// The staging directory of the running process, for the signal handler.
static ACTIVE: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Set by SIGINT or SIGTERM: jobs still running must not write any more.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Whether the run was interrupted (jobs check this before writing).
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// A report being assembled.
#[derive(Debug)]
pub struct Staging {
    target: PathBuf,
    dir: PathBuf,
    committed: bool,
}

fn prefix(target: &Path) -> String {
    let name = target
        .file_name()
        .map_or_else(|| "report".into(), |n| n.to_string_lossy().into_owned());
    format!(".{name}.staging-")
}

fn parent(target: &Path) -> PathBuf {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Hard-link (or copy, across devices) every file under `from` into `to`.
fn link_tree(from: &Path, to: &Path) -> io::Result<()> {
    fs::create_dir_all(to)?;
    for entry in fs::read_dir(from)? {
        let entry = entry?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if entry.file_type()?.is_dir() {
            link_tree(&src, &dst)?;
        } else if fs::hard_link(&src, &dst).is_err() {
            fs::copy(&src, &dst)?;
        }
    }
    Ok(())
}

impl Staging {
    /// Start a report for `target`: remove stale staging directories of killed runs, create
    /// this one, and carry over the target's existing data.
    pub fn begin(target: &Path) -> io::Result<Staging> {
        let parent = parent(target);
        fs::create_dir_all(&parent)?;
        let prefix = prefix(target);
        for entry in fs::read_dir(&parent)? {
            let entry = entry?;
            if entry.file_name().to_string_lossy().starts_with(&prefix) {
                fs::remove_dir_all(entry.path())?;
            }
        }
        let dir = parent.join(format!("{prefix}{}", std::process::id()));
        fs::create_dir_all(&dir)?;
        *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) = Some(dir.clone());
        let staging = Staging {
            target: target.to_path_buf(),
            dir,
            committed: false,
        };
        // Everything the previous report had (data, figures, summary) is carried over, so a run
        // of some cases keeps the others'; what this run writes replaces it atomically.
        if target.is_dir() {
            link_tree(target, &staging.dir)?;
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

    /// Put the staged report in place of the target, in one step.
    pub fn commit(mut self) -> io::Result<()> {
        if self.target.exists() {
            exchange(&self.dir, &self.target)?;
            // The staging path now holds the previous report.
            fs::remove_dir_all(&self.dir)?;
        } else {
            fs::rename(&self.dir, &self.target)?;
        }
        self.committed = true;
        *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) = None;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.dir);
            *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) = None;
        }
    }
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let ca = CString::new(a.as_os_str().as_bytes()).map_err(io::Error::other)?;
    let cb = CString::new(b.as_os_str().as_bytes()).map_err(io::Error::other)?;
    // SAFETY: two valid NUL-terminated paths; renameat2 does not retain them.
    let r = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if r == 0 {
        return Ok(());
    }
    let e = io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::ENOSYS) | Some(libc::EINVAL) => exchange_by_renames(a, b),
        _ => Err(e),
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    exchange_by_renames(a, b)
}

/// Fallback: b → aside, a → b, aside → a (not atomic: a crash between the renames leaves the
/// previous report under the aside name, which the next run removes).
fn exchange_by_renames(a: &Path, b: &Path) -> io::Result<()> {
    let mut name = a.file_name().unwrap_or_default().to_os_string();
    name.push("-previous");
    let aside = a.with_file_name(name);
    fs::rename(b, &aside)?;
    fs::rename(a, b)?;
    fs::rename(&aside, a)
}

/// On SIGINT or SIGTERM, remove the active staging directory and exit with 130, so an
/// interrupted run leaves the previous report as it was and no stray files.
pub fn install_signal_cleanup() {
    let _ = ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        if let Some(dir) = ACTIVE.lock().unwrap_or_else(|e| e.into_inner()).take() {
            let _ = fs::remove_dir_all(&dir);
            // A job that was already writing may re-create the directory; it checks the flag
            // before any further write, so a second pass after it finishes clears it for good.
            std::thread::sleep(std::time::Duration::from_millis(200));
            let _ = fs::remove_dir_all(&dir);
        }
        eprintln!("interrupted: the previous report is unchanged");
        std::process::exit(130);
    });
}
