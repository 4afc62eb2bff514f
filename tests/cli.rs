//! The `crosscheck` binary: listing cases and refusing bad input before running anything.

mod common;
use common::{RIGID_CASES, SPRINGS_CASES};
use std::process::Command;

fn crosscheck(args: &[&str], dir: &std::path::Path) -> std::process::Output {
    // Where no cases/ is at hand, the shipped cases are written out under the cache directory:
    // the tests' own, not the user's.
    Command::new(env!("CARGO_BIN_EXE_crosscheck"))
        .args(args)
        .current_dir(dir)
        .env(
            "XDG_CACHE_HOME",
            std::env::temp_dir().join("crosscheck-tests"),
        )
        .env_remove("CROSSCHECK_CASES")
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
    // The 13 seed cases of `cases/`, the 22 of the stress family in `cases/stress/` (11
    // `stress_*`, 11 `contact_*`) and the 12 of the friction family in `cases/friction/`,
    // each of which says so.
    assert_eq!(lines.len(), 47, "{stdout}");
    let rough: Vec<&&str> = lines
        .iter()
        .filter(|l| l.starts_with("friction_"))
        .collect();
    assert_eq!(rough.len(), 12, "{stdout}");
    assert!(rough.iter().all(|l| l.contains("friction(1)")), "{stdout}");
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

/// Elsewhere, the binary uses the cases shipped in it (written out under the cache directory);
/// `--cases DIR` and `CROSSCHECK_CASES` choose others, and one that is not a directory is a
/// clear message and exit 2.
#[test]
fn cases_are_found_anywhere() {
    let dir = tempfile::tempdir().unwrap();
    let cache = tempfile::tempdir().unwrap();
    let anywhere = |args: &[&str], cases: Option<&str>| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_crosscheck"));
        command
            .args(args)
            .current_dir(dir.path())
            .env("XDG_CACHE_HOME", cache.path())
            .env_remove("CROSSCHECK_CASES");
        if let Some(c) = cases {
            command.env("CROSSCHECK_CASES", c);
        }
        command.output().expect("run crosscheck")
    };
    let out = anywhere(&["list"], None);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 47);
    // They were written under the cache directory, not here.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let out = anywhere(
        &[
            "run",
            "springs_grounded_a",
            "--engines",
            "analytic,explicit",
            "--out",
            "o",
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        dir.path()
            .join("o/data/springs_grounded_a/explicit.csv")
            .is_file()
    );

    // A directory of one case, by the environment and by the option (which wins).
    let one = tempfile::tempdir().unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    std::fs::copy(
        shipped.join("springs_grounded_b.toml"),
        one.path().join("springs_grounded_b.toml"),
    )
    .unwrap();
    let out = anywhere(&["list"], Some(one.path().to_str().unwrap()));
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 1);
    let out = anywhere(
        &["list", "--cases", shipped.to_str().unwrap()],
        Some(one.path().to_str().unwrap()),
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 47);

    let out = anywhere(&["list"], Some("no/such/dir"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("no case directory no/such/dir") && stderr.contains("CROSSCHECK_CASES"),
        "{stderr}"
    );
    let out = anywhere(&["run", "--out", "p"], Some("no/such/dir"));
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.path().join("p").exists());
}

#[test]
fn run_refuses_an_unknown_case_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = crosscheck(&["run", "no_such_case", "--out", "somewhere"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no case `no_such_case`"), "{stderr}");
    let out = crosscheck(
        &["run", "springs_grounded_z", "--out", "somewhere"],
        dir.path(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("did you mean `springs_grounded_a`?"),
        "{stderr}"
    );
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
    let out = crosscheck(&["run", "--engines", "explict"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("unknown engine `explict`, did you mean `explicit`?"),
        "{stderr}"
    );
}

/// `run` gates a pipeline: `--fail-on-miss` exits 1 when a judged cell of the engines named
/// misses its tolerance (the report is written either way), `--junit` writes a test case per
/// cell, and a gate that could judge nothing is refused before anything runs.
#[test]
fn run_gates_a_pipeline_on_its_verdicts() {
    let dir = tempfile::tempdir().unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let text = std::fs::read_to_string(shipped.join("springs_grounded_a.toml")).unwrap();
    // The explicit engine's error here is 7.5e-7 of the peak (central differences at the
    // case's increment, second order): within 1e-4, never within 1e-12.
    let tight = text.replace("\nexplicit = 1.0e-4", "\nexplicit = 1.0e-12");
    assert_ne!(tight, text);
    std::fs::write(
        dir.path().join("tight.toml"),
        tight.replace("springs_grounded_a", "tight"),
    )
    .unwrap();
    let cases = dir.path().join("tight.toml");
    let engines = "analytic,reference,explicit,explicit_small";
    let run = |case: &str, gate: &str| {
        crosscheck(
            &[
                "run",
                case,
                "--engines",
                engines,
                "--out",
                "o",
                gate,
                "--junit",
                "j.xml",
            ],
            dir.path(),
        )
    };
    let out = run(cases.to_str().unwrap(), "--fail-on-miss");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("tight / explicit: 7."), "{stderr}");
    assert!(!stderr.contains("tight / explicit_small"), "{stderr}");
    assert!(dir.path().join("o/REPORT.md").is_file());
    let xml = std::fs::read_to_string(dir.path().join("j.xml")).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let cases_xml: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .collect();
    assert_eq!(cases_xml.len(), 2, "{xml}");
    let failed: Vec<_> = cases_xml
        .iter()
        .filter(|n| n.children().any(|c| c.has_tag_name("failure")))
        .map(|n| n.attribute("name").unwrap())
        .collect();
    assert_eq!(failed, ["explicit"], "{xml}");
    let verdicts = std::fs::read_to_string(dir.path().join("o/verdicts.json")).unwrap();
    let verdicts: serde_json::Value = serde_json::from_str(&verdicts).unwrap();
    assert_eq!(verdicts["counts"]["missed"], 1);
    assert_eq!(verdicts["counts"]["met"], 1);

    // Gated on the engine that meets its tolerance only, or on the shipped case: exit 0.
    let out = run(cases.to_str().unwrap(), "--fail-on-miss=explicit_small");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run("springs_grounded_a", "--fail-on-miss");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // No exact solution to judge against, or an engine the run has not got: exit 2, nothing run.
    let out = crosscheck(
        &[
            "run",
            "springs_grounded_a",
            "--engines",
            "explicit",
            "--out",
            "p",
            "--fail-on-miss",
        ],
        dir.path(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("exact solutions"));
    let out = crosscheck(
        &[
            "run",
            "springs_grounded_a",
            "--engines",
            engines,
            "--out",
            "p",
            "--fail-on-miss=explict",
        ],
        dir.path(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("did you mean `explicit`?"));
    assert!(!dir.path().join("p").exists());
}
