//! Two reports compared, in two tiers as code_aster's TEST_RESU checks a value twice:
//! **physics**, each side's error against the exact solution and its tolerance
//! (`results.csv`; a cell that passed and now fails is a regression), and **machine**, the
//! histories themselves (`data/<case>/<engine>.csv`) compared row by row (the largest
//! difference over the column's scale, [`change_scale`]: its peak, or the scale its round-off
//! comes from where that is larger; above a threshold it is drift, even where both pass).

use crate::comparison::change_scale;
use crate::comparison::summary::SCHEMA_VERSION;
use crate::report::data::read_history;
use crate::report::format::{instant, sci};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Default threshold of the machine tier: a history that moved by more than this fraction of
/// its column's scale ([`change_scale`]) has drifted. Round-off from another order of
/// operations is a few ulps of that scale per increment and accumulates over a run: a bias of
/// one ulp on every force the explicit engine applies moves the shipped cases' columns by up
/// to 1.5e-10 of their scale (a penalty contact force, whose penetration is about 1e-5 of the
/// positions it is the difference of), except where it moves a contact's opening by an
/// increment (contact_slide_ball: 1.3e-6 of the contact force's scale, once it opens).
/// 1e-9 is above the first and far below any tolerance.
pub const DRIFT: f64 = 1e-9;

/// Why two reports cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum Unusable {
    /// Not a report directory.
    #[error("{0}: not a crosscheck report (no summary.json and results.csv)")]
    NotAReport(PathBuf),
    /// A schema version this build cannot read.
    #[error("{path}: summary.json has schema version {found}; this build reads {SCHEMA_VERSION}")]
    Schema {
        /// The report.
        path: PathBuf,
        /// Its version.
        found: u64,
    },
    /// A file that cannot be read.
    #[error("{0}")]
    Read(String),
    /// Two reports that share no history and no verdict: a comparison would look at nothing.
    #[error(
        "the reports share no cell, so nothing was compared ({base} cells in the base, {new} in \
         the new one); compare reports of the same cases and engines"
    )]
    Nothing {
        /// Cells of the base report.
        base: usize,
        /// Cells of the new report.
        new: usize,
    },
    /// Cells or columns present on one side only.
    #[error("the reports do not hold the same {what}: {list}")]
    Mismatch {
        /// Cells, columns or rows.
        what: String,
        /// The first few that differ, each with the side that has it.
        list: String,
    },
}

/// One cell and column of `results.csv`: its error and verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Error over the peak (absolute where `relative` is false).
    pub error: f64,
    /// Whether the error is relative to the peak.
    pub relative: bool,
    /// The tolerance, where the case declares one for the engine.
    pub tolerance: Option<f64>,
    /// Whether it is within it.
    pub pass: Option<bool>,
}

/// (case, engine, column).
pub type Key = (String, String, String);

/// A report, read.
#[derive(Debug, Clone)]
pub struct Report {
    /// Its directory.
    pub dir: PathBuf,
    /// `results.csv`, by cell and column.
    pub verdicts: BTreeMap<Key, Verdict>,
    /// Each run's status in `summary.json` (`ok`, `failed`, ...), by (case, engine).
    pub statuses: BTreeMap<(String, String), String>,
    /// Each case's scene scales by column (`summary.json`'s `scales`), what a column that
    /// stays near zero is compared against ([`change_scale`]); none in a report written
    /// before it kept them.
    pub scales: BTreeMap<String, BTreeMap<String, f64>>,
}

/// One column's comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct Change {
    /// Case, engine, column.
    pub key: Key,
    /// The physics tier, base and new (None where `results.csv` has no such row, e.g. an
    /// energy column).
    pub physics: Option<(Verdict, Verdict)>,
    /// The machine tier: the largest difference between the two histories over the base
    /// column's scale ([`change_scale`]; absolute where that is 0); `None` where a report does
    /// not keep the cell's history ([`Since::not_kept`]).
    pub drift: Option<f64>,
    /// The same difference over the base column's own peak (absolute where that is 0): how
    /// much the column itself moved.
    pub of_peak: Option<f64>,
    /// Where the difference grows: each row (its time) at which the largest difference so far,
    /// over the scale, rises, with that value (the last is [`Change::drift`]).
    pub growth: Vec<(f64, f64)>,
}

