//! The first screen of `REPORT.md`: the user's three questions answered from the run. How
//! close each engine gets (tolerances met, median and worst error), what accuracy costs
//! (CPU time to 1e-2 and 1e-4 of the peak against `explicit`'s), and where it stays stable
//! (the bisected critical increment); then what changed since the previous report.

use super::format::sci;
use super::provenance::Provenance;
use super::regression::Since;
use super::summary::{CaseSummary, EngineSummary, Summary, ToleranceCheck};
use crate::comparison::EXACT_SOLUTIONS;
use crate::comparison::work_precision::{CostToAccuracy, Reached};
use std::fmt::Write;

/// The engine every cost is measured against.
const BASE: &str = "explicit";

/// The accuracies the first screen asks for.
const TARGETS: [f64; 2] = [1e-2, 1e-4];

/// The first screen (about 60 lines); `since`: what changed since the report this run
/// replaces, if there was one.
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
        .map(|(name, t)| format!("{name} {t:.1} s"))
        .collect();
    let _ = writeln!(
        w,
        "{}; {}; {}; {}. The run took {took:.0} s ({}); what was run in full is at the top of \
         [accuracy.md](accuracy.md).\n",
        p.version,
        p.rapier,
        p.machine,
        p.date,
        list.join(", ")
    );
    let engines = judged_engines(s);
    conclusions(w, s, &engines);
    engine_table(w, s, &engines);
    let cases = representatives(s);
    cost_table(w, &cases, &engines);
    critical_table(w, &cases, &engines);
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

/// An engine's worst error against its own model on each case where it has one: (error, case).
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

fn median(sorted: &[f64]) -> Option<f64> {
    match sorted.len() {
        0 => None,
        n if n % 2 == 1 => Some(sorted[n / 2]),
        n => Some((sorted[n / 2 - 1] * sorted[n / 2]).sqrt()),
    }
}

/// A cost at a target on a run.
fn cost(r: &EngineSummary, target: f64) -> Option<&CostToAccuracy> {
    r.cost_to_accuracy.iter().find(|c| c.target == target)
}

