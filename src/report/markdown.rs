//! `REPORT.md`, rendered from a [`Summary`]: every number in it is one of the summary's.

use super::Timings;
use super::format::{figure, sci, sci_or_dash};
use super::provenance::Provenance;
use super::verdicts::engine_table_header;
use super::work_precision::{self, SweepRows};
use crate::comparison::discrepancy::Order;
use crate::comparison::summary::{CaseSummary, EngineSummary, Summary};
use crate::run::Status;
use std::fmt::Write;

/// The worst column of an engine's comparison against its baseline (the exact solution of its
/// own model): (name, max, rms, end).
fn worst(r: &EngineSummary) -> Option<(&str, f64, f64, f64)> {
    let c = r.against_baseline.as_ref()?;
    let w = c
        .columns
        .iter()
        .filter(|c| c.relative)
        .max_by(|a, b| a.max.total_cmp(&b.max))?;
    Some((w.column.as_str(), w.max, w.rms, w.end))
}

/// The worst max error of an engine against the closed form (model form included).
fn total(r: &EngineSummary) -> Option<f64> {
    r.against_analytic.as_ref().and_then(|c| c.worst_max)
}

/// The report's pages: `REPORT.md` (the first screen and an index), one page per question,
/// one per case.
#[derive(Debug, Clone, Default)]
pub struct Pages {
    /// `REPORT.md`.
    pub report: String,
    /// `accuracy.md`: how close each engine gets, and why where it does not.
    pub accuracy: String,
    /// `cost.md`: what accuracy costs.
    pub cost: String,
    /// `stability.md`: where each engine stays stable.
    pub stability: String,
    /// `cases/<case>.md`, by case id.
    pub cases: Vec<(String, String)>,
}

/// What the report is rendered from besides the summary.
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    /// Wall-clock seconds per case and engine.
    pub timings: &'a Timings,
    /// What was run.
    pub provenance: &'a Provenance,
    /// Each case's sweep rows (the cost of accuracy).
    pub sweeps: &'a SweepRows,
    /// The stability map.
    pub maps: &'a crate::comparison::stability::Map,
    /// Accuracy on request's runs.
    pub requests: &'a [crate::run::on_request::Request],
    /// How long each part of the run took, seconds, in order (empty: not said).
    pub parts: &'a [(&'a str, f64)],
    /// What changed since the report this run replaces, if there was one.
    pub since: Option<&'a super::regression::Since>,
}

/// A page's title and the link back to the first screen.
fn page_head(w: &mut String, title: &str, back: &str) {
    let _ = writeln!(w, "# {title}\n\n[← the report]({back}REPORT.md)\n");
}

/// Render the report's pages.
pub fn render(s: &Summary, inputs: &Inputs) -> Pages {
    let mut pages = Pages::default();
    let mut report = String::new();
    super::first_screen::render(
        &mut report,
        s,
        inputs.provenance,
        inputs.parts,
        inputs.since,
    );
    index(&mut report, s);
    pages.report = report;
    let mut cost = String::new();
    page_head(&mut cost, "What accuracy costs", "");
    work_precision::overview(&mut cost, s, inputs.sweeps);
    crate::report::on_request::overview(&mut cost, inputs.requests);
    pages.cost = cost;
    let mut stability = String::new();
    page_head(&mut stability, "Where each engine stays stable", "");
    crate::report::stability::overview(&mut stability, inputs.maps);
    pages.stability = stability;
    pages.accuracy = accuracy(s, inputs);
    for c in &s.cases {
        let mut page = String::new();
        page_head(&mut page, &c.id, "../");
        case_section(&mut page, c);
        if let Some(rows) = inputs.sweeps.get(&c.id) {
            work_precision::case_part(&mut page, c, rows);
        }
        pages.cases.push((c.id.clone(), page));
    }
    pages
}

