//! The report survives signals in every phase, a second run, hostile paths and inputs, a
//! closed or full standard output, and resource refusals. Every test that runs against an
//! existing report asserts it is byte-identical afterwards (or, where a run was meant to
//! succeed, complete), and that no stray file is left beside it.
mod common;
use common::snapshot;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The engines that step in time and are studied (a discrepancy budget each).
fn studied() -> usize {
    crosscheck::run::registry::all()
        .iter()
        .filter(|e| e.stepping().is_some())
        .count()
}

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_crosscheck"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

/// Names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const SMALL: [&str; 2] = ["springs_grounded_a", "rigid2d_pin_lumped"];

/// A root with a finished report of the two small cases at `root/report`.
fn previous_report() -> (tempfile::TempDir, PathBuf, BTreeMap<String, Vec<u8>>) {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("report");
    let status = bin()
        .args(["run", "-q"])
        .args(SMALL)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    let before = snapshot(&out);
    // Engines that step in time and are studied have a discrepancy budget: all but the closed
    // form and the reference (and rapier's older releases, with `rapier-versions`).
    let stepping = studied();
    assert_eq!(
        before.len(),
        2 * (crosscheck::run::registry::all().len() + stepping) + 2 * 3 + 2 + 2 + 3 + 6,
        "CSVs, budget CSVs, case figures (histories, errors, sketch), budget figures per family, \
         case pages, summary, verdicts, timings, REPORT.md, results.csv, README.md and the three \
         question pages"
    );
    (root, out, before)
}

/// Start a run paused at `phase`; returns once it says so.
fn paused_run(phase: &str, out: &Path, extra: &[&str]) -> Child {
    let mut child = bin()
        .env("CROSSCHECK_PAUSE_AT", phase)
        .args(["run", "-q"])
        .args(SMALL)
        .args(extra)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let mut lines = BufReader::new(stderr).lines();
    let wanted = format!("paused at {phase}");
    loop {
        match lines.next() {
            Some(Ok(l)) if l.contains(&wanted) => break,
            Some(Ok(_)) => {}
            other => panic!("the run never paused at {phase}: {other:?}"),
        }
    }
    // Keep draining stderr so the child never blocks on it.
    std::thread::spawn(move || for _ in lines {});
    child
}

fn signal(child: &Child, sig: i32) {
    // SAFETY: sending a signal to our own child process.
    unsafe { libc::kill(child.id() as i32, sig) };
}

/// A signal in each phase of a run stops it with 130 and leaves the previous report byte for
/// byte, with no staging directory or lock file left.
#[test]
fn a_signal_in_any_phase_loses_nothing() {
    let (root, out, before) = previous_report();
    let phases = ["load", "run", "csv", "figures", "summary", "report", "swap"];
    for (k, phase) in phases.iter().enumerate() {
        let sig = if k % 2 == 0 {
            libc::SIGTERM
        } else {
            libc::SIGINT
        };
        let mut child = paused_run(phase, &out, &[]);
        signal(&child, sig);
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(130), "phase {phase}");
        assert_eq!(snapshot(&out), before, "phase {phase}: the previous report");
        assert_eq!(
            names(root.path()),
            ["report"],
            "phase {phase}: no stray files"
        );
    }
}

