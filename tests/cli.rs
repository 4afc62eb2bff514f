//! The `crosscheck` binary: listing cases and refusing bad input before running anything.

mod common;
use common::{RIGID_CASES, SPRINGS_CASES};
use std::process::Command;

fn crosscheck(args: &[&str], dir: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_crosscheck"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run crosscheck")
}

#[test]
fn list_prints_one_line_per_case() {
    // The cases are found where the user is: `cases/` in the working directory.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = crosscheck(&["list"], dir);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "status {:?}\n{stderr}", out.status);
    let lines: Vec<&str> = stdout.lines().collect();
    // The 13 seed cases of `cases/` and the 22 of the stress family in `cases/stress/` (11
    // `stress_*`, 11 `contact_*`).
    assert_eq!(lines.len(), 35, "{stdout}");
    assert_eq!(
        lines.iter().filter(|l| l.starts_with("contact_")).count(),
        11,
        "{stderr}"
    );
    assert_eq!(
        lines.iter().filter(|l| l.starts_with("stress_")).count(),
        11,
        "{stdout}"
    );
    for id in RIGID_CASES.into_iter().chain(SPRINGS_CASES) {
        let hits = lines
            .iter()
            .filter(|l| l.split_whitespace().next() == Some(id))
            .count();
        assert_eq!(
            hits, 1,
            "case `{id}` should head exactly one line:\n{stdout}"
        );
    }
    for l in &lines {
        let dim = l.split_whitespace().nth(2);
        assert!(matches!(dim, Some("2D" | "3D")), "{l}");
    }
}

/// Elsewhere, `--cases DIR` says where they are; without it, a clear message and exit 2.
#[test]
fn cases_are_found_in_the_working_directory_or_with_cases() {
    let dir = tempfile::tempdir().unwrap();
    let out = crosscheck(&["list"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("no case directory") && stderr.contains("--cases DIR"),
        "{stderr}"
    );
    let cases = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let out = crosscheck(&["list", "--cases", cases.to_str().unwrap()], dir.path());
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 35);
    let out = crosscheck(&["run", "--out", "o"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.path().join("o").exists());
}

#[test]
fn run_refuses_an_unknown_case_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = crosscheck(&["run", "no_such_case", "--out", "somewhere"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no case `no_such_case`"), "{stderr}");
    assert!(!dir.path().join("somewhere").exists());
}

#[test]
fn run_refuses_an_invalid_case_file_naming_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let src =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/springs_grounded_a.toml");
    let text = std::fs::read_to_string(&src).expect("the shipped case");
    let bad = dir.path().join("springs_grounded_a.toml");
    std::fs::write(&bad, text.replacen("dimension = 2", "dimension = 4", 1)).unwrap();
    let out = crosscheck(&["run", bad.to_str().unwrap(), "--out", "o"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("springs_grounded_a.toml:"), "{stderr}");
    assert!(stderr.contains("dimension"), "{stderr}");
    assert!(!dir.path().join("o").exists());
}

#[test]
fn run_refuses_an_unknown_engine_listing_valid_ones() {
    let dir = tempfile::tempdir().unwrap();
    let out = crosscheck(&["run", "--engines", "explicit,warp"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("unknown engine `warp`"), "{stderr}");
    assert!(stderr.contains("explicit_small"), "{stderr}");
    assert!(!dir.path().join("report").exists());
}
