//! The stability map's files: `stability.csv` ([`COLUMNS`], one row per run: case, engine
//! and ratio, with each pair's critical increment), `figures/stability-<engine>.svg` (cases ×
//! ratio, outcome as colour, the critical increment marked), and the report section that says
//! in words where each engine stays stable and accurate.

use crate::report::format::csv_finite as number;
use crate::run::stability::{
    BISECTION_WIDTH, Bound, Critical, ENERGY_GROWTH_LIMIT, Map, Outcome, Point, RATIOS,
};
#[cfg(feature = "figures")]
use plotters::prelude::*;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The CSV header. Units: `increment_s` and `critical_increment_s` in seconds; `ratio` of the
/// map's stable increment; `critical_ratio` of the explicit engine's computed one.
pub const COLUMNS: [&str; 11] = [
    "case",
    "engine",
    "search",
    "ratio",
    "increment_s",
    "outcome",
    "error_max",
    "energy_growth",
    "critical_increment_s",
    "critical_ratio",
    "critical_bound",
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

/// A map as CSV text: every grid run (`search` = `grid`), then each pair's runs beyond the
/// grid (`bisection`); every row carries its pair's critical increment (empty where it has
/// none). An absent or non-finite value is an empty field.
pub fn csv(map: &Map) -> String {
    let mut s = COLUMNS.join(",") + "\n";
    let critical_of = |case: &str, engine: &str| {
        map.critical
            .iter()
            .find(|c| c.case == case && c.engine == engine)
    };
    let probes = map.critical.iter().flat_map(|c| c.probes.iter());
    let rows = map
        .points
        .iter()
        .map(|p| ("grid", p))
        .chain(probes.map(|p| ("bisection", p)));
    for (search, p) in rows {
        let c = critical_of(&p.case, &p.engine);
        let fields = [
            p.case.clone(),
            p.engine.clone(),
            search.to_string(),
            number(p.ratio),
            optional(p.increment),
            p.outcome.name().to_string(),
            optional(p.error_max),
            optional(p.energy_growth),
            optional(c.map(|c| c.increment)),
            optional(c.map(Critical::explicit_ratio)),
            c.map_or(String::new(), |c| c.bound.name().to_string()),
        ];
        s += &(fields.join(",") + "\n");
    }
    s
}

/// Read `stability.csv` back (None if missing or not one): the grid runs, and each pair's
/// critical increment (without its probes).
pub fn read(path: &Path) -> Option<Map> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut lines = text.lines();
    if lines.next()? != COLUMNS.join(",") {
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
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        if f.len() != COLUMNS.len() {
            return None;
        }
        let (case, engine) = (f[0].to_string(), f[1].to_string());
        if let (Some(increment), Some(ratio), Some(bound)) =
            (num(f[8])?, num(f[9])?, Bound::parse(f[10]))
            && !map
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
                probes: Vec::new(),
            });
        }
        if f[2] == "grid" {
            map.points.push(Point {
                case,
                engine,
                ratio: f[3].parse().ok()?,
                increment: num(f[4])?,
                outcome: Outcome::parse(f[5])?,
                error_max: num(f[6])?,
                energy_growth: num(f[7])?,
                message: None,
            });
        }
    }
    Some(map)
}

/// The map found under `out` (empty when there is none).
pub fn read_all(out: &Path) -> Map {
    read(&csv_path(out)).unwrap_or_default()
}

/// The critical increment as the report prints it: seconds, with `≥` or `<` where the search
/// did not bracket it.
pub fn critical_cell(c: &Critical) -> String {
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
        // Okabe–Ito blue, yellow and vermillion: apart in lightness as well as hue.
        Outcome::Accurate => RGBColor(0, 114, 178),
        Outcome::Inaccurate => RGBColor(240, 228, 66),
        Outcome::Unstable => RGBColor(213, 94, 0),
        Outcome::Failed => RGBColor(120, 120, 120),
        Outcome::NotApplicable => RGBColor(236, 239, 241),
    }
}

#[cfg(feature = "figures")]
/// Where a ratio falls on the map's columns: log-linear between the centres of the two grid
/// ratios around it, clamped to the first and last centres.
fn column_x(ratios: &[f64], r: f64, left: u32, width: u32) -> i32 {
    let centre = |j: usize| (left + width * j as u32 + width / 2) as f64;
    let j = ratios.iter().rposition(|x| *x <= r).unwrap_or(0);
    let x = match ratios.get(j + 1) {
        Some(next) if r >= ratios[j] => {
            centre(j) + (r / ratios[j]).ln() / (next / ratios[j]).ln() * width as f64
        }
        _ => centre(j),
    };
    x.round() as i32
}