/// The rest of `REPORT.md`: where each answer is in full, the data files, and every case.
fn index(w: &mut String, s: &Summary) {
    let _ = writeln!(
        w,
        "## In full\n\n\
         - [How close each engine gets](accuracy.md): every cell's verdict, the causes of the \
         misses with their controls, equivalences, where each discrepancy comes from, contact that \
         opens and closes.\n\
         - [What accuracy costs](cost.md): observed orders and floors, time to each accuracy, \
         accuracy on request.\n\
         - [Where each engine stays stable](stability.md): the stability maps and every critical \
         increment.\n\
         - Data (columns and units in [README.md](README.md)): `results.csv`, `sweep.csv`, \
         `stability.csv`, `on_request.csv`, `summary.json`, `data/<case>/<engine>.csv`.\n"
    );
    if !super::versions::lineages(s).is_empty() {
        let _ = writeln!(
            w,
            "- [Releases side by side](#releases-side-by-side), below the cases: what each older \
             release of rapier gets on every case, and why it differs.\n"
        );
    }
    let checks = s.tolerance_checks();
    let _ = writeln!(w, "| case | what it is | tolerances met |\n|---|---|---:|");
    for c in &s.cases {
        let mine: Vec<_> = checks.iter().filter(|k| k.case == c.id).collect();
        let met = mine.iter().filter(|k| k.met()).count();
        let _ = writeln!(
            w,
            "| [{0}](cases/{0}.md) | {1} | {met} of {2} |",
            c.id,
            c.title,
            mine.len()
        );
    }
}