/// A second signal ends the run at once; the report is still whole, and the next run removes
/// the staging directory it left.
#[test]
fn a_second_signal_aborts_at_once_and_still_loses_nothing() {
    let (root, out, before) = previous_report();
    let mut child = paused_run("csv", &out, &[]);
    // Two signals before the main thread looks: the handler exits on the second.
    signal(&child, libc::SIGTERM);
    signal(&child, libc::SIGTERM);
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    assert_eq!(snapshot(&out), before);
    let status = bin()
        .args(["run", "-q", "springs_grounded_a", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(
        names(root.path()),
        ["report"],
        "the dead run's staging is gone"
    );
    assert_eq!(snapshot(&out).len(), before.len());
}

/// Two runs on one output: the second refuses with --no-wait (exit 2), or waits for the first
/// and then writes a complete report.
#[test]
fn one_writer_per_output() {
    let (root, out, before) = previous_report();
    let mut first = paused_run("run", &out, &[]);
    let refused = bin()
        .args(["run", "-q", "--no-wait", "springs_grounded_b", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("another crosscheck run") && stderr.contains(&first.id().to_string()),
        "{stderr}"
    );
    assert_eq!(snapshot(&out), before);
    // A waiting run: it says so, then goes on when the first one ends.
    let waiting = bin()
        .args(["run", "-q", "springs_grounded_b", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(snapshot(&out), before, "the waiting run wrote nothing");
    signal(&first, libc::SIGTERM);
    assert_eq!(first.wait().unwrap().code(), Some(130));
    let done = waiting.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert!(done.status.success(), "{stderr}");
    assert!(
        stderr.contains("waiting: another crosscheck run"),
        "{stderr}"
    );
    let after = snapshot(&out);
    assert_eq!(
        after.len(),
        before.len() + crosscheck::run::registry::all().len() + studied() + 3 + 1, // CSVs, budget CSVs, 3 figures, its page
        "the new case's CSVs and figure"
    );
    for (name, bytes) in &before {
        if name.starts_with("data/") {
            assert_eq!(after.get(name), Some(bytes), "{name} kept");
        }
    }
    assert_eq!(names(root.path()), ["report"]);
}

/// `--out` at a regular file, or below one, is refused before anything runs; the file is
/// untouched and nothing is created beside it.
#[test]
fn out_must_be_a_directory() {
    let root = tempfile::tempdir().unwrap();
    let file = root.path().join("notes.txt");
    std::fs::write(&file, "the user's notes").unwrap();
    for out in [file.clone(), file.join("sub")] {
        let o = bin()
            .args(["run", "-q", "springs_grounded_a", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&file.display().to_string()) && stderr.contains("nothing was run"),
            "{stderr}"
        );
        assert!(o.stdout.is_empty());
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "the user's notes");
    assert_eq!(names(root.path()), ["notes.txt"]);
}

/// `--out .` writes the report's entries into the working directory and touches nothing else.
#[test]
fn out_dot_keeps_the_users_files() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("notes.txt"), "mine").unwrap();
    std::fs::create_dir(dir.path().join("data-of-mine")).unwrap();
    for case in SMALL {
        let o = bin()
            .current_dir(dir.path())
            .args(["run", "-q", case, "--out", ".", "--cases"])
            .arg(cases_dir())
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_eq!(
        names(dir.path()),
        [
            "README.md",
            "REPORT.md",
            "accuracy.md",
            "cases",
            "cost.md",
            "data",
            "data-of-mine",
            "figures",
            "notes.txt",
            "results.csv",
            "stability.md",
            "summary.json",
            "timings.json",
            "verdicts.json"
        ]
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(
        names(&dir.path().join("data")),
        ["rigid2d_pin_lumped", "springs_grounded_a"]
    );
}

/// A pipe whose reading end is already closed.
fn closed_pipe() -> Stdio {
    let mut fds = [0; 2];
    // SAFETY: pipe fills two descriptors; we close the reading one and hand the writing one
    // to the child, which owns it from then on.
    unsafe {
        assert_eq!(libc::pipe(fds.as_mut_ptr()), 0);
        libc::close(fds[0]);
        use std::os::fd::FromRawFd;
        Stdio::from(std::fs::File::from_raw_fd(fds[1]))
    }
}

/// A full standard output gives a clear error and exit 1, never a panic; a closed one (the
/// reader left, as `| head` does) ends the output quietly with the command's own exit code. A
/// run puts its report in place either way (the table is printed after the swap).
#[test]
fn closed_or_full_stdout_is_an_error_not_a_panic() {
    let list = bin().args(["list"]).stdout(closed_pipe()).output().unwrap();
    let stderr = String::from_utf8_lossy(&list.stderr);
    assert_eq!(list.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    let full = std::fs::File::create("/dev/full").unwrap();
    let list = bin().args(["list"]).stdout(full).output().unwrap();
    let stderr = String::from_utf8_lossy(&list.stderr);
    assert_eq!(list.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot write to standard output"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");

    let (root, out, before) = previous_report();
    for (stdout, code) in [
        (closed_pipe(), 0),
        (Stdio::from(std::fs::File::create("/dev/full").unwrap()), 1),
    ] {
        let run = bin()
            .args(["run", "-q", "springs_grounded_b", "--out"])
            .arg(&out)
            .stdout(stdout)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(code), "{stderr}");
        assert_eq!(
            stderr.contains("cannot write to standard output"),
            code == 1,
            "{stderr}"
        );
        let after = snapshot(&out);
        assert_eq!(
            after.len(),
            before.len() + crosscheck::run::registry::all().len() + studied() + 3 + 1, // CSVs, budget CSVs, 3 figures, its page
            "the report is in place"
        );
    }
    assert_eq!(names(root.path()), ["report"]);
}

#[test]
fn a_full_standard_error_is_an_exit_code_not_a_panic() {
    // Every message of these commands goes to standard error, which cannot take it: the exit
    // code must still say what happened (2: bad input, 1: the output cannot be written), never
    // 101 (a panic).
    let root = tempfile::tempdir().unwrap();
    let missing = root.path().join("missing.toml");
    let blocked = root.path().join("file");
    std::fs::write(&blocked, "not a directory").unwrap();
    for (args, code) in [
        (vec!["check".into(), missing.clone()], 2),
        (vec!["run".into(), "-q".into(), missing.clone()], 2),
        (
            vec![
                "run".into(),
                "-q".into(),
                "springs_grounded_a".into(),
                "--out".into(),
                blocked.join("report"),
            ],
            2,
        ),
    ] {
        let status = bin()
            .args(&args)
            .stdout(Stdio::null())
            .stderr(Stdio::from(std::fs::File::create("/dev/full").unwrap()))
            .status()
            .unwrap();
        assert_eq!(status.code(), Some(code), "{args:?}");
    }
}

#[test]
fn a_scene_with_nothing_free_to_move_runs_on_every_engine() {
    // One mass on a spring, held in every DOF for the whole step: every engine reports it at
    // rest (no engine may panic on an empty set of free coordinates).
    let root = tempfile::tempdir().unwrap();
    let case = root.path().join("held.toml");
    let text = std::fs::read_to_string(cases_dir().join("springs_grounded_a.toml"))
        .unwrap()
        .replace("id = \"springs_grounded_a\"", "id = \"held\"")
        .replace(
            "hold = [{ node = \"3\", dofs = [\"uy\"] }]\n\n# Tolerances",
            "hold = [{ node = \"3\", dofs = [\"all\"] }]\n\n# Tolerances",
        );
    assert!(
        text.contains("dofs = [\"all\"] }]\n\n# Tolerances"),
        "the dynamic step is held"
    );
    std::fs::write(&case, text).unwrap();
    let out = root.path().join("report");
    let run = bin()
        .args(["run", "-q"])
        .arg(&case)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_eq!(run.status.code(), Some(0), "{stdout}");
    assert!(!stdout.contains("panicked"), "{stdout}");
    for engine in crosscheck::run::registry::all() {
        let stem = crosscheck::contract::file_stem(engine.name());
        let csv = out.join("data/held").join(format!("{stem}.csv"));
        let text = std::fs::read_to_string(&csv).unwrap_or_else(|e| panic!("{csv:?}: {e}"));
        let held = text.lines().skip(1).all(|row| {
            row.split(',')
                .nth(1)
                .is_some_and(|u| u.parse::<f64>().unwrap() == 1.0)
        });
        assert!(held, "{}: u_end moved from 1", engine.name());
    }
}

/// `crosscheck run ARGS --out OUT` is refused with exit 2, saying `expected` and that nothing
/// was run, and the report at `out` is still `before`.
fn refused<A: AsRef<std::ffi::OsStr> + std::fmt::Debug>(
    args: &[A],
    expected: &str,
    out: &Path,
    before: &BTreeMap<String, Vec<u8>>,
) {
    let o = bin()
        .args(["run", "-q"])
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(expected),
        "{args:?}: no `{expected}` in {stderr}"
    );
    assert!(stderr.contains("nothing was run"), "{args:?}: {stderr}");
    assert_eq!(&snapshot(out), before, "{args:?}: the previous report");
}

/// A run above its resource limits is refused before anything runs, with the figures.
#[test]
fn runs_above_their_limits_are_refused_with_the_figures() {
    let (root, out, before) = previous_report();
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(cases_dir().join("springs_grounded_a.toml")).unwrap();
    let write = |name: &str, from: &str, to: &str| -> PathBuf {
        let t = text
            .replacen(
                "id = \"springs_grounded_a\"",
                &format!("id = \"{name}\""),
                1,
            )
            .replacen(from, to, 1);
        assert_ne!(t, text);
        let p = dir.path().join(format!("{name}.toml"));
        std::fs::write(&p, t).unwrap();
        p
    };
    let long = write("long_run", "duration = 1.0\n", "duration = 1.0e9\n");
    let rows = write("many_rows", "rows = 501", "rows = 1000000000");
    let cases: [(Vec<std::ffi::OsString>, &str); 5] = [
        (
            vec![
                "springs_grounded_a".into(),
                "--increment".into(),
                "1e-12".into(),
            ],
            "1.000e12 increments",
        ),
        (vec![long.into_os_string()], "(--max-increments)"),
        (vec![rows.into_os_string()], "1000000000 output rows exceed"),
        (
            vec![
                "springs_grounded_a".into(),
                "--max-rows".into(),
                "300".into(),
            ],
            "501 output rows exceed the limit of 300",
        ),
        (
            vec!["--max-memory".into(), "1e5".into()],
            "above the limit of 1.000e5 (--max-memory",
        ),
    ];
    for (args, expected) in cases {
        refused(&args, expected, &out, &before);
    }
    assert_eq!(names(root.path()), ["report"]);
}

/// Command-line overrides are validated like the same values in a case file.
#[test]
fn overrides_are_validated_like_case_values() {
    let (root, out, before) = previous_report();
    for (args, expected) in [
        (
            ["--increment", "1e-2"],
            "--increment: case rigid2d_pin_lumped: time.increment",
        ),
        (
            ["--increment", "5e-324"],
            "--increment 5e-324: outside the supported range",
        ),
        (
            ["--penalty", "1e300"],
            "--penalty 1e300: outside the supported range",
        ),
        // A stiffer penalty lowers the rigid case's stable increment below its given one.
        (
            ["--penalty", "1e16"],
            "--penalty: case rigid2d_pin_lumped: time.increment",
        ),
    ] {
        let mut all: Vec<&str> = SMALL.to_vec();
        all.extend(args);
        refused(&all, expected, &out, &before);
    }
    assert_eq!(names(root.path()), ["report"]);
}

/// Run `check` on a path with a deadline (a FIFO must not block it).
fn check_within(path: &Path, seconds: u64) -> Output {
    let mut child = bin()
        .arg("check")
        .arg(path)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(seconds) {
            child.kill().unwrap();
            panic!("check {} did not finish in {seconds} s", path.display());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

/// Only regular files of at most 1 MiB in UTF-8 are read; everything else is refused with the
/// path (and, for bad UTF-8, the line and column), exit 2.
#[test]
fn only_small_regular_utf8_files_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.toml");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let folder = dir.path().join("folder.toml");
    std::fs::create_dir(&folder).unwrap();
    let big = dir.path().join("big.toml");
    std::fs::write(&big, "#".repeat((1 << 20) + 1)).unwrap();
    let text = std::fs::read_to_string(cases_dir().join("springs_grounded_a.toml")).unwrap();
    let utf8 = dir.path().join("springs_grounded_a.toml");
    let mut bytes = text.into_bytes();
    let at = bytes.windows(5).position(|w| w == b"title").unwrap() + 9;
    bytes[at] = 0xff;
    std::fs::write(&utf8, &bytes).unwrap();
    let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    let column = at - bytes[..at].iter().rposition(|&b| b == b'\n').unwrap();
    for (path, expected) in [
        (fifo.clone(), "not a regular file".to_string()),
        (PathBuf::from("/dev/zero"), "not a regular file".to_string()),
        (folder, "not a regular file".to_string()),
        (big, "a case file may have at most 1048576".to_string()),
        (
            utf8.clone(),
            format!(
                "{}:{line}:{column}: the file is not valid UTF-8",
                utf8.display()
            ),
        ),
    ] {
        let o = check_within(&path, 20);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {stderr}", path.display());
        assert!(
            stderr.contains(&path.display().to_string()) && stderr.contains(&expected),
            "{}: no `{expected}` in {stderr}",
            path.display()
        );
    }
}

/// Extreme but valid: a direction or frame axis of magnitude 1e300 is normalised without
/// overflow, so the run gives the same answer as with a unit vector.
#[test]
fn huge_directions_are_normalised_without_overflow() {
    for (id, from, to) in [
        (
            "springs_n2n_b",
            "direction = [1.0, 0.0]",
            "direction = [1.0e300, 0.0]",
        ),
        (
            "springs_grounded_c",
            "x_axis = [1.0, 1.0]",
            "x_axis = [1.0e300, 1.0e300]",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let text = std::fs::read_to_string(cases_dir().join(format!("{id}.toml"))).unwrap();
        assert!(text.contains(from), "{id}");
        let file = dir.path().join(format!("{id}.toml"));
        std::fs::write(&file, text.replace(from, to)).unwrap();
        let out = dir.path().join("out");
        let o = bin()
            .args(["run", "-q", "--engines", "explicit,analytic", "--out"])
            .arg(&out)
            .arg(&file)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let reference = tempfile::tempdir().unwrap();
        let o = bin()
            .args(["run", "-q", id, "--engines", "explicit,analytic", "--out"])
            .arg(reference.path())
            .output()
            .unwrap();
        assert!(o.status.success());
        for engine in ["explicit", "analytic"] {
            let csv = format!("data/{id}/{engine}.csv");
            assert_eq!(
                std::fs::read(out.join(&csv)).unwrap(),
                std::fs::read(reference.path().join(&csv)).unwrap(),
                "{id} / {engine}: the same history as with a unit vector"
            );
        }
    }
}

/// A write that fails part-way (here: a file-size limit, as a full disk would) gives a clear
/// error and exit 1, and the previous report stays as it was.
#[test]
fn a_failing_write_keeps_the_previous_report() {
    use std::os::unix::process::CommandExt;
    let (root, out, before) = previous_report();
    let mut cmd = bin();
    cmd.args(["run", "-q", "springs_grounded_b", "--out"])
        .arg(&out);
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let limit = libc::rlimit {
                rlim_cur: 4096,
                rlim_max: 4096,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let o = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot write the report (the previous one is unchanged)")
            && stderr.contains("File too large"),
        "{stderr}"
    );
    assert_eq!(snapshot(&out), before);
    assert_eq!(names(root.path()), ["report"]);
}
