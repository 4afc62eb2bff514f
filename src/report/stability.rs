//! The stability map's files: `stability.csv` ([`COLUMNS`], one row per run: case, engine,
//! search and ratio, with its growth and each pair's critical increment),
//! `figures/stability-<engine>.svg` (cases × ratio, outcome as colour, the critical increment
//! marked), and the report section that says in words where each engine stays stable. Every
//! outcome and bound is the comparison's ([`crate::comparison::stability`]); this module writes
//! them.

use crate::comparison::stability::{
    BELOW, BISECTION_WIDTH, Bound, CEILING, Critical, LADDER, Map, Point, RATIOS, Search,
};
use crate::comparison::verdict::growth::{
    self as growth_rule, CONFIRM, GROWTH, Growth, Outcome, Verdict,
};
use crate::report::format::{csv_finite as number, sci};
#[cfg(feature = "figures")]
use plotters::prelude::*;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The CSV header. Units: `increment_s`, `energy_peak_t_s`, `critical_increment_s` and
/// `own_step_s` in seconds; `ratio` and `critical_ratio` of the explicit engine's computed
/// stable increment; `continued` in case durations; energies as levels (kinetic + elastic
/// energy over the initial energy plus the work of the loads).
pub const COLUMNS: [&str; 16] = [
    "case",
    "engine",
    "search",
    "ratio",
    "increment_s",
    "continued",
    "outcome",
    "error_max",
    "energy_peak",
    "energy_peak_t_s",
    "energy_end",
    "growth_second_half",
    "critical_increment_s",
    "critical_ratio",
    "critical_bound",
    "own_step_s",
];

/// `out/stability.csv`.
pub fn csv_path(out: &Path) -> PathBuf {
    out.join("stability.csv")
}

/// `out/figures/stability-<engine>.svg`.
pub fn figure_path(out: &Path, engine: &str) -> PathBuf {
    let stem = crate::contract::file_stem(engine);
    out.join("figures").join(format!("stability-{stem}.svg"))
}

fn optional(x: Option<f64>) -> String {
    x.filter(|v| v.is_finite()).map_or_else(String::new, number)
}

