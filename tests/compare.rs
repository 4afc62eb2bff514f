//! `crosscheck compare BASE NEW`: two runs of the same build compare clean; round-off in an
//! energy balance or in a column at rest is not drift; a history perturbed by 10 % from a
//! given row is named as drift, from that row, over its peak and its scale; a newly failing
//! cell is a physics regression; JUnit XML parses; reports are compared over what they share and refused (exit 2) when that is nothing;
//! baselines are saved, compared and accepted.
use crosscheck::comparison::summary::SCHEMA_VERSION;
use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_crosscheck"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn report(out: &Path, cases: &[&str]) {
    let status = bin()
        .args(["run", "-q"])
        .args(cases)
        .arg("--out")
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success());
}

fn compare(base: &Path, new: &Path, extra: &[&str]) -> Output {
    bin()
        .arg("compare")
        .arg(base)
        .arg(new)
        .args(extra)
        .output()
        .unwrap()
}

/// Rewrite column `column` of `file` (a CSV) through `f`.
fn edit_column(file: &Path, column: &str, f: impl Fn(&str) -> String) {
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let k = header.split(',').position(|c| c == column).unwrap();
    let mut out = vec![header.to_string()];
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        cells[k] = f(&cells[k]);
        out.push(cells.join(","));
    }
    std::fs::write(file, out.join("\n") + "\n").unwrap();
}

/// Rewrite column `column` of `file` row by row through `f(t, value)`.
fn edit_rows(file: &Path, column: &str, f: impl Fn(f64, f64) -> f64) {
    let t = column_of(file, "t");
    let row = std::cell::Cell::new(0);
    edit_column(file, column, |x| {
        let value = f(t[row.get()], x.parse().unwrap());
        row.set(row.get() + 1);
        format!("{value:e}")
    });
}

