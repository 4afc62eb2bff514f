//! The sweep's files: `sweep.csv` (one row per point of every case: [`COLUMNS`]) and
//! `figures/<case>.work-precision.svg` (error against CPU time, log–log, one path per engine
//! and setting family, the Pareto front, unstable points at the edge, timing whiskers, the
//! case's tolerances).

use crate::comparison::reach::Ended;
use crate::comparison::verdict::cost::{self, CostToAccuracy, Reached};
use crate::comparison::work_precision::{self, COLUMNS, CaseSweep, Row};
#[cfg(feature = "figures")]
use crate::report::format::tick;
use crate::report::format::{csv_finite as number, sci};
#[cfg(feature = "figures")]
use crate::report::palette;
#[cfg(feature = "figures")]
use plotters::prelude::*;
#[cfg(feature = "figures")]
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `out/sweep.csv`.
pub fn csv_path(out: &Path) -> PathBuf {
    out.join("sweep.csv")
}

/// `out/figures/<case>.work-precision.svg`.
pub fn figure_path(out: &Path, case: &str) -> PathBuf {
    out.join("figures")
        .join(format!("{case}.work-precision.svg"))
}

fn optional(x: Option<f64>) -> String {
    x.map_or_else(String::new, number)
}

/// Sweep rows as CSV text (numbers in Rust's shortest round-trip form; an absent or
/// non-finite value is an empty field; a field with a comma quoted).
pub fn csv(rows: &[Row]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(COLUMNS);
    for r in rows {
        let _ = w.write_record([
            r.case.clone(),
            r.engine.clone(),
            r.precision.clone(),
            r.path.clone(),
            r.varied.clone(),
            number(r.increment),
            r.iterations.map_or_else(String::new, |i| i.to_string()),
            optional(r.penalty_stiffness),
            r.steps.to_string(),
            optional(r.error_max),
            optional(r.error_rms),
            number(r.cpu_s_min),
            number(r.cpu_s_median),
            number(r.cpu_s_max),
            r.status.clone(),
        ]);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Read a sweep CSV back (None if it is missing or not one).
pub fn read(path: &Path) -> Option<Vec<Row>> {
    let mut reader = csv::Reader::from_path(path).ok()?;
    if reader.headers().ok()?.iter().ne(COLUMNS) {
        return None;
    }
    let num = |s: &str| -> Option<Option<f64>> {
        if s.is_empty() {
            Some(None)
        } else {
            s.parse::<f64>().ok().map(Some)
        }
    };
    reader
        .records()
        .map(|record| {
            let f = record.ok()?;
            Some(Row {
                case: f[0].to_string(),
                engine: f[1].to_string(),
                precision: f[2].to_string(),
                path: f[3].to_string(),
                varied: f[4].to_string(),
                increment: num(&f[5])??,
                iterations: if f[6].is_empty() {
                    None
                } else {
                    Some(f[6].parse().ok()?)
                },
                penalty_stiffness: num(&f[7])?,
                steps: f[8].parse().ok()?,
                error_max: num(&f[9])?,
                error_rms: num(&f[10])?,
                cpu_s_min: num(&f[11])??,
                cpu_s_median: num(&f[12])??,
                cpu_s_max: num(&f[13])??,
                status: f[14].to_string(),
            })
        })
        .collect()
}

#[cfg(feature = "figures")]
/// Errors below this are drawn at it (round-off).
const ERROR_FLOOR: f64 = 1e-16;

#[cfg(feature = "figures")]
/// The work–precision diagram of one case's sweep; `tolerances` are the case's declared ones
/// (engine → max error over peak). None when no point has both an error and a time.
pub fn render(sweep: &CaseSweep, tolerances: &BTreeMap<String, f64>) -> Option<String> {
    let rows = sweep.rows();
    let ok: Vec<&Row> = rows
        .iter()
        .filter(|r| r.status == "ok" && r.error_max.is_some_and(f64::is_finite))
        .collect();
    if ok.is_empty() {
        return None;
    }
    let errors = ok
        .iter()
        .map(|r| r.error_max.unwrap_or(1.0).max(ERROR_FLOOR));
    let (elo, ehi) = errors.fold((f64::INFINITY, 0.0f64), |(a, b), e| (a.min(e), b.max(e)));
    let tol_hi = tolerances.values().fold(0.0f64, |m, t| m.max(*t));
    let (x0, x1) = (elo / 3.0, (ehi.max(tol_hi) * 3.0).min(1e3));
    let times = rows
        .iter()
        .flat_map(|r| [r.cpu_s_min, r.cpu_s_max])
        .filter(|t| *t > 0.0 && t.is_finite());
    let (tlo, thi) = times.fold((f64::INFINITY, 0.0f64), |(a, b), t| (a.min(t), b.max(t)));
    if !(tlo.is_finite() && thi > 0.0 && x1 > x0) {
        return None;
    }
    let (y0, y1) = (tlo / 2.0, thi * 2.0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1180, 700)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let (title, body) = root.split_vertically(50);
        title
            .titled(
                &format!(
                    "{}: what accuracy costs (each point one setting; whiskers: min–max CPU \
                     time of the repeats)",
                    sweep.case
                ),
                ("sans-serif", 16),
            )
            .ok()?;
        let (panel, legend) = body.split_horizontally(880);
        let mut chart = ChartBuilder::on(&panel)
            .margin(10)
            .x_label_area_size(44)
            .y_label_area_size(80)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .ok()?;
        chart
            .configure_mesh()
            .x_desc("error against the exact solution of the engine's own model (max over peak)")
            .y_desc("CPU seconds per simulated second")
            .x_label_formatter(&|x| tick(*x, 0.0))
            .y_label_formatter(&|y| tick(*y, 0.0))
            .max_light_lines(0)
            .draw()
            .ok()?;
        // Tolerances.
        let mut by_value: BTreeMap<String, Vec<&str>> = BTreeMap::new();
        for (engine, t) in tolerances {
            if palette::engine(engine) != RGBColor(0, 0, 0) {
                by_value.entry(number(*t)).or_default().push(engine);
            }
        }
        for (k, (value, engines)) in by_value.iter().enumerate() {
            let t: f64 = value.parse().unwrap_or(0.0);
            if !(x0..x1).contains(&t) {
                continue;
            }
            let c = palette::engine(engines[0]);
            chart
                .draw_series(LineSeries::new([(t, y0), (t, y1)], c.stroke_width(1)))
                .ok()?;
            chart
                .draw_series([Text::new(
                    format!("tolerance {}", engines.join(", ")),
                    (t / 1.1, y1 / 1.3 / 1.8f64.powi(k as i32)),
                    ("sans-serif", 11)
                        .into_font()
                        .color(&c)
                        .pos(Pos::new(HPos::Right, VPos::Top)),
                )])
                .ok()?;
        }
        // The 1e-4 line and the order-1 and order-2 guides (CPU time ∝ error^(-1/p)).
        let guide = RGBColor(90, 90, 90);
        if (x0..x1).contains(&1e-4) {
            chart
                .draw_series(DashedLineSeries::new(
                    [(1e-4, y0), (1e-4, y1)],
                    4,
                    4,
                    guide.stroke_width(1),
                ))
                .ok()?;
            chart
                .draw_series([Text::new(
                    "1e-4",
                    (1e-4 * 1.1, y0 * 1.3),
                    ("sans-serif", 12).into_font(),
                )])
                .ok()?;
        }
        let anchor = (x1 / 30.0, y0 * 1.5);
        for p in [1.0, 2.0] {
            let at = |x: f64| anchor.1 * (x / anchor.0).powf(-1.0 / p);
            let start = x0.max(anchor.0 * (y1 / anchor.1).powf(-p));
            let xs = (0..=20).map(|i| start * (anchor.0 / start).powf(i as f64 / 20.0));
            chart
                .draw_series(DashedLineSeries::new(
                    xs.map(|x| (x, at(x))),
                    2,
                    5,
                    guide.stroke_width(1),
                ))
                .ok()?;
            chart
                .draw_series([Text::new(
                    format!("order {p}"),
                    (start * 1.2, at(start) / 1.15),
                    ("sans-serif", 12).into_font().color(&guide),
                )])
                .ok()?;
        }
        // Each engine: every setting a faint dot, its own Pareto front a line.
        let mut entries: Vec<(String, RGBColor)> = Vec::new();
        for engine in engines_of(rows.iter()) {
            let mine: Vec<Row> = rows
                .iter()
                .filter(|r| r.engine == engine)
                .cloned()
                .collect();
            if mine.is_empty() {
                continue;
            }
            let c = palette::engine(engine);
            let point = |r: &Row| (r.error_max.unwrap_or(1.0).max(ERROR_FLOOR), r.cpu_s_min);
            let ok: Vec<&Row> = mine
                .iter()
                .filter(|r| r.status == "ok" && r.error_max.is_some())
                .collect();
            chart
                .draw_series(
                    ok.iter()
                        .map(|r| Circle::new(point(r), 3, c.mix(0.35).filled())),
                )
                .ok()?;
            for r in ok.iter().filter(|r| r.cpu_s_max > r.cpu_s_min * 1.001) {
                let (x, y) = point(r);
                chart
                    .draw_series(LineSeries::new([(x, y), (x, r.cpu_s_max)], c.mix(0.5)))
                    .ok()?;
            }
            let front: Vec<(f64, f64)> = work_precision::pareto(&mine)
                .into_iter()
                .map(|i| point(&mine[i]))
                .collect();
            chart
                .draw_series(LineSeries::new(front.iter().copied(), c.stroke_width(2)))
                .ok()?;
            chart
                .draw_series(front.iter().map(|p| Circle::new(*p, 4, c.filled())))
                .ok()?;
            for r in mine.iter().filter(|r| r.status != "ok") {
                let y = r.cpu_s_min.clamp(y0, y1);
                chart
                    .draw_series([Cross::new((x1 / 1.25, y), 5, c.stroke_width(2))])
                    .ok()?;
            }
            entries.push((engine.to_string(), c));
        }
        // Legend, in its own column.
        let font = ("sans-serif", 12).into_font();
        let mut row = 0;
        let mut line = |text: String, c: RGBColor, mark: u8| -> Option<()> {
            let y = 20 + 18 * row;
            row += 1;
            match mark {
                0 => {
                    legend
                        .draw(&PathElement::new([(4, y), (24, y)], c.stroke_width(2)))
                        .ok()?;
                    legend.draw(&Circle::new((14, y), 4, c.filled())).ok()?
                }
                1 => legend
                    .draw(&Circle::new((14, y), 3, c.mix(0.35).filled()))
                    .ok()?,
                _ => legend
                    .draw(&Cross::new((14, y), 5, c.stroke_width(2)))
                    .ok()?,
            }
            legend
                .draw(&Text::new(text, (30, y - 6), font.clone()))
                .ok()?;
            Some(())
        };
        for (label, c) in entries {
            line(format!("{label}: cheapest for its error"), c, 0)?;
        }
        line(
            "other settings (increment, k_p, substeps)".into(),
            RGBColor(0, 0, 0),
            1,
        )?;
        line(
            "unstable or failed (right edge)".into(),
            RGBColor(0, 0, 0),
            2,
        )?;
        line("dashed: order 1 and 2 slopes, 1e-4".into(), WHITE, 1)?;
        root.present().ok()?;
    }
    Some(svg)
}

/// Write `sweep.csv` (the previous file's rows of cases this sweep did not run kept, every
/// row in case order) and each case's work–precision figure into `out` (each file atomically;
/// an interruption checkpoint before each).
#[cfg_attr(not(feature = "figures"), allow(unused_variables))]
pub fn write(
    out: &Path,
    sweeps: &[CaseSweep],
    scenes: &[crate::scene::Scene],
) -> Result<(), crate::report::data::DataError> {
    use crate::report::data::{DataError, write_atomic};
    if sweeps.is_empty() {
        return Ok(());
    }
    crate::interrupt::checkpoint("sweep").map_err(|_| DataError::Interrupted)?;
    let mut rows: Vec<Row> = read(&csv_path(out)).unwrap_or_default();
    rows.retain(|r| !sweeps.iter().any(|s| s.case == r.case));
    rows.extend(sweeps.iter().flat_map(CaseSweep::rows));
    rows.sort_by(|a, b| a.case.cmp(&b.case));
    write_atomic(&csv_path(out), csv(&rows).as_bytes())?;
    #[cfg(feature = "figures")]
    for s in sweeps {
        crate::interrupt::checkpoint("sweep").map_err(|_| DataError::Interrupted)?;
        let tolerances = scenes
            .iter()
            .find(|c| c.id == s.case)
            .map(|c| c.tolerances.clone().into_iter().collect())
            .unwrap_or_default();
        if let Some(svg) = render(s, &tolerances) {
            write_atomic(&figure_path(out, &s.case), svg.as_bytes())?;
        }
    }
    Ok(())
}

/// Plain text for standard output: per case and engine, the observed order, the floor, and
/// the CPU time to reach each of [`work_precision::TARGETS`].
pub fn text(sweeps: &[CaseSweep]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for c in sweeps {
        let rows = c.rows();
        let _ = writeln!(s, "{} ({} points)", c.case, rows.len());
        for f in &c.fits {
            let order = f.observed_order.as_ref().map_or("-".into(), |o| {
                format!(
                    "{:.2} over h {:.2e}..{:.2e} ({} points)",
                    o.value, o.finest, o.coarsest, o.points
                )
            });
            let floor = f.floor.as_ref().map_or("none reached".into(), |f| {
                format!("{:.2e}: {}", f.value, f.cause)
            });
            let reach: Vec<String> = work_precision::TARGETS
                .iter()
                .map(|t| match cost::cheapest(&rows, &f.engine, *t) {
                    cost::Reach::Reached(r) => {
                        format!("{t:.0e}: {:.2e} s/s", r.cpu_s_min)
                    }
                    cost::Reach::NotReached(best) => format!(
                        "{t:.0e}: not reached{}",
                        best.map_or(String::new(), |b| format!(" (best {b:.2e})"))
                    ),
                })
                .collect();
            let _ = writeln!(
                s,
                "  {:<18} order {order}; floor {floor}; {}",
                f.engine,
                reach.join(", ")
            );
        }
    }
    s
}

/// Each case's sweep rows, by case id.
pub type SweepRows = BTreeMap<String, Vec<Row>>;

/// The sweep rows written in `out` (`sweep.csv`), by case.
pub fn read_all(out: &Path) -> SweepRows {
    let mut by_case = SweepRows::new();
    for r in read(&csv_path(out)).unwrap_or_default() {
        by_case.entry(r.case.clone()).or_default().push(r);
    }
    by_case
}

/// The short name of a floor's cause (before any detail in parentheses or after a colon).
pub fn short_cause(cause: &str) -> &str {
    cause.split([':', '(']).next().unwrap_or(cause).trim()
}

/// A time-to-accuracy cell: CPU seconds per simulated second and the setting, or "not
/// reached" with the smallest error attained.
pub fn reach_cell(rows: &[Row], engine: &str, target: f64, setting: bool) -> String {
    match cost::cheapest(rows, engine, target) {
        cost::Reach::Reached(r) if setting => {
            let mut s = format!("{} (h {}", sci(r.cpu_s_min), sci(r.increment));
            if let Some(k) = r.penalty_stiffness {
                s += &format!(", k_p {}", sci(k));
            }
            if let Some(n) = r.iterations {
                s += &format!(", {n} substeps");
            }
            s + ")"
        }
        cost::Reach::Reached(r) => sci(r.cpu_s_min),
        cost::Reach::NotReached(Some(best)) => format!("not reached ({})", sci(best)),
        cost::Reach::NotReached(None) => "–".into(),
    }
}

/// The engines whose runs take a share of the sweep's budget (rapier: a fifth), grouped by
/// the budget they get, as " (`rapier_f64`, `rapier_f32`: 2e5 substeps)"; empty when every
/// engine takes all of it.
fn budget_shares(engines: &[&str], budget: f64) -> String {
    let mut groups: Vec<(String, Vec<String>)> = Vec::new();
    for e in engines {
        let Some(stepping) = crate::run::registry::named(e).and_then(|e| e.stepping()) else {
            continue;
        };
        if stepping.budget_share >= 1.0 {
            continue;
        }
        let unit = if stepping.substeps.is_some() {
            "substeps"
        } else {
            "increments"
        };
        let amount = format!("{:.0e} {unit}", budget * stepping.budget_share);
        match groups.iter_mut().find(|g| g.0 == amount) {
            Some(g) => g.1.push(format!("`{e}`")),
            None => groups.push((amount, vec![format!("`{e}`")])),
        }
    }
    if groups.is_empty() {
        return String::new();
    }
    let parts: Vec<String> = groups
        .iter()
        .map(|(amount, names)| format!("{}: {amount}", names.join(", ")))
        .collect();
    format!(" ({})", parts.join("; "))
}

/// The engines of sweep rows, in the order they first appear (the run's engine order).
fn engines_of<'a>(rows: impl Iterator<Item = &'a Row>) -> Vec<&'a str> {
    crate::report::in_order_met(rows.map(|r| r.engine.as_str()))
}