/// A map as CSV text: every run in the map's order; every row carries its pair's critical
/// increment (empty where it has none). An absent or non-finite value is an empty field.
pub fn csv(map: &Map) -> String {
    let mut writer = csv::Writer::from_writer(Vec::new());
    let _ = writer.write_record(COLUMNS);
    for p in &map.points {
        let c = map
            .critical
            .iter()
            .find(|c| c.case == p.case && c.engine == p.engine);
        let g = p.growth.as_ref();
        let _ = writer.write_record([
            p.case.clone(),
            p.engine.clone(),
            p.search.name().to_string(),
            number(p.ratio),
            optional(p.increment),
            p.continued.map_or(String::new(), |k| k.to_string()),
            p.outcome.name().to_string(),
            optional(p.error_max),
            optional(g.map(|g| g.peak)),
            optional(g.map(|g| g.peak_time)),
            optional(g.map(|g| g.end)),
            optional(g.map(|g| g.second_half)),
            optional(c.map(|c| c.increment)),
            optional(c.map(Critical::explicit_ratio)),
            c.map_or(String::new(), |c| c.bound.name().to_string()),
            optional(c.map(|c| c.own_step)),
        ]);
    }
    String::from_utf8(writer.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Read `stability.csv` back (None if missing or not one of this layout).
pub fn read(path: &Path) -> Option<Map> {
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
    let mut map = Map::default();
    for record in reader.records() {
        let f = record.ok()?;
        let (case, engine) = (f[0].to_string(), f[1].to_string());
        if let (Some(increment), Some(ratio), Some(bound), Some(own_step)) = (
            num(&f[12])?,
            num(&f[13])?,
            Bound::parse(&f[14]),
            num(&f[15])?,
        ) && !map
            .critical
            .iter()
            .any(|c| c.case == case && c.engine == engine)
        {
            map.critical.push(Critical {
                case: case.clone(),
                engine: engine.clone(),
                increment,
                explicit_stable: increment / ratio,
                bound,
                own_step,
            });
        }
        let growth = match (num(&f[8])?, num(&f[9])?, num(&f[10])?, num(&f[11])?) {
            (Some(peak), Some(peak_time), Some(end), Some(second_half)) => Some(Growth {
                verdict: if f[6] == *"unstable" {
                    Verdict::Growing
                } else {
                    Verdict::Bounded
                },
                peak,
                peak_time,
                end,
                second_half,
            }),
            _ => None,
        };
        map.points.push(Point {
            case,
            engine,
            search: Search::parse(&f[2])?,
            ratio: f[3].parse().ok()?,
            increment: num(&f[4])?,
            continued: f[5].parse().ok(),
            outcome: Outcome::parse(&f[6])?,
            error_max: num(&f[7])?,
            growth,
            message: None,
        });
    }
    Some(map)
}

/// The map found under `out` (empty when there is none).
pub fn read_all(out: &Path) -> Map {
    read(&csv_path(out)).unwrap_or_default()
}

/// The critical increment as the report prints it: seconds, with `≥` or `<` where the search
/// did not bracket it; where a bound "at least" stops short of the engine's own step (its case
/// too short to continue, or a run failed), it says so instead of giving a number.
pub fn critical_cell(c: &Critical) -> String {
    if !c.covers_own_step() {
        return format!("not mapped past {:.3e}", c.increment);
    }
    let prefix = match c.bound {
        Bound::Bisected => "",
        Bound::AtLeast => "≥ ",
        Bound::Below => "< ",
    };
    format!("{prefix}{:.3e}", c.increment)
}

#[cfg(feature = "figures")]
fn colour(o: Outcome) -> RGBColor {
    match o {
        // Okabe–Ito blue, sky blue, yellow and vermillion: apart in lightness as well as hue.
        Outcome::Accurate => RGBColor(0, 114, 178),
        Outcome::Bounded => RGBColor(86, 180, 233),
        Outcome::Inaccurate => RGBColor(240, 228, 66),
        Outcome::Unstable => RGBColor(213, 94, 0),
        Outcome::TooShort => RGBColor(204, 204, 204),
        Outcome::Failed => RGBColor(120, 120, 120),
        Outcome::NotApplicable => RGBColor(236, 239, 241),
    }
}

/// The legend's words for an outcome.
#[cfg(feature = "figures")]
fn legend(o: Outcome) -> &'static str {
    match o {
        Outcome::Accurate => "accurate (bounded, within the case's tolerance)",
        Outcome::Inaccurate => "inaccurate (bounded)",
        Outcome::Bounded => "bounded (no tolerance declared)",
        Outcome::Unstable => "unstable (energy still growing by a decade at the end)",
        Outcome::TooShort => "too short to tell",
        Outcome::Failed => "failed",
        Outcome::NotApplicable => "not applicable",
    }
}

#[cfg(feature = "figures")]
/// Where a ratio falls on the grid's columns: log-linear between the centres of the two grid
/// ratios around it, clamped to the first and last centres.
fn column_x(r: f64, left: u32, width: u32) -> i32 {
    let centre = |j: usize| (left + width * j as u32 + width / 2) as f64;
    let j = RATIOS.iter().rposition(|x| *x <= r).unwrap_or(0);
    let x = match RATIOS.get(j + 1) {
        Some(next) if r >= RATIOS[j] => {
            centre(j) + (r / RATIOS[j]).ln() / (next / RATIOS[j]).ln() * width as f64
        }
        _ => centre(j),
    };
    x.round() as i32
}

/// A figure's columns: the grid's ratios, then the engine's own step and the largest ratio
/// tried beyond the grid (each case's own, printed in its cell).
#[cfg(feature = "figures")]
#[derive(Clone, Copy, PartialEq)]
enum FigureColumn {
    Grid(f64),
    OwnStep,
    Beyond,
}

#[cfg(feature = "figures")]
/// One engine's map: a row per case, a column per grid ratio, then its own step and the
/// furthest run beyond the grid (ratio printed in the cell); the outcome as colour; each row's
/// critical increment marked where it falls on the grid and printed in seconds at its right.
pub fn render(engine: &str, points: &[&Point], critical: &[&Critical]) -> Option<String> {
    let mut cases: Vec<&str> = points.iter().map(|p| p.case.as_str()).collect();
    cases.dedup();
    if cases.is_empty() {
        return None;
    }
    let columns: Vec<FigureColumn> = RATIOS
        .iter()
        .map(|r| FigureColumn::Grid(*r))
        .chain([FigureColumn::OwnStep, FigureColumn::Beyond])
        .collect();
    let cell = (64u32, 22u32);
    let left = 200u32;
    let top = 60u32;
    let legend_height = 110u32;
    let right = 190u32;
    let width = left + cell.0 * columns.len() as u32 + right;
    let height = top + cell.1 * cases.len() as u32 + legend_height;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let font = ("sans-serif", 13).into_font();
        let small = ("sans-serif", 11).into_font();
        let title = ("sans-serif", 16).into_font();
        root.draw(&Text::new(
            format!("Stability map: {engine} (increment = ratio × the explicit stable increment)"),
            (10, 8),
            title,
        ))
        .ok()?;
        for (j, c) in columns.iter().enumerate() {
            let x = (left + cell.0 * j as u32) as i32;
            let label = match c {
                FigureColumn::Grid(r) => format!("{r}×"),
                FigureColumn::OwnStep => "own step".into(),
                FigureColumn::Beyond => "furthest".into(),
            };
            root.draw(&Text::new(label, (x + 8, top as i32 - 20), font.clone()))
                .ok()?;
        }
        for (i, case) in cases.iter().enumerate() {
            let y = (top + cell.1 * i as u32) as i32;
            root.draw(&Text::new(case.to_string(), (8, y + 4), font.clone()))
                .ok()?;
            let mine: Vec<&&Point> = points.iter().filter(|p| p.case == *case).collect();
            for (j, c) in columns.iter().enumerate() {
                let x = (left + cell.0 * j as u32) as i32;
                let p = match c {
                    FigureColumn::Grid(r) => mine
                        .iter()
                        .find(|p| p.search == Search::Grid && p.ratio == *r)
                        .copied(),
                    FigureColumn::OwnStep => {
                        mine.iter().find(|p| p.search == Search::OwnStep).copied()
                    }
                    FigureColumn::Beyond => mine
                        .iter()
                        .filter(|p| p.search == Search::Beyond)
                        .max_by(|a, b| a.ratio.total_cmp(&b.ratio))
                        .copied(),
                };
                let fill = p.map_or(WHITE, |p| colour(p.outcome));
                root.draw(&Rectangle::new(
                    [(x, y), (x + cell.0 as i32 - 2, y + cell.1 as i32 - 2)],
                    fill.filled(),
                ))
                .ok()?;
                if let (Some(p), FigureColumn::OwnStep | FigureColumn::Beyond) = (p, c) {
                    let ink = if p.outcome == Outcome::Accurate {
                        WHITE
                    } else {
                        BLACK
                    };
                    root.draw(&Text::new(
                        format!("{}×", crate::report::format::ratio(p.ratio)),
                        (x + 6, y + 5),
                        small.clone().color(&ink),
                    ))
                    .ok()?;
                }
            }
            if let Some(c) = critical.iter().find(|c| c.case == *case) {
                if c.explicit_ratio() <= RATIOS[RATIOS.len() - 1] {
                    let x = column_x(c.explicit_ratio(), left, cell.0);
                    let (y0, y1) = (y + 2, y + cell.1 as i32 - 4);
                    root.draw(&Polygon::new(
                        vec![(x - 5, y0), (x + 5, y0), (x, y1)],
                        BLACK.filled(),
                    ))
                    .ok()?;
                }
                let text = format!("{} s", critical_cell(c));
                let at = (left + cell.0 * columns.len() as u32 + 8) as i32;
                root.draw(&Text::new(text, (at, y + 4), font.clone()))
                    .ok()?;
            }
        }
        root.draw(&Text::new(
            "critical increment",
            (
                (left + cell.0 * columns.len() as u32 + 8) as i32,
                top as i32 - 20,
            ),
            font.clone(),
        ))
        .ok()?;
        // The stable increment: a line between the last ratio ≤ 1 and the first above.
        if let Some(j) = RATIOS.iter().position(|r| *r > 1.0) {
            let x = (left + cell.0 * j as u32) as i32 - 1;
            root.draw(&PathElement::new(
                vec![
                    (x, top as i32 - 6),
                    (x, (top + cell.1 * cases.len() as u32) as i32),
                ],
                BLACK.stroke_width(2),
            ))
            .ok()?;
        }
        let mut y = (top + cell.1 * cases.len() as u32 + 16) as i32;
        let mut x = 10;
        for o in Outcome::ALL {
            let label = legend(o);
            let w = 30 + 7 * label.chars().count() as i32;
            if x + w > width as i32 {
                x = 10;
                y += 22;
            }
            root.draw(&Rectangle::new(
                [(x, y), (x + 16, y + 14)],
                colour(o).filled(),
            ))
            .ok()?;
            root.draw(&Text::new(label, (x + 22, y + 1), font.clone()))
                .ok()?;
            x += w;
        }
        root.draw(&Text::new(
            format!(
                "black line: the explicit stable increment (ratio 1); ▼: the largest bounded \
                 increment, bisected to {:.0} %, where it falls on the grid",
                (BISECTION_WIDTH - 1.0) * 100.0
            ),
            (10, y + 28),
            font,
        ))
        .ok()?;
        root.present().ok()?;
    }
    Some(svg)
}

