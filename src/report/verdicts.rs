//! The report's verdicts: how many judged cells meet their tolerance; each cell that misses,
//! and each rapier cell far from `explicit`, with its cause and the control that shows it; the
//! verdict matrix; the model-form gap, apart from every engine's error; and what each engine
//! is held to, and why.

use super::format::sci;
use crate::comparison::attribution::{Attribution, ControlRun};
use crate::comparison::summary::{EngineSummary, Summary, ToleranceCheck};
use crate::comparison::verdict::cause::{Explanation, FLAG_RATIO, Flag, MIN_ORDER};
use crate::comparison::{CLOSED_FORM, EXACT_SOLUTIONS, FINITE_ROTATION_REFERENCE};
use crate::engines::ControlKind;
use crate::run::Status;
use std::collections::BTreeMap;
use std::fmt::Write;

/// What each engine is held to, and why: (engines, reasoning). The values are each case's own
/// (`[tolerances]` in its file); this is the reasoning they follow.
pub const POLICY: [(&str, &str); 3] = [
    (
        "`explicit`, `explicit_small`",
        "From the physics, per case (its file states the figures): the scheme's second order at \
         the case's increment, the penalty contact's compliance (about k/k_p of the peak where the \
         contact stays closed, about v·π√(m/k_p) per impact where it opens and closes), with a \
         margin of two to ten: 1e-4 on the spring systems, 1e-3 on the rigid and smooth stress \
         cases, 1e-2 where contact strikes.",
    ),
    (
        "`rapier_f64`, `rapier_f32` (matched)",
        "A few per cent of the peak (5e-2) on every case: what an engineer accepts of a \
         general-purpose engine as a cross-check when it steps with the explicit engine's \
         increment and converged solver settings (rapier's own regression tests hold a rebound \
         to ±0.05 of the drop).",
    ),
    (
        "`rapier_f64_default`, `rapier_f32_default`",
        "A quarter of the peak (0.25) on every case: what a game accepts at rapier's defaults \
         (1/60 s): the motion recognisably the same, a bounce reaching most of its height, a swing \
         most of its amplitude, a spin staying a spin.",
    ),
];

/// Write the verdicts section.
pub fn section(w: &mut String, s: &Summary) {
    let checks = s.tolerance_checks();
    headline(w, &checks);
    matrix(w, s);
    causes(w, s, &checks);
    invariances(w, s);
    model_form(w, s);
    policy(w, s);
}

/// The count of cells that meet their tolerance, of every cell judged.
fn headline(w: &mut String, checks: &[ToleranceCheck]) {
    let met = checks.iter().filter(|c| c.met()).count();
    // The cells a condition picks, listed after what they have in common.
    let listed = |what: &str, pick: &dyn Fn(&ToleranceCheck) -> bool| {
        let cells: Vec<String> = checks
            .iter()
            .filter(|c| pick(c))
            .map(|c| format!("{} / {}", c.case, c.engine))
            .collect();
        if cells.is_empty() {
            String::new()
        } else {
            format!(" {} cells {what}: {}.", cells.len(), cells.join(", "))
        }
    };
    let missing = listed("have no tolerance declared", &|c| c.tolerance.is_none());
    let unjudged = listed(
        "have no compared column with a peak, so nothing to judge",
        &|c| c.measured.is_none() && c.met.is_none() && c.tolerance.is_some(),
    );
    let _ = writeln!(
        w,
        "## Verdicts\n\n**{met} of {} cells meet their tolerance.** A cell is one engine on one case \
         it applies to: it ran and was compared with the exact solution of its own model over at \
         least one row, or it failed. Each error is the largest over the compared rows, over the \
         peak of its column, worst column; a column whose exact solution is zero over those rows \
         (a held DOF, a contact force before the first impact) has no peak and is shown in its \
         unit in the case's section, never mixed in.{missing}{unjudged}\n",
        checks.len(),
    );
}