/// `accuracy.md`: what was run, the verdicts and their causes, and every engine's errors.
fn accuracy(s: &Summary, inputs: &Inputs) -> String {
    let mut o = String::new();
    let w = &mut o;
    page_head(w, "How close each engine gets", "");
    at_a_glance(w, s, inputs.provenance, inputs.parts);
    let timings = inputs.timings;
    let _ = writeln!(
        w,
        "crosscheck runs classic explicit-dynamics verification problems whose exact answer is known \
         and asks of each engine: how close does it get, what does that accuracy cost in time, and \
         does it stay stable. Every number below was measured by the run that wrote this file \
         (`cargo run --release`, {}) and is also in `summary.json` (wall times in `timings.json`); \
         the time histories are in `data/<case>/<engine>.csv`.\n",
        s.generator
    );
    let _ = writeln!(
        w,
        "**Engines.** `analytic`: closed forms: the damped oscillators of the spring systems, and for the \
         rigid-body cases the benchmark's small-rotation model with rigid, persistent contact (exact \
         through the matrix exponential). `explicit`: our central-difference integrator with finite \
         rotation and penalty contact. `explicit_small`: the same integrator with the benchmark's \
         small-rotation idealisation, i.e. the closed form's own model, so what separates it from \
         `analytic` is discretisation and penalty compliance only. `reference`: the converged solution \
         of the finite-rotation model (rigid persistent contact, an 8th-order integrator with error \
         control at a relative tolerance of 1e-12), the exact answer `explicit` and rapier approximate; \
         what separates it from `analytic` is model form (the closed form linearises the rotation), \
         and on the linear spring cases the two are the same solution.\n"
    );
    let _ = writeln!(
        w,
        "**Metrics.** Every engine is judged against the exact solution of its own model (*against*): \
         `explicit` and rapier against `reference` (finite rotation), `explicit_small` against \
         `analytic` (small rotation); where `reference` did not run, the closed form. `reference` \
         against `analytic` is the model-form gap, no engine's error. Per contract column, over the \
         rows where that solution is valid: the largest absolute error divided by the peak of its \
         column (*max*), the RMS error over the same peak (*rms*) and the error at the last row over \
         the peak (*end*); a displacement whose exact solution is zero over those rows (a held DOF, \
         a node friction holds) is divided by the scene's extent instead, so creep and drift are \
         judged; any other column that is zero there is compared in its unit, in the case's section. *vs closed form* is the \
         worst *max* against `analytic`, model form included. *Energy balance*: the largest |kinetic + elastic \
         + dissipated − external work − initial| over the largest of the kinetic + elastic energy, \
         the external work and the energy dissipated. Tolerances \
         are declared per case and engine in `cases/<id>.toml` and apply to the worst *max* against the \
         engine's own model.\n"
    );

    for (title, applicable) in [
        ("Runs that failed or went unstable", true),
        ("Engines that do not apply", false),
    ] {
        let listed: Vec<String> = s
            .cases
            .iter()
            .flat_map(|c| {
                c.runs.iter().filter_map(move |r| {
                    r.error
                        .as_ref()
                        .filter(|_| r.status.applicable() == applicable)
                        .map(|e| format!("- {} / {}: {e}", c.id, r.engine))
                })
            })
            .collect();
        if !listed.is_empty() {
            let _ = writeln!(w, "\n{title}:\n\n{}", listed.join("\n"));
        }
    }

    // Accuracy and cost.
    let _ = writeln!(
        w,
        "\n## Accuracy and cost\n\n{}\n",
        super::provenance::RAPIER_BUILD
    );
    let _ = writeln!(
        w,
        "| case | engine | against | max (column) | rms | end | vs closed form | energy balance | contact margin | dt | steps | k_p | wall [ms] |"
    );
    let _ = writeln!(
        w,
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for c in &s.cases {
        let margin = c.contact.as_ref().map_or("–".into(), |m| sci(m.margin));
        for r in &c.runs {
            let (max, rms, end) = match worst(r) {
                // An exact solution against the other: the model-form gap, no engine's error.
                Some((col, max, rms, end))
                    if crate::comparison::EXACT_SOLUTIONS.contains(&r.engine.as_str()) =>
                {
                    (
                        format!("model form {} ({col})", sci(max)),
                        sci(rms),
                        sci(end),
                    )
                }
                Some((col, max, rms, end)) => (format!("{} ({col})", sci(max)), sci(rms), sci(end)),
                None if r.status == Status::NotApplicable => ("n/a".into(), "–".into(), "–".into()),
                None if r.status != Status::Ok => (r.status.name().into(), "–".into(), "–".into()),
                None => match &r.against_baseline {
                    Some(a) if a.rows == 0 => ("no rows compared".into(), "–".into(), "–".into()),
                    Some(_) => ("no column with a peak".into(), "–".into(), "–".into()),
                    None => ("closed form".into(), "–".into(), "–".into()),
                },
            };
            let against = r.baseline.as_deref().unwrap_or("–");
            let closed = sci_or_dash(total(r));
            let balance = sci_or_dash(r.against_analytic.as_ref().and_then(|a| a.energy_balance));
            let wall = timings
                .get(&c.id)
                .and_then(|t| t.get(&r.engine))
                .map_or("–".into(), |x| format!("{:.1}", x * 1e3));
            let steps = match (r.steps, r.increment) {
                (Some(n), Some(h)) if h > 0.0 => n.to_string(),
                _ => "–".into(),
            };
            let _ = writeln!(
                w,
                "| {} | {} | {against} | {max} | {rms} | {end} | {closed} | {balance} | {margin} | {} | {steps} | {} | {wall} |",
                c.id,
                r.engine,
                sci_or_dash(r.increment.filter(|h| *h > 0.0)),
                sci_or_dash(r.penalty_stiffness)
            );
        }
    }

    cross_check_section(w, s);
    crate::report::contact::section(w, s);
    crate::report::friction::section(w, s);
    o
}

/// The worst error of a named engine's run against its own model's exact solution.
fn error_of(c: &CaseSummary, engine: &str) -> Option<f64> {
    c.runs
        .iter()
        .find(|r| r.engine == engine)
        .and_then(worst)
        .map(|w| w.1)
}

/// The worst error of a named engine's run against the closed form.
fn total_of(c: &CaseSummary, engine: &str) -> Option<f64> {
    c.run(engine).and_then(total)
}

/// rapier (matched, f64) and our explicit engine, each against the converged finite-rotation
/// reference, next to the model-form gap (reference against the closed form), and what that
/// says.
fn cross_check_section(w: &mut String, s: &Summary) {
    let judged_by_reference = |c: &CaseSummary, engine: &str| {
        c.runs
            .iter()
            .any(|r| r.engine == engine && r.baseline.as_deref() == Some("reference"))
    };
    let rows: Vec<_> = s
        .cases
        .iter()
        .filter(|c| judged_by_reference(c, "explicit") && judged_by_reference(c, "rapier_f64"))
        .filter_map(|c| {
            Some((
                c,
                total_of(c, "reference")?,
                error_of(c, "explicit")?,
                error_of(c, "rapier_f64")?,
                Summary::cross(c, "rapier_f64", "explicit")?,
            ))
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(w, "\n## Cross-check: rapier against our engine\n");
    let _ = writeln!(
        w,
        "Both engines simulate finite rotation, so each is measured against `reference`, the converged \
         solution of that model; *model form* is how far that model is from the closed form (which \
         linearises the rotation), a gap neither engine should close. The engine nearer `reference` is the \
         more accurate one; their difference from each other is shown too.\n"
    );
    let _ = writeln!(
        w,
        "| case | model form (reference vs analytic) | explicit vs reference | rapier_f64 vs reference | rapier_f64 vs explicit | reading |"
    );
    let _ = writeln!(w, "|---|---:|---:|---:|---:|---|");
    for (c, model, ex, er, d) in rows {
        let reading = if ex <= er {
            format!(
                "`explicit` is {} times nearer the reference than `rapier_f64`",
                ratio(er, ex)
            )
        } else {
            format!(
                "`rapier_f64` is {} times nearer the reference than `explicit`",
                ratio(ex, er)
            )
        };
        let reading = if model > 10.0 * ex.max(er) {
            format!("{reading}; both are far nearer it than the closed form is (model form)")
        } else {
            reading
        };
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {reading} |",
            c.id,
            sci(model),
            sci(ex),
            sci(er),
            sci_or_dash(d.worst_max)
        );
    }
}

/// `a / b` as the report prints a ratio.
fn ratio(a: f64, b: f64) -> String {
    if b > 0.0 {
        format!("{:.1}", a / b)
    } else {
        "∞".into()
    }
}

/// What a rapier run's own measurements say: energy lost, contact penetration, and how far
/// single precision and default settings move it.
fn engine_notes(c: &CaseSummary, r: &EngineSummary) -> String {
    let mut out = String::new();
    if !r.engine.starts_with("rapier") {
        return out;
    }
    if let Some(e) = r.against_analytic.as_ref().and_then(|a| a.energy_balance) {
        let _ = write!(
            out,
            " Energy balance off by {} of the largest energy (mechanical, work or dissipated)",
            sci(e)
        );
        let undamped = c.family == "springs" && c.id.contains("grounded");
        out.push_str(if undamped {
            " (rapier integrates joint springs implicitly: numerical damping on top of the dashpot's)."
        } else {
            "."
        });
    }
    for (name, v) in &r.measures {
        if let Some(pair) = name.strip_prefix("mean_penetration:") {
            let max = r
                .measures
                .get(&format!("max_penetration:{pair}"))
                .copied()
                .unwrap_or(f64::NAN);
            let gap = r
                .measures
                .get(&format!("max_separation:{pair}"))
                .copied()
                .unwrap_or(0.0);
            let _ = write!(
                out,
                " Contact `{pair}`: mean penetration {}, largest {}",
                sci(*v),
                sci(max)
            );
            if gap > 0.0 {
                let _ = write!(out, "; its largest separation {}", sci(gap));
            }
            out.push('.');
        }
    }
    let shift = |candidate: &str, reference: &str| {
        Summary::cross(c, candidate, reference).and_then(|x| x.worst_max)
    };
    if r.engine == "rapier_f32"
        && let Some(g) = shift("rapier_f32", "rapier_f64")
    {
        let _ = write!(
            out,
            " Single precision moves it by {} of the peak from `rapier_f64`.",
            sci(g)
        );
    }
    if r.engine == "rapier_f64_default"
        && let Some(g) = shift("rapier_f64_default", "rapier_f64")
    {
        let _ = write!(
            out,
            " rapier's defaults (1/60 s, default solver and contact softness) move it by {} of the peak from the matched run.",
            sci(g)
        );
    }
    out
}

fn case_section(w: &mut String, c: &CaseSummary) {
    let _ = writeln!(w, "{} ({}D, {} s).\n", c.title, c.dimension, c.duration);
    let id = &c.id;
    for (alt, file) in [
        ("the scene, drawn from the case file", "sketch.svg"),
        ("every engine's histories", "svg"),
        (
            "each engine's error against its own model, and its energy balance, over time \
             (log scale)",
            "errors.svg",
        ),
    ] {
        let link = figure(&format!("{id}: {alt}"), &format!("../figures/{id}.{file}"));
        let _ = write!(w, "{link}");
    }
    if let Some(m) = &c.contact {
        let validity = match m.valid_until {
            None => {
                "it stays compressive over the whole run, so the closed form is valid throughout"
                    .to_string()
            }
            Some(t) => format!(
                "it turns tensile at t = {}, so rows from there on are marked invalid and not compared",
                sci(t)
            ),
        };
        let _ = writeln!(
            w,
            "Closed form: the contact force starts at {} (the load and the initial motion press face and node \
             together at once); its smallest value is {} of its peak; {validity}. Penalty contacts start at the \
             penetration and rate that carry this force, so the penalty mode is not set ringing.\n",
            sci(m.initial_force),
            sci(m.margin)
        );
    }
    initial_contact_force(w, c);
    on_request(w, c);
    for r in &c.runs {
        let Some((col, max, _, _)) = worst(r) else {
            continue;
        };
        if crate::comparison::EXACT_SOLUTIONS.contains(&r.engine.as_str()) {
            let _ = writeln!(
                w,
                "- `{}` against `{}`: {} of the peak (`{col}`), the model-form gap, no engine's error.",
                r.engine,
                r.baseline.as_deref().unwrap_or("–"),
                sci(max)
            );
            continue;
        }
        // An older release is held to its current release's tolerance (the versions section).
        let (current, release) = crate::contract::release_of(&r.engine);
        let held = release
            .and_then(|_| c.run(current)?.tolerance)
            .map(|t| (t, max <= t));
        let verdict = match (r.tolerance, r.meets_tolerance, held) {
            (Some(t), Some(true), _) => format!("meets its tolerance {}", sci(t)),
            (Some(t), Some(false), _) => format!("**does not meet** its tolerance {}", sci(t)),
            (_, _, Some((t, true))) => format!(
                "within `{current}`'s tolerance {} ([releases side by side](../REPORT.md#releases-side-by-side))",
                sci(t)
            ),
            (_, _, Some((t, false))) => format!(
                "**over** `{current}`'s tolerance {} ([releases side by side](../REPORT.md#releases-side-by-side))",
                sci(t)
            ),
            _ => "has no declared tolerance".into(),
        };
        let over_extent = r
            .against_baseline
            .as_ref()
            .and_then(|a| a.columns.iter().find(|x| x.column == col))
            .is_some_and(|x| x.over_extent);
        let of = if over_extent {
            "of the scene's extent"
        } else {
            "of the peak"
        };
        let _ = writeln!(
            w,
            "- `{}`: worst error {} {of} against `{}` (`{col}`); {verdict}.{}",
            r.engine,
            sci(max),
            r.baseline.as_deref().unwrap_or("–"),
            engine_notes(c, r)
        );
    }
    let small = c
        .runs
        .iter()
        .find(|r| r.engine == "explicit_small")
        .and_then(worst);
    let finite = total_of(c, "explicit");
    if let (Some(gap), Some(small), Some(finite)) = (
        Summary::cross(c, "explicit", "explicit_small").and_then(|g| g.worst_max),
        small,
        finite,
    ) {
        let kind = if gap > 10.0 * small.1 {
            format!(
                "The finite-rotation run differs from the small-rotation one by {} of the peak while the \
                 small-rotation run is within {} of the closed form: the {} gap between `explicit` and \
                 `analytic` is model form (the closed form linearises the rotation), not solver error{}.",
                sci(gap),
                sci(small.1),
                sci(finite),
                match (total_of(c, "reference"), error_of(c, "explicit")) {
                    (Some(model), Some(own)) => format!(
                        "; the converged finite-rotation `reference` is {} from the closed form, and \
                         `explicit` is within {} of it",
                        sci(model),
                        sci(own)
                    ),
                    _ => String::new(),
                }
            )
        } else {
            format!(
                "Finite and small rotation agree to {} of the peak here (no rotation, or too little to matter): \
                 the remaining error is discretisation{}.",
                sci(gap),
                if c.contact.is_some() {
                    " and penalty compliance"
                } else {
                    ""
                }
            )
        };
        let _ = writeln!(w, "\n{kind}");
    }
    budget_table(w, c);
    let _ = writeln!(
        w,
        "\n| engine | against | column | peak | max | rms | end |"
    );
    let _ = writeln!(w, "|---|---|---|---:|---:|---:|---:|");
    for r in &c.runs {
        let against = r.baseline.as_deref().unwrap_or("–");
        if let Some(a) = &r.against_baseline {
            for col in &a.columns {
                // A column without a peak: its errors in its unit.
                let (peak, unit) = if col.over_extent {
                    (
                        format!("0 (over the extent {})", sci(col.peak)),
                        String::new(),
                    )
                } else if col.relative {
                    (sci(col.peak), String::new())
                } else {
                    (
                        format!("0 (errors in {})", col.unit),
                        format!(" {}", col.unit),
                    )
                };
                let _ = writeln!(
                    w,
                    "| {} | {against} | {} | {peak} | {}{unit} | {}{unit} | {}{unit} |",
                    r.engine,
                    col.column,
                    sci(col.max),
                    sci(col.rms),
                    sci(col.end)
                );
            }
        }
    }
}

/// Accuracy on request (`--tolerance`, `[time] tolerance`): per engine that ran on request,
/// the tolerance asked for, the error achieved against its own model, the error it predicted,
/// the increment and penalty stiffness it chose, and what that cost (its increments and its
/// pilots'); a refusal says why.
fn on_request(w: &mut String, c: &CaseSummary) {
    let rows: Vec<String> = c
        .runs
        .iter()
        .filter_map(|r| {
            let eps = *r.measures.get("requested_tolerance")?;
            let achieved = r.against_baseline.as_ref()?.worst_max?;
            let verdict = if crate::comparison::verdict::in_band(achieved, eps) {
                "within [ε/10, ε]"
            } else if achieved > eps {
                "**above ε**"
            } else {
                "below ε/10"
            };
            Some(format!(
                "| {} | {} | {} | {} | {verdict} | {} | {} | {} + {} |",
                r.engine,
                sci(eps),
                sci(achieved),
                sci_or_dash(r.measures.get("predicted_error").copied()),
                sci_or_dash(r.increment),
                sci_or_dash(r.penalty_stiffness),
                r.steps.unwrap_or(0),
                r.counters.get("pilot_increments").copied().unwrap_or(0)
            ))
        })
        .collect();
    // Asked for a tolerance, an engine that declines says why.
    let refused: Vec<String> = c
        .runs
        .iter()
        .filter(|_| c.requested.is_some())
        .filter(|r| r.status == Status::NotApplicable)
        .filter_map(|r| Some(format!("- `{}`: {}", r.engine, r.error.as_ref()?)))
        .collect();
    if rows.is_empty() && refused.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\n**Accuracy on request.** Each engine chose its own increment (and penalty stiffness) \
         for the tolerance ε; achieved is its error against its own model's exact solution, \
         predicted what its error model said; the cost is its increments plus those of its \
         pilot runs.\n"
    );
    if !rows.is_empty() {
        let _ = writeln!(
            w,
            "| engine | ε | achieved | predicted | | h | k_p | increments + pilots |\n|---|---:|---:|---:|---|---:|---:|---:|\n{}",
            rows.join("\n")
        );
    }
    if !refused.is_empty() {
        let _ = writeln!(w, "\n{}", refused.join("\n"));
    }
}

/// The contact force at t = 0, measured apart from the errors (which start at the first
/// increment): each engine's signed error there against its own model, and what rapier's is.
fn initial_contact_force(w: &mut String, c: &CaseSummary) {
    let cells: Vec<String> = c
        .runs
        .iter()
        .filter(|r| r.increment.is_some_and(|h| h > 0.0)) // the stepping engines
        .filter_map(|r| {
            let a = r.against_baseline.as_ref()?;
            let e = a
                .initial_errors
                .values()
                .max_by(|x, y| x.abs().total_cmp(&y.abs()))?;
            Some(format!("`{}` {e:+.2e}", r.engine))
        })
        .collect();
    if cells.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "Contact force at t = 0 (engine − its own model, over the peak; measured apart, the errors below \
         start at the first increment): {}. rapier resolves contact by impulses, so what it reports at \
         t = 0 is its first increment's normal impulse divided by the increment: the force while its soft \
         contact is still building up (at a smaller increment it is lower still, not nearer), not the \
         force of the initial state. From the first output row on it follows the model (see the errors \
         below).\n",
        cells.join(", ")
    );
}