/// Write `stability.csv` (keeping the previous file's rows of engines this map did not run)
/// and each engine's figure.
pub fn write(out: &Path, map: &Map) -> Result<(), crate::report::data::DataError> {
    use crate::report::data::{DataError, write_atomic};
    if map.points.is_empty() {
        return Ok(());
    }
    crate::interrupt::checkpoint("stability").map_err(|_| DataError::Interrupted)?;
    let ran = |engine: &str| map.points.iter().any(|p| p.engine == engine);
    let mut all = read_all(out);
    all.points.retain(|p| !ran(&p.engine));
    all.critical.retain(|c| !ran(&c.engine));
    all.points.extend(map.points.iter().cloned());
    all.critical.extend(map.critical.iter().cloned());
    let order = engine_order();
    all.points.sort_by_key(|p| order(&p.engine));
    all.critical.sort_by_key(|c| order(&c.engine));
    write_atomic(&csv_path(out), csv(&all).as_bytes())?;
    #[cfg(feature = "figures")]
    write_figures(out, map)?;
    Ok(())
}

/// A report's engines in order: the registry's in its order, then any other (a user's) in
/// the order met (a stable sort keeps that).
fn engine_order() -> impl Fn(&str) -> usize {
    let known: Vec<String> = crate::run::registry::all()
        .iter()
        .map(|e| e.name().to_string())
        .collect();
    move |e: &str| known.iter().position(|x| x == e).unwrap_or(known.len())
}

