//! The report's friction section: on every case with friction, when each engine's node moves
//! and comes to rest, where it ends and how far it strays where the exact solution does not
//! move, beside the exact solution read by the same rule ([`crate::comparison::friction`]).

use super::format::{sci, sci_or_dash};
use crate::comparison::friction::{FrictionEvents, Motion, REST};
use crate::comparison::summary::{CaseSummary, EngineSummary, Summary};
use std::fmt::Write;

/// Write the section (nothing when no case has friction).
pub fn section(w: &mut String, s: &Summary) {
    let cases: Vec<&CaseSummary> = s
        .cases
        .iter()
        .filter(|c| c.runs.iter().any(|r| r.friction.is_some()))
        .collect();
    if cases.is_empty() {
        return;
    }
    let _ = writeln!(w, "\n## Friction\n");
    let _ = writeln!(
        w,
        "Cases with Coulomb friction, each engine beside the exact solution of its own model \
         (`reference`, exact through every stick and slip; `analytic` for `reference`), both \
         read by one rule: the node is at rest where its speed is at most {REST:e} of the exact \
         solution's peak speed, so each time is an output row's and the exact time read the \
         same way sits in the same row interval. *moves* is the first row it moves at, \
         *settles* the row from which it keeps the exact solution's final speed to the end: \
         at rest, or for a ball the speed it rolls on at (– : not by the end), \
         *ends* its displacement along its velocity column's direction at the last row, and \
         *strays* the largest motion in the face's plane along a column whose exact solution \
         does not move (creep on a stick, drift off an isotropic slide's line). Penalty \
         friction (`explicit`) sticks elastically, by μN/k. rapier has one coefficient and \
         refuses a pair whose static coefficient is above its kinetic one \
         (`docs/rapier.md`).\n"
    );
    let _ = writeln!(
        w,
        "| case | engine | moves (s) | exact | settles (s) | exact | ends | exact | strays |"
    );
    let _ = writeln!(w, "|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (c, r, f) in judged(&cases) {
        let _ = writeln!(w, "{}", row(&c.id, &r.engine, &f.engine, &f.exact));
    }
    events(w, &cases);
    same_answer(w, &cases);
    energy(w, &cases);
}

/// Cases of one dimension whose exact solutions end at the same place (the same slide launched
/// in other directions in the face's plane): each engine's end on each, their spread and its
/// largest stray. An isotropic Coulomb law gives one end and no stray.
fn same_answer(w: &mut String, cases: &[&CaseSummary]) {
    let exact_end = |c: &CaseSummary| {
        c.runs
            .iter()
            .find_map(|r| r.friction.as_ref())
            .map(|f| f.exact.end)
    };
    let mut groups: Vec<Vec<&CaseSummary>> = Vec::new();
    for c in cases.iter().copied() {
        let Some(end) = exact_end(c).filter(|e| *e != 0.0) else {
            continue;
        };
        let same = |g: &Vec<&CaseSummary>| {
            g[0].dimension == c.dimension
                && exact_end(g[0]).is_some_and(|e| (e - end).abs() <= 1e-9 * end.abs())
        };
        match groups.iter_mut().find(|g| same(g)) {
            Some(g) => g.push(c),
            None => groups.push(vec![c]),
        }
    }
    for g in groups.iter().filter(|g| g.len() > 1) {
        let ids: Vec<&str> = g.iter().map(|c| c.id.as_str()).collect();
        let _ = writeln!(
            w,
            "\nThe same exact answer, {} (ends at {}): each engine's end on each, their spread, \
             and its largest stray. An isotropic Coulomb law gives one end and no stray.\n",
            ids.join(", "),
            sci_or_dash(exact_end(g[0]))
        );
        let _ = writeln!(w, "| engine | {} | spread | strays |", ids.join(" | "));
        let _ = writeln!(w, "|---|{}---:|---:|", "---:|".repeat(ids.len()));
        let engines: Vec<&str> = judged(g)
            .iter()
            .map(|(_, r, _)| r.engine.as_str())
            .collect();
        let mut seen = Vec::new();
        for engine in engines {
            if seen.contains(&engine) {
                continue;
            }
            seen.push(engine);
            let motions: Vec<Option<&Motion>> = g
                .iter()
                .map(|c| {
                    let r = c.runs.iter().find(|r| r.engine == engine)?;
                    r.friction.as_ref().map(|f| &f.engine)
                })
                .collect();
            let ends: Vec<f64> = motions.iter().flatten().map(|m| m.end).collect();
            let spread = ends.iter().fold(f64::MIN, |m, x| m.max(*x))
                - ends.iter().fold(f64::MAX, |m, x| m.min(*x));
            let stray = motions
                .iter()
                .flatten()
                .map(|m| m.stray)
                .fold(0.0, f64::max);
            let cells: Vec<String> = motions
                .iter()
                .map(|m| m.map_or("–".into(), |m| format!("{:.9}", m.end)))
                .collect();
            let _ = writeln!(
                w,
                "| `{engine}` | {} | {} | {} |",
                cells.join(" | "),
                sci(spread),
                sci(stray)
            );
        }
    }
}