/// The report's section on what accuracy costs: how the sweep works, then per case and engine
/// the observed order and floor, and the CPU time to 1e-4 of the peak.
pub fn overview(w: &mut String, s: &crate::comparison::summary::Summary, sweeps: &SweepRows) {
    use std::fmt::Write;
    let engines = engines_of(sweeps.values().flatten());
    if engines.is_empty() {
        return;
    }
    let grid = crate::run::sweep::Grid::default();
    let _ = writeln!(
        w,
        "\n## What accuracy costs\n\nEach engine was rerun over a grid of settings (the sweep: \
         `sweep.csv`, one work–precision diagram per case on its page). The time \
         increment goes from 0.9 of the stable one (or the output interval; rapier's default \
         configuration from its 1/60 s) down by √10 per point; the explicit engines do so at each \
         penalty stiffness of 1e2 … 1e6 × the largest spring stiffness, rapier's matched \
         configuration also over 1 … 64 substeps, f32 and f64. A path stops where its error stalls \
         (two points in a row each more than {} of the one before) or where the next point would take more than \
         {:.0e} increments{}. Errors are against the exact solution of \
         the engine's own model, as in the verdicts; CPU time is the running thread's, setup \
         included, per simulated second, the minimum of {} runs (one for points over a tenth of \
         the budget). {}\n",
        grid.stall,
        grid.max_increments,
        budget_shares(&engines, grid.max_increments),
        grid.repeat,
        crate::report::provenance::RAPIER_BUILD
    );
    let _ = writeln!(
        w,
        "**Observed order and floor.** The order is the least-squares slope of log error against \
         log increment over the points above {}× the path's floor (for the explicit engines on \
         contact cases, along the penalty stiffnesses each at 0.9 of its own stable increment, \
         since at one stiffness the compliance floor comes at the first refinement); the floor is \
         where refinement stopped paying, named by what limits it.\n",
        work_precision::FLOOR_MARGIN
    );
    let header: Vec<String> = engines.iter().map(|e| format!("`{e}`")).collect();
    let _ = writeln!(w, "| case | {} |", header.join(" | "));
    let _ = writeln!(w, "|---|{}", "---|".repeat(engines.len()));
    for c in &s.cases {
        if !sweeps.contains_key(&c.id) {
            continue;
        }
        let cells: Vec<String> = engines
            .iter()
            .map(|e| {
                let Some(r) = c.runs.iter().find(|r| r.engine == *e) else {
                    return "–".into();
                };
                let order = r.observed_order.map_or("–".into(), |p| format!("{p:.2}"));
                match &r.floor {
                    Some(f) => format!("{order}; floor {} {}", sci(f.value), short_cause(&f.cause)),
                    None => order,
                }
            })
            .collect();
        let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
    }
    for target in crate::comparison::work_precision::TARGETS {
        let _ = writeln!(
            w,
            "\n**CPU seconds per simulated second to reach {target:.0e} of the peak**: the \
             cheapest run within it (the sweep's, or a run toward it); ≈: extrapolated along the \
             observed order p from the most accurate point, where no run could check it within \
             its budget; floor: where refinement stops paying above it, never extrapolated \
             across; not reached: the smallest error attained.\n"
        );
        let _ = writeln!(w, "| case | {} |", header.join(" | "));
        let _ = writeln!(w, "|---|{}", "---:|".repeat(engines.len()));
        for c in s.cases.iter().filter(|c| sweeps.contains_key(&c.id)) {
            let cells: Vec<String> = engines
                .iter()
                .map(|e| {
                    c.run(e)
                        .and_then(|r| r.cost_to_accuracy.iter().find(|k| k.target == target))
                        .map_or("–".into(), cost_cell)
                })
                .collect();
            let _ = writeln!(w, "| {} | {} |", c.id, cells.join(" | "));
        }
    }
    checks(w, s);
    let _ = writeln!(w);
}

