//! Interruption: SIGINT, SIGTERM and SIGHUP set a flag; long work stops at its next safe point.
//!
//! The signal handler does nothing but set the flag ([`install`]); the code that owns the files
//! polls it ([`requested`], [`checkpoint`]) and cleans up its own staging directory before
//! exiting with 130, so a signal can never race a write. A second signal while the first is
//! being handled ends the process at once (exit 130); the report is still safe, because only
//! the final swap touches the target.
//!
//! For deterministic tests, `CROSSCHECK_PAUSE_AT=<phase>` makes the process stop at the named
//! [`checkpoint`] (printing `crosscheck: paused at <phase>` on stderr) until a signal arrives,
//! or for at most 60 s.

use std::io::Write as _;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static PAUSED: AtomicBool = AtomicBool::new(false);

/// Environment variable naming the checkpoint to pause at (tests only).
pub const PAUSE_VARIABLE: &str = "CROSSCHECK_PAUSE_AT";

/// The exit code of an interrupted run.
pub const EXIT_CODE: u8 = 130;

/// Install the handler: the first signal sets the flag, a second one exits with 130 (with the
/// `cli` feature, which brings the signal handling; a library embedding crosscheck sets the
/// flag from its own).
#[cfg(feature = "cli")]
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            let _ = writeln!(std::io::stderr(), "interrupted again: stopping now");
            std::process::exit(i32::from(EXIT_CODE));
        }
    });
}

/// Whether an interruption was requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Request an interruption from inside the process (tests).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// An interruption that stopped the work at a safe point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("interrupted")]
pub struct Interrupted;

/// A safe point named `phase`: `Err(Interrupted)` if a signal has arrived. Pauses here first
/// when `CROSSCHECK_PAUSE_AT` names this phase (once per process).
pub fn checkpoint(phase: &str) -> Result<(), Interrupted> {
    if std::env::var(PAUSE_VARIABLE).is_ok_and(|p| p == phase)
        && !PAUSED.swap(true, Ordering::SeqCst)
    {
        let _ = writeln!(std::io::stderr(), "crosscheck: paused at {phase}");
        let start = Instant::now();
        while !requested() && start.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    if requested() {
        Err(Interrupted)
    } else {
        Ok(())
    }
}