fn order(o: Option<&Order>) -> String {
    match o {
        None => "–".into(),
        Some(Order::Observed(p)) => format!("{p:.2}"),
        Some(Order::Converged) => "converged".into(),
        Some(Order::NotAsymptotic) => "not asymptotic".into(),
    }
}

/// The discrepancy budget of each engine's worst column.
fn budget_table(w: &mut String, c: &CaseSummary) {
    let rows: Vec<_> = c
        .runs
        .iter()
        .filter_map(|r| Some((r, r.dominant_source()?)))
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\nDiscrepancy budget against the closed form, each engine's worst column (largest value over \
         the column's peak; the histories, which add up row by row, are in \
         `data/{}/<engine>.budget.csv`):\n",
        c.id
    );
    let _ = writeln!(
        w,
        "| engine | column | total | model form | time step | penalty | solver | order in h | order in 1/k_p | dominant |"
    );
    let _ = writeln!(w, "|---|---|---:|---:|---:|---:|---:|---:|---:|---|");
    for (r, (b, dominant, _)) in rows {
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.engine,
            b.column,
            sci(b.total),
            sci(b.model_form),
            sci(b.time_step),
            sci(b.penalty),
            sci(b.solver),
            order(Some(&b.time_order)),
            order(b.penalty_order.as_ref()),
            dominant.replace('_', " ")
        );
    }
}

