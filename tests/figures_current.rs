//! No speed figure older than the engine it measured. Every committed speed figure records the
//! commit it was measured at (BENCHMARKS.md's table line, `report/scaling/*.provenance`); the
//! engines' sources at that commit must be HEAD's, or the figure describes code that is gone;
//! the README's sentence on the chain quotes the committed chain study.

use crosscheck::report::scaling::FIT_FROM_N;
use crosscheck::run::scaling::fitted_exponent;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The sources whose speed the committed figures measure: the engines and the floor loops they
/// are held against.
const ENGINE_SOURCES: [&str; 3] = [
    "src/engines/explicit",
    "src/engines/rapier",
    "src/run/floor",
];

/// The committed speed figures and the file each records its commit in.
const FIGURES: [(&str, &str); 3] = [
    ("the seed-case table and element cost", "BENCHMARKS.md"),
    ("the chain study", "report/scaling/scaling.provenance"),
    (
        "the element-cost study",
        "report/scaling/elements.provenance",
    ),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn git(dir: &Path, args: &[&str]) -> Result<String, String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .map_err(|e| format!("git {}: {e}", args.join(" ")))?;
    if !out.status.success() {
        return Err(format!(
            "git {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The commit a figure's file names: the hex word after the first "commit ", refused where the
/// figure was measured with uncommitted changes.
fn recorded_commit(text: &str) -> Result<String, String> {
    let (_, after) = text
        .split_once("commit ")
        .ok_or("names no commit".to_string())?;
    let hash: String = after
        .chars()
        .take_while(|c| c.is_ascii_hexdigit())
        .collect();
    if hash.len() < 7 {
        return Err(format!(
            "names no commit hash ({:?})",
            &after[..after.len().min(20)]
        ));
    }
    let line = after.lines().next().unwrap_or_default();
    if line.contains("uncommitted changes") {
        return Err(format!("was measured at {hash} with uncommitted changes"));
    }
    Ok(hash)
}

/// What is stale in the checkout at `dir`: one line per figure whose recorded commit is
/// missing, unusable, or has engine sources that differ from HEAD's (naming the files).
fn stale(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for (figure, file) in FIGURES {
        let text = match std::fs::read_to_string(dir.join(file)) {
            Ok(t) => t,
            Err(e) => {
                out.push(format!("{figure} ({file}): cannot read: {e}"));
                continue;
            }
        };
        let hash = match recorded_commit(&text) {
            Ok(h) => h,
            Err(e) => {
                out.push(format!("{figure} ({file}) {e}"));
                continue;
            }
        };
        let mut args = vec!["diff", "--name-only", &hash, "HEAD", "--"];
        args.extend(ENGINE_SOURCES);
        match git(dir, &args) {
            Ok(changed) if changed.is_empty() => {}
            Ok(changed) => out.push(format!(
                "{figure} ({file}) was measured at {hash}; changed since: {}",
                changed.lines().collect::<Vec<_>>().join(", ")
            )),
            Err(e) => out.push(format!("{figure} ({file}): {e}")),
        }
    }
    out
}

#[test]
fn every_committed_speed_figure_was_measured_at_the_engines_of_head() {
    let stale = stale(&root());
    assert!(
        stale.is_empty(),
        "speed figures older than the code they describe (rerun scripts/benchmarks.sh at a \
         commit and commit what it writes):\n{}",
        stale.join("\n")
    );
}

#[test]
fn changing_one_engine_file_makes_every_figure_stale() {
    let work = std::env::temp_dir().join(format!("crosscheck-figures-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    let source = root();
    let clone = Command::new("git")
        .args(["clone", "-q"])
        .arg(&source)
        .arg(&work)
        .status()
        .expect("git runs");
    assert!(clone.success(), "git clone of {}", source.display());
    let file = "src/engines/explicit/mod.rs";
    let path = work.join(file);
    let mut text = std::fs::read_to_string(&path).expect("the engine's module");
    text.push_str("\n// a change after the figures were measured\n");
    std::fs::write(&path, text).expect("written");
    let identity = ["-c", "user.name=test", "-c", "user.email=test@example.com"];
    let mut args = identity.to_vec();
    args.extend(["commit", "-q", "-am", "change an engine file"]);
    git(&work, &args).expect("committed");
    let stale = stale(&work);
    std::fs::remove_dir_all(&work).ok();
    assert_eq!(
        stale.len(),
        FIGURES.len(),
        "every figure is stale: {stale:#?}"
    );
    for line in &stale {
        assert!(line.contains(file), "names the changed file: {line}");
    }
}

#[test]
fn a_figure_measured_with_uncommitted_changes_names_no_usable_commit() {
    assert_eq!(
        recorded_commit("commit 1234abcd5678\n"),
        Ok("1234abcd5678".into())
    );
    assert!(recorded_commit("commit 1234abcd5678 + uncommitted changes\n").is_err());
    assert!(recorded_commit("Measured on AMD EPYC, 2 cores, 2026-11-28").is_err());
    assert_eq!(
        recorded_commit("Measured on AMD EPYC, 2 cores, commit 4f245de, 2026-11-28"),
        Ok("4f245de".into())
    );
}

/// `explicit`'s points of the committed chain study from N = [`FIT_FROM_N`] up: (N, ns per
/// increment, ns per DOF-increment over the streaming limit).
fn committed_chain() -> Vec<(f64, f64, f64)> {
    let path = root().join("report/scaling/scaling.csv");
    let mut reader = csv::Reader::from_path(&path).expect("the committed chain study");
    let headers = reader.headers().expect("a header").clone();
    let column = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("scaling.csv has no column {name}"))
    };
    let (engine, n, step) = (column("engine"), column("n"), column("ns_per_step"));
    let (dof, limit) = (column("ns_per_dof_step"), column("limit_ns_per_dof_step"));
    let number = |row: &csv::StringRecord, i: usize| -> f64 { row[i].parse().expect("a number") };
    reader
        .records()
        .map(|r| r.expect("a row"))
        .filter(|r| &r[engine] == "explicit" && number(r, n) >= FIT_FROM_N as f64)
        .map(|r| {
            (
                number(&r, n),
                number(&r, step),
                number(&r, dof) / number(&r, limit),
            )
        })
        .collect()
}

#[test]
fn the_readme_states_the_chains_growth_and_ratio_as_the_committed_study_measured_them() {
    // The README's sentence on the chain quotes the fitted exponent (two decimals) and the
    // range of the cost per DOF over the streaming limit (one decimal) of the committed
    // `report/scaling/scaling.csv`, so a study written again fails here until the README says
    // what it measured.
    let points = committed_chain();
    assert!(
        points.len() >= 2,
        "the committed study has explicit from 10^3 up"
    );
    // An unresolved point (NaN) would drop out of the range unseen.
    for (n, step, ratio) in &points {
        assert!(
            step.is_finite() && ratio.is_finite(),
            "N = {n}: unresolved in the committed study"
        );
    }
    let fit: Vec<(f64, f64)> = points.iter().map(|p| (p.0, p.1)).collect();
    let (exponent, _) = fitted_exponent(&fit).expect("a fit");
    let low = points.iter().map(|p| p.2).fold(f64::INFINITY, f64::min);
    let high = points.iter().map(|p| p.2).fold(0.0, f64::max);
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let readme = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    for claim in [
        format!("N^{exponent:.2} from 10^3 to 10^6"),
        format!("at {low:.1}–{high:.1}× a plain loop"),
    ] {
        assert!(readme.contains(&claim), "README.md does not say {claim:?}");
    }
}
