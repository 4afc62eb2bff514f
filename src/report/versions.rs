//! The versions section of `REPORT.md`: a third-party engine's releases side by side (rapier
//! 0.34 and 0.35 beside the current release, with the `rapier-versions` feature). Each older
//! release's cells are judged against the tolerance the case declares for the current
//! release's engine of the same configuration; the errors and the drift between releases are
//! `crosscheck compare`'s two tiers ([`super::regression`]) read from this report's files.

use super::contact::{drop_cases, restitution_table};
use super::format::sci;
use super::regression::{self, Report};
use super::verdicts::{cause_and_control, control};
use crate::comparison::summary::{CaseSummary, EngineSummary, Summary};
use crate::contract::release_of;
use crate::run::controls::ControlKind;
use std::fmt::Write;
use std::path::Path;

/// One configuration's engines across releases: the current one's name and its releases'
/// names, oldest first, the current last.
#[derive(Debug, Clone, PartialEq)]
pub struct Lineage {
    /// The current release's engine (`rapier_f64`).
    pub current: String,
    /// Every release's engine, oldest first, `current` last.
    pub releases: Vec<String>,
}

/// The lineages of the engines of `s` that ran on more than one release, in report order.
pub fn lineages(s: &Summary) -> Vec<Lineage> {
    let mut out: Vec<Lineage> = Vec::new();
    for e in &s.engines {
        let (base, Some(_)) = release_of(e) else {
            continue;
        };
        match out.iter_mut().find(|l| l.current == base) {
            Some(l) => l.releases.insert(l.releases.len() - 1, e.clone()),
            None if s.engines.iter().any(|x| x == base) => out.push(Lineage {
                current: base.to_string(),
                releases: vec![e.clone(), base.to_string()],
            }),
            None => {}
        }
    }
    out
}

/// A release's label in the tables: its tag (`0.34`), or the current release's.
fn label(engine: &str) -> &str {
    release_of(engine).1.unwrap_or(CURRENT)
}

/// The current release's label.
#[cfg(feature = "rapier")]
const CURRENT: &str = crate::engines::rapier::Release::Current.label();
#[cfg(not(feature = "rapier"))]
const CURRENT: &str = "current";

/// A cell's verdict against the current release's tolerance (the one rule,
/// [`crate::comparison::verdict::tolerance`]): `Some(true)` within it, `Some(false)` over it or
/// failed, `None` not judged (no tolerance, no compared row).
fn verdict(c: &CaseSummary, engine: &str) -> Option<bool> {
    c.run(engine)?.meets_tolerance
}

/// A cell's worst error, or `failed`.
fn worst(c: &CaseSummary, engine: &str) -> String {
    match c.run(engine) {
        Some(r) if r.error.is_some() => "failed".into(),
        Some(r) => r
            .against_baseline
            .as_ref()
            .and_then(|a| a.worst_max)
            .map_or("–".into(), sci),
        None => "–".into(),
    }
}

/// An error of `results.csv`: over the peak, or in the column's unit where the exact column
/// has no peak over the compared rows (`abs.`).
fn error_cell(v: &regression::Verdict) -> String {
    if v.relative {
        sci(v.error)
    } else {
        format!("{} abs.", sci(v.error))
    }
}

/// The versions section (nothing where no engine ran on more than one release).
pub fn section(w: &mut String, s: &Summary, out: &Path) {
    let lineages = lineages(s);
    if lineages.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "## Releases side by side\n\n\
         The same cases through older releases of rapier beside the current one, in f64, matched \
         and default configurations, each release built on its own crate behind one scene-to-rapier \
         plan. Each older release is held to the tolerance the case declares for the current \
         release's engine; its cells are not counted in the verdicts above. Drift: the largest \
         difference of a release's history from the current release's, over the column's peak \
         (the machine tier of `crosscheck compare`).\n"
    );
    headline(w, s, &lineages);
    differing(w, s, &lineages);
    rebounds(w, s, &lineages);
    match regression::read(out) {
        Ok(report) => {
            contact_forces(w, s, &report, &lineages);
            every_column(w, s, &report, &lineages);
        }
        Err(e) => {
            let _ = writeln!(w, "The per-column tables could not be read: {e}.\n");
        }
    }
}