/// One screen: what was run, the verdict matrix, the dominant source of each discrepancy.
fn at_a_glance(w: &mut String, s: &Summary, p: &Provenance, parts: &[(&str, f64)]) {
    let _ = writeln!(
        w,
        "**What was run.** {}; {}; {} (built with `enhanced-determinism`: see *Accuracy and \
         cost*). Machine: {}. Date (UTC): {}. Settings: {}.\n",
        p.version, p.rustc, p.rapier, p.machine, p.date, p.settings
    );
    if !parts.is_empty() {
        let list: Vec<String> = parts
            .iter()
            .map(|(name, t)| format!("{name} {t:.1} s"))
            .collect();
        let _ = writeln!(
            w,
            "**How long each part took** (wall clock, {} threads): {}; then writing this report.\n",
            rayon::current_num_threads(),
            list.join(", ")
        );
    }
    super::verdicts::section(w, s);
    // Every engine but the closed form (which the equivalence table shows first).
    let engines: Vec<&String> = s
        .engines
        .iter()
        .filter(|e| *e != crate::comparison::CLOSED_FORM)
        .collect();
    equivalence_table(w, s, &engines);
    let stepping: Vec<&String> = engines
        .iter()
        .copied()
        .filter(|e| {
            s.cases
                .iter()
                .flat_map(|c| &c.runs)
                .any(|r| &&r.engine == e && r.budget.is_some())
        })
        .collect();
    if stepping.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\n## Where each discrepancy comes from\n\nEach engine's error against the closed form \
         (`analytic`) is split into four parts that add up to it row by row (the discrepancy budget, \
         in each case's section): *model form* (the finite-rotation model against the closed form's \
         linearised one), *time step* (the run against the same engine at h → 0), *penalty* \
         (penalty contact against rigid contact, k_p → ∞) and *solver* (what remains against the \
         engine's own model). Each cell names the largest part of the engine's worst column, with its \
         value over the column's peak, and where that is model form, the largest of the engine's own \
         parts.\n"
    );
    engine_table_header(w, &stepping, "---|");
    for c in &s.cases {
        let cells: Vec<String> = stepping
            .iter()
            .map(|e| {
                c.runs
                    .iter()
                    .find(|r| &&r.engine == e)
                    .and_then(|r| r.dominant_source())
                    .map_or("–".into(), |(col, part, norm)| {
                        let mut cell =
                            format!("{} {} ({})", part.replace('_', " "), sci(norm), col.column);
                        // Behind the model form, what the engine itself contributes.
                        let own = [
                            ("time step", col.time_step),
                            ("penalty", col.penalty),
                            ("solver", col.solver),
                        ]
                        .into_iter()
                        .max_by(|a, b| a.1.total_cmp(&b.1));
                        if let (true, Some((name, v))) = (part == "model_form", own) {
                            let _ = write!(cell, "; own: {name} {}", sci(v));
                        }
                        cell
                    })
            })
            .collect();
        let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
    }
    let mut families: Vec<&str> = s
        .cases
        .iter()
        .filter(|c| c.runs.iter().any(|r| r.budget.is_some()))
        .map(|c| c.family.as_str())
        .collect();
    families.sort_unstable();
    families.dedup();
    for f in families {
        let link = figure(
            &format!("discrepancy budget, {f}: each source's share"),
            &format!("figures/budget-{f}.svg"),
        );
        if !link.is_empty() {
            let _ = writeln!(w, "\n{}", link.trim_end());
        }
    }
    let _ = writeln!(w);
}

