//! A run split across machines: `run --partition k/n` gives each case to exactly one shard,
//! equivalent cases to the same one, and `crosscheck merge` joins the shards' reports into the
//! report one run writes (results.csv, sweep.csv and stability.csv equal to one run's, apart
//! from the sweep's CPU-time columns).
use crosscheck::comparison::{self, equivalence};
use crosscheck::pipeline::{self, Partition};
use crosscheck::run::{self, Plan};
use std::path::Path;
use std::process::Command;

fn bin(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_crosscheck"));
    c.current_dir(dir)
        .arg("--cases")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("cases"));
    c
}

/// Every shipped case in one shard of four, and every pair of equivalent cases (the same
/// closed form) in the same shard.
#[test]
fn every_case_in_one_shard_and_equivalent_cases_together() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let mut names: Vec<String> = crosscheck::case::discover_suite(&dir)
        .unwrap()
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    names.sort();
    let cases = run::load_cases(&names, &dir).unwrap();
    let shards: Vec<Vec<String>> = (1..=4)
        .map(|k| {
            pipeline::partition(cases.clone(), Partition { k, n: 4 })
                .into_iter()
                .map(|s| s.id)
                .collect()
        })
        .collect();
    let shard_of = |id: &str| -> Vec<usize> {
        (0..4)
            .filter(|k| shards[*k].iter().any(|c| c == id))
            .collect()
    };
    for scene in &cases {
        assert_eq!(shard_of(&scene.id).len(), 1, "{}: {shards:?}", scene.id);
    }
    assert!(shards.iter().all(|s| !s.is_empty()), "{shards:?}");
    let plan = Plan {
        cases: cases.clone(),
        engines: run::registry::named(comparison::CLOSED_FORM)
            .into_iter()
            .collect(),
        settings: Default::default(),
    };
    let outcome = run::execute(&plan, false);
    let pairs = equivalence::measure(&cases, &[], |c, e| outcome.history(c, e).cloned());
    assert!(!pairs.is_empty(), "the shipped cases hold equivalent pairs");
    for e in &pairs {
        assert_eq!(
            shard_of(&e.case),
            shard_of(&e.same_as),
            "{} ~ {}",
            e.case,
            e.same_as
        );
    }
    assert!("3/2".parse::<Partition>().is_err());
    assert_eq!("count:2/4".parse(), Ok(Partition { k: 2, n: 4 }));
}

/// A CSV's rows with the named columns blanked (the timing columns).
fn without(path: &Path, timing: &[&str]) -> Vec<Vec<String>> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let mut rows = vec![header.clone()];
    for record in reader.records() {
        let record = record.unwrap();
        rows.push(
            record
                .iter()
                .zip(&header)
                .map(|(x, h)| {
                    if timing.contains(&h.as_str()) {
                        String::new()
                    } else {
                        x.to_string()
                    }
                })
                .collect(),
        );
    }
    rows
}

#[test]
fn merged_shards_equal_one_run() {
    let root = tempfile::tempdir().unwrap();
    let cases = ["rigid2d_pin_lumped", "springs_grounded_b", "springs_n2n_b"];
    let run = |out: &str, extra: &[&str]| {
        let status = bin(root.path())
            .args(["run", "-q"])
            .args(cases)
            .args([
                "--engines",
                "analytic,reference,explicit,explicit_small",
                "--sweep",
                "--stability",
            ])
            .args(["--out", out])
            .args(extra)
            .status()
            .unwrap();
        assert!(status.success());
    };
    run("whole", &[]);
    run("one", &["--partition", "1/2"]);
    run("two", &["--partition", "2/2"]);
    for shard in ["one", "two"] {
        assert!(
            root.path().join(shard).join("summary.json").is_file(),
            "{shard} ran nothing"
        );
    }
    let merged = bin(root.path())
        .args(["merge", "one", "two", "--out", "merged"])
        .output()
        .unwrap();
    assert!(
        merged.status.success(),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    let (whole, merged) = (root.path().join("whole"), root.path().join("merged"));
    let cpu = [
        "cpu_s_per_simulated_s",
        "cpu_s_per_simulated_s_median",
        "cpu_s_per_simulated_s_max",
    ];
    for (file, timing) in [
        ("results.csv", &[][..]),
        ("sweep.csv", &cpu[..]),
        ("stability.csv", &[][..]),
    ] {
        let (a, b) = (
            without(&whole.join(file), timing),
            without(&merged.join(file), timing),
        );
        assert!(a.len() > 1, "{file} is empty");
        assert_eq!(a, b, "{file}");
    }
    for case in cases {
        assert!(merged.join(format!("cases/{case}.md")).is_file());
        assert!(merged.join(format!("data/{case}/explicit.csv")).is_file());
    }
    // A shard's directory must be its own; a missing shard, or a whole run's report, is no
    // set of shards of one run.
    let again = bin(root.path())
        .args([
            "run",
            "-q",
            "springs_n2n_b",
            "--partition",
            "1/2",
            "--out",
            "one",
        ])
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("a directory of its own"));
    for (shards, said) in [
        (&["one"][..], "a shard is missing"),
        (&["whole"][..], "a whole run's report, not a shard"),
    ] {
        let out = bin(root.path())
            .arg("merge")
            .args(shards)
            .args(["--out", "bad"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(said), "{stderr}");
    }
    // Shards that overlap are not shards of one run.
    let overlap = bin(root.path())
        .args(["merge", "one", "whole", "--out", "bad"])
        .output()
        .unwrap();
    assert_eq!(overlap.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&overlap.stderr).contains("shards of one run hold disjoint cases")
    );
}
