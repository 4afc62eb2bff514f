//! Memory is independent of the number of steps: a run of 10^7 increments, explicit and rapier,
//! keeps its peak resident set under 50 MB (the output is 501 rows whatever the step count).
//!
//! Long (about a minute, most of it rapier's 10^7 steps): `cargo test --release -- --ignored`,
//! which `.ci/run` runs once. The buffers' capacities are asserted in process, on the explicit
//! engine (about a second); rapier's recorder has the same test in `tests/rapier.rs`.
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::scene::IncrementRule;
use std::process::Command;

/// 10^7 explicit increments leave the output buffers at the size the output rows need: the
/// history holds `output_rows` rows of one value per column, allocated once (capacity equal to
/// length), whatever the step count.
#[test]
fn ten_million_explicit_increments_keep_buffers_at_the_output_size() {
    let path = crosscheck::case::cases_dir().join("springs_grounded_a.toml");
    let scene = crosscheck::case::load(&path).unwrap();
    let settings = RunSettings {
        increment: Some(IncrementRule::Given(scene.duration() / 1e7)),
        ..RunSettings::default()
    };
    let out = ExplicitEngine::finite().run(&scene, &settings).unwrap();
    assert_eq!(out.info.steps, 10_000_000);
    let history = &out.history;
    assert_eq!(history.rows.len(), scene.output_rows);
    assert_eq!(history.rows.capacity(), scene.output_rows);
    for row in &history.rows {
        assert_eq!(row.len(), history.columns.len());
        assert_eq!(row.capacity(), history.columns.len());
    }
}

/// Peak resident set of the waited-for children so far, in bytes (Linux reports kilobytes).
fn children_peak_rss() -> u64 {
    // SAFETY: getrusage fills the struct we own.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) },
        0
    );
    usage.ru_maxrss as u64 * 1024
}

#[test]
#[ignore = "long: 10^7 increments per engine; run by .ci/run with --ignored"]
fn ten_million_increments_stay_under_50_mb() {
    const LIMIT: u64 = 50 * 1024 * 1024;
    let out = tempfile::tempdir().unwrap();
    let built = |e: &&str| crosscheck::run::registry::named(e).is_some();
    for engine in ["explicit", "rapier_f64"].into_iter().filter(built) {
        let status = Command::new(env!("CARGO_BIN_EXE_crosscheck"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["run", "-q", "springs_grounded_a", "--increment", "1e-7"])
            .args(["--engines", engine, "--out"])
            .arg(out.path())
            .status()
            .unwrap();
        assert!(status.success(), "{engine}");
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.path().join("summary.json")).unwrap(),
        )
        .unwrap();
        let steps = summary["cases"][0]["runs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["engine"] == engine)
            .unwrap()["steps"]
            .as_u64()
            .unwrap();
        assert_eq!(steps, 10_000_000, "{engine}");
        let peak = children_peak_rss();
        println!("{engine}: 10^7 increments, peak RSS so far {peak} bytes");
        assert!(peak < LIMIT, "{engine}: peak RSS {peak} bytes ≥ 50 MB");
    }
}