/// Each cell that misses its tolerance, then each rapier cell over [`FLAG_RATIO`] × `explicit`'s
/// error, with its cause and controls; then what each cause named means.
fn causes(w: &mut String, s: &Summary, checks: &[ToleranceCheck]) {
    let run = |case: &str, engine: &str| -> Option<&EngineSummary> {
        s.cases
            .iter()
            .find(|c| c.id == case)?
            .runs
            .iter()
            .find(|r| r.engine == engine)
    };
    let misses: Vec<String> = checks
        .iter()
        .filter(|c| c.met == Some(false))
        .filter_map(|c| {
            let r = run(c.case, c.engine)?;
            Some(match (&r.error, &r.attribution) {
                (Some(e), _) => format!(
                    "| {} | {} | {} | tolerance {} | the run did not finish: {e} | – | – |",
                    c.case,
                    c.engine,
                    r.status.name(),
                    c.tolerance.map_or("–".into(), sci)
                ),
                (None, Some(a)) => attribution_row(a, c.baseline),
                (None, None) => format!(
                    "| {} | {} | {} (`{}`) | tolerance {} | no control was run | – | – |",
                    c.case,
                    c.engine,
                    c.measured.map_or("–".into(), sci),
                    c.baseline,
                    c.tolerance.map_or("–".into(), sci)
                ),
            })
        })
        .collect();
    let far: Vec<String> = s
        .cases
        .iter()
        .flat_map(|c| &c.runs)
        .filter_map(|r| Some((r.attribution.as_ref()?, r.baseline.as_deref()?)))
        .filter(|(a, _)| matches!(a.flag, Flag::OverExplicit(_)))
        .filter(|(a, _)| !crate::contract::on_older_release(&a.engine))
        .map(|(a, baseline)| attribution_row(a, baseline))
        .collect();
    if misses.is_empty() && far.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "Each cell below was rerun with one suspected cause varied, something the exact solution \
         does not depend on: the increment, on a ladder of quarters down to the matched \
         increment (the explicit engine's); the penalty stiffness × 16 with the increment / 4; \
         f64 for f32; a contact softness ten times stiffer (the matched configuration's, for \
         rapier's defaults); restitution 0 on contact pairs that start closed and never strike. \
         Where none alone explains it, the others are run again at the ladder's finest \
         increment (combined with the time step). Each is measured against the same exact \
         solution. A cell's *line* is the one it crossed: its tolerance, or {FLAG_RATIO} × \
         `explicit`'s error. The cause is the control that brings the cell under its line (the \
         one with the smallest error; a single control before a combination), or the time step \
         where the ladder's error falls along an order of at least {MIN_ORDER} (with the \
         increment that would reach the line along it); *in part* where the ladder falls and then \
         levels. Otherwise the cell is unexplained, and every control is listed.\n"
    );
    let header = "| case | engine | error (against) | listed for | cause | the control that shows it | other controls |\n|---|---|---:|---|---|---|---|";
    for (title, rows) in [
        ("Cells that miss their tolerance".to_string(), &misses),
        (
            format!("rapier within its tolerance but over {FLAG_RATIO} × `explicit`'s error"),
            &far,
        ),
    ] {
        if !rows.is_empty() {
            let _ = writeln!(
                w,
                "### {title} ({})\n\n{header}\n{}\n",
                rows.len(),
                rows.join("\n")
            );
        }
    }
    let named: Vec<ControlKind> = s
        .cases
        .iter()
        .flat_map(|c| &c.runs)
        .filter(|r| !crate::contract::on_older_release(&r.engine))
        .filter_map(|r| Some(r.attribution.as_ref()?.explaining()?.kind))
        .fold(Vec::new(), |mut v, k| {
            if !v.contains(&k) {
                v.push(k);
            }
            v
        });
    let _ = writeln!(w, "What each cause named means:\n");
    for kind in named {
        let _ = writeln!(w, "- *{}*: {}", cause_label(kind, ""), cause_meaning(kind));
    }
    let _ = writeln!(w);
}

