//! Runtime guards, interrupted runs and determinism.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::run::{self, Plan};
use crosscheck::scene::IncrementRule;
use std::collections::BTreeMap;
use std::process::Command;
use std::time::Duration;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crosscheck"))
}

/// A run above the stable increment stops with a diagnosis instead of producing garbage.
#[test]
fn an_unstable_run_stops_with_a_diagnosis() {
    let scene = scene("rigid2d_pin_lumped");
    let stable = ExplicitEngine::finite()
        .stable_increment(&scene, &RunSettings::default())
        .unwrap();
    let err = ExplicitEngine::finite()
        .run(
            &scene,
            &RunSettings {
                increment: Some(IncrementRule::Forced(stable.increment * 1.5)),
                ..Default::default()
            },
        )
        .unwrap_err()
        .to_string();
    println!("{err}");
    assert!(
        err.contains("unstable") && err.contains(&format!("{:e}", stable.increment)),
        "{err}"
    );
}

/// One case failing does not stop the others; the report marks it.
#[test]
fn a_failed_case_does_not_stop_the_others() {
    let out = tempfile::tempdir().unwrap();
    let mut bad = scene("rigid2d_pin_lumped");
    bad.settings.increment = IncrementRule::Forced(1e-3);
    let plan = Plan {
        cases: vec![bad, scene("springs_n2n_b")],
        engines: crosscheck::run::registry::all(),
        settings: RunSettings::default(),
    };
    let outcome = run::execute(&plan, false);
    // The closed form of the bad case still runs (and so does rapier, which is implicit and
    // has no stability limit); both explicit runs of it fail.
    assert_eq!(outcome.failures(), 2);
    assert!(
        outcome
            .jobs
            .iter()
            .filter(|j| j.case == "springs_n2n_b")
            .all(|j| j.is_ok())
    );
    let summary = crosscheck::report::write(
        out.path(),
        &plan,
        &outcome,
        &Default::default(),
        &out.path().join("none"),
    )
    .unwrap();
    let bad_runs = &summary
        .cases
        .iter()
        .find(|c| c.id == "rigid2d_pin_lumped")
        .unwrap()
        .runs;
    assert!(
        bad_runs
            .iter()
            .filter(|r| r.engine.starts_with("explicit"))
            .all(|r| r.error.as_deref().is_some_and(|e| e.contains("unstable")))
    );
    let md = std::fs::read_to_string(out.path().join("accuracy.md")).unwrap();
    assert!(
        md.contains("Runs that failed or went unstable")
            && md.contains("rigid2d_pin_lumped / explicit")
    );
}

/// A few cases from every family: seed springs and rigid bodies, contact that strikes (judged
/// against `reference`), contact without a closed form where `explicit_small` does not apply,
/// a friction slide, and the ramp case rapier refuses.
const SAMPLE: [&str; 6] = [
    "springs_grounded_a",
    "rigid2d_pin_lumped",
    "contact_drop_e09",
    "contact_balls_oblique",
    "friction_slide_stop_2d",
    "friction_ramp_breakaway",
];

/// The previous report an interrupted run must leave: two cases, so that a rerun of one can be
/// seen to keep the other's files.
const PREVIOUS: [&str; 2] = ["springs_grounded_a", "rigid2d_pin_lumped"];

/// Kill a run of the whole report mid-way (slow: a tiny increment) with `signal`; the previous
/// report (of [`PREVIOUS`]) must be left byte for byte.
fn interrupt(signal: i32) -> (tempfile::TempDir, BTreeMap<String, Vec<u8>>) {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("report");
    assert!(
        bin()
            .args(["run", "-q"])
            .args(PREVIOUS)
            .arg("--out")
            .arg(&out)
            .status()
            .unwrap()
            .success()
    );
    let before = snapshot(&out);
    let mut child = bin()
        .args(["run", "-q", "--increment", "2e-7", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    // SAFETY: sending a signal to our own child process.
    unsafe { libc::kill(child.id() as i32, signal) };
    let status = child.wait().unwrap();
    assert!(!status.success(), "the run was interrupted");
    assert_eq!(
        snapshot(&out),
        before,
        "the previous report is intact, byte for byte"
    );
    (root, before)
}

#[test]
fn sigkill_leaves_the_previous_report_whole() {
    let (root, before) = interrupt(libc::SIGKILL);
    // The staging directory a SIGKILL leaves behind is removed by the next run.
    let out = root.path().join("report");
    assert!(
        bin()
            .args(["run", "-q", "springs_grounded_a", "--out"])
            .arg(&out)
            .status()
            .unwrap()
            .success()
    );
    let names: Vec<String> = std::fs::read_dir(root.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["report".to_string()], "no stray files");
    assert_eq!(
        snapshot(&out).len(),
        before.len(),
        "the other cases' data is kept"
    );
}

#[test]
fn sigterm_and_sigint_leave_no_stray_files() {
    for signal in [libc::SIGTERM, libc::SIGINT] {
        let (root, _) = interrupt(signal);
        let names: Vec<String> = std::fs::read_dir(root.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            names,
            vec!["report".to_string()],
            "signal {signal}: no stray files"
        );
    }
}

/// Two runs of [`SAMPLE`] give byte-identical CSVs (budgets included) and summaries whatever
/// the thread count (wall times are kept apart in timings.json, and REPORT.md shows them). The
/// whole suite's files are counted in `tests/report.rs`, on its run.
#[test]
fn runs_are_deterministic_across_thread_counts() {
    let root = tempfile::tempdir().unwrap();
    let mut snaps = Vec::new();
    for threads in ["1", "2"] {
        let out = root.path().join(format!("t{threads}"));
        let ok = bin()
            .env("RAYON_NUM_THREADS", threads)
            .args(["run", "-q"])
            .args(SAMPLE)
            .arg("--out")
            .arg(&out)
            .status()
            .unwrap();
        assert!(ok.success());
        let mut s = snapshot(&out);
        s.retain(|k, _| k.ends_with(".csv") || k == "summary.json");
        snaps.push(s);
    }
    // A CSV per case and engine, a budget CSV per case and studied stepping engine, results.csv
    // and the summary; the two contact cases have no closed form (no CSV, no budgets) and
    // `explicit_small` refuses contact_balls_oblique; rapier refuses the ramp case (μ_s > μ_k): each of its
    // engines loses a CSV there, and the stepping ones their budget.
    let engines = crosscheck::run::registry::all();
    let stepping = engines.iter().filter(|e| e.stepping().is_some()).count();
    let rapier = engines
        .iter()
        .filter(|e| e.name().starts_with("rapier"))
        .count();
    let rapier_stepping = engines
        .iter()
        .filter(|e| e.name().starts_with("rapier") && e.stepping().is_some())
        .count();
    assert_eq!(
        snaps[0].len(),
        6 * engines.len() - 2 - 1 - rapier + 4 * stepping - rapier_stepping + 2,
        "{:?}",
        snaps[0].keys().collect::<Vec<_>>()
    );
    assert_eq!(snaps[0], snaps[1]);
}