impl Change {
    /// Its history moved by more than `threshold` of its scale.
    pub fn drifted(&self, threshold: f64) -> bool {
        self.drift.is_some_and(|d| d > threshold)
    }

    /// The time of the first row at which the history differs by more than `threshold` of
    /// its scale, where it does.
    pub fn onset(&self, threshold: f64) -> Option<f64> {
        self.growth
            .iter()
            .find(|(_, d)| *d > threshold)
            .map(|(t, _)| *t)
    }

    /// Passed in the base report and fails in the new one.
    pub fn newly_failing(&self) -> bool {
        matches!(&self.physics, Some((a, b)) if a.pass == Some(true) && b.pass == Some(false))
    }
}

/// Read a report directory.
pub fn read(dir: &Path) -> Result<Report, Unusable> {
    let (summary, results) = (dir.join("summary.json"), dir.join("results.csv"));
    if !summary.is_file() || !results.is_file() {
        return Err(Unusable::NotAReport(dir.to_path_buf()));
    }
    let text = std::fs::read_to_string(&summary)
        .map_err(|e| Unusable::Read(format!("{}: {e}", summary.display())))?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Unusable::Read(format!("{}: {e}", summary.display())))?;
    let found = json["schema_version"].as_u64().unwrap_or(0);
    if found != u64::from(SCHEMA_VERSION) {
        return Err(Unusable::Schema {
            path: dir.to_path_buf(),
            found,
        });
    }
    let mut statuses = BTreeMap::new();
    for case in json["cases"].as_array().into_iter().flatten() {
        for run in case["runs"].as_array().into_iter().flatten() {
            if let (Some(id), Some(engine), Some(status)) = (
                case["id"].as_str(),
                run["engine"].as_str(),
                run["status"].as_str(),
            ) {
                statuses.insert((id.to_string(), engine.to_string()), status.to_string());
            }
        }
    }
    let scales = json["cases"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|case| {
            let columns = case["scales"].as_object()?;
            let scales = columns
                .iter()
                .filter_map(|(c, s)| Some((c.clone(), s.as_f64()?)));
            Some((case["id"].as_str()?.to_string(), scales.collect()))
        })
        .collect();
    Ok(Report {
        dir: dir.to_path_buf(),
        verdicts: read_results(&results)?,
        statuses,
        scales,
    })
}

fn read_results(path: &Path) -> Result<BTreeMap<Key, Verdict>, Unusable> {
    let bad = |e: String| Unusable::Read(format!("{}: {e}", path.display()));
    let mut reader = csv::Reader::from_path(path).map_err(|e| bad(e.to_string()))?;
    let header = reader.headers().map_err(|e| bad(e.to_string()))?.clone();
    let at = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| bad(format!("no column `{name}`")))
    };
    let [case, engine, column, error, relative, tolerance, pass] = [
        at("case")?,
        at("engine")?,
        at("column")?,
        at("error")?,
        at("relative")?,
        at("tolerance")?,
        at("pass")?,
    ];
    let mut out = BTreeMap::new();
    for record in reader.records() {
        let r = record.map_err(|e| bad(e.to_string()))?;
        let field = |k: usize| r.get(k).unwrap_or("");
        let number = |k: usize| field(k).parse::<f64>().ok();
        out.insert(
            (
                field(case).into(),
                field(engine).into(),
                field(column).into(),
            ),
            Verdict {
                error: number(error).unwrap_or(f64::NAN),
                relative: field(relative) == "true",
                tolerance: number(tolerance),
                pass: match field(pass) {
                    "true" => Some(true),
                    "false" => Some(false),
                    _ => None,
                },
            },
        );
    }
    Ok(out)
}

/// One column's machine tier between two histories of one cell: the largest difference over
/// the base column's scale, and where it grows ([`Change::growth`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnDrift {
    /// The column.
    pub column: String,
    /// The largest difference over the scale (absolute where the scale is 0).
    pub drift: f64,
    /// The largest difference over the column's own peak (absolute where that is 0).
    pub of_peak: f64,
    /// [`Change::growth`].
    pub growth: Vec<(f64, f64)>,
}

