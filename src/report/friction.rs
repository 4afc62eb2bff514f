//! The report's friction section: on every case with friction, when each engine's node moves
//! and comes to rest, where it ends and how far it strays where the exact solution does not
//! move, beside the exact solution read by the same rule ([`crate::comparison::friction`]).

use super::format::{sci, sci_or_dash};
use crate::comparison::friction::{Motion, REST};
use crate::comparison::summary::{CaseSummary, Summary};
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
         *rests* the row from which it stays at rest (– : never, or still moving at the end), \
         *ends* its displacement along its velocity column's direction at the last row, and \
         *strays* the largest motion in the face's plane along a column whose exact solution \
         does not move (creep on a stick, drift off an isotropic slide's line). Penalty \
         friction (`explicit`) sticks elastically, by μN/k. rapier has one coefficient: a \
         pair whose static and kinetic coefficients differ gets the kinetic one \
         (`docs/rapier.md`).\n"
    );
    let _ = writeln!(
        w,
        "| case | engine | moves (s) | exact | rests (s) | exact | ends | exact | strays |"
    );
    let _ = writeln!(w, "|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for c in cases {
        for r in c
            .runs
            .iter()
            .filter(|r| !crate::contract::on_older_release(&r.engine))
        {
            let Some(f) = &r.friction else { continue };
            let _ = writeln!(w, "{}", row(&c.id, &r.engine, &f.engine, &f.exact));
        }
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