/// The exact events of each case, as `reference` locates them (by bisection, to its
/// integrator's tolerance): where each stick, slip and reversal of the slip falls.
fn events(w: &mut String, cases: &[&CaseSummary]) {
    let _ = writeln!(
        w,
        "\nThe exact events, as `reference` locates them (by bisection, to its integrator's \
         tolerance): the times the rows above place within an output interval.\n"
    );
    let _ = writeln!(w, "| case | exact events (s) |");
    let _ = writeln!(w, "|---|---|");
    for c in cases {
        let Some(r) = c
            .runs
            .iter()
            .find(|x| x.engine == crate::comparison::FINITE_ROTATION_REFERENCE)
        else {
            continue;
        };
        let mut found: Vec<(f64, String)> = r
            .measures
            .iter()
            .filter_map(|(name, t)| {
                let kind = name.strip_suffix("_time")?;
                let (what, i) = kind.rsplit_once('_')?;
                matches!(what, "stick" | "slip" | "reversal")
                    .then(|| (*t, format!("{what} {i} at {t:.7}")))
            })
            .collect();
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        let listed: Vec<String> = found.into_iter().map(|(_, s)| s).collect();
        let _ = writeln!(w, "| {} | {} |", c.id, listed.join("; "));
    }
}

/// Every case's engines with friction events, older releases left out.
fn judged<'a>(
    cases: &[&'a CaseSummary],
) -> Vec<(&'a CaseSummary, &'a EngineSummary, &'a FrictionEvents)> {
    cases
        .iter()
        .flat_map(|c| c.runs.iter().map(move |r| (*c, r)))
        .filter(|(_, r)| !crate::contract::on_older_release(&r.engine))
        .filter_map(|(c, r)| Some((c, r, r.friction.as_ref()?)))
        .collect()
}

/// The energy table: what friction dissipated against `reference`'s exact
/// `frictional_dissipation`, and the balance left at the end, as an amount and a mean rate.
fn energy(w: &mut String, cases: &[&CaseSummary]) {
    let _ = writeln!(
        w,
        "\nThe energy friction dissipated by the end (`e_frictional`, Abaqus's ALLFD) beside \
         `reference`'s exact `frictional_dissipation`, and the energy balance left at the end \
         (`e_balance`, friction counted), also as a mean rate over the run. rapier reports no \
         dissipation: its `e_frictional` is read from its friction impulses times each contact \
         point's slip over a step, so its balance is its own numerical dissipation, first order \
         in the increment (halving the increment halves it: `docs/rapier.md`, \
         `tests/friction_rapier.rs`).\n"
    );
    let _ = writeln!(
        w,
        "| case | engine | dissipated (J) | exact | balance (J) | balance per second (W) |"
    );
    let _ = writeln!(w, "|---|---|---:|---:|---:|---:|");
    for (c, r, f) in judged(cases) {
        let Some(dissipated) = f.engine.dissipated else {
            continue;
        };
        let exact = c
            .runs
            .iter()
            .find(|x| x.engine == crate::comparison::FINITE_ROTATION_REFERENCE)
            .and_then(|x| x.measures.get("frictional_dissipation").copied());
        let balance = f.engine.balance;
        let _ = writeln!(
            w,
            "| {} | `{}` | {} | {} | {} | {} |",
            c.id,
            r.engine,
            sci(dissipated),
            sci_or_dash(exact),
            sci_or_dash(balance),
            sci_or_dash(balance.map(|b| b / c.duration)),
        );
    }
}

/// One engine's row.
fn row(case: &str, engine: &str, m: &Motion, exact: &Motion) -> String {
    format!(
        "| {case} | `{engine}` | {} | {} | {} | {} | {} | {} | {} |",
        sci_or_dash(m.starts),
        sci_or_dash(exact.starts),
        sci_or_dash(m.rests),
        sci_or_dash(exact.rests),
        sci(m.end),
        sci(exact.end),
        sci(m.stray)
    )
}
