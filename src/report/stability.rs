//! The stability map's files: `stability/<engine>.csv` ([`COLUMNS`], one row per case and
//! ratio), `figures/stability-<engine>.svg` (cases × ratio, outcome as colour), and the report
//! section that says in words where each engine stays stable and accurate.

use crate::report::data::format_finite as number;
use crate::run::stability::{ENERGY_GROWTH_LIMIT, ENGINES, Outcome, Point, RATIOS};
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The CSV header.
pub const COLUMNS: [&str; 6] = [
    "case",
    "ratio",
    "increment",
    "outcome",
    "error_max",
    "energy_growth",
];

/// `out/stability/<engine>.csv`.
pub fn csv_path(out: &Path, engine: &str) -> PathBuf {
    out.join("stability").join(format!("{engine}.csv"))
}

/// `out/figures/stability-<engine>.svg`.
pub fn figure_path(out: &Path, engine: &str) -> PathBuf {
    out.join("figures").join(format!("stability-{engine}.svg"))
}

fn optional(x: Option<f64>) -> String {
    x.filter(|v| v.is_finite()).map_or_else(String::new, number)
}

/// One engine's points as CSV text (an absent or non-finite value is an empty field).
pub fn csv(points: &[&Point]) -> String {
    let mut s = COLUMNS.join(",") + "\n";
    for p in points {
        let fields = [
            p.case.clone(),
            number(p.ratio),
            optional(p.increment),
            p.outcome.name().to_string(),
            optional(p.error_max),
            optional(p.energy_growth),
        ];
        s += &(fields.join(",") + "\n");
    }
    s
}

/// Read an engine's CSV back as points (None if missing or not one).
pub fn read(path: &Path, engine: &str) -> Option<Vec<Point>> {
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
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            if f.len() != COLUMNS.len() {
                return None;
            }
            Some(Point {
                case: f[0].to_string(),
                engine: engine.to_string(),
                ratio: f[1].parse().ok()?,
                increment: num(f[2])?,
                outcome: Outcome::parse(f[3])?,
                error_max: num(f[4])?,
                energy_growth: num(f[5])?,
                message: None,
            })
        })
        .collect()
}

/// Every engine's map found under `out`.
pub fn read_all(out: &Path) -> BTreeMap<String, Vec<Point>> {
    ENGINES
        .iter()
        .filter_map(|e| Some((e.to_string(), read(&csv_path(out, e), e)?)))
        .collect()
}

fn colour(o: Outcome) -> RGBColor {
    match o {
        Outcome::Accurate => RGBColor(102, 187, 106),
        Outcome::Inaccurate => RGBColor(255, 202, 40),
        Outcome::Unstable => RGBColor(229, 57, 53),
        Outcome::Failed => RGBColor(158, 158, 158),
        Outcome::NotApplicable => RGBColor(236, 239, 241),
    }
}

/// One engine's map: a row per case, a column per ratio, the outcome as colour.
pub fn render(engine: &str, points: &[&Point]) -> Option<String> {
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
    let width = left + cell.0 * ratios.len() as u32 + 20;
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
        }
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
                Outcome::Unstable => format!("unstable (energy > {ENERGY_GROWTH_LIMIT}×)"),
                Outcome::Failed => "failed".to_string(),
                Outcome::NotApplicable => "not applicable".to_string(),
            };
            root.draw(&Text::new(label.clone(), (x + 22, y + 1), font.clone()))
                .ok()?;
            x += 30 + 7 * label.chars().count() as i32;
        }
        root.draw(&Text::new(
            "black line: the stable increment (ratio 1)",
            (10, y + 26),
            font,
        ))
        .ok()?;
        root.present().ok()?;
    }
    Some(svg)
}

/// Write every engine's CSV and figure.
pub fn write(out: &Path, points: &[Point]) -> Result<(), crate::report::data::DataError> {
    use crate::report::data::{DataError, write_atomic};
    for engine in ENGINES {
        let mine: Vec<&Point> = points.iter().filter(|p| p.engine == engine).collect();
        if mine.is_empty() {
            continue;
        }
        crate::interrupt::checkpoint("stability").map_err(|_| DataError::Interrupted)?;
        write_atomic(&csv_path(out, engine), csv(&mine).as_bytes())?;
        if let Some(svg) = render(engine, &mine) {
            write_atomic(&figure_path(out, engine), svg.as_bytes())?;
        }
    }
    Ok(())
}

/// The report section: per engine, the map and a sentence on where it stays stable.
pub fn overview(w: &mut String, maps: &BTreeMap<String, Vec<Point>>) {
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
         (its initial energy plus the work of the loads), *accurate* when its largest error against \
         its own model's exact solution is within the case's tolerance for it (a rapier engine \
         without one takes the case's `rapier_f64` tolerance, any other the tightest the case \
         declares), *inaccurate* when bounded but outside it. Cases without a stable increment \
         (the free spins) are not mapped; a case an engine does not model is *not applicable* \
         (not counted as failed). Data: `stability/<engine>.csv`.\n",
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
    for (engine, points) in maps {
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
            first_unstable.map_or("never".to_string(), |r| format!(
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
    let _ = writeln!(w);
    for (engine, points) in maps {
        let _ = writeln!(w, "**`{engine}`.** {}\n", words(engine, points));
        let _ = writeln!(
            w,
            "![stability map of {engine}](figures/stability-{engine}.svg)\n"
        );
    }
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
            s += " It never went unstable: its springs are implicit, so past the explicit limit it \
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