/// The values of column `column` of `file` (a CSV).
fn column_of(file: &Path, column: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines = text.lines();
    let k = lines.next().unwrap().split(',').position(|c| c == column);
    let k = k.unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

/// The largest magnitude in `values`.
fn peak(values: &[f64]) -> f64 {
    values.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

/// The engine whose history is perturbed: `rapier_f64` (`explicit` in a build without rapier).
const PERTURBED: &str = if cfg!(feature = "rapier") {
    "rapier_f64"
} else {
    "explicit"
};

#[test]
fn two_runs_compare_clean_and_a_perturbed_history_is_named() {
    let root = tempfile::tempdir().unwrap();
    let (a, b) = (root.path().join("a"), root.path().join("b"));
    let cases = ["springs_grounded_a", "rigid2d_pin_lumped"];
    report(&a, &cases);
    report(&b, &cases);
    // The same build, the same inputs: byte-identical histories, no drift at all.
    let out = compare(&a, &b, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(
        stdout.contains("0 newly failing") && stdout.contains("0 drifted"),
        "{stdout}"
    );

    // Round-off is not drift. `explicit`'s energy balance, a residual of round-off (about 1e-3 J
    // here, against 3.3e3 J of kinetic energy), moved by 1e-13 of that energy: 500 ulps of it,
    // and 3e-7 of the balance's own peak. A column at rest but for round-off (ux, held at 0;
    // set to 1e-17 m in both reports) moved by 1e-17 m, all of its own peak and 3e-18 of the
    // scene's extent. Both are read against the scale their round-off comes from: clean.
    let history = |r: &Path| r.join("data/rigid2d_pin_lumped/explicit.csv");
    let energy = {
        let (k, e) = (
            column_of(&history(&a), "e_kinetic"),
            column_of(&history(&a), "e_elastic"),
        );
        k.iter().zip(&e).fold(0.0_f64, |m, (k, e)| m.max(k + e))
    };
    edit_rows(&history(&b), "e_balance", |_, x| x + 1e-13 * energy);
    assert!(1e-13 * energy > 1e-9 * peak(&column_of(&history(&a), "e_balance")));
    edit_rows(&history(&a), "ux", |_, _| 1e-17);
    edit_rows(&history(&b), "ux", |_, _| 2e-17);
    let out = compare(&a, &b, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("0 drifted"), "{stdout}");

    // rapier_f64's ux_node on one case 10 % larger from t = 0.05 s: the largest change over its
    // peak, and over its scale, the scene's extent (the farthest node from the origin, as the
    // base's summary.json keeps it; larger than the peak); named, from the first row at or
    // after 0.05 s.
    let perturbed = b.join(format!("data/rigid2d_pin_lumped/{PERTURBED}.csv"));
    let times = column_of(&perturbed, "t");
    let from = *times.iter().find(|t| **t >= 0.05).unwrap();
    let ux_node = column_of(&perturbed, "ux_node");
    let after: Vec<f64> = ux_node
        .iter()
        .zip(&times)
        .filter(|(_, t)| **t >= from)
        .map(|(x, _)| *x)
        .collect();
    let (whole, moved) = (peak(&ux_node), 0.1 * peak(&after));
    edit_rows(
        &perturbed,
        "ux_node",
        |t, x| if t >= from { 1.1 * x } else { x },
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("summary.json")).unwrap()).unwrap();
    let case = summary["cases"].as_array().unwrap().iter();
    let case = case
        .clone()
        .find(|c| c["id"] == "rigid2d_pin_lumped")
        .unwrap();
    // The farthest node from the origin is G1 at (2, -3) (cases/rigid2d_pin_lumped.toml).
    let extent = case["scales"]["ux_node"].as_f64().unwrap();
    assert_eq!(extent, 13.0_f64.sqrt());
    assert!(extent > whole, "{extent} {whole}");
    let junit = root.path().join("junit.xml");
    let out = compare(&a, &b, &["--junit", junit.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    // The largest change is 10 % of the largest |ux_node| from `from`, and the first changed
    // row already moved by far more than 1e-9 of the scale (10 % of 1 mm against 3.6 m); the
    // time as the report prints one, to six significant digits.
    let at: f64 = format!("{from:.5e}").parse().unwrap();
    let row = format!(
        "| rigid2d_pin_lumped | `{PERTURBED}` | ux_node | {:.2e} | {:.2e} | {at} |",
        moved / whole,
        moved / extent,
    );
    assert!(stdout.contains(&row), "{row}\n{stdout}");
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).expect("JUnit XML parses");
    let failures: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("failure"))
        .map(|n| {
            let case = n.parent().unwrap();
            format!(
                "{} {}",
                case.attribute("classname").unwrap(),
                case.attribute("name").unwrap()
            )
        })
        .collect();
    assert_eq!(
        failures,
        [format!("rigid2d_pin_lumped/{PERTURBED} ux_node")]
    );
    // Drift alone does not fail --physics-only.
    assert_eq!(compare(&a, &b, &["--physics-only"]).status.code(), Some(0));

    // A cell that passed and now fails is a physics regression, with both numbers.
    edit_column(&b.join("results.csv"), "pass", |x| {
        if x == "true" {
            "false".into()
        } else {
            x.into()
        }
    });
    let out = compare(&a, &b, &["--physics-only"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("## Newly failing"), "{stdout}");

    // A base kept without its histories (as the committed report is): the machine tier has
    // nothing to compare, so the full comparison is refused and --physics-only says so.
    std::fs::remove_dir_all(a.join("data")).unwrap();
    let out = compare(&a, &b, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the machine tier compared no history: the base report does not keep them")
            && stderr.contains("--physics-only"),
        "{stderr}"
    );
    let junit = root.path().join("physics.xml");
    let out = compare(
        &a,
        &b,
        &["--physics-only", "--junit", junit.to_str().unwrap()],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("machine tier: no history compared (the base report does not keep them")
            && stdout.contains("## Newly failing")
            && !stdout.contains("in the new report only"),
        "{stdout}"
    );
    // The machine suite holds no test case: no history was compared.
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).expect("JUnit XML parses");
    let machine = doc
        .descendants()
        .find(|n| n.has_tag_name("testsuite") && n.attribute("name") == Some("machine"))
        .unwrap();
    assert_eq!(machine.attribute("tests"), Some("0"), "{xml}");
}

/// Reports that hold different cases are compared over the cells both hold, the others
/// listed; reports that share nothing, or are not reports, or are of another schema version,
/// are refused with exit 2 and the reason.
#[test]
fn reports_are_compared_over_what_they_share_and_refused_when_nothing() {
    let root = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        root.path().join("a"),
        root.path().join("b"),
        root.path().join("c"),
    );
    report(&a, &["springs_grounded_a", "springs_grounded_b"]);
    report(&b, &["springs_grounded_a"]);
    report(&c, &["springs_n2n_b"]);
    let out = compare(&a, &b, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("0 drifted"), "{stdout}");
    assert!(
        stdout.contains("in the base report only (not compared): springs_grounded_b / `analytic`"),
        "{stdout}"
    );
    let refused = |base: &Path, new: &Path, expected: &str| {
        let out = compare(base, new, &[]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(expected),
            "expected `{expected}` in {stderr}"
        );
    };
    refused(&a, &c, "the reports share no cell, so nothing was compared");

    // A cell whose run now fails has no history and no verdict: a regression, not a cell
    // "no longer run".
    let broken = root.path().join("broken");
    report(&broken, &["springs_grounded_a"]);
    std::fs::remove_file(broken.join("data/springs_grounded_a/explicit.csv")).unwrap();
    let results = std::fs::read_to_string(broken.join("results.csv")).unwrap();
    let kept: Vec<&str> = results
        .lines()
        .filter(|l| !l.starts_with("springs_grounded_a,explicit,"))
        .collect();
    std::fs::write(broken.join("results.csv"), kept.join("\n") + "\n").unwrap();
    let summary = std::fs::read_to_string(broken.join("summary.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&summary).unwrap();
    for run in json["cases"][0]["runs"].as_array_mut().unwrap() {
        if run["engine"] == "explicit" {
            run["status"] = "failed".into();
        }
    }
    std::fs::write(broken.join("summary.json"), json.to_string()).unwrap();
    let out = compare(&b, &broken, &["--physics-only"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("springs_grounded_a / `explicit`: failed in the new report"),
        "{stdout}"
    );
    refused(&a, root.path(), "not a crosscheck report");
    let summary = b.join("summary.json");
    let text = std::fs::read_to_string(&summary).unwrap();
    let newer = text.replacen(
        format!("\"schema_version\": {SCHEMA_VERSION}").as_str(),
        "\"schema_version\": 99",
        1,
    );
    assert_ne!(text, newer, "summary.json names its schema version");
    std::fs::write(&summary, newer).unwrap();
    refused(&b, &b, "schema version 99");
}

/// The machine tier compares every history both reports hold, judged or not: two runs with
/// no exact solution (no verdict at all) still name a history moved by 10 %.
#[test]
fn histories_without_an_exact_solution_are_compared() {
    let root = tempfile::tempdir().unwrap();
    let (a, b) = (root.path().join("a"), root.path().join("b"));
    for out in [&a, &b] {
        let status = bin()
            .args([
                "run",
                "-q",
                "springs_grounded_a",
                "--engines",
                "explicit",
                "--out",
            ])
            .arg(out)
            .status()
            .unwrap();
        assert!(status.success());
    }
    assert_eq!(compare(&a, &b, &[]).status.code(), Some(0));
    edit_column(
        &b.join("data/springs_grounded_a/explicit.csv"),
        "u_end",
        |x| format!("{:e}", 1.1 * x.parse::<f64>().unwrap()),
    );
    let out = compare(&a, &b, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("| springs_grounded_a | `explicit` | u_end | 1.00e-1 |"),
        "{stdout}"
    );
}

/// Baselines: `--accept` makes NEW the baseline; a run saves one by name and is compared with
/// it, failing when its histories moved.
#[test]
fn baselines_are_saved_compared_and_accepted() {
    let root = tempfile::tempdir().unwrap();
    let (a, b) = (root.path().join("a"), root.path().join("b"));
    report(&a, &["springs_grounded_a"]);
    report(&b, &["springs_grounded_a"]);
    let file = "data/springs_grounded_a/explicit.csv";
    edit_column(&b.join(file), "u_end", |x| {
        format!("{:e}", 1.1 * x.parse::<f64>().unwrap())
    });
    assert_eq!(compare(&a, &b, &[]).status.code(), Some(1));
    let out = compare(&a, &b, &["--accept"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(compare(&a, &b, &[]).status.code(), Some(0));
    assert_eq!(
        std::fs::read(a.join(file)).unwrap(),
        std::fs::read(b.join(file)).unwrap()
    );

    // A run saves its report as a named baseline beside it, and a later run compares with it.
    let out_dir = root.path().join("report");
    let saved_in = root.path().join("baselines");
    let run = |extra: &[&str]| {
        bin()
            .args(["run", "-q", "springs_grounded_a", "--out"])
            .arg(&out_dir)
            .arg("--baseline-dir")
            .arg(&saved_in)
            .args(extra)
            .output()
            .unwrap()
    };
    let missing = run(&["--baseline", "main"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no baseline `main`"));
    assert!(!out_dir.exists(), "nothing run");
    assert_eq!(run(&["--save-baseline", "main"]).status.code(), Some(0));
    let saved = saved_in.join("main");
    assert!(saved.join(file).is_file());
    let again = run(&["--baseline", "main"]);
    let stdout = String::from_utf8_lossy(&again.stdout);
    assert_eq!(again.status.code(), Some(0), "{stdout}");
    assert!(
        stdout.contains("against the baseline `main`") && stdout.contains("0 drifted"),
        "{stdout}"
    );
    // The baseline moved (as a change of the engine would move the run): exit 1, named.
    edit_column(&saved.join(file), "u_end", |x| {
        format!("{:e}", 0.9 * x.parse::<f64>().unwrap())
    });
    let moved = run(&["--baseline", "main"]);
    let stdout = String::from_utf8_lossy(&moved.stdout);
    assert_eq!(moved.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("| springs_grounded_a | `explicit` | u_end |"),
        "{stdout}"
    );
    assert!(run(&["--baseline", "bad/name"]).status.code() == Some(2));
    // A baseline kept without its histories is compared by its verdicts, and says so.
    std::fs::remove_dir_all(saved.join("data")).unwrap();
    let verdicts = run(&["--baseline", "main"]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&verdicts.stdout),
        String::from_utf8_lossy(&verdicts.stderr),
    );
    assert_eq!(verdicts.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stderr.contains("the baseline `main` keeps no histories")
            && stdout.contains("machine tier: no history compared"),
        "{stdout}{stderr}"
    );
}

/// The main command says what changed since the report it replaces, with `compare`'s two
/// tiers: nothing after a second run of the same build; a history of the previous report
/// 10 % larger in one column is named with its drift, 0.1/1.1 of that report's peak (its
/// scale: the peak, larger than the scene's 1 m extent); one of
/// another schema version is said to be incomparable.
#[test]
fn the_main_command_says_what_changed_since_the_previous_report() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("report");
    let cases = ["springs_grounded_a"];
    let first_screen = || std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    report(&out, &cases);
    assert!(!first_screen().contains("Since the previous report"));
    report(&out, &cases);
    let text = first_screen();
    assert!(
        text.contains("no verdict changed, no error moved by more than 1 % and no history by"),
        "{text}"
    );
    edit_column(
        &out.join("data/springs_grounded_a/explicit.csv"),
        "u_end",
        |x| format!("{:e}", 1.1 * x.parse::<f64>().unwrap()),
    );
    report(&out, &cases);
    let text = first_screen();
    assert!(
        text.contains("1 history columns moved by more than 1.00e-9 of their scale")
            && text.contains("springs_grounded_a / `explicit` u_end by 9.09e-2"),
        "{text}"
    );
    // A previous report that keeps one history less, then none: the verdicts compared, and
    // said so.
    std::fs::remove_file(out.join("data/springs_grounded_a/explicit.csv")).unwrap();
    report(&out, &cases);
    let text = first_screen();
    assert!(
        text.contains(
            "and no history by more than 1.00e-9 of its scale; the histories of 1 cells \
                       not compared (the previous report does not keep them)"
        ),
        "{text}"
    );
    std::fs::remove_dir_all(out.join("data")).unwrap();
    report(&out, &cases);
    let text = first_screen();
    assert!(
        text.contains(
            "no verdict changed, no error moved by more than 1 %; histories not compared (the \
             previous report does not keep them)"
        ),
        "{text}"
    );
    // A previous report of another schema version is said to be incomparable, not skipped.
    let path = out.join("summary.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    json["schema_version"] = serde_json::json!(0);
    std::fs::write(&path, json.to_string()).unwrap();
    report(&out, &cases);
    let text = first_screen();
    assert!(
        text.contains("it cannot be compared with this one") && text.contains("schema version 0"),
        "{text}"
    );
}