/// The invariance controls: per case and parameter the exact solution ignores, the engines
/// whose verdict depends on it, with their errors at both values.
fn invariances(w: &mut String, s: &Summary) {
    if s.invariances.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "### Parameters the exact solution ignores\n\nWhere a case's exact solution does not \
         depend on a parameter (the restitution of a contact that never strikes; the penalty of \
         a contact that never closes), every judged cell was run again at both of its natural \
         values, against the same exact solution. An engine whose verdict changes with it is \
         named: its verdict on the case rests on a value the physics leaves free. The value the \
         case states is marked (stated). *Exact change*: how far the exact solution itself \
         moved between the two values, over its peak; where it is above round-off the \
         parameter is not ignored after all, and no engine is judged on it.\n"
    );
    let _ = writeln!(
        w,
        "| case | parameter | values | exact change | engines whose verdict depends on it (error at each value) | verdict the same |\n|---|---|---|---:|---|---|"
    );
    for i in &s.invariances {
        let depends: Vec<String> = i
            .engines
            .iter()
            .filter(|p| p.depends())
            .map(|p| {
                let e = |k: usize| p.errors[k].map_or("failed".to_string(), sci);
                let mark = |k: usize| if p.met[k] == Some(true) { "✓" } else { "✗" };
                format!(
                    "`{}` ({} {}, {} {})",
                    p.engine,
                    mark(0),
                    e(0),
                    mark(1),
                    e(1)
                )
            })
            .collect();
        let same: Vec<String> = i
            .engines
            .iter()
            .filter(|p| !p.depends())
            .map(|p| format!("`{}`", p.engine))
            .collect();
        let value = |k: usize| {
            if i.stated == Some(k) {
                format!("{} (stated)", i.values[k])
            } else {
                i.values[k].clone()
            }
        };
        let _ = writeln!(
            w,
            "| {} | {} | {} / {} | {} | {} | {} |",
            i.case,
            i.parameter,
            value(0),
            value(1),
            i.exact_change.map_or("–".into(), sci),
            if depends.is_empty() {
                "none".to_string()
            } else {
                depends.join("; ")
            },
            same.join(", ")
        );
    }
    let _ = writeln!(w);
}

/// One attributed cell as a table row: its error, why it is listed, the cause and every
/// control.
fn attribution_row(a: &Attribution, baseline: &str) -> String {
    let why = match a.flag {
        Flag::MissesTolerance(t) => format!("tolerance {}", sci(t)),
        Flag::OverExplicit(x) if x > 0.0 => {
            format!("{:.0} × `explicit`'s {}", a.error / x, sci(x))
        }
        Flag::OverExplicit(x) => format!("`explicit`'s {}", sci(x)),
    };
    let (cause, shown) = cause_and_control(a);
    let others: Vec<String> = a
        .controls
        .iter()
        .enumerate()
        .filter(|(k, _)| Some(*k) != a.cause.map(|c| c.control))
        .map(|(_, c)| control(c))
        .collect();
    format!(
        "| {} | {} | {} (`{baseline}`) | {why} | {cause} | {shown} | {} |",
        a.case,
        a.engine,
        sci(a.error),
        if others.is_empty() {
            "–".to_string()
        } else {
            others.join("; ")
        }
    )
}

/// A control with its error (or why it failed).
pub fn control(c: &ControlRun) -> String {
    match (c.error, &c.failure) {
        (Some(e), _) => format!("{}: {}", c.change, sci(e)),
        (None, Some(f)) => format!("{}: failed ({f})", c.change),
        (None, None) => format!("{}: –", c.change),
    }
}

/// The cause a cell's controls name (bold; unexplained where none explains it), and the
/// control that shows it with how.
pub fn cause_and_control(a: &Attribution) -> (String, String) {
    let (Some(cause), Some(c)) = (a.cause, a.explaining()) else {
        return ("**unexplained**".to_string(), "–".to_string());
    };
    let name = cause_name(a).unwrap_or_default();
    match cause.explanation {
        Explanation::Under => (format!("**{name}**"), control(c)),
        Explanation::AlongOrder { order, needed } if c.kind == ControlKind::Penalty => (
            format!("**{name}**"),
            format!(
                "{}; the error falls as (1/k_p)^{order:.2}, under the line at k_p ≈ {}",
                control(c),
                sci(needed)
            ),
        ),
        Explanation::AlongOrder { order, needed } => (
            format!("**{name}**"),
            format!(
                "{}; the error falls as h^{order:.2}, under the line at h ≈ {} s",
                control(c),
                sci(needed)
            ),
        ),
        Explanation::InPart { order, level } => (
            format!("**{name}** (the rest unexplained)"),
            format!(
                "{}; the error falls as h^{order:.2} and levels at {}",
                control(c),
                sci(level)
            ),
        ),
    }
}