/// Per lineage, how many cells each release meets.
fn headline(w: &mut String, s: &Summary, lineages: &[Lineage]) {
    for l in lineages {
        let per: Vec<String> = l
            .releases
            .iter()
            .map(|e| {
                let judged: Vec<bool> = s.cases.iter().filter_map(|c| verdict(c, e)).collect();
                let met = judged.iter().filter(|v| **v).count();
                format!("{} {met} of {}", label(e), judged.len())
            })
            .collect();
        let _ = writeln!(
            w,
            "- **`{}`: {}** cells within the current release's tolerance.",
            l.current,
            per.join(", ")
        );
    }
    let _ = writeln!(w);
}

/// The cells where an older release's verdict is not the current release's, with the cause
/// its controls show.
fn differing(w: &mut String, s: &Summary, lineages: &[Lineage]) {
    let mut rows = Vec::new();
    // The causes the rows name, each with an engine that names it.
    let mut named: Vec<(ControlKind, String)> = Vec::new();
    for l in lineages {
        for c in &s.cases {
            let now = verdict(c, &l.current);
            for e in l.releases.iter().filter(|e| **e != l.current) {
                let then = verdict(c, e);
                if then.is_none() || then == now {
                    continue;
                }
                let tolerance = c.run(&l.current).and_then(|r| r.tolerance);
                // Where the older release meets the tolerance, it is the current one that
                // misses: its cause.
                let shown = if then == Some(true) { &l.current } else { e };
                let why = cause(c.run(shown));
                let why = if then == Some(true) {
                    format!("the current release misses: {why}")
                } else {
                    why
                };
                let explaining = c
                    .run(shown)
                    .and_then(|r| r.attribution.as_ref()?.explaining())
                    .map(|k| k.kind);
                if let Some(kind) = explaining.filter(|k| !named.iter().any(|(n, _)| n == k)) {
                    named.push((kind, shown.clone()));
                }
                rows.push(format!(
                    "| {} | `{e}` | {} | {} | {} | {why} |",
                    c.id,
                    worst(c, e),
                    worst(c, &l.current),
                    tolerance.map_or("–".into(), sci),
                ));
            }
        }
    }
    if rows.is_empty() {
        let _ = writeln!(
            w,
            "Every older release's cell has the current release's verdict.\n"
        );
        return;
    }
    let _ = writeln!(
        w,
        "**Where a release's verdict differs from the current one's** ({}), with the cause its \
         control experiments show: the controls of any cell ([accuracy.md](accuracy.md)), and on \
         0.34 three more, a contact softness ten times softer (its restitution depends on it), \
         the contact impulse read as n/(n + 1) of what it reports, and gyroscopic forces on (3D); \
         the control and its error after the colon:\n\n\
         | case | engine | worst error | current release's | tolerance | cause |\n\
         |---|---|---:|---:|---:|---|",
        rows.len()
    );
    for r in rows {
        let _ = writeln!(w, "{r}");
    }
    let _ = writeln!(w);
    meanings(w, &named);
}

/// What each cause the table names means.
fn meanings(w: &mut String, named: &[(ControlKind, String)]) {
    if named.is_empty() {
        return;
    }
    for (kind, engine) in named {
        let _ = writeln!(
            w,
            "- **{}**: {}.",
            super::verdicts::cause_label(*kind, engine),
            super::verdicts::cause_meaning(*kind)
        );
    }
    let _ = writeln!(w);
}

/// The cause a cell's controls show, with the control that shows it; what was tried where
/// none does.
fn cause(r: Option<&EngineSummary>) -> String {
    let Some(r) = r else {
        return "–".into();
    };
    if let Some(e) = &r.error {
        return format!("the run failed: {e}");
    }
    let Some(a) = &r.attribution else {
        return "no control was run".into();
    };
    match cause_and_control(a) {
        (cause, shown) if a.explaining().is_some() => format!("{cause}: {shown}"),
        (cause, _) => {
            let tried: Vec<String> = a.controls.iter().map(control).collect();
            format!("{cause} (tried {})", tried.join("; "))
        }
    }
}

/// The restitution table, each release's rebound side by side.
fn rebounds(w: &mut String, s: &Summary, lineages: &[Lineage]) {
    let cases: Vec<&CaseSummary> = s.cases.iter().collect();
    let drops = drop_cases(&cases);
    if drops.is_empty() {
        return;
    }
    let names: Vec<&str> = lineages
        .iter()
        .flat_map(|l| l.releases.iter().map(String::as_str))
        .collect();
    let _ = writeln!(
        w,
        "**First rebound over the drop, per release** (exact: e²; rapier's `restitution` on the \
         ball and the block, a fixed body):\n"
    );
    restitution_table(w, &drops, &names);
}

