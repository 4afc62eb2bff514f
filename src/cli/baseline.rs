//! The commands between reports: baselines, as criterion and insta users expect them
//! (`compare` and its `--accept`, a run's `--baseline NAME` and `--save-baseline NAME`, kept in
//! `baselines/NAME` in the working directory or `--baseline-dir DIR`), and `merge`, which
//! joins the reports of a partitioned run's shards.

use super::{CompareArgs, Stdout, outcome};
use crate::pipeline;
use crate::report::{self, staging};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// A baseline's name: letters, digits, `_`, `-` and `.`, not starting with `.` (it names a
/// directory).
pub(super) fn name(s: &str) -> Result<String, String> {
    let portable = s
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if s.is_empty() || !portable || s.starts_with('.') {
        return Err(
            "a baseline name is letters, digits, `_`, `-` and `.`, not starting with `.`"
                .to_string(),
        );
    }
    Ok(s.to_string())
}

/// Where the baseline `name` is kept in the baselines' directory `dir`.
pub(super) fn path(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

/// `crosscheck compare`: print the comparison (exit 1 when a tier fails, 2 when the reports
/// cannot be compared); with `--accept`, then make NEW the baseline (exit 0 once it is).
pub(super) fn compare_command(args: CompareArgs) -> ExitCode {
    let compared = pipeline::compare(
        &args.base,
        &args.new,
        args.threshold,
        args.physics_only,
        args.junit.as_deref(),
    );
    if !args.accept {
        return outcome(compared);
    }
    let mut out = Stdout::default();
    match compared {
        Ok((text, _)) => out.print(&text),
        Err(why) => out.print(&format!("(not compared: {why})\n")),
    }
    if !args.new.join("summary.json").is_file() {
        eprintln!(
            "error: {} is not a crosscheck report; nothing was accepted",
            args.new.display()
        );
        return out.finish(ExitCode::from(2));
    }
    // Only a report (or nothing yet) is replaced: never a directory of the user's own files.
    let base_empty = std::fs::read_dir(&args.base).map_or(true, |mut d| d.next().is_none());
    if !base_empty && !args.base.join("summary.json").is_file() {
        eprintln!(
            "error: {} holds files and no crosscheck report; nothing was accepted",
            args.base.display()
        );
        return out.finish(ExitCode::from(2));
    }
    let code = match copy_report(&args.new, &args.base) {
        Ok(()) => {
            out.print(&format!(
                "accepted: {} is now the baseline in {}\n",
                args.new.display(),
                args.base.display()
            ));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}; {} is unchanged", args.base.display());
            ExitCode::FAILURE
        }
    };
    out.finish(code)
}

/// Put a copy of the report in `source` in place of `target`'s, under `target`'s lock.
pub(super) fn copy_report(source: &Path, target: &Path) -> Result<(), String> {
    let target = staging::resolve_output(target).map_err(|e| e.to_string())?;
    let _lock = staging::OutputLock::acquire(&target, true)
        .map_err(|e| format!("cannot lock {}: {e}", target.display()))?;
    staging::replace_report(source, &target, &report::ENTRIES)
        .map_err(|e| format!("cannot put the report in {}: {e}", target.display()))
}

/// Before a run: the baseline `name` in `baselines` must exist to be compared with (exit 2
/// otherwise, nothing run).
pub(super) fn check_exists(baselines: &Path, name: Option<&str>) -> Result<(), ExitCode> {
    let Some(name) = name else {
        return Ok(());
    };
    let dir = path(baselines, name);
    if dir.join("summary.json").is_file() {
        return Ok(());
    }
    eprintln!(
        "error: no baseline `{name}` ({} holds no report; save one with --save-baseline \
         {name}); nothing was run",
        dir.display()
    );
    Err(ExitCode::from(2))
}

/// After a run whose report is in place at `target`: compare it with the baseline `compare`
/// in `baselines` (exit 1 when a tier fails, printing the comparison), then save it there as
/// `save`.
pub(super) fn after_run(
    target: &Path,
    baselines: &Path,
    (compare, save): (Option<&str>, Option<&str>),
    stdout: &mut Stdout,
) -> ExitCode {
    let mut code = ExitCode::SUCCESS;
    if let Some(name) = compare {
        let base = path(baselines, name);
        // A baseline kept without its histories (accepted from a report that leaves `data/`
        // out) is compared by its verdicts, and says so.
        let physics_only = !base.join("data").is_dir();
        if physics_only {
            eprintln!(
                "note: the baseline `{name}` keeps no histories (no data/): its verdicts alone \
                 are compared"
            );
        }
        match pipeline::compare(&base, target, report::regression::DRIFT, physics_only, None) {
            Ok((text, failed)) => {
                stdout.print(&format!("\nagainst the baseline `{name}`:\n{text}"));
                if failed {
                    code = ExitCode::FAILURE;
                }
            }
            Err(why) => {
                eprintln!("error: cannot compare with the baseline `{name}`: {why}");
                code = ExitCode::FAILURE;
            }
        }
    }
    if let Some(name) = save {
        let dir = path(baselines, name);
        match copy_report(target, &dir) {
            Ok(()) => stdout.print(&format!("baseline `{name}` saved: {}\n", dir.display())),
            Err(e) => {
                eprintln!("error: cannot save the baseline `{name}`: {e}");
                code = ExitCode::FAILURE;
            }
        }
    }
    code
}

/// `crosscheck merge SHARD... --out DIR`: the shards' reports joined into one, put in place
/// (exit 2 when they are not shards of one run, 1 when it cannot be written).
pub(super) fn merge_command(shards: &[PathBuf], out: &Path, wait: bool) -> ExitCode {
    use crate::report::merge::MergeError;
    let target = match staging::resolve_output(out) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}; nothing was merged");
            return ExitCode::from(2);
        }
    };
    let (_lock, staged) = match super::studies::lock_and_stage(&target, wait, &report::ENTRIES) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let mut stdout = Stdout::default();
    let code = match pipeline::merge(shards, staged) {
        Ok(summary) => {
            stdout.print(&format!(
                "merged {} shard(s), {} cases: {}\n",
                shards.len(),
                summary.cases.len(),
                report::report_path(out).display()
            ));
            ExitCode::SUCCESS
        }
        Err(MergeError::Data(report::data::DataError::Interrupted)) => super::interrupted(),
        Err(e @ MergeError::Data(_)) => {
            eprintln!("error: {e}; the previous report is unchanged");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("error: {e}; nothing was merged");
            ExitCode::from(2)
        }
    };
    stdout.finish(code)
}
