//! `crosscheck judge`: a history from another code, judged against the case's exact solution.
//! Here the other code is `explicit` itself, sampled at other times than the case's, so the
//! expected verdicts are known: within the case's tolerance as it is, outside it with one
//! column scaled by 1.05; and every malformed file is refused with its line and column.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use std::path::Path;
use std::process::{Command, Output};

fn judge(file: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_crosscheck"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["judge", "rigid2d_pin_lumped"])
        .arg(file)
        .args(extra)
        .output()
        .unwrap()
}

/// `explicit`'s history of rigid2d_pin_lumped at 2,999 rows (none but the ends on the case's
/// 501 output times), as CSV with the time column named `time`, `ux_node` multiplied by
/// `factor`, and every line passed through `edit` (line number, text; an empty result drops
/// the line).
fn their_csv(
    dir: &Path,
    factor: f64,
    edit: impl Fn(usize, String) -> String,
) -> std::path::PathBuf {
    let mut scene = scene("rigid2d_pin_lumped");
    scene.output_rows = 2999;
    let run = ExplicitEngine::finite()
        .run(&scene, &RunSettings::default())
        .unwrap();
    let h = &run.history;
    let names: Vec<String> = h
        .columns
        .iter()
        .map(|c| if c == "t" { "time".into() } else { c.clone() })
        .collect();
    let k = h.columns.iter().position(|c| c == "ux_node").unwrap();
    let mut lines = vec![names.join(",")];
    for row in &h.rows {
        let cells: Vec<String> = row
            .iter()
            .enumerate()
            .map(|(j, x)| format!("{:e}", if j == k { x * factor } else { *x }))
            .collect();
        lines.push(cells.join(","));
    }
    let text: Vec<String> = lines
        .into_iter()
        .enumerate()
        .map(|(i, l)| edit(i + 1, l))
        .filter(|l| !l.is_empty())
        .collect();
    let path = dir.join("theirs.csv");
    std::fs::write(&path, text.join("\n") + "\n").unwrap();
    path
}

#[test]
fn a_resampled_history_passes_and_a_scaled_column_fails_by_name() {
    let dir = tempfile::tempdir().unwrap();
    // The case holds `explicit` to 1e-3 of the peak (measured 7.4e-5 on its own rows). Linear
    // interpolation between rows 3.3e-5 s apart adds at most (ω·Δt)²/8 = 2.6e-5 of the peak
    // at the fastest structural mode (ω = 436 rad/s): within 1e-3 with room.
    let file = their_csv(dir.path(), 1.0, |_, l| l);
    let out = judge(&file, &["--time", "time", "--tolerance", "1e-3"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("PASS"), "{stdout}");
    assert!(stdout.contains("interpolated linearly"), "{stdout}");

    // ux_node 5 % too large: 5e-2 of the peak, over 1e-3; only that column fails.
    let file = their_csv(dir.path(), 1.05, |_, l| l);
    let out = judge(&file, &["--time", "time", "--tolerance", "1e-3"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("FAIL: ux_node over"), "{stdout}");

    // The same, converted back by the user: --scale ux_node=1/1.05.
    let out = judge(
        &file,
        &[
            "--time",
            "time",
            "--scale",
            &format!("ux_node={}", 1.0 / 1.05),
        ],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

/// Their file, edited, is refused with exit 2 and a message that contains `expected`.
fn refused(edit: impl Fn(usize, String) -> String, extra: &[&str], expected: &str) {
    let dir = tempfile::tempdir().unwrap();
    let file = their_csv(dir.path(), 1.0, edit);
    let mut args = vec!["--time", "time"];
    args.extend_from_slice(extra);
    let out = judge(&file, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(expected),
        "expected `{expected}` in: {stderr}"
    );
}

#[test]
fn malformed_histories_are_refused_with_line_and_column() {
    // A missing column, named with what it stands for.
    refused(
        |i, l| {
            if i == 1 {
                l.replace("ux_node", "x_node")
            } else {
                l
            }
        },
        &[],
        "theirs.csv:1: no column `ux_node`",
    );
    // A non-numeric cell and a NaN, with their line and column.
    let cell = |bad: &'static str| {
        move |i: usize, l: String| {
            if i == 10 {
                let mut c: Vec<&str> = l.split(',').collect();
                c[1] = bad;
                c.join(",")
            } else {
                l
            }
        }
    };
    refused(
        cell("abc"),
        &[],
        "theirs.csv:10: column `rz`: `abc` is not a finite number",
    );
    refused(cell("NaN"), &[], "theirs.csv:10: column `rz`: `NaN`");
    // A blank line before it: the bad cell is on the file's line 11 (a blank line is no
    // record, yet a line of the file).
    refused(
        |i, l| match i {
            5 => format!("\n{l}"),
            10 => cell("abc")(i, l),
            _ => l,
        },
        &[],
        "theirs.csv:11: column `rz`: `abc` is not a finite number",
    );
    // Time that does not increase.
    refused(
        |i, l| {
            if i == 5 {
                let (_, rest) = l.split_once(',').unwrap();
                format!("0e0,{rest}")
            } else {
                l
            }
        },
        &[],
        "theirs.csv:5: column `time`: time 0e0 does not increase",
    );
    // Their rows end before the case's last output time: no extrapolation.
    refused(
        |i, l| if i > 2000 { String::new() } else { l },
        &[],
        "refusing to extrapolate",
    );
    // An option naming a column the case does not have.
    refused(
        |_, l| l,
        &["--scale", "uz=2"],
        "`uz` is not a contract column",
    );
}