/// A cost to an accuracy as cost.md prints it: CPU seconds per simulated second, measured or
/// (≈) extrapolated, or the floor or smallest error that stops it.
fn cost_cell(c: &CostToAccuracy) -> String {
    match (c.reached, c.cpu_s_per_simulated_s) {
        (Reached::Measured, Some(v)) => sci(v),
        (Reached::Extrapolated, Some(v)) => {
            format!("≈ {} (p {:.2})", sci(v), c.order.unwrap_or(f64::NAN))
        }
        (Reached::AtLeast, Some(v)) => format!(
            "> {} (runs at it: {})",
            sci(v),
            c.error.map_or("–".into(), sci)
        ),
        (Reached::AsEquivalent, _) => format!("as {}", c.cause.as_deref().unwrap_or("–")),
        (Reached::Floor, _) => format!(
            "floor {} ({})",
            c.error.map_or("–".into(), sci),
            short_cause(c.cause.as_deref().unwrap_or(""))
        ),
        _ => c.error.map_or("not reached".into(), |e| {
            format!("not reached ({})", sci(e))
        }),
    }
}

/// The extrapolations checked by runs: predicted against measured.
fn checks(w: &mut String, s: &crate::comparison::summary::Summary) {
    use std::fmt::Write;
    if s.checks.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\n**Extrapolations checked.** Every cost to 1e-2 or 1e-4 the sweep left to an \
         extrapolation, where a run at the increment it predicts takes at most {}× the sweep's \
         budget of increments for one run (about a minute of CPU for rapier's matched \
         configuration), was run there; then, where that missed, at {} of the accuracy along the \
         fitted order, up to {} runs, stopping where the local order over at least a factor {} of \
         increment fell below half the fitted one (the error levels: a floor). A case equivalent \
         to another is checked on that one only (its costs read \"as\" it). CPU: seconds per \
         simulated second.\n",
        crate::comparison::reach::BUDGET,
        crate::comparison::reach::AIM,
        crate::comparison::reach::RUNS,
        crate::comparison::reach::SPAN,
    );
    let _ = writeln!(
        w,
        "| case | engine | to | predicted: increment, CPU (order) | measured at it: error, CPU | further runs: increment, error | outcome |\n|---|---|---:|---|---|---|---|"
    );
    for c in &s.checks {
        let first = c.runs.first();
        let measured = first.map_or("–".into(), |r| {
            format!("{}, {}", r.1.map_or("failed".into(), sci), sci(r.2))
        });
        let further: Vec<String> = c
            .runs
            .iter()
            .skip(1)
            .map(|r| format!("{} s: {}", sci(r.0), r.1.map_or("failed".into(), sci)))
            .collect();
        let _ = writeln!(
            w,
            "| {} | `{}` | {:.0e} | {} s, {} (p {:.2}) | {measured} | {} | {} |",
            c.case,
            c.engine,
            c.target,
            sci(c.predicted_increment),
            sci(c.predicted_cpu),
            c.order,
            if further.is_empty() {
                "–".to_string()
            } else {
                further.join("; ")
            },
            outcome(s, c)
        );
    }
}

