//! `figures/rebound.svg`: the first rebound over the drop against the restitution e, every
//! engine on every drop case, over the exact e² curve.

use super::format::tick;
use super::palette;
use crate::comparison::summary::Summary;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Each engine's markers are moved this far in e from the next one's, so that markers at one
/// value all show.
const SPREAD: f64 = 0.005;

/// `out/figures/rebound.svg`.
pub fn figure_path(out: &Path) -> PathBuf {
    out.join("figures").join("rebound.svg")
}

/// Each engine's (e, rebound over drop) on the cases where the reference measured a first
/// rebound (e: the reference's rebound speed over its approach speed at that impact).
pub fn points(s: &Summary) -> Vec<(String, f64, f64)> {
    let mut out = Vec::new();
    for c in &s.cases {
        let Some(e) = c
            .runs
            .iter()
            .find(|r| r.engine == "reference")
            .and_then(|r| {
                Some(r.measures.get("impact_1_rebound")? / r.measures.get("impact_1_speed")?)
            })
        else {
            continue;
        };
        for r in c
            .runs
            .iter()
            .filter(|r| !crate::contract::on_older_release(&r.engine))
        {
            if let Some(rebound) = r.impacts.as_ref().and_then(|i| i.rebound) {
                out.push((r.engine.clone(), e, rebound));
            }
        }
    }
    out
}

/// The figure (None without points): e on x, rebound over drop on y, e² thick and grey
/// under every engine's markers (each engine offset slightly in e so coinciding markers stay
/// visible), one legend.
pub fn render(points: &[(String, f64, f64)]) -> Option<String> {
    if points.is_empty() {
        return None;
    }
    let mut engines: Vec<&str> = Vec::new();
    for (e, _, _) in points {
        if !engines.contains(&e.as_str()) {
            engines.push(e);
        }
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 560)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let (panel, legend) = root.split_horizontally(660);
        let mut chart = ChartBuilder::on(&panel)
            .caption(
                "First rebound over the drop against restitution e",
                ("sans-serif", 16),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.05..1.05, -0.05..1.1)
            .ok()?;
        chart
            .configure_mesh()
            .x_desc("restitution e (the reference's, at its first impact; engines spread ±0.015)")
            .y_desc("rebound height / drop height")
            .x_label_formatter(&|x| tick(*x, 1.0))
            .y_label_formatter(&|y| tick(*y, 1.0))
            .max_light_lines(0)
            .draw()
            .ok()?;
        let curve = (0..=100).map(|i| {
            let e = i as f64 / 100.0;
            (e, e * e)
        });
        chart
            .draw_series(LineSeries::new(curve, palette::CLOSED_FORM.stroke_width(7)))
            .ok()?;
        let n = engines.len() as f64;
        for (k, engine) in engines.iter().enumerate() {
            let c = palette::engine(engine);
            let dx = SPREAD * (k as f64 - (n - 1.0) / 2.0);
            chart
                .draw_series(
                    points
                        .iter()
                        .filter(|p| p.0 == *engine)
                        .map(|p| Circle::new((p.1 + dx, p.2), 5, c.filled())),
                )
                .ok()?;
        }
        let font = ("sans-serif", 13).into_font();
        legend
            .draw(&PathElement::new(
                [(10, 40), (40, 40)],
                palette::CLOSED_FORM.stroke_width(7),
            ))
            .ok()?;
        legend
            .draw(&Text::new("e² (exact)", (48, 33), font.clone()))
            .ok()?;
        for (k, engine) in engines.iter().enumerate() {
            let y = 66 + 24 * k as i32;
            legend
                .draw(&Circle::new((25, y), 5, palette::engine(engine).filled()))
                .ok()?;
            legend
                .draw(&Text::new(engine.to_string(), (48, y - 7), font.clone()))
                .ok()?;
        }
        root.present().ok()?;
    }
    Some(svg)
}