/// Maps of disjoint cases (the shards of a partitioned run) as one map in the order one run
/// over all their cases writes: by engine, then by case id, each pair's runs as run.
pub fn merged(maps: Vec<Map>) -> Map {
    let mut all = Map::default();
    for m in maps {
        all.points.extend(m.points);
        all.critical.extend(m.critical);
    }
    let order = engine_order();
    all.points
        .sort_by(|a, b| (order(&a.engine), &a.case).cmp(&(order(&b.engine), &b.case)));
    all.critical
        .sort_by(|a, b| (order(&a.engine), &a.case).cmp(&(order(&b.engine), &b.case)));
    all
}

/// Write a whole map (no previous rows kept): `stability.csv` and each engine's figure.
pub fn write_whole(out: &Path, map: &Map) -> Result<(), crate::report::data::DataError> {
    use crate::report::data::write_atomic;
    if map.points.is_empty() {
        return Ok(());
    }
    write_atomic(&csv_path(out), csv(map).as_bytes())?;
    #[cfg(feature = "figures")]
    write_figures(out, map)?;
    Ok(())
}

/// Each engine's figure of `map`.
#[cfg(feature = "figures")]
fn write_figures(out: &Path, map: &Map) -> Result<(), crate::report::data::DataError> {
    for engine in crate::report::in_order_met(map.points.iter().map(|p| p.engine.as_str())) {
        let mine: Vec<&Point> = map.points.iter().filter(|p| p.engine == engine).collect();
        if mine.is_empty() {
            continue;
        }
        let critical: Vec<&Critical> = map.critical.iter().filter(|c| c.engine == engine).collect();
        if let Some(svg) = render(engine, &mine, &critical) {
            crate::report::data::write_atomic(&figure_path(out, engine), svg.as_bytes())?;
        }
    }
    Ok(())
}