/// Each column's [`ColumnDrift`] between two histories of one cell, read against the base
/// history and the case's scene `scales` ([`change_scale`]); `Err` where their columns or rows
/// differ.
fn drift_of(
    base: &Path,
    new: &Path,
    scales: Option<&BTreeMap<String, f64>>,
) -> Result<Vec<ColumnDrift>, Unusable> {
    let read = |p: &Path| read_history(p).map_err(|e| Unusable::Read(e.to_string()));
    let (a, b) = (read(base)?, read(new)?);
    if a.columns != b.columns || a.rows.len() != b.rows.len() {
        return Err(Unusable::Mismatch {
            what: "columns or rows".into(),
            list: format!(
                "{} has {} columns and {} rows, {} has {} and {}",
                base.display(),
                a.columns.len(),
                a.rows.len(),
                new.display(),
                b.columns.len(),
                b.rows.len()
            ),
        });
    }
    let scene = |name: &str| scales.and_then(|s| s.get(name)).copied().unwrap_or(0.0);
    Ok(a.columns
        .iter()
        .enumerate()
        .skip(1)
        .map(|(j, name)| {
            let scale = change_scale(&a, name, scene(name));
            let over = |scale: f64| if scale > 0.0 { 1.0 / scale } else { 1.0 };
            let (mut largest, mut growth) = (0.0_f64, Vec::new());
            for (x, y) in a.rows.iter().zip(&b.rows) {
                let d = difference(x[j], y[j]);
                if d > largest {
                    largest = d;
                    growth.push((x[0], d * over(scale)));
                }
            }
            let peak = a.rows.iter().fold(0.0_f64, |m, r| m.max(r[j].abs()));
            ColumnDrift {
                column: name.clone(),
                drift: largest * over(scale),
                of_peak: largest * over(peak),
                growth,
            }
        })
        .collect())
}

/// |a − b|, with a value that is not a number on one side only infinitely far from the other
/// (on both, where they agree, 0).
fn difference(a: f64, b: f64) -> f64 {
    match (a.is_nan(), b.is_nan()) {
        (false, false) => (a - b).abs(),
        (true, true) => 0.0,
        _ => f64::INFINITY,
    }
}

/// The machine tier between two engines of one report on one case: the largest difference of
/// each column of `new`'s history from `base`'s, over `base`'s peak ([`ColumnDrift::of_peak`]:
/// what each column moved between an engine's releases side by side, which are not round-off
/// apart).
pub fn drift_between(
    report: &Report,
    case: &str,
    base: &str,
    new: &str,
) -> Result<Vec<(String, f64)>, Unusable> {
    let file = |engine: &str| crate::report::data::csv_path(&report.dir, case, engine);
    let drifts = drift_of(&file(base), &file(new), report.scales.get(case))?;
    Ok(drifts.into_iter().map(|d| (d.column, d.of_peak)).collect())
}

/// The (case, engine) cells of a report, in order: those `results.csv` judges, those with a
/// history in `data/` (an engine compared with no exact solution has a history and no verdict)
/// and those whose run succeeded (a report may be kept without its histories).
fn cells_of(report: &Report) -> Vec<(String, String)> {
    let mut c: Vec<(String, String)> = report
        .verdicts
        .keys()
        .map(|k| (k.0.clone(), k.1.clone()))
        .collect();
    c.extend(histories_of(&report.dir));
    let ran = report.statuses.iter().filter(|(_, s)| *s == "ok");
    c.extend(ran.map(|(cell, _)| cell.clone()));
    c.sort();
    c.dedup();
    c
}

/// The (case, engine) of every history in `dir/data/<case>/<engine>.csv` (budget CSVs aside).
fn histories_of(dir: &Path) -> Vec<(String, String)> {
    let listing = |d: &Path| -> Vec<PathBuf> {
        std::fs::read_dir(d)
            .map(|l| l.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default()
    };
    let mut out = Vec::new();
    for case in listing(&dir.join("data")).iter().filter(|p| p.is_dir()) {
        let case_id = case.file_name().unwrap_or_default().to_string_lossy();
        for file in listing(case) {
            let name = file.file_name().unwrap_or_default().to_string_lossy();
            if let Some(engine) = name.strip_suffix(".csv")
                && !engine.ends_with(".budget")
            {
                let engine = crate::contract::engine_of_stem(engine);
                out.push((case_id.to_string(), engine));
            }
        }
    }
    out
}

/// Which reports do not keep a cell's history though its run succeeded there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotKept {
    /// The base (previous) report.
    Base,
    /// The new one.
    New,
    /// Neither keeps it.
    Both,
}