/// What a check came to, as the cost it leaves (the verdict's, not the check's own ending).
fn outcome(s: &crate::comparison::summary::Summary, c: &crate::comparison::reach::Check) -> String {
    let cost = s
        .cases
        .iter()
        .find(|k| k.id == c.case)
        .and_then(|k| k.run(&c.engine))
        .and_then(|r| r.cost_to_accuracy.iter().find(|k| k.target == c.target));
    match (cost.map(|k| k.reached), c.ended) {
        (Some(Reached::Measured), _) => "reached: measured".into(),
        (Some(Reached::Floor), _) => "levels off: a floor".into(),
        (Some(Reached::AtLeast), _) => "fell short within the budget: a lower bound".into(),
        (_, Ended::Failed) => "a run failed".into(),
        _ => "–".into(),
    }
}

/// A case section's part on what accuracy costs: the diagram, then per engine the order, the
/// floor, the CPU time to each target and the cheapest setting within the case's tolerance.
pub fn case_part(w: &mut String, c: &crate::comparison::summary::CaseSummary, rows: &[Row]) {
    use std::fmt::Write;
    let _ = write!(
        w,
        "\n**What accuracy costs.** Data: `sweep.csv`, the rows of case `{}`.\n\n{}",
        c.id,
        crate::report::format::figure(
            &format!(
                "{}: work–precision diagram (error against CPU time per simulated second, log–log)",
                c.id
            ),
            &format!("../figures/{}.work-precision.svg", c.id)
        )
    );
    let _ = writeln!(
        w,
        "| engine | observed order (increments) | floor | to 1e-2 | to 1e-4 | to 1e-6 | cheapest within the tolerance |"
    );
    let _ = writeln!(w, "|---|---|---|---:|---:|---:|---|");
    for e in engines_of(rows.iter()) {
        let run = c.runs.iter().find(|r| r.engine == e);
        let order = run
            .and_then(|r| r.order_fit.as_ref())
            .map_or("–".into(), |o| {
                format!(
                    "{:.2} ({} … {}, {} points)",
                    o.value,
                    sci(o.coarsest),
                    sci(o.finest),
                    o.points
                )
            });
        let floor = run
            .and_then(|r| r.floor.as_ref())
            .map_or("none within the budget".into(), |f| {
                format!("{}: {}", sci(f.value), f.cause)
            });
        let within = match run.and_then(|r| r.tolerance) {
            Some(t) => format!("{}: {}", sci(t), reach_cell(rows, e, t, true)),
            None => "no tolerance declared".into(),
        };
        let reach: Vec<String> = work_precision::TARGETS
            .iter()
            .map(|t| reach_cell(rows, e, *t, false))
            .collect();
        let _ = writeln!(
            w,
            "| {e} | {order} | {floor} | {} | {within} |",
            reach.join(" | ")
        );
    }
}
