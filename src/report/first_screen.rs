//! The first screen of `REPORT.md`: the user's three questions answered from the run, read at a
//! glance (at most [`MAX_LINES`] lines, no paragraph over [`MAX_PARAGRAPH`] characters, one
//! unit per table column). How close each engine gets (tolerances met, median and worst
//! error, its flagged cells by cause), what accuracy costs (CPU time to 1e-2 and 1e-4 of the
//! peak against `explicit`'s, and the floors that stop it), and where it stays stable (the
//! critical increment, and its own step); then what changed since the previous report. Every
//! figure is the comparison's ([`crate::comparison::summary`]); this module only writes them.

use super::format::{ratio, sci};
use super::provenance::Provenance;
use super::regression::Since;
use crate::comparison::EXACT_SOLUTIONS;
use crate::comparison::stability::Bound;
use crate::comparison::summary::{CaseSummary, Summary, ToleranceCheck};
use crate::comparison::verdict::cause::FLAG_RATIO;
use crate::comparison::verdict::cost::{CostToAccuracy, Reached};
use std::fmt::Write;

/// The engine every cost is measured against.
const BASE: &str = "explicit";

/// The accuracies the first screen asks for.
const TARGETS: [f64; 2] = [1e-2, 1e-4];

/// The most lines the first screen takes (up to the index).
pub const MAX_LINES: usize = 60;

/// The most characters a paragraph of the first screen has.
pub const MAX_PARAGRAPH: usize = 400;

/// The first screen; `since`: what changed since the report this run replaces, if there was
/// one.
pub fn render(
    w: &mut String,
    s: &Summary,
    p: &Provenance,
    parts: &[(&str, f64)],
    since: Option<&Since>,
) {
    let _ = writeln!(w, "# crosscheck report\n");
    let took: f64 = parts.iter().map(|(_, t)| t).sum();
    let list: Vec<String> = parts
        .iter()
        .map(|(name, t)| format!("{name} {t:.0} s"))
        .collect();
    let _ = writeln!(
        w,
        "{}; {}; {}. The run took {took:.0} s: {}. What was run: [accuracy.md](accuracy.md).\n",
        p.version,
        p.machine,
        p.date,
        list.join(", ")
    );
    let _ = writeln!(
        w,
        "- *cell*: one engine on one case it applies to, judged against the exact solution of \
         its own model with the tolerance the case declares for it.\n\
         - *matched*: rapier at the explicit engine's increment with converged solver settings \
         (`rapier_f64`, `rapier_f32`).\n\
         - *default*: rapier's own settings, 1/60 s (`rapier_f64_default`, \
         `rapier_f32_default`).\n\
         - *flagged*: a cell that misses its tolerance, or a rapier cell over {FLAG_RATIO:.0}× \
         `{BASE}`'s error; each is rerun with controls for its cause.\n\
         - *floor*: the smallest error an engine reaches before refining its increment stops \
         paying, with what limits it.\n"
    );
    let engines = judged_engines(s);
    how_close(w, s, &engines);
    cost(w, s, &engines);
    floors(w, s, &engines);
    stable(w, s, &engines);
    if let Some(since) = since {
        let _ = writeln!(w, "{}", since.paragraph());
    }
}

/// The engines with a verdict, in report order (an older release's are in the versions section).
fn judged_engines(s: &Summary) -> Vec<&str> {
    s.engines
        .iter()
        .map(String::as_str)
        .filter(|e| !EXACT_SOLUTIONS.contains(e))
        .filter(|e| !crate::contract::on_older_release(e))
        .filter(|e| s.cases.iter().any(|c| c.run(e).is_some()))
        .collect()
}

/// An engine's worst error against its own model on each case where it has one, smallest
/// first: (error, case).
fn errors<'a>(s: &'a Summary, engine: &str) -> Vec<(f64, &'a str)> {
    let mut e: Vec<(f64, &str)> = s
        .cases
        .iter()
        .filter_map(|c| {
            let a = c.run(engine)?.against_baseline.as_ref()?;
            Some((a.worst_max?, c.id.as_str()))
        })
        .collect();
    e.sort_by(|a, b| a.0.total_cmp(&b.0));
    e
}

/// The median of sorted values (the geometric mean of the middle two for an even count).
fn median(sorted: &[f64]) -> Option<f64> {
    match sorted.len() {
        0 => None,
        n if n % 2 == 1 => Some(sorted[n / 2]),
        n => Some((sorted[n / 2 - 1] * sorted[n / 2]).sqrt()),
    }
}

/// How many of an engine's cells meet their tolerance, saying how many have none declared.
fn met_of(cells: &[&ToleranceCheck]) -> String {
    let met = cells.iter().filter(|c| c.met()).count();
    let without = cells.iter().filter(|c| c.tolerance.is_none()).count();
    match without {
        0 => format!("{met} of {}", cells.len()),
        n => format!("{met} of {} ({n} without a tolerance)", cells.len()),
    }
}

