//! The report's contact section: contact that opens and closes, each engine against the
//! event-driven `reference`: the restitution table (first rebound over the drop against e²),
//! when each engine strikes, what each impact does to the energy, and how deep the node goes
//! in. Rendered from the summary's `impacts` entries ([`crate::comparison::contact`]).

use super::format::sci;
use crate::comparison::summary::{CaseSummary, Summary};
use crate::contract::IMPACTS_REPORTED;
use std::fmt::Write;

/// The exact solution the impacts are measured against.
const REFERENCE: &str = "reference";

/// The engines with impacts on a case, in report order, the reference first (an older
/// release's are in the versions section).
fn engines(c: &CaseSummary) -> Vec<&str> {
    c.runs
        .iter()
        .filter(|r| r.impacts.is_some())
        .filter(|r| !crate::contract::on_older_release(&r.engine))
        .map(|r| r.engine.as_str())
        .collect()
}

/// Write the section (nothing when no case has contact that opens and closes).
pub fn section(w: &mut String, s: &Summary) {
    let cases: Vec<&CaseSummary> = s
        .cases
        .iter()
        .filter(|c| c.runs.iter().any(|r| r.impacts.is_some()))
        .collect();
    if cases.is_empty() {
        return;
    }
    let _ = writeln!(w, "\n## Contact that opens and closes\n");
    let _ = writeln!(
        w,
        "Cases whose contact opens and closes on parry shapes, every engine against `reference`, \
         which is exact through each switch: it locates every impact (Newton's restitution law, \
         instantaneous) and every opening (where the contact force reaches zero). Penalty contact \
         takes π√(m/k_p) per impact, so after one it lags the rigid answer by about v·π√(m/k_p): \
         the difference falls like k_p^(-1/2), not 1/k_p (measured in `tests/contact.rs`). \
         Contact forces are compared only before the first impact (the reference's impulses are \
         not forces). Figures: each case's histories in `figures/<case>.svg`.\n"
    );
    // The restitution table.
    let drops = drop_cases(&cases);
    if !drops.is_empty() {
        let names = engines(drops[0]);
        let _ = write!(
            w,
            "Rebound height of the first impact over the drop, against e² (penalty contact: a \
             contact dashpot sized for e; rapier: its `restitution`, the block a fixed body):\n\n{}",
            super::format::figure(
                "first rebound over the drop against e, every engine, over e²",
                "figures/rebound.svg"
            )
        );
        restitution_table(w, &drops, &names);
    }
    // Impact times and energy.
    let _ = writeln!(
        w,
        "First impact: its time (reference) and each engine's, as the difference in increments \
         of that engine (explicit: the first increment with a contact force; rapier: the middle \
         of its first step with a contact impulse, 1/60 s long in the default configuration); \
         impacts counted; the energy change over the first impact (kinetic + elastic − work of \
         the loads, after minus before, over the kinetic energy before: −(1 − e²) for \
         restitution e, 0 for an elastic impact; after is the first row where the contact has \
         let go or, where it comes to rest, the last row before the next impact; the reference \
         keeps no energies, its impacts follow the law exactly), and the same over each of the \
         first impacts (up to the five an engine reports): the one farthest from zero, and \
         over how many impacts; and the deepest penetration \
         at the rows (the largest −gap of the case's `gap` columns: penalty contact lets the \
         node in by about v/ω_p at an impact of speed v, the reference never):\n"
    );
    let _ = writeln!(
        w,
        "| case | engine | impacts | first impact [s] | Δ first [increments] | energy change, first impact | farthest from 0, each impact (over) | deepest penetration [m] |"
    );
    let _ = writeln!(w, "|---|---|---:|---:|---:|---:|---:|---:|");
    for c in &cases {
        let exact = c
            .runs
            .iter()
            .find(|r| r.engine == REFERENCE)
            .and_then(|r| r.impacts.as_ref()?.times.first().copied());
        for r in c.runs.iter() {
            let Some(i) = &r.impacts else { continue };
            let first = i.times.first().copied();
            let shift = match (first, exact, r.increment) {
                (Some(t), Some(x), Some(h)) if h > 0.0 && r.engine != REFERENCE => {
                    format!("{:.1}", (t - x) / h)
                }
                _ => "–".into(),
            };
            let energy = i.energy_change.first().copied().map_or("–".into(), sci);
            let farthest = i
                .energy_change
                .iter()
                .take(IMPACTS_REPORTED)
                .copied()
                .reduce(|a, b| if b.abs() > a.abs() { b } else { a })
                .map_or("–".into(), |x| {
                    format!(
                        "{} ({})",
                        sci(x),
                        i.energy_change.len().min(IMPACTS_REPORTED)
                    )
                });
            let penetration = i.penetration.map_or("–".into(), sci);
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} | {shift} | {energy} | {farthest} | {penetration} |",
                c.id,
                r.engine,
                i.count.map_or(i.times.len().to_string(), |n| n.to_string()),
                first.map_or("–".into(), |t| format!("{t:.6}")),
            );
        }
    }
    let _ = writeln!(w);
}

/// The cases where some engine measured a first rebound (a drop onto a surface).
pub fn drop_cases<'a>(cases: &[&'a CaseSummary]) -> Vec<&'a CaseSummary> {
    cases
        .iter()
        .copied()
        .filter(|c| {
            c.runs
                .iter()
                .any(|r| r.impacts.as_ref().is_some_and(|i| i.rebound.is_some()))
        })
        .collect()
}

/// The restitution table: each drop case's e (the reference's, at its first impact), e², and
/// each of `names`' first rebound over the drop.
pub fn restitution_table(w: &mut String, drops: &[&CaseSummary], names: &[&str]) {
    let _ = writeln!(w, "| case | e | e² | {} |", names.join(" | "));
    let _ = writeln!(w, "|---|---:|---:|{}", "---:|".repeat(names.len()));
    for c in drops {
        // The restitution the reference applied at the first impact: rebound over approach.
        let e = c.run(REFERENCE).and_then(|r| {
            Some(r.measures.get("impact_1_rebound")? / r.measures.get("impact_1_speed")?)
        });
        let cells: Vec<String> = names
            .iter()
            .map(|n| {
                c.runs
                    .iter()
                    .find(|r| r.engine == *n)
                    .and_then(|r| r.impacts.as_ref()?.rebound)
                    // Below the table's resolution, 0 (not −0.0000).
                    .map_or("–".into(), |x| {
                        format!("{:.4}", if x.abs() < 5e-5 { 0.0 } else { x })
                    })
            })
            .collect();
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} |",
            c.id,
            e.map_or("–".into(), |e| format!("{e:.2}")),
            e.map_or("–".into(), |e| format!("{:.4}", e * e)),
            cells.join(" | ")
        );
    }
    let _ = writeln!(w);
}