/// The least-squares ratio of one contact force history to another (Σab / Σb²), where both
/// have the column and the second is not zero throughout.
fn force_ratio(report: &Report, case: &str, engine: &str, current: &str) -> Option<f64> {
    let read = |e: &str| {
        super::data::read_history(&super::data::csv_path(&report.dir, case, e))
            .ok()?
            .column("contact_force")
    };
    let (a, b) = (read(engine)?, read(current)?);
    let (ab, bb) = a
        .iter()
        .zip(&b)
        .fold((0.0, 0.0), |(ab, bb), (x, y)| (ab + x * y, bb + y * y));
    (bb > 0.0).then(|| ab / bb)
}

/// The contact-force column per release: its error, and each older release's force over the
/// current one's.
fn contact_forces(w: &mut String, s: &Summary, report: &Report, lineages: &[Lineage]) {
    let mut rows = Vec::new();
    for l in lineages {
        for c in &s.cases {
            let key = |e: &str| (c.id.clone(), e.to_string(), "contact_force".to_string());
            if !report.verdicts.contains_key(&key(&l.current)) {
                continue;
            }
            let ratios: Vec<Option<f64>> = l
                .releases
                .iter()
                .filter(|e| **e != l.current)
                .map(|e| force_ratio(report, &c.id, e, &l.current))
                .collect();
            if ratios.iter().all(Option::is_none) {
                continue; // no contact force in the current release's history
            }
            let errors: Vec<String> = l
                .releases
                .iter()
                .map(|e| report.verdicts.get(&key(e)).map_or("–".into(), error_cell))
                .collect();
            let ratios: Vec<String> = l
                .releases
                .iter()
                .zip(&ratios)
                .map(|(e, r)| {
                    format!(
                        "{} {}",
                        label(e),
                        r.map_or("–".into(), |r| format!("{r:.3}"))
                    )
                })
                .collect();
            rows.push(format!(
                "| {} | `{}` | {} | {} |",
                c.id,
                l.current,
                errors.join(" / "),
                ratios.join(", ")
            ));
        }
    }
    if rows.is_empty() {
        return;
    }
    let order: Vec<&str> = lineages[0].releases.iter().map(|e| label(e)).collect();
    let _ = writeln!(
        w,
        "**Contact force per release**: the `contact_force` column's error over its peak ({}; \
         `abs.`: in newtons, where the exact force is zero over the compared rows, before an \
         impact), and each older release's force over the current one's (least squares over the \
         rows). Rapier reports a contact's normal impulse over the step; crosscheck divides it \
         by the step.\n\n| case | configuration | error ({}) | force over the current release's |\n\
         |---|---|---|---|",
        order.join(", "),
        order.join(" / ")
    );
    for r in rows {
        let _ = writeln!(w, "{r}");
    }
    let _ = writeln!(w);
}

/// Every case and column: each release's error and its drift from the current release.
fn every_column(w: &mut String, s: &Summary, report: &Report, lineages: &[Lineage]) {
    let _ = writeln!(
        w,
        "<details><summary>Every case and column: each release's error over the peak \
         (absolute where the column has none), and its drift from the current release</summary>\n\n\
         | case | column | engine | error per release (oldest first) | drift from the current release |\n\
         |---|---|---|---|---|"
    );
    for l in lineages {
        for c in &s.cases {
            let columns: Vec<&str> = report
                .verdicts
                .keys()
                .filter(|k| k.0 == c.id && k.1 == l.current)
                .map(|k| k.2.as_str())
                .collect();
            let drifts: Vec<(&str, Vec<(String, f64)>)> = l
                .releases
                .iter()
                .filter(|e| **e != l.current)
                .map(|e| {
                    let d = regression::drift_between(report, &c.id, &l.current, e);
                    (label(e), d.unwrap_or_default())
                })
                .collect();
            for col in columns {
                let errors: Vec<String> = l
                    .releases
                    .iter()
                    .map(|e| {
                        let key = (c.id.clone(), e.clone(), col.to_string());
                        let v = report.verdicts.get(&key);
                        format!("{} {}", label(e), v.map_or("–".into(), error_cell))
                    })
                    .collect();
                let drift: Vec<String> = drifts
                    .iter()
                    .map(|(tag, d)| {
                        let x = d.iter().find(|(n, _)| n == col).map(|(_, x)| *x);
                        format!("{tag} {}", x.map_or("–".into(), sci))
                    })
                    .collect();
                let _ = writeln!(
                    w,
                    "| {} | {col} | `{}` | {} | {} |",
                    c.id,
                    l.current,
                    errors.join(", "),
                    drift.join(", ")
                );
            }
        }
    }
    let _ = writeln!(w, "\n</details>\n");
}