/// An engine's CPU time to `target` over `explicit`'s, per case where both have one (measured
/// or extrapolated): (ratio, extrapolated, case).
fn cost_ratios<'a>(s: &'a Summary, engine: &str, target: f64) -> Vec<(f64, bool, &'a str)> {
    let mut out: Vec<(f64, bool, &str)> = s
        .cases
        .iter()
        .filter_map(|c| {
            let mine = cost(c.run(engine)?, target)?;
            let base = cost(c.run(BASE)?, target)?;
            let ratio = mine.cpu_s_per_simulated_s? / base.cpu_s_per_simulated_s?;
            let extrapolated =
                mine.reached == Reached::Extrapolated || base.reached == Reached::Extrapolated;
            Some((ratio, extrapolated, c.id.as_str()))
        })
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// A ratio as the first screen prints it.
fn times(x: f64) -> String {
    if x < 0.1 {
        format!("{x:.1e}")
    } else if x < 10.0 {
        format!("{x:.1}")
    } else if x < 1e3 {
        format!("{x:.0}")
    } else {
        format!("{x:.1e}")
    }
}

/// The median of unsorted values.
fn median_of(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    median(&values)
}

/// Each engine's critical increment over `explicit`'s stable one, per mapped case, smallest
/// first: (ratio, case, bounded up to the largest ratio tried).
fn critical_ratios<'a>(s: &'a Summary, engine: &str) -> Vec<(f64, &'a str, bool)> {
    let mut v: Vec<(f64, &str, bool)> = s
        .cases
        .iter()
        .filter_map(|c| {
            let k = c.run(engine)?.critical_increment.as_ref()?;
            Some((k.explicit_ratio, c.id.as_str(), k.bound == "at_least"))
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// Three to five sentences, each from the tables below: tolerances, what 1e-2 and 1e-4 cost
/// the matched rapier, where `explicit` and rapier stay stable, what no control explains.
fn conclusions(w: &mut String, s: &Summary, engines: &[&str]) {
    let checks = s.tolerance_checks();
    let per: Vec<String> = engines
        .iter()
        .map(|e| {
            let mine: Vec<_> = checks.iter().filter(|c| c.engine == *e).collect();
            format!("`{e}` {}", met_of(&mine))
        })
        .collect();
    let mut lines = vec![format!(
        "**{} of {} cells meet their tolerance** ({}).",
        checks.iter().filter(|c| c.met()).count(),
        checks.len(),
        per.join(", ")
    )];
    let rapier = "rapier_f64";
    let costs: Vec<String> = TARGETS
        .iter()
        .filter_map(|&target| {
            let r = cost_ratios(s, rapier, target);
            let values: Vec<f64> = r.iter().map(|x| x.0).collect();
            let (m, lo, hi) = (median(&values)?, r.first()?, r.last()?);
            // The orders of the cells extrapolated, where any were.
            let orders: Vec<f64> = r
                .iter()
                .filter_map(|(_, _, id)| {
                    let c = s.cases.iter().find(|c| c.id == *id)?;
                    let k = cost(c.run(rapier)?, target)?;
                    (k.reached == Reached::Extrapolated).then_some(k.order?)
                })
                .collect();
            let extrapolated = match (
                orders.iter().copied().reduce(f64::min),
                orders.iter().copied().reduce(f64::max),
            ) {
                (Some(a), Some(b)) => format!(
                    ", {} of them extrapolated along its observed order {a:.2}–{b:.2}",
                    orders.len()
                ),
                _ => String::new(),
            };
            Some(format!(
                "{target:.0e} of the peak {}× (median over {} swept cases, {}× to {}×{extrapolated})",
                times(m),
                r.len(),
                times(lo.0),
                times(hi.0)
            ))
        })
        .collect();
    if !costs.is_empty() {
        lines.push(format!(
            "Against `{BASE}`'s CPU time, `{rapier}` (matched) takes to reach {}.",
            costs.join("; to reach ")
        ));
    }
    let base = critical_ratios(s, BASE);
    if let Some(low) = base.first() {
        let below = base.iter().filter(|x| x.0 < 0.98).count();
        let bounded = format!(
            "`{BASE}` stays bounded up to its computed stable increment (within 2 %) on {} of {} \
             mapped cases",
            base.len() - below,
            base.len()
        );
        lines.push(if below == 0 {
            format!("{bounded} (the lowest limit: {:.2}× on {}).", low.0, low.1)
        } else {
            format!(
                "{bounded} and goes unstable below it on {below}, down to {:.2}× on {}.",
                low.0, low.1
            )
        });
    }
    let rapiers: Vec<(f64, &str, bool)> = engines
        .iter()
        .filter(|e| e.starts_with("rapier"))
        .flat_map(|e| critical_ratios(s, e))
        .collect();
    if !rapiers.is_empty() {
        let bounded = rapiers.iter().filter(|x| x.2).count();
        let low = rapiers
            .iter()
            .filter(|x| !x.2)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        lines.push(format!(
            "rapier stays bounded up to {}× that increment in {bounded} of {} engine–case pairs{}.",
            crate::run::stability::BEYOND.last().copied().unwrap_or(4.0),
            rapiers.len(),
            low.map_or(String::new(), |l| format!(
                " (the lowest limit: {:.0}× on {})",
                l.0, l.1
            ))
        ));
    }
    let unexplained: Vec<String> = s
        .cases
        .iter()
        .flat_map(|c| c.runs.iter().map(move |r| (c, r)))
        .filter(|(_, r)| {
            r.attribution
                .as_ref()
                .is_some_and(|a| a.explaining().is_none())
        })
        .filter(|(_, r)| !crate::contract::on_older_release(&r.engine))
        .map(|(c, r)| format!("{} / `{}`", c.id, r.engine))
        .collect();
    if !unexplained.is_empty() {
        lines.push(format!(
            "{} flagged cells have no control that explains them: {} ([accuracy.md](accuracy.md)).",
            unexplained.len(),
            unexplained.join(", ")
        ));
    }
    let _ = writeln!(w, "{}\n", lines.join(" "));
}

/// How many of an engine's cells meet their tolerance, saying how many have none declared
/// (a user's engine, until its cases declare one).
fn met_of(cells: &[&ToleranceCheck]) -> String {
    let met = cells.iter().filter(|c| c.met()).count();
    let without = cells.iter().filter(|c| c.tolerance.is_none()).count();
    match without {
        0 => format!("{met} of {}", cells.len()),
        n if n == cells.len() => format!("{met} of {n} (none has a tolerance declared)"),
        n => format!(
            "{met} of {} ({n} without a tolerance declared)",
            cells.len()
        ),
    }
}

/// One row per engine: tolerances, errors, cost against `explicit`, stability, flags.
fn engine_table(w: &mut String, s: &Summary, engines: &[&str]) {
    let checks = s.tolerance_checks();
    let _ = writeln!(
        w,
        "| engine | tolerances met | median error | worst error | CPU to 1e-2 / `{BASE}`'s | CPU to 1e-4 / `{BASE}`'s | critical increment / `{BASE}`'s stable | flagged cells by cause |"
    );
    let _ = writeln!(w, "|---|---:|---:|---|---|---|---|---|");
    for e in engines {
        let mine: Vec<_> = checks.iter().filter(|c| c.engine == *e).collect();
        let errs = errors(s, e);
        let values: Vec<f64> = errs.iter().map(|x| x.0).collect();
        let worst = errs
            .last()
            .map_or("–".into(), |(v, c)| format!("{} ({c})", sci(*v)));
        let ratio_cell = |target: f64| {
            let r = cost_ratios(s, e, target);
            let values: Vec<f64> = r.iter().map(|x| x.0).collect();
            match (median(&values), r.first(), r.last()) {
                _ if *e == BASE => median_of(
                    s.cases
                        .iter()
                        .filter_map(|c| cost(c.run(e)?, target)?.cpu_s_per_simulated_s)
                        .collect(),
                )
                .map_or("–".into(), |m| format!("{} s/s (median)", sci(m))),
                (Some(m), Some(lo), Some(hi)) => {
                    let ext = r.iter().filter(|x| x.1).count();
                    let note = if ext > 0 {
                        format!(", {ext} of {} extrapolated", r.len())
                    } else {
                        String::new()
                    };
                    format!("{}× ({}–{}{note})", times(m), times(lo.0), times(hi.0))
                }
                _ => "–".into(),
            }
        };
        let crit = critical_ratios(s, e);
        let crit_cell = match crit.iter().min_by(|a, b| a.0.total_cmp(&b.0)) {
            None => "–".into(),
            Some(low) => {
                let at_least = crit.iter().filter(|x| x.2).count();
                let lowest = if low.2 {
                    format!("≥ {:.0} on all", low.0)
                } else {
                    format!("lowest {:.2} ({})", low.0, low.1)
                };
                if at_least > 0 && !low.2 {
                    format!(
                        "{lowest}; ≥ {:.0} on {at_least} of {}",
                        crate::run::stability::BEYOND.last().copied().unwrap_or(4.0),
                        crit.len()
                    )
                } else {
                    lowest
                }
            }
        };
        let met = met_of(&mine);
        let _ = writeln!(
            w,
            "| `{e}` | {met} | {} | {worst} | {} | {} | {crit_cell} | {} |",
            median(&values).map_or("–".into(), sci),
            ratio_cell(1e-2),
            ratio_cell(1e-4),
            flags(s, e)
        );
    }
    let _ = writeln!(
        w,
        "\nErrors: largest over the compared rows, over the column's peak, worst column, against \
         the exact solution of the engine's own model. CPU: thread seconds per simulated second \
         to the cheapest setting of the sweep within the accuracy, over `{BASE}`'s, median \
         (range) over the swept cases; an engine that the sweep did not take there is \
         extrapolated along its observed order (error ∝ hᵖ, time ∝ 1/h). Critical increment: the \
         largest that stays bounded, bisected to 1 %. Flagged: cells that miss their tolerance or \
         (rapier) are over 10× `{BASE}`'s error, by the control that explains them.\n"
    );
}

/// An engine's flagged cells by cause: "time step 12, unexplained 2".
fn flags(s: &Summary, engine: &str) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for c in &s.cases {
        let Some(a) = c.run(engine).and_then(|r| r.attribution.as_ref()) else {
            continue;
        };
        let label = a.explaining().map_or("unexplained".to_string(), |k| {
            super::verdicts::cause_label(k.kind, engine).to_string()
        });
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

/// The swept cases, one per problem: a case found equivalent to another
/// ([`Summary::equivalences`]) is represented by that one.
fn representatives(s: &Summary) -> Vec<&CaseSummary> {
    s.cases
        .iter()
        .filter(|c| c.runs.iter().any(|r| !r.cost_to_accuracy.is_empty()))
        .filter(|c| !s.equivalences.iter().any(|e| e.case == c.id))
        .collect()
}

/// A cost cell: `explicit`'s in CPU seconds per simulated second, another engine's over it.
fn cost_cell(c: &CaseSummary, engine: &str, target: f64) -> String {
    let Some(mine) = c.run(engine).and_then(|r| cost(r, target)) else {
        return "–".into();
    };
    let base = c
        .run(BASE)
        .and_then(|r| cost(r, target))
        .and_then(|b| b.cpu_s_per_simulated_s);
    let approx = if mine.reached == Reached::Extrapolated {
        "≈ "
    } else {
        ""
    };
    let order = mine.order.map_or(String::new(), |p| format!(" (p {p:.2})"));
    match (mine.cpu_s_per_simulated_s, base) {
        (Some(v), _) if engine == BASE => format!("{approx}{} s/s{order}", sci(v)),
        (Some(v), Some(b)) => format!("{approx}{}×{order}", times(v / b)),
        (Some(v), None) => format!("{approx}{} s/s{order}", sci(v)),
        (None, _) => match mine.reached {
            Reached::Floor => format!(
                "floor {} ({})",
                sci(mine.error.unwrap_or(f64::NAN)),
                super::work_precision::short_cause(mine.cause.as_deref().unwrap_or(""))
            ),
            _ => mine.error.map_or("not reached".into(), |e| {
                format!("not reached ({})", sci(e))
            }),
        },
    }
}

/// Per swept case (one per problem), each engine's CPU time to 1e-4.
fn cost_table(w: &mut String, cases: &[&CaseSummary], engines: &[&str]) {
    if cases.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "**CPU time to 1e-4 of the peak**: `{BASE}`'s in CPU seconds per simulated second, the \
         others' as a multiple of it; ≈: extrapolated along the observed order p; floor: where \
         refinement stopped paying, named ([cost.md](cost.md) has 1e-2 and 1e-6, every case and \
         setting).\n"
    );
    header(w, engines);
    for c in cases {
        let cells: Vec<String> = engines.iter().map(|e| cost_cell(c, e, 1e-4)).collect();
        let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
    }
    let _ = writeln!(w);
}

fn header(w: &mut String, engines: &[&str]) {
    let names: Vec<String> = engines.iter().map(|e| format!("`{e}`")).collect();
    let _ = writeln!(w, "| case | {} |", names.join(" | "));
    let _ = writeln!(w, "|---|{}", "---:|".repeat(engines.len()));
}

/// Per swept case, each engine's critical increment in seconds.
fn critical_table(w: &mut String, cases: &[&CaseSummary], engines: &[&str]) {
    if !cases
        .iter()
        .any(|c| c.runs.iter().any(|r| r.critical_increment.is_some()))
    {
        return;
    }
    let _ = writeln!(
        w,
        "**Largest stable increment**, seconds (the largest that stays bounded, bisected to 1 %; \
         ≥: bounded up to the largest tried; –: a free spin has no stable increment to map; every \
         case in [stability.md](stability.md)).\n"
    );
    header(w, engines);
    for c in cases {
        let cells: Vec<String> = engines
            .iter()
            .map(|e| {
                c.run(e)
                    .and_then(|r| r.critical_increment.as_ref())
                    .map_or("–".into(), |k| {
                        let prefix = match k.bound.as_str() {
                            "at_least" => "≥ ",
                            "below" => "< ",
                            _ => "",
                        };
                        format!("{prefix}{:.3e}", k.seconds)
                    })
            })
            .collect();
        let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
    }
    let _ = writeln!(w);
}