/// How close: the count, then one row per engine.
fn how_close(w: &mut String, s: &Summary, engines: &[&str]) {
    let checks = s.tolerance_checks();
    let _ = writeln!(
        w,
        "**How close?** {} of {} cells meet their tolerance. Errors: the largest over the \
         compared rows, over the column's peak, worst column ([accuracy.md](accuracy.md)).\n",
        checks.iter().filter(|c| c.met()).count(),
        checks.len(),
    );
    let _ = writeln!(
        w,
        "| engine | cells met | median error | worst error | worst case | flagged cells by cause |\n|---|---:|---:|---:|---|---|"
    );
    for e in engines {
        let mine: Vec<_> = checks.iter().filter(|c| c.engine == *e).collect();
        let errs = errors(s, e);
        let values: Vec<f64> = errs.iter().map(|x| x.0).collect();
        let (worst, case) = errs
            .last()
            .map_or(("–".into(), "–"), |(v, c)| (sci(*v), *c));
        let _ = writeln!(
            w,
            "| `{e}` | {} | {} | {worst} | {case} | {} |",
            met_of(&mine),
            median(&values).map_or("–".into(), sci),
            flags(s, e)
        );
    }
    let _ = writeln!(w);
}

/// An engine's flagged cells by cause: "time step 12, unexplained 2".
fn flags(s: &Summary, engine: &str) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for c in &s.cases {
        let Some(a) = c.run(engine).and_then(|r| r.attribution.as_ref()) else {
            continue;
        };
        let label = super::verdicts::cause_name(a).unwrap_or_else(|| "unexplained".to_string());
        match counts.iter_mut().find(|(l, _)| *l == label) {
            Some((_, n)) => *n += 1,
            None => counts.push((label, 1)),
        }
    }
    if counts.is_empty() {
        return "none".into();
    }
    counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    counts
        .iter()
        .map(|(l, n)| format!("{l} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A cost at a target on a case, for an engine.
fn cost_of<'a>(c: &'a CaseSummary, engine: &str, target: f64) -> Option<&'a CostToAccuracy> {
    c.run(engine)?
        .cost_to_accuracy
        .iter()
        .find(|k| k.target == target)
}

/// The swept cases, one per problem: a case found equivalent to another is represented by it.
fn representatives(s: &Summary) -> Vec<&CaseSummary> {
    s.cases
        .iter()
        .filter(|c| c.runs.iter().any(|r| !r.cost_to_accuracy.is_empty()))
        .filter(|c| !s.equivalences.iter().any(|e| e.case == c.id))
        .collect()
}

/// One cost column of the cost table: the median ratio to `explicit`'s (range) over the cases
/// where both have a CPU time, and how those were found.
fn cost_column(s: &Summary, engine: &str, target: f64) -> (String, String) {
    let mut ratios: Vec<(f64, Reached)> = representatives(s)
        .iter()
        .filter_map(|c| {
            let mine = cost_of(c, engine, target)?;
            let base = cost_of(c, BASE, target)?.cpu_s_per_simulated_s?;
            Some((mine.cpu_s_per_simulated_s? / base, mine.reached))
        })
        .collect();
    ratios.sort_by(|a, b| a.0.total_cmp(&b.0));
    let values: Vec<f64> = ratios.iter().map(|r| r.0).collect();
    let cell = match (median(&values), values.first(), values.last()) {
        (Some(m), Some(lo), Some(hi)) => {
            format!("{}× ({}–{})", ratio(m), ratio(*lo), ratio(*hi))
        }
        _ => "–".into(),
    };
    let count = |r: Reached| ratios.iter().filter(|x| x.1 == r).count();
    let floors = representatives(s)
        .iter()
        .filter(|c| cost_of(c, engine, target).is_some_and(|k| k.reached == Reached::Floor))
        .count();
    let how = format!(
        "{} / {} / {}",
        count(Reached::Measured),
        count(Reached::Extrapolated),
        count(Reached::AtLeast)
    );
    if values.is_empty() && floors > 0 {
        return (format!("floor on {floors}"), how);
    }
    (cell, how)
}