/// Both tiers of one cell, every column of its history; with the report that does not keep
/// the history where one does not (then the verdicts alone are compared).
fn cell_changes(
    base: &Report,
    new: &Report,
    case: &str,
    engine: &str,
) -> Result<(Vec<Change>, Option<NotKept>), Unusable> {
    let file = |r: &Report| crate::report::data::csv_path(&r.dir, case, engine);
    let ran = |r: &Report| {
        r.statuses
            .get(&(case.to_string(), engine.to_string()))
            .map(String::as_str)
            == Some("ok")
    };
    let not_kept = match (file(base).is_file(), file(new).is_file()) {
        (true, true) => None,
        (false, true) if ran(base) => Some(NotKept::Base),
        (true, false) if ran(new) => Some(NotKept::New),
        (false, false) if ran(base) || ran(new) => Some(NotKept::Both),
        // No history on either side (a run that failed in both): the verdicts alone.
        (false, false) => None,
        (has_base, _) => {
            let side = if has_base { "base" } else { "new" };
            return Err(Unusable::Mismatch {
                what: "histories".into(),
                list: format!("{case} / {engine}: a history in the {side} report only"),
            });
        }
    };
    // A base report written before reports kept their scales reads them from the new one.
    let scales = base.scales.get(case).or(new.scales.get(case));
    let drifts: Vec<(String, Option<ColumnDrift>)> = if file(base).is_file() && file(new).is_file()
    {
        let drifts = drift_of(&file(base), &file(new), scales)?;
        drifts
            .into_iter()
            .map(|d| (d.column.clone(), Some(d)))
            .collect()
    } else {
        base.verdicts
            .keys()
            .filter(|k| k.0 == case && k.1 == engine)
            .map(|k| (k.2.clone(), None))
            .collect()
    };
    let changes = drifts
        .into_iter()
        .map(|(column, drift)| {
            let key = (case.to_string(), engine.to_string(), column);
            let physics = base
                .verdicts
                .get(&key)
                .zip(new.verdicts.get(&key))
                .map(|(a, b)| (a.clone(), b.clone()));
            let (drift, of_peak, growth) = drift.map_or((None, None, Vec::new()), |d| {
                (Some(d.drift), Some(d.of_peak), d.growth)
            });
            Change {
                key,
                physics,
                drift,
                of_peak,
                growth,
            }
        })
        .collect();
    Ok((changes, not_kept))
}

/// Compare two reports: both tiers of every column of the cells both hold (every history
/// both keep, whether or not an exact solution judged it; the verdicts alone where a report
/// does not keep the history), the cells either holds alone listed; `Err` where they share
/// nothing to compare.
pub fn compare(base: &Report, new: &Report) -> Result<Since, Unusable> {
    let compared = since(base, new);
    if compared.changes.is_empty() && compared.broken.is_empty() {
        return Err(Unusable::Nothing {
            base: cells_of(base).len(),
            new: cells_of(new).len(),
        });
    }
    Ok(compared)
}

/// What changed between a report and the one that replaces it (the main command's "since the
/// previous report"): [`compare`]'s two tiers over the cells both hold, and the cells either
/// holds alone.
#[derive(Debug, Clone, Default)]
pub struct Since {
    /// Both tiers of every column of the cells both reports hold.
    pub changes: Vec<Change>,
    /// Cells (case, engine) only the new report has.
    pub added: Vec<(String, String)>,
    /// Cells only the previous report has (not run in the new one).
    pub gone: Vec<(String, String)>,
    /// Cells the previous report has whose run in the new one failed or went unstable (case,
    /// engine, status): no history, no verdict, and a regression.
    pub broken: Vec<(String, String, String)>,
    /// Cells both have whose histories cannot be compared (other columns or rows), and why.
    pub incomparable: Vec<String>,
    /// Why the two reports cannot be compared at all (a previous report of another schema
    /// version, an unreadable file), where they cannot.
    pub unusable: Option<String>,
    /// Cells whose run succeeded in both but whose history a report does not keep (`data/`
    /// left out, as the committed report leaves it): their verdicts alone are compared.
    pub not_kept: Vec<(String, String, NotKept)>,
    /// Cells whose histories were compared.
    pub histories_compared: usize,
}