/// The equivalence checks: each case against the equivalent case it was found to match, with
/// every engine's measured difference.
fn equivalence_table(w: &mut String, s: &Summary, engines: &[&String]) {
    if s.equivalences.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\n## Equivalence checks\n\nCases that build one problem in different ways (element kinds, a held \
         node, 2D or 3D, lumped or surface masses) must give one answer. Pairs are found, not declared: two \
         cases are equivalent on a column when their closed forms agree there to {} of its peak. Each cell: \
         the largest difference between the two cases' histories over those columns, over the column's \
         peak (a contact force from the first increment on).\n",
        sci(crate::comparison::equivalence::AGREEMENT)
    );
    let closed = crate::comparison::CLOSED_FORM.to_string();
    let mut all: Vec<&String> = vec![&closed];
    all.extend(engines.iter().copied());
    let names: Vec<String> = all.iter().map(|e| format!("`{e}`")).collect();
    let _ = writeln!(
        w,
        "| case = equivalent case | columns | {} |",
        names.join(" | ")
    );
    let _ = writeln!(w, "|---|---|{}", "---:|".repeat(all.len()));
    for e in &s.equivalences {
        let cells: Vec<String> = all
            .iter()
            .map(|engine| e.differences.get(*engine).map_or("–".into(), |d| sci(*d)))
            .collect();
        let _ = writeln!(
            w,
            "| {} = {} | {} | {} |",
            e.case,
            e.same_as,
            e.columns.join(", "),
            cells.join(" | ")
        );
    }
}