/// What accuracy costs: per engine, the CPU time to 1e-2 and 1e-4 over `explicit`'s.
fn cost(w: &mut String, s: &Summary, engines: &[&str]) {
    let cases = representatives(s);
    if cases.is_empty() {
        return;
    }
    let base: Vec<f64> = {
        let mut v: Vec<f64> = cases
            .iter()
            .filter_map(|c| cost_of(c, BASE, 1e-4)?.cpu_s_per_simulated_s)
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let _ = writeln!(
        w,
        "**At what cost?** CPU time to reach 1e-2 and 1e-4 of the peak over `{BASE}`'s (whose \
         median to 1e-4 is {} CPU-s per simulated s), median (range) over {} swept problems; \
         counted: measured by a run / ≈ extrapolated along the observed order / a lower bound \
         (runs within budget fell short) ([cost.md](cost.md)).\n",
        median(&base).map_or("–".into(), sci),
        cases.len()
    );
    let _ = writeln!(
        w,
        "| engine | to 1e-2 | counted | to 1e-4 | counted |\n|---|---:|---:|---:|---:|"
    );
    for e in engines.iter().filter(|e| **e != BASE) {
        let cells: Vec<String> = TARGETS
            .iter()
            .map(|t| {
                let (cell, how) = cost_column(s, e, *t);
                format!("{cell} | {how}")
            })
            .collect();
        let _ = writeln!(w, "| `{e}` | {} |", cells.join(" | "));
    }
    let _ = writeln!(w);
}

/// The floors that stop an engine above 1e-4, as error values, per swept problem.
fn floors(w: &mut String, s: &Summary, engines: &[&str]) {
    let cases: Vec<&CaseSummary> = representatives(s)
        .into_iter()
        .filter(|c| {
            engines
                .iter()
                .any(|e| cost_of(c, e, 1e-4).is_some_and(|k| k.reached == Reached::Floor))
        })
        .collect();
    if cases.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "**Floors above 1e-4**: the smallest error over the peak each engine reaches on the \
         problem before refinement stops paying (its cause in [cost.md](cost.md)).\n"
    );
    let names: Vec<String> = engines.iter().map(|e| format!("`{e}`")).collect();
    let _ = writeln!(
        w,
        "| case | {} |\n|---|{}",
        names.join(" | "),
        "---:|".repeat(engines.len())
    );
    for c in cases {
        let cells: Vec<String> = engines
            .iter()
            .map(|e| match cost_of(c, e, 1e-4) {
                Some(k) if k.reached == Reached::Floor => k.error.map_or("–".into(), sci),
                _ => "–".into(),
            })
            .collect();
        let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
    }
    let _ = writeln!(w);
}

/// Where each engine stays stable: per engine, its lowest critical increment over the explicit
/// stable one, how many cases it stays bounded on up to its ceiling, and its own step.
fn stable(w: &mut String, s: &Summary, engines: &[&str]) {
    let any = s
        .cases
        .iter()
        .any(|c| c.runs.iter().any(|r| r.critical_increment.is_some()));
    if !any {
        return;
    }
    let _ = writeln!(
        w,
        "**Stable?** Unstable means energy still growing at the end of a run, confirmed on a \
         horizon 4× longer; a transient that decays is bounded. Ratios are over the explicit \
         engine's computed stable increment; each engine is mapped up to 4× the largest \
         increment it runs at anywhere here, and at least 64× ([stability.md](stability.md)).\n"
    );
    let _ = writeln!(
        w,
        "| engine | cases mapped | bounded at its own step | lowest critical ratio | lowest on | bounded to its ceiling |\n|---|---:|---:|---:|---|---:|"
    );
    let mut failures = Vec::new();
    for e in engines {
        let mine: Vec<(&str, &crate::comparison::summary::CriticalIncrement)> = s
            .cases
            .iter()
            .filter_map(|c| Some((c.id.as_str(), c.run(e)?.critical_increment.as_ref()?)))
            .collect();
        let failed: Vec<(&str, &crate::comparison::summary::StabilityFailure)> = s
            .cases
            .iter()
            .filter_map(|c| Some((c.id.as_str(), c.run(e)?.stability_failure.as_ref()?)))
            .collect();
        if mine.is_empty() && failed.is_empty() {
            continue;
        }
        let own: Vec<bool> = (mine.iter().filter_map(|(_, k)| k.bounded_at_own_step))
            .chain(failed.iter().filter_map(|(_, f)| f.bounded_at_own_step))
            .collect();
        failures.extend(failed.iter().map(|(case, f)| (e, *case, *f)));
        let bisected = mine
            .iter()
            .filter(|(_, k)| k.bound != Bound::AtLeast)
            .min_by(|a, b| a.1.explicit_ratio.total_cmp(&b.1.explicit_ratio));
        let (low, on) = bisected.map_or(("–".to_string(), "–"), |(c, k)| {
            (format!("{:.2}", k.explicit_ratio), *c)
        });
        let ceiling = mine
            .iter()
            .filter(|(_, k)| k.bound == Bound::AtLeast && k.covers_own_step())
            .count();
        let _ = writeln!(
            w,
            "| `{e}` | {} | {} of {} | {low} | {on} | {ceiling} of {} |",
            mine.len() + failed.len(),
            own.iter().filter(|b| **b).count(),
            own.len(),
            mine.len()
        );
    }
    let _ = writeln!(w);
    for (e, case, f) in &failures {
        let _ = writeln!(
            w,
            "- `{e}` on {case}: a map run stopped with an error from {:.2}× (no critical \
             increment; stability.csv has the runs): {}",
            f.lowest_ratio,
            f.error.as_deref().unwrap_or("no reason given")
        );
    }
    if !failures.is_empty() {
        let _ = writeln!(w);
    }
}