/// What changed from the report in `previous` to the one in `new`: `None` where `previous`
/// holds no report; [`Since::unusable`] says why where the two cannot be compared.
pub fn since_dirs(previous: &Path, new: &Path) -> Option<Since> {
    let compared = match (read(previous), read(new)) {
        (Err(Unusable::NotAReport(_)), _) => return None,
        (Ok(base), Ok(new)) => since(&base, &new),
        (Err(e), _) | (_, Err(e)) => Since {
            unusable: Some(e.to_string()),
            ..Since::default()
        },
    };
    Some(compared)
}

/// [`compare`] over the cells `base` and `new` share, the others counted apart.
pub fn since(base: &Report, new: &Report) -> Since {
    let (a, b) = (cells_of(base), cells_of(new));
    let mut since = Since {
        added: b.iter().filter(|c| !a.contains(c)).cloned().collect(),
        ..Since::default()
    };
    for cell in a.iter().filter(|c| !b.contains(c)) {
        match new.statuses.get(cell).map(String::as_str) {
            Some(status @ ("failed" | "unstable")) => {
                since
                    .broken
                    .push((cell.0.clone(), cell.1.clone(), status.to_string()));
            }
            _ => since.gone.push(cell.clone()),
        }
    }
    for (case, engine) in a.iter().filter(|c| b.contains(c)) {
        match cell_changes(base, new, case, engine) {
            Ok((changes, not_kept)) => {
                if changes.iter().any(|c| c.drift.is_some()) {
                    since.histories_compared += 1;
                }
                since.changes.extend(changes);
                if let Some(side) = not_kept {
                    since.not_kept.push((case.clone(), engine.clone(), side));
                }
            }
            Err(e) => since.incomparable.push(e.to_string()),
        }
    }
    since
}

/// An error has moved when it changed by more than this fraction.
pub const MOVED: f64 = 0.01;