#[cfg(feature = "figures")]
/// One engine's map: a row per case, a column per ratio, the outcome as colour; each row's
/// critical increment (bisected) marked and printed in seconds at its right.
pub fn render(engine: &str, points: &[&Point], critical: &[&Critical]) -> Option<String> {
    let mut cases: Vec<&str> = points.iter().map(|p| p.case.as_str()).collect();
    cases.dedup();
    let mut ratios: Vec<f64> = points.iter().map(|p| p.ratio).collect();
    ratios.sort_by(f64::total_cmp);
    ratios.dedup();
    if cases.is_empty() || ratios.is_empty() {
        return None;
    }
    let cell = (64u32, 22u32);
    let left = 200u32;
    let top = 60u32;
    let legend_height = 70u32;
    let right = 150u32;
    let width = left + cell.0 * ratios.len() as u32 + right;
    let height = top + cell.1 * cases.len() as u32 + legend_height;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let font = ("sans-serif", 13).into_font();
        let title = ("sans-serif", 16).into_font();
        root.draw(&Text::new(
            format!("Stability map: {engine} (increment = ratio × the explicit stable increment)"),
            (10, 8),
            title,
        ))
        .ok()?;
        for (j, r) in ratios.iter().enumerate() {
            let x = (left + cell.0 * j as u32) as i32;
            root.draw(&Text::new(
                format!("{r}×"),
                (x + 16, top as i32 - 20),
                font.clone(),
            ))
            .ok()?;
        }
        for (i, case) in cases.iter().enumerate() {
            let y = (top + cell.1 * i as u32) as i32;
            root.draw(&Text::new(case.to_string(), (8, y + 4), font.clone()))
                .ok()?;
            for (j, r) in ratios.iter().enumerate() {
                let x = (left + cell.0 * j as u32) as i32;
                let outcome = points
                    .iter()
                    .find(|p| p.case == *case && p.ratio == *r)
                    .map(|p| p.outcome);
                let fill = outcome.map_or(WHITE, colour);
                root.draw(&Rectangle::new(
                    [(x, y), (x + cell.0 as i32 - 2, y + cell.1 as i32 - 2)],
                    fill.filled(),
                ))
                .ok()?;
            }
            if let Some(c) = critical.iter().find(|c| c.case == *case) {
                let x = column_x(&ratios, c.explicit_ratio(), left, cell.0);
                let (y0, y1) = (y + 2, y + cell.1 as i32 - 4);
                root.draw(&Polygon::new(
                    vec![(x - 5, y0), (x + 5, y0), (x, y1)],
                    BLACK.filled(),
                ))
                .ok()?;
                let text = format!("{} s", critical_cell(c));
                let at = (left + cell.0 * ratios.len() as u32 + 8) as i32;
                root.draw(&Text::new(text, (at, y + 4), font.clone()))
                    .ok()?;
            }
        }
        root.draw(&Text::new(
            "critical increment",
            (
                (left + cell.0 * ratios.len() as u32 + 8) as i32,
                top as i32 - 20,
            ),
            font.clone(),
        ))
        .ok()?;
        // The stable increment: a line between the last ratio ≤ 1 and the first above.
        if let Some(j) = ratios.iter().position(|r| *r > 1.0) {
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
        let y = (top + cell.1 * cases.len() as u32 + 24) as i32;
        let mut x = 10;
        for o in [
            Outcome::Accurate,
            Outcome::Inaccurate,
            Outcome::Unstable,
            Outcome::Failed,
            Outcome::NotApplicable,
        ] {
            root.draw(&Rectangle::new(
                [(x, y), (x + 16, y + 14)],
                colour(o).filled(),
            ))
            .ok()?;
            let label = match o {
                Outcome::Accurate => "accurate (within the case's tolerance)".to_string(),
                Outcome::Inaccurate => "inaccurate (bounded)".to_string(),
                Outcome::Unstable => {
                    format!("unstable (energy > {ENERGY_GROWTH_LIMIT}× a stable run's reading)")
                }
                Outcome::Failed => "failed".to_string(),
                Outcome::NotApplicable => "not applicable".to_string(),
            };
            root.draw(&Text::new(label.clone(), (x + 22, y + 1), font.clone()))
                .ok()?;
            x += 30 + 7 * label.chars().count() as i32;
        }
        root.draw(&Text::new(
            format!(
                "black line: the explicit stable increment (ratio 1); ▼: the largest bounded \
                 increment, bisected to {:.0} %",
                (BISECTION_WIDTH - 1.0) * 100.0
            ),
            (10, y + 26),
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
    let known: Vec<String> = crate::engines::all()
        .iter()
        .map(|e| e.name().to_string())
        .collect();
    // The registry's engines in its order, then any other (a user's) in the order met.
    let order = |e: &str| known.iter().position(|x| x == e).unwrap_or(known.len());
    all.points.sort_by_key(|p| order(&p.engine));
    all.critical.sort_by_key(|c| order(&c.engine));
    write_atomic(&csv_path(out), csv(&all).as_bytes())?;
    #[cfg(feature = "figures")]
    for engine in crate::report::in_order_met(map.points.iter().map(|p| p.engine.as_str())) {
        let mine: Vec<&Point> = map.points.iter().filter(|p| p.engine == engine).collect();
        if mine.is_empty() {
            continue;
        }
        let critical: Vec<&Critical> = map.critical.iter().filter(|c| c.engine == engine).collect();
        if let Some(svg) = render(engine, &mine, &critical) {
            write_atomic(&figure_path(out, engine), svg.as_bytes())?;
        }
    }
    Ok(())
}

/// The map's runs per engine, in the map's order.
fn by_engine(map: &Map) -> Vec<(&str, Vec<Point>)> {
    crate::report::in_order_met(map.points.iter().map(|p| p.engine.as_str()))
        .into_iter()
        .map(|e| {
            let mine: Vec<Point> = map
                .points
                .iter()
                .filter(|p| p.engine == e)
                .cloned()
                .collect();
            (e, mine)
        })
        .filter(|(_, p)| !p.is_empty())
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
        "\n### The critical increment\n\nPer case and engine, the largest increment at which the run \
         stays bounded, in seconds, and in brackets its ratio to the explicit engine's computed stable \
         increment: between the map's last bounded and first unstable ratio, bisected until the two are \
         within {:.0} % (`search` = `bisection` in `stability.csv`). Where the engine stayed bounded up \
         to {}× it is at least that (≥); where it was unstable down to {}×, less than that (<). A \
         critical increment below 1 for an explicit engine would mean a run went unstable below \
         its computed stable increment.\n",
        (BISECTION_WIDTH - 1.0) * 100.0,
        crate::run::stability::BEYOND.last().copied().unwrap_or(4.0),
        crate::run::stability::BELOW.last().copied().unwrap_or(0.25),
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

/// The report section: per engine, the map and a sentence on where it stays stable; then the
/// critical increments.
pub fn overview(w: &mut String, map: &Map) {
    let maps = by_engine(map);
    if maps.is_empty() {
        return;
    }
    let _ = writeln!(
        w,
        "\n## Where each engine stays stable\n\nEvery stepping engine ran every case at increments of \
         {} × the explicit engine's computed stable increment (`crosscheck stability`; the explicit \
         engines at that ratio of their own, rapier, which has no stable increment, at that ratio of \
         the explicit one's), each increment exactly. A run is *unstable* when the engine stopped it \
         as such or its kinetic plus elastic energy rose above {ENERGY_GROWTH_LIMIT}× what it may hold \
         (its initial energy plus the work of the loads) times what a stable run of the engine's \
         scheme reads at that ratio (central differences: 1/(1 − r²) below 1), *accurate* when its largest error against \
         its own model's exact solution is within the case's tolerance for it (a rapier engine \
         without one takes the case's `rapier_f64` tolerance, any other the tightest the case \
         declares), *inaccurate* when bounded but outside it. Cases without a stable increment \
         (the free spins) are not mapped; a case an engine does not model is *not applicable* \
         (not counted as failed). Data: `stability.csv`.\n",
        RATIOS
            .iter()
            .map(|r| r.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        w,
        "| engine | cases | accurate at 0.25× | accurate at 0.98× | first unstable ratio (cases) | unstable at 1.02× | unstable at 4× | failed |\n|---|---:|---:|---:|---|---:|---:|---:|"
    );
    for (engine, points) in &maps {
        let cases = {
            let mut c: Vec<&str> = points.iter().map(|p| p.case.as_str()).collect();
            c.sort();
            c.dedup();
            c.len()
        };
        let count = |r: f64, o: Outcome| {
            points
                .iter()
                .filter(|p| p.ratio == r && p.outcome == o)
                .count()
        };
        let first_unstable = points
            .iter()
            .filter(|p| p.outcome == Outcome::Unstable)
            .map(|p| p.ratio)
            .reduce(f64::min);
        let _ = writeln!(
            w,
            "| `{engine}` | {cases} | {} | {} | {} | {} | {} | {} |",
            count(0.25, Outcome::Accurate),
            count(0.98, Outcome::Accurate),
            first_unstable.map_or("not up to 4×".to_string(), |r| format!(
                "{r}× ({})",
                count(r, Outcome::Unstable)
            )),
            count(1.02, Outcome::Unstable),
            count(4.0, Outcome::Unstable),
            points
                .iter()
                .filter(|p| p.outcome == Outcome::Failed)
                .count(),
        );
    }
    critical_table(w, map);
    let _ = writeln!(w);
    for (engine, points) in &maps {
        let _ = writeln!(
            w,
            "**`{engine}`.** {}{}\n",
            words(engine, points),
            beyond_the_grid(map, engine)
        );
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

/// Where an engine bounded on the whole grid went unstable beyond it, with the matched
/// configuration at the same increments as the control (a default configuration differs from
/// it in its solver settings only).
fn beyond_the_grid(map: &Map, engine: &str) -> String {
    let last = RATIOS.last().copied().unwrap_or(4.0);
    let above: Vec<&Critical> = map
        .critical
        .iter()
        .filter(|c| c.engine == engine && c.bound == Bound::Bisected)
        .filter(|c| c.explicit_ratio() > last)
        .collect();
    if above.is_empty() {
        return String::new();
    }
    let cases: Vec<String> = above
        .iter()
        .map(|c| format!("{} ({:.1}×)", c.case, c.explicit_ratio()))
        .collect();
    let matched = engine.replace("_default", "");
    let control = if matched != engine
        && above.iter().all(|c| {
            map.critical
                .iter()
                .any(|m| m.engine == matched && m.case == c.case && m.bound == Bound::AtLeast)
        }) {
        format!(
            " At the same increments `{matched}` (the matched configuration: the same engine \
             with converged solver settings) stays bounded up to {}× on every one of them, so \
             what goes unstable is rapier's default solver configuration at that increment, \
             not the scene.",
            crate::run::stability::BEYOND
                .last()
                .copied()
                .unwrap_or(last)
        )
    } else {
        String::new()
    };
    format!(
        " Beyond the grid it goes unstable on {} of its cases, at these critical increments \
         (over the explicit stable increment): {}.{control}",
        above.len(),
        cases.join(", ")
    )
}

/// The map in plain words.
fn words(engine: &str, points: &[Point]) -> String {
    let at = |r: f64| -> Vec<&Point> { points.iter().filter(|p| p.ratio == r).collect() };
    let share = |r: f64, o: Outcome| {
        let all = at(r);
        format!(
            "{} of {}",
            all.iter().filter(|p| p.outcome == o).count(),
            all.len()
        )
    };
    let below: Vec<&Point> = points
        .iter()
        .filter(|p| p.ratio < 1.0 && p.outcome == Outcome::Unstable)
        .collect();
    let stable_below = below.len();
    let mut below_cases: Vec<&str> = below.iter().map(|p| p.case.as_str()).collect();
    below_cases.dedup();

    let explicit = engine.starts_with("explicit");
    let mut s = String::new();
    let mut refused: Vec<&str> = points
        .iter()
        .filter(|p| p.outcome == Outcome::NotApplicable)
        .map(|p| p.case.as_str())
        .collect();
    refused.dedup();
    if explicit {
        let _ = write!(
            s,
            "Below its stable increment it ran {} unstable runs{}; at 0.98× {} cases were accurate; at \
             1.02× {} were unstable (stopped with the growing mode named), at 1.1× {}.",
            stable_below,
            if below.is_empty() {
                String::new()
            } else {
                format!(
                    " ({}): no mode grows below the limit; what stops these runs is a penalty \
                     impact (each run's message names it: `crosscheck run CASE \
                     --increment-ratio R`): a contact mode with ω·h above √2 resolves an impact \
                     in about one increment and can send the node back faster than it struck \
                     (up to ((ω·h)² − 1) times), which the energy criterion counts as unstable",
                    below_cases.join(", ")
                )
            },
            share(0.98, Outcome::Accurate),
            share(1.02, Outcome::Unstable),
            share(1.1, Outcome::Unstable),
        );
        let inaccurate: Vec<&str> = at(0.98)
            .iter()
            .filter(|p| p.outcome == Outcome::Inaccurate)
            .map(|p| p.case.as_str())
            .collect();
        if !inaccurate.is_empty() {
            let _ = write!(
                s,
                " Bounded but outside tolerance at 0.98×: {}.",
                inaccurate.join(", ")
            );
        }
    } else {
        let _ = write!(
            s,
            "Accurate at 0.25× on {}, at 1.02× on {}, at 4× on {}; unstable at 4× on {}; failed at 4× on {}.",
            share(0.25, Outcome::Accurate),
            share(1.02, Outcome::Accurate),
            share(4.0, Outcome::Accurate),
            share(4.0, Outcome::Unstable),
            share(4.0, Outcome::Failed),
        );
        if points.iter().all(|p| p.outcome != Outcome::Unstable) {
            s += " It never went unstable on the grid: its springs are implicit, so past the explicit limit it \
                  loses accuracy (energy, amplitude) instead of blowing up.";
        }
    }
    if !refused.is_empty() {
        let _ = write!(
            s,
            " Not applicable (the engine does not model it, and says why): {}.",
            refused.join(", ")
        );
    }
    s
}