/// The map's runs per engine, in the map's order.
fn by_engine(map: &Map) -> Vec<(&str, Vec<&Point>)> {
    crate::report::in_order_met(map.points.iter().map(|p| p.engine.as_str()))
        .into_iter()
        .map(|e| (e, map.points.iter().filter(|p| p.engine == e).collect()))
        .collect()
}

/// The critical increments, a row per case and a column per engine: seconds, and the ratio to
/// the explicit engine's computed stable increment.
pub fn critical_table(w: &mut String, map: &Map) {
    if map.critical.is_empty() {
        return;
    }
    let engines = crate::report::in_order_met(map.critical.iter().map(|c| c.engine.as_str()));
    let mut cases: Vec<&str> = map.critical.iter().map(|c| c.case.as_str()).collect();
    cases.sort_unstable();
    cases.dedup();
    let _ = writeln!(
        w,
        "\n### The critical increment\n\nPer case and engine, the largest increment at which the \
         run stays bounded, in seconds, and in brackets its ratio to the explicit engine's \
         computed stable increment: between the last bounded and the first unstable run, \
         bisected until the two are within {:.0} % (`search` = `bisection` in `stability.csv`). \
         Where the engine stayed bounded up to its ceiling ({CEILING}× the largest increment it \
         runs at in this report) it is at least that (≥); where it was unstable down to {}×, \
         less than that (<).\n",
        (BISECTION_WIDTH - 1.0) * 100.0,
        BELOW[BELOW.len() - 1],
    );
    let names: Vec<String> = engines.iter().map(|e| format!("`{e}`")).collect();
    let _ = writeln!(w, "| case | {} |", names.join(" | "));
    let _ = writeln!(w, "|---|{}", "---:|".repeat(engines.len()));
    for case in cases {
        let cells: Vec<String> = engines
            .iter()
            .map(|e| {
                map.critical
                    .iter()
                    .find(|c| c.case == case && c.engine == *e)
                    .map_or("–".into(), |c| {
                        format!("{} s ({:.2})", critical_cell(c), c.explicit_ratio())
                    })
            })
            .collect();
        let _ = writeln!(w, "| {case} | {} |", cells.join(" | "));
    }
}