impl Since {
    /// One paragraph: verdicts that flipped (physics), errors that moved by more than
    /// [`MOVED`], histories that drifted by more than [`DRIFT`] of their scale (machine), and
    /// the cells added, gone or not comparable.
    pub fn paragraph(&self) -> String {
        let cell = |c: &Change| format!("{} / `{}` {}", c.key.0, c.key.1, c.key.2);
        let flipped: Vec<String> = self
            .changes
            .iter()
            .filter_map(|c| {
                let (a, b) = c.physics.as_ref()?;
                let verdict = match (a.pass, b.pass) {
                    (Some(true), Some(false)) => "now misses its tolerance",
                    (Some(false), Some(true)) => "now meets its tolerance",
                    _ => return None,
                };
                Some(format!(
                    "{} {verdict} ({} → {})",
                    cell(c),
                    sci(a.error),
                    sci(b.error)
                ))
            })
            .collect();
        let mut moved: Vec<(f64, String)> = self
            .changes
            .iter()
            .filter_map(|c| {
                let (a, b) = c
                    .physics
                    .as_ref()
                    .filter(|(a, b)| a.relative && b.relative)?;
                let ratio = b.error / a.error;
                (a.error > 0.0 && (ratio - 1.0).abs() > MOVED).then(|| {
                    let text = format!("{} {} → {}", cell(c), sci(a.error), sci(b.error));
                    (ratio.ln().abs(), text)
                })
            })
            .collect();
        moved.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut drifted: Vec<&Change> = self.changes.iter().filter(|c| c.drifted(DRIFT)).collect();
        drifted.sort_by(|a, b| b.drift.unwrap_or(0.0).total_cmp(&a.drift.unwrap_or(0.0)));
        let steady =
            flipped.is_empty() && moved.is_empty() && drifted.is_empty() && self.broken.is_empty();
        let mut parts = Vec::new();
        if !flipped.is_empty() {
            let shown: Vec<&str> = flipped.iter().take(3).map(String::as_str).collect();
            let rest = if flipped.len() > 3 {
                "; the rest: `crosscheck compare`"
            } else {
                ""
            };
            parts.push(format!(
                "{} verdicts changed ({}{rest})",
                flipped.len(),
                shown.join("; ")
            ));
        }
        if !moved.is_empty() {
            let shown: Vec<&str> = moved.iter().take(3).map(|m| m.1.as_str()).collect();
            parts.push(format!(
                "{} errors moved by more than {:.0} % (most: {})",
                moved.len(),
                MOVED * 100.0,
                shown.join("; ")
            ));
        }
        if !drifted.is_empty() {
            let shown: Vec<String> = drifted
                .iter()
                .take(3)
                .map(|c| format!("{} by {}", cell(c), sci(c.drift.unwrap_or(0.0))))
                .collect();
            parts.push(format!(
                "{} history columns moved by more than {} of their scale (most: {})",
                drifted.len(),
                sci(DRIFT),
                shown.join("; ")
            ));
        }
        if !self.broken.is_empty() {
            let shown: Vec<String> = self
                .broken
                .iter()
                .take(3)
                .map(|(case, engine, status)| format!("{case} / `{engine}` ({status})"))
                .collect();
            parts.push(format!(
                "{} cells whose run now fails ({})",
                self.broken.len(),
                shown.join("; ")
            ));
        }
        for (cells, what) in [
            (&self.added, "new cells"),
            (&self.gone, "cells no longer run"),
        ] {
            if !cells.is_empty() {
                parts.push(format!("{} {what}", cells.len()));
            }
        }
        if !self.incomparable.is_empty() {
            parts.push(format!(
                "{} cells whose histories cannot be compared ({})",
                self.incomparable.len(),
                self.incomparable[0]
            ));
        }
        let head = "**Since the previous report in this directory** (the two tiers of \
                    `crosscheck compare`):";
        if let Some(why) = &self.unusable {
            return format!("{head} it cannot be compared with this one: {why}.\n");
        }
        let moved_none = format!(
            "no verdict changed, no error moved by more than {:.0} %",
            MOVED * 100.0
        );
        let steady_line = if self.histories_compared == 0 && !self.not_kept.is_empty() {
            format!(
                "{moved_none}; histories not compared ({})",
                self.kept_by("previous")
            )
        } else {
            if !self.not_kept.is_empty() {
                parts.push(format!(
                    "the histories of {} cells not compared ({})",
                    self.not_kept.len(),
                    self.kept_by("previous")
                ));
            }
            format!(
                "{moved_none} and no history by more than {} of its scale",
                sci(DRIFT)
            )
        };
        if parts.is_empty() {
            return format!("{head} {steady_line}.\n");
        }
        if steady && !self.changes.is_empty() {
            parts.insert(0, format!("in the cells both hold, {steady_line}"));
        } else if self.histories_compared == 0 && !self.not_kept.is_empty() {
            parts.push(format!(
                "histories not compared ({})",
                self.kept_by("previous")
            ));
        }
        format!("{head} {}.\n", parts.join("; "))
    }

    /// Which report does not keep the histories of [`Self::not_kept`], in words (the base
    /// report called `base_name`): "the previous report keeps none of them", "…keeps them in
    /// neither".
    fn kept_by(&self, base_name: &str) -> String {
        let count = |side: NotKept| self.not_kept.iter().filter(|c| c.2 == side).count();
        let mut said = Vec::new();
        for (side, report) in [
            (NotKept::Base, format!("the {base_name} report")),
            (NotKept::New, "the new report".to_string()),
            (NotKept::Both, "either report".to_string()),
        ] {
            match count(side) {
                0 => {}
                n if n == self.not_kept.len() => said.push(format!("{report} does not keep them")),
                n => said.push(format!("{report} does not keep {n}")),
            }
        }
        said.join(", ")
    }

    /// Why the machine tier compared nothing, where a report keeps no history of the cells
    /// both hold (they were compared by their verdicts alone).
    pub fn machine_tier_missing(&self) -> Option<String> {
        (self.histories_compared == 0 && !self.not_kept.is_empty()).then(|| {
            format!(
                "the machine tier compared no history: {} (`data/`)",
                self.kept_by("base")
            )
        })
    }
}

