//! Accuracy on request's files: `on_request.csv` ([`COLUMNS`], one row per case, engine and
//! tolerance) and the report section that sets each tolerance asked for against the error the
//! engine achieved, with what it chose and what it cost.

use crate::report::data::{DataError, write_atomic};
use crate::report::format::csv_finite as number;
use crate::run::on_request::{Request, TOLERANCES};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The CSV header.
pub const COLUMNS: [&str; 9] = [
    "case",
    "engine",
    "requested",
    "achieved",
    "increment_s",
    "penalty_n_per_m",
    "steps",
    "cpu_s",
    "message",
];

/// `out/on_request.csv`.
pub fn csv_path(out: &Path) -> PathBuf {
    out.join("on_request.csv")
}

fn optional(x: Option<f64>) -> String {
    x.filter(|v| v.is_finite()).map_or_else(String::new, number)
}

/// The requests as CSV text (an absent value is an empty field; a message is quoted).
pub fn csv(requests: &[Request]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(COLUMNS);
    for r in requests {
        let _ = w.write_record([
            r.case.clone(),
            r.engine.clone(),
            number(r.requested),
            optional(r.achieved),
            optional(r.increment),
            optional(r.penalty_stiffness),
            r.steps.map_or_else(String::new, |n| n.to_string()),
            optional(r.cpu_seconds),
            r.message.clone().unwrap_or_default(),
        ]);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Write `out/on_request.csv` (nothing when the study did not run: a previous report's file
/// stays).
pub fn write(out: &Path, requests: &[Request]) -> Result<(), DataError> {
    if requests.is_empty() {
        return Ok(());
    }
    crate::interrupt::checkpoint("on_request").map_err(|_| DataError::Interrupted)?;
    write_atomic(&csv_path(out), csv(requests).as_bytes())
}

/// Read `out/on_request.csv` back (empty if missing or not one).
pub fn read(out: &Path) -> Vec<Request> {
    let Ok(mut r) = csv::Reader::from_path(csv_path(out)) else {
        return Vec::new();
    };
    if r.headers().map_or(true, |h| h.iter().ne(COLUMNS)) {
        return Vec::new();
    }
    let num = |s: &str| s.parse::<f64>().ok();
    r.records()
        .filter_map(|rec| {
            let f = rec.ok()?;
            Some(Request {
                case: f.get(0)?.to_string(),
                engine: f.get(1)?.to_string(),
                requested: num(f.get(2)?)?,
                achieved: num(f.get(3)?),
                increment: num(f.get(4)?),
                penalty_stiffness: num(f.get(5)?),
                steps: f.get(6)?.parse().ok(),
                cpu_seconds: num(f.get(7)?),
                message: Some(f.get(8)?.to_string()).filter(|m| !m.is_empty()),
            })
        })
        .collect()
}

/// The report section: per engine, a table of cases × tolerance, each cell the error achieved
/// (its ratio to the tolerance) and the CPU time it took, or why the engine declined.
pub fn overview(w: &mut String, requests: &[Request]) {
    if requests.is_empty() {
        return;
    }
    let mut engines: Vec<&str> = Vec::new();
    for r in requests {
        if !engines.contains(&r.engine.as_str()) {
            engines.push(&r.engine);
        }
    }
    let in_band = requests
        .iter()
        .filter(|r| {
            r.achieved
                .is_some_and(|a| crate::comparison::verdict::in_band(a, r.requested))
        })
        .count();
    let _ = writeln!(
        w,
        "\n## Accuracy on request\n\nEach engine was asked for a largest error of ε of each \
         column's peak (`crosscheck run --tolerance ε`) and chose its own increment and penalty \
         stiffness from its error model (second-order phase error and penalty compliance, capped \
         by the stable increment). Each cell: the error it achieved against its own model's exact \
         solution, its ratio to ε (the aim is the band ε/10 … ε), and the CPU seconds the run took \
         (its pilot runs included). {in_band} of {} requests landed in the band. Rapier answers \
         on the command line too (`--engines rapier_f64`), choosing its increment from its \
         observed first-order error or saying why ε is out of reach; it is not part of this run \
         (its pilot runs cost about 40 s at 1e-3), nor is ε = 1e-6, which the tests ask of both \
         engines on every seed case (measured 0.29–0.40 of it; about 9 CPU-seconds). Data: \
         `on_request.csv`.\n",
        requests.len()
    );
    for engine in engines {
        let mine: Vec<&Request> = requests.iter().filter(|r| r.engine == engine).collect();
        let mut cases: Vec<&str> = mine.iter().map(|r| r.case.as_str()).collect();
        cases.dedup();
        let _ = writeln!(w, "**`{engine}`**\n");
        let header: Vec<String> = TOLERANCES.iter().map(|t| format!("ε = {t:.0e}")).collect();
        let _ = writeln!(w, "| case | {} |", header.join(" | "));
        let _ = writeln!(w, "|---|{}", "---:|".repeat(TOLERANCES.len()));
        for case in cases {
            let cells: Vec<String> = TOLERANCES
                .iter()
                .map(
                    |t| match mine.iter().find(|r| r.case == case && r.requested == *t) {
                        None => "–".to_string(),
                        Some(r) => match (r.achieved, r.cpu_seconds) {
                            (Some(a), Some(c)) => format!("{a:.2e} ({:.2}), {c:.3} s", a / t),
                            (None, Some(c)) => format!("no exact solution, {c:.3} s"),
                            _ => format!(
                                "declined: {}",
                                r.message.as_deref().unwrap_or("no message")
                            ),
                        },
                    },
                )
                .collect();
            let _ = writeln!(w, "| {case} | {} |", cells.join(" | "));
        }
        let _ = writeln!(w);
    }
}