/// The cause a cell's controls name, short ("time step (rapier's 1/60 s) and model: rapier's
/// soft contact", "time step, in part"); `None`: unexplained.
pub fn cause_name(a: &Attribution) -> Option<String> {
    let cause = a.cause?;
    let c = a.explaining()?;
    let label = cause_label(c.kind, &a.engine);
    Some(match cause.explanation {
        _ if c.combined => format!(
            "{} and {label}",
            cause_label(ControlKind::TimeStep, &a.engine)
        ),
        Explanation::InPart { .. } => format!("{label}, in part"),
        _ => label.to_string(),
    })
}

/// The cause a control's kind names, short, with rapier's setting where it is rapier's.
pub fn cause_label(kind: ControlKind, engine: &str) -> &'static str {
    let engine = crate::contract::release_of(engine).0;
    match kind {
        ControlKind::TimeStep if engine.ends_with("_default") => "time step (rapier's 1/60 s)",
        ControlKind::TimeStep if engine.starts_with("rapier") => "time step (first-order substeps)",
        ControlKind::TimeStep => "time step",
        ControlKind::Penalty => "model: penalty contact",
        ControlKind::Precision => "precision (f32)",
        ControlKind::ContactSoftness => "model: rapier's soft contact",
        ControlKind::Restitution if engine.starts_with("rapier") => {
            "model: rapier's restitution on a resting contact"
        }
        ControlKind::Restitution => "model: restitution on a contact that never strikes",
        ControlKind::ImpulseReading => "reading: rapier 0.34's reported contact impulse",
        ControlKind::Gyroscopic => "setting: rapier 0.34's gyroscopic forces, off by default",
    }
}

/// What a cause means, in the problem's words and rapier's.
pub fn cause_meaning(kind: ControlKind) -> &'static str {
    match kind {
        ControlKind::TimeStep => {
            "the error falls as the increment does: the engine's own discretisation (rapier is \
             first order in its substeps; its default configuration steps 1/60 s)"
        }
        ControlKind::Penalty => {
            "the error falls as the penalty stiffness grows: penalty contact yields by force/k_p \
             and an impact lasts π√(m/k_p), where the exact contact is rigid and instantaneous"
        }
        ControlKind::Precision => "the same run in f64 is within reach: single-precision round-off",
        ControlKind::ContactSoftness => {
            "another `contact_softness` brings the error down: a stiffer one (rapier's positional \
             correction of penetration, a spring–damper of that frequency) where the contact \
             yields; a softer one on rapier 0.34, which puts restitution in every substep's \
             contact constraint, where a stiff contact takes part of the bounce"
        }
        ControlKind::Restitution => {
            "the contact never strikes in the exact solution, so its restitution should not \
             matter; the engine's result depends on it all the same. Rapier cannot rest a \
             contact of restitution above 0: one of 1 is bouncy at every step, and one above 0 \
             whenever its point is new again, its impulse having fallen to zero (`is_bouncy`), \
             so whatever approach is left at the end of a step (round-off in f32, the curvature \
             of a node sliding over a ball) is reflected, and the node hops along the face. The \
             explicit engine's contact dashpot, sized for e < 1, acts whenever the contact is \
             closed, on the gap rate its penalty's compliance leaves, where the exact contact \
             dissipates nothing"
        }
        ControlKind::ImpulseReading => {
            "the same motion, its contact impulse read as n/(n + 1) of what rapier 0.34 reports \
             (n substeps), is within reach: 0.34 adds the previous step's warm-start impulse, one \
             substep's worth, to the step's total (`total_impulse_magnitude`; rapier 0.35.2 \
             changed it to the step's own)"
        }
        ControlKind::Gyroscopic => {
            "the same run with the bodies' gyroscopic torque integrated \
             (`gyroscopic_forces_enabled`) is within reach: rapier 0.34 leaves it out unless a \
             body asks for it, and 0.35 turned it on by default; without it a free body spinning \
             off a principal axis keeps its angular velocity, where the exact one precesses or \
             flips"
        }
    }
}

/// A verdict matrix cell: ✓/✗ and the worst error against the engine's own model.
pub fn verdict_cell(r: &EngineSummary) -> String {
    match (r.status, r.tolerance) {
        (Status::Ok, _) => {}
        (Status::NotApplicable, _) => return "n/a".into(),
        (status, Some(_)) => return format!("✗ {}", status.name()),
        (status, None) => return format!("{} (no tolerance)", status.name()),
    }
    let Some(a) = &r.against_baseline else {
        return "–".into();
    };
    let Some(worst) = a.worst_max else {
        return if a.rows == 0 {
            "no rows compared"
        } else {
            "no column with a peak"
        }
        .into();
    };
    match r.meets_tolerance {
        Some(true) => format!("✓ {}", sci(worst)),
        Some(false) => format!("✗ {}", sci(worst)),
        None => format!("{} (no tolerance)", sci(worst)),
    }
}