/// The comparison as markdown: a verdict line, then the physics regressions and the drifted
/// columns (largest first), each with both numbers.
pub fn markdown(base: &Path, new: &Path, compared: &Since, threshold: f64) -> String {
    let changes = &compared.changes;
    let failing: Vec<&Change> = changes.iter().filter(|c| c.newly_failing()).collect();
    let mut drifted: Vec<&Change> = changes.iter().filter(|c| c.drifted(threshold)).collect();
    drifted.sort_by(|a, b| b.drift.unwrap_or(0.0).total_cmp(&a.drift.unwrap_or(0.0)));
    let machine = match compared.machine_tier_missing() {
        Some(_) => format!(
            "no history compared ({}, `data/`)",
            compared.kept_by("base")
        ),
        None => format!(
            "{} drifted by more than {} of their scale (a column's peak, or where larger the \
             energy or scene scale its round-off comes from)",
            drifted.len(),
            sci(threshold)
        ),
    };
    let mut s = format!(
        "# {} → {}\n\n{} columns compared: {} newly failing their tolerance (physics); machine \
         tier: {machine}.\n",
        base.display(),
        new.display(),
        changes.len(),
        failing.len(),
    );
    if !compared.not_kept.is_empty() && compared.histories_compared > 0 {
        let cells: Vec<String> = compared
            .not_kept
            .iter()
            .take(5)
            .map(|(c, e, _)| format!("{c} / `{e}`"))
            .collect();
        let _ = writeln!(
            s,
            "\nThe histories of {} cells are not compared ({}): {}{}.",
            compared.not_kept.len(),
            compared.kept_by("base"),
            cells.join(", "),
            if compared.not_kept.len() > 5 {
                ", …"
            } else {
                ""
            }
        );
    }
    for (cells, what) in [
        (&compared.added, "in the new report only (not compared)"),
        (&compared.gone, "in the base report only (not compared)"),
    ] {
        if !cells.is_empty() {
            let _ = writeln!(s, "\n{} cells {what}: {}.", cells.len(), cell_list(cells));
        }
    }
    if !compared.broken.is_empty() {
        s += "\n## Runs that now fail (physics tier)\n\n";
        for (case, engine, status) in &compared.broken {
            let _ = writeln!(s, "- {case} / `{engine}`: {status} in the new report");
        }
    }
    if !compared.incomparable.is_empty() {
        s += "\n## Histories that cannot be compared (machine tier)\n\n";
        for why in &compared.incomparable {
            let _ = writeln!(s, "- {why}");
        }
    }
    let error = |v: &Verdict| {
        format!(
            "{}{}",
            sci(v.error),
            if v.relative { "" } else { " (absolute)" }
        )
    };
    if !failing.is_empty() {
        s += "\n## Newly failing\n\n| case | engine | column | base error | new error | tolerance |\n|---|---|---|---:|---:|---:|\n";
        for c in &failing {
            let (a, b) = c.physics.as_ref().expect("newly failing has both");
            let _ = writeln!(
                s,
                "| {} | `{}` | {} | {} | {} | {} |",
                c.key.0,
                c.key.1,
                c.key.2,
                error(a),
                error(b),
                b.tolerance.map_or("–".into(), sci)
            );
        }
    }
    if !drifted.is_empty() {
        s += "\n## Drifted\n\n| case | engine | column | drift / peak | drift / scale | from t, s | base error | new error |\n|---|---|---|---:|---:|---:|---:|---:|\n";
        for c in &drifted {
            let (a, b) = c
                .physics
                .as_ref()
                .map_or(("–".into(), "–".into()), |(a, b)| (error(a), error(b)));
            let _ = writeln!(
                s,
                "| {} | `{}` | {} | {} | {} | {} | {a} | {b} |",
                c.key.0,
                c.key.1,
                c.key.2,
                sci(c.of_peak.unwrap_or(0.0)),
                sci(c.drift.unwrap_or(0.0)),
                c.onset(threshold).map_or("–".into(), instant)
            );
        }
    }
    s
}