/// The report section: how runs are judged, per engine a summary row, the critical
/// increments, then each engine's map with the runs that came back bounded after a transient.
pub fn overview(w: &mut String, map: &Map) {
    let maps = by_engine(map);
    if maps.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\nEvery stepping engine ran every case that has a stable increment at {} × the explicit \
         engine's computed stable increment (the explicit engines at that ratio of their own, \
         rapier at that ratio of the explicit one's), each increment exactly; at the increment \
         its own job ran at (*own step*); and, where it stayed bounded, on × {LADDER} at a time \
         up to {CEILING}× the largest increment it runs at anywhere in this report (rapier's \
         default configuration: past 1/60 s). A case shorter than {} increments at an \
         increment is continued in time (its last step lengthened, its own rows unchanged).\n",
        RATIOS
            .iter()
            .map(|r| r.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        crate::run::stability::MIN_INCREMENTS,
    );
    let _ = writeln!(
        w,
        "A run is *unstable* when the engine stopped it as such (its state turned non-finite, or \
         its own guard named a growing mode), or when its energy is still growing at the end: \
         cut into {} windows, its largest energy level (kinetic + elastic over the initial \
         energy plus the work of the loads) is in the last one, at least {GROWTH}× the level of \
         the window that ends halfway. Such a run is confirmed on a horizon {CONFIRM}× longer \
         before it is called unstable. A transient that peaks and decays is *bounded*; its peak \
         is reported beside (`energy_peak` in `stability.csv`). A bounded run is *accurate* \
         when its largest error against its own model's exact solution, on the case's own \
         rows, is within the case's tolerance for the engine. A case an engine does not model \
         is *not applicable*; the free spins have no stable increment and are not mapped.\n",
        growth_rule::WINDOWS,
    );
    let _ = writeln!(
        w,
        "| engine | cases it applies to | at its own step: accurate of judged | unstable on the grid (first ratio) | bounded to its ceiling | largest transient of a bounded run: level (case, ratio, time) | failed |\n|---|---:|---:|---|---:|---|---:|"
    );
    for (engine, points) in &maps {
        let _ = writeln!(w, "{}", summary_row(engine, points, map));
    }
    critical_table(w, map);
    let _ = writeln!(w);
    for (engine, _) in &maps {
        let _ = write!(
            w,
            "{}",
            crate::report::format::figure(
                &format!("stability map of {engine}"),
                &format!(
                    "figures/stability-{}.svg",
                    crate::contract::file_stem(engine)
                )
            )
        );
    }
}

/// One engine's row of the overview table.
fn summary_row(engine: &str, points: &[&Point], map: &Map) -> String {
    let mut cases: Vec<&str> = points
        .iter()
        .filter(|p| p.outcome != Outcome::NotApplicable)
        .map(|p| p.case.as_str())
        .collect();
    cases.dedup();
    let own: Vec<&&Point> = points
        .iter()
        .filter(|p| p.search == Search::OwnStep)
        .filter(|p| matches!(p.outcome, Outcome::Accurate | Outcome::Inaccurate))
        .collect();
    let accurate_own = own
        .iter()
        .filter(|p| p.outcome == Outcome::Accurate)
        .count();
    let grid_unstable: Vec<&&Point> = points
        .iter()
        .filter(|p| p.search == Search::Grid && p.outcome == Outcome::Unstable)
        .collect();
    let first = grid_unstable
        .iter()
        .map(|p| p.ratio)
        .reduce(f64::min)
        .map_or("none".to_string(), |r| {
            let mut at: Vec<&str> = grid_unstable.iter().map(|p| p.case.as_str()).collect();
            at.dedup();
            format!("{} cases (from {r}×)", at.len())
        });
    let mine: Vec<&Critical> = map.critical.iter().filter(|c| c.engine == engine).collect();
    let ceiling = mine
        .iter()
        .filter(|c| c.bound == Bound::AtLeast && c.covers_own_step())
        .count();
    let transient = points
        .iter()
        .filter(|p| p.outcome.bounded())
        .filter_map(|p| Some((p.growth?.peak, *p)))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map_or("–".to_string(), |(peak, p)| {
            format!(
                "{} ({}, {}×, t = {} s)",
                sci(peak),
                p.case,
                crate::report::format::ratio(p.ratio),
                p.growth.map_or("–".into(), |g| sci(g.peak_time))
            )
        });
    let failed = points
        .iter()
        .filter(|p| p.outcome == Outcome::Failed)
        .count();
    format!(
        "| `{engine}` | {} | {accurate_own} of {} | {first} | {ceiling} of {} | {transient} | {failed} |",
        cases.len(),
        own.len(),
        mine.len(),
    )
}