/// Cases × judged engines.
fn matrix(w: &mut String, s: &Summary) {
    let engines: Vec<&String> = s
        .engines
        .iter()
        .filter(|e| !EXACT_SOLUTIONS.contains(&e.as_str()))
        .filter(|e| !crate::contract::on_older_release(e))
        .collect();
    let _ = writeln!(
        w,
        "### Every cell\n\nThe engine's worst error against the exact solution of its own model \
         (`explicit_small` against `analytic`, `explicit` and rapier against `reference`), ✓ \
         where it meets the case's tolerance, ✗ where it does not; – where the engine has no \
         exact solution to be compared with there, n/a where it does not apply.\n"
    );
    engine_table_header(w, &engines, "---:|");
    for c in &s.cases {
        let cells: Vec<String> = engines
            .iter()
            .map(|e| match c.runs.iter().find(|r| &&r.engine == e) {
                None => "–".into(),
                Some(r) => verdict_cell(r),
            })
            .collect();
        let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
    }
    let _ = writeln!(w);
}

/// The reference against the closed form, per case: the model-form gap, not an error of any
/// engine.
fn model_form(w: &mut String, s: &Summary) {
    let rows: Vec<String> = s
        .cases
        .iter()
        .filter_map(|c| {
            let r = c
                .runs
                .iter()
                .find(|r| r.engine == FINITE_ROTATION_REFERENCE)?;
            let a = r.against_analytic.as_ref()?;
            let worst = a
                .columns
                .iter()
                .filter(|c| c.relative)
                .max_by(|x, y| x.max.total_cmp(&y.max));
            let cell = match (a.rows, worst) {
                (0, _) => "no rows compared (the closed form is valid at no row)".to_string(),
                (_, Some(col)) => format!("{} (`{}`)", sci(col.max), col.column),
                (_, None) => "no column with a peak".to_string(),
            };
            Some(format!("| {} | {cell} |", c.id))
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "### Model form: the finite-rotation model against the closed form\n\n`reference` (the \
         converged finite-rotation model, rigid contact) against `{CLOSED_FORM}` (the benchmark's \
         small-rotation closed form), largest difference over the column's peak. This is no \
         engine's error: where the two models coincide (the spring systems) it is the \
         reference's own accuracy; where the closed form linearises the rotation it is the gap \
         between the two models, which an engine of either model should show.\n\n| case | \
         `reference` against `{CLOSED_FORM}` |\n|---|---:|\n{}\n",
        rows.join("\n")
    );
}

/// What each engine is held to: the tolerances the cases declare, with the reasoning.
fn policy(w: &mut String, s: &Summary) {
    let mut declared: BTreeMap<&str, BTreeMap<String, usize>> = BTreeMap::new();
    for c in &s.cases {
        for r in &c.runs {
            if let Some(t) = r.tolerance {
                *declared
                    .entry(r.engine.as_str())
                    .or_default()
                    .entry(sci(t))
                    .or_default() += 1;
            }
        }
    }
    let _ = writeln!(
        w,
        "### What each engine is held to\n\n| engines | why |\n|---|---|\n{}\n",
        POLICY
            .iter()
            .map(|(e, why)| format!("| {e} | {why} |"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    let listed: Vec<String> = declared
        .iter()
        .map(|(engine, values)| {
            let v: Vec<String> = values
                .iter()
                .map(|(t, n)| format!("{t} ({n} cases)"))
                .collect();
            format!("`{engine}` {}", v.join(", "))
        })
        .collect();
    let _ = writeln!(w, "Declared in the case files: {}.\n", listed.join("; "));
}

/// The header of a cases × engines table: `case`, then each engine, cells aligned by `align`.
pub(super) fn engine_table_header(w: &mut String, engines: &[&String], align: &str) {
    let names: Vec<String> = engines.iter().map(|e| format!("`{e}`")).collect();
    let _ = writeln!(w, "| case | {} |", names.join(" | "));
    let _ = writeln!(w, "|---|{}", align.repeat(engines.len()));
}