/// Cells (case, engine) in words: each one where there are few, otherwise by engine, with its
/// cases where they are few and their count where they are many.
fn cell_list(cells: &[(String, String)]) -> String {
    const FEW: usize = 10;
    if cells.len() <= FEW {
        let each: Vec<String> = cells.iter().map(|(c, e)| format!("{c} / `{e}`")).collect();
        return each.join(", ");
    }
    let mut by_engine: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (case, engine) in cells {
        by_engine.entry(engine).or_default().push(case);
    }
    let each: Vec<String> = by_engine
        .iter()
        .map(|(engine, cases)| match cases.len() {
            n if n <= 3 => format!("`{engine}` on {}", cases.join(", ")),
            n => format!("`{engine}` on {n} cases ({}, …)", cases[..2].join(", ")),
        })
        .collect();
    each.join("; ")
}

/// The comparison as JUnit XML: a suite per tier, a test case per column (`case/engine` its
/// class, the column its name), a failure where the tier fails (machine: unless
/// `physics_only`), and in the machine tier one per history that cannot be compared.
pub fn junit(compared: &Since, threshold: f64, physics_only: bool) -> String {
    use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};
    let changes = &compared.changes;
    let physics: Vec<&Change> = changes.iter().filter(|c| c.physics.is_some()).collect();
    // The machine tier's cases: the columns whose histories both reports keep.
    let all: Vec<&Change> = changes.iter().filter(|c| c.drift.is_some()).collect();
    let suite = |name: &str, cases: &[&Change], fails: &dyn Fn(&Change) -> Option<String>| {
        let mut suite = TestSuite::new(name);
        suite.add_test_cases(cases.iter().map(|c| {
            let status = match fails(c) {
                Some(message) => {
                    let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
                    status.set_message(message);
                    status
                }
                None => TestCaseStatus::success(),
            };
            let mut case = TestCase::new(c.key.2.as_str(), status);
            case.set_classname(format!("{}/{}", c.key.0, c.key.1));
            case
        }));
        suite
    };
    let mut report = Report::new("crosscheck compare");
    let mut physics_suite = suite("physics", &physics, &|c: &Change| {
        let (a, b) = c.physics.as_ref()?;
        c.newly_failing().then(|| {
            format!(
                "newly failing: error {} (was {}), tolerance {}",
                sci(b.error),
                sci(a.error),
                b.tolerance.map_or("–".into(), sci)
            )
        })
    });
    for (case, engine, status) in &compared.broken {
        let mut status_of = TestCaseStatus::non_success(NonSuccessKind::Failure);
        status_of.set_message(format!("the run now fails: {status}"));
        let mut test = TestCase::new("run", status_of);
        test.set_classname(format!("{case}/{engine}"));
        physics_suite.add_test_case(test);
    }
    report.add_test_suite(physics_suite);
    let mut machine = suite("machine", &all, &|c: &Change| {
        (!physics_only && c.drifted(threshold)).then(|| {
            format!(
                "drifted by {} of the scale (threshold {})",
                sci(c.drift.unwrap_or(0.0)),
                sci(threshold)
            )
        })
    });
    for why in &compared.incomparable {
        let mut status = if physics_only {
            TestCaseStatus::skipped()
        } else {
            TestCaseStatus::non_success(NonSuccessKind::Failure)
        };
        status.set_message(why.as_str());
        machine.add_test_case(TestCase::new("history", status));
    }
    report.add_test_suite(machine);
    report.to_string().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_that_is_not_a_number_on_one_side_only_is_infinitely_far() {
        assert_eq!(difference(1.0, 1.5), 0.5);
        assert_eq!(difference(f64::NAN, 1.0), f64::INFINITY);
        assert_eq!(difference(1.0, f64::NAN), f64::INFINITY);
        assert_eq!(difference(f64::NAN, f64::NAN), 0.0);
    }

    #[test]
    fn many_cells_are_listed_by_engine() {
        let cell = |c: usize, e: &str| (format!("case{c:02}"), e.to_string());
        let few: Vec<_> = (0..2).map(|c| cell(c, "a")).collect();
        assert_eq!(cell_list(&few), "case00 / `a`, case01 / `a`");
        let mut many: Vec<_> = (0..10).map(|c| cell(c, "a")).collect();
        many.extend((0..2).map(|c| cell(c, "b")));
        assert_eq!(
            cell_list(&many),
            "`a` on 10 cases (case00, case01, …); `b` on case00, case01"
        );
    }
}
