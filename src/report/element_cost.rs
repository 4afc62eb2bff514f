//! The element-cost study's files: `DIR/elements.csv` (one row per scene: its elements, passes
//! and measured and predicted ns per increment) and `DIR/figures/elements.svg` (measured
//! against predicted, log–log, with the line of equality and the band of 1.5× either way).

use crate::report::format::{csv_finite as number, csv_table};
#[cfg(feature = "figures")]
use crate::report::palette;
use crate::run::element_cost::{Origin, Study, TERMS};
use crate::scene::Dimension;
#[cfg(feature = "figures")]
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The CSV's columns, in order.
pub const COLUMNS: [&str; 14] = [
    "case",
    "origin",
    "dimension",
    "particles",
    "bodies",
    "springs",
    "dashpots",
    "contacts",
    "loads",
    "increment_s",
    "passes",
    "ns_per_increment",
    "ns_per_element",
    "predicted_ns_per_increment",
];

/// `DIR/elements.csv`.
pub fn csv_path(out: &Path) -> PathBuf {
    out.join("elements.csv")
}

/// `DIR/figures/elements.svg`.
pub fn figure_path(out: &Path) -> PathBuf {
    out.join("figures").join("elements.svg")
}

fn origin(o: Origin) -> &'static str {
    match o {
        Origin::Seed => "seed",
        Origin::Generated => "generated",
    }
}

fn dimension(d: Dimension) -> &'static str {
    match d {
        Dimension::Two => "2d",
        Dimension::Three => "3d",
    }
}

/// The study as CSV text.
pub fn csv(study: &Study) -> String {
    let rows = study.ratios().map(|(p, ratio)| {
        let e = &p.elements;
        vec![
            p.case.clone(),
            origin(p.origin).to_string(),
            dimension(p.dimension).to_string(),
            e.particles.to_string(),
            e.bodies.to_string(),
            e.springs.to_string(),
            e.dashpots.to_string(),
            e.contacts.to_string(),
            e.loads.to_string(),
            number(p.increment),
            number(p.passes),
            number(p.ns_per_increment),
            number(p.ns_per_element()),
            number(p.ns_per_increment / ratio),
        ]
    });
    csv_table(&COLUMNS, rows)
}

/// The fitted models and how well they predict, as markdown: one row per term and dimension,
/// then the spread of measured over predicted for the family (fitted) and the seed cases
/// (predicted only).
pub fn summary(study: &Study) -> String {
    let mut s = String::from("| term | 2D, ns | 3D, ns |\n|---|---:|---:|\n");
    for (k, term) in TERMS.iter().enumerate() {
        let coefficient = |d| {
            study
                .model(d)
                .map_or("–".to_string(), |m| format!("{:.1}", m.coefficients[k]))
        };
        s += &format!(
            "| {term} | {} | {} |\n",
            coefficient(Dimension::Two),
            coefficient(Dimension::Three)
        );
    }
    for (o, what) in [
        (Origin::Generated, "generated family (fitted)"),
        (Origin::Seed, "seed cases (predicted, not fitted)"),
    ] {
        let ratios: Vec<f64> = study
            .ratios()
            .filter(|(p, _)| p.origin == o)
            .map(|(_, r)| r)
            .collect();
        let (lo, hi) = ratios
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(*r), b.max(*r)));
        s += &format!(
            "\n{what}: {} scenes, measured / predicted from {lo:.2} to {hi:.2}",
            ratios.len()
        );
    }
    s + "\n"
}

#[cfg(feature = "figures")]
/// The figure: measured against predicted ns per increment, log–log; the family as filled
/// circles, the seed cases as crosses, 2D and 3D in two colours; the line of equality solid and
/// the band of 1.5× dashed. The legend sits lower right, below the diagonal.
pub fn render(study: &Study) -> Option<String> {
    let points: Vec<(Origin, Dimension, f64, f64)> = study
        .ratios()
        .filter(|(p, r)| p.ns_per_increment > 0.0 && r.is_finite() && *r > 0.0)
        .map(|(p, r)| {
            (
                p.origin,
                p.dimension,
                p.ns_per_increment / r,
                p.ns_per_increment,
            )
        })
        .collect();
    if points.is_empty() {
        return None;
    }
    let (lo, hi) = points.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.2.min(p.3)), b.max(p.2.max(p.3)))
    });
    let range = lo / 2.0..hi * 2.0;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 680)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "explicit: measured against predicted cost of one increment (one thread)",
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(range.clone().log_scale(), range.clone().log_scale())
            .ok()?;
        chart
            .configure_mesh()
            .x_desc("predicted by the model fitted to the generated family [ns per increment]")
            .y_desc("measured [ns per increment]")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0}"))
            .draw()
            .ok()?;
        let grey = RGBColor(90, 90, 90);
        let (a, b) = (range.start, range.end);
        chart
            .draw_series(LineSeries::new([(a, a), (b, b)], grey.stroke_width(1)))
            .ok()?
            .label("measured = predicted")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], grey.stroke_width(1)));
        for factor in [1.5, 1.0 / 1.5] {
            let series = DashedLineSeries::new(
                [(a, a * factor), (b, b * factor)],
                6,
                4,
                grey.stroke_width(1),
            );
            let drawn = chart.draw_series(series).ok()?;
            if factor > 1.0 {
                drawn.label("1.5× either way").legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], grey.stroke_width(1))
                });
            }
        }
        for (d, colour) in [
            (Dimension::Two, palette::BLUE),
            (Dimension::Three, palette::VERMILLION),
        ] {
            let of = |o: Origin| {
                points
                    .iter()
                    .filter(move |p| p.0 == o && p.1 == d)
                    .map(|p| (p.2, p.3))
            };
            chart
                .draw_series(of(Origin::Generated).map(|p| Circle::new(p, 4, colour.filled())))
                .ok()?
                .label(format!("generated family, {}", dimension(d).to_uppercase()))
                .legend(move |(x, y)| Circle::new((x + 9, y), 4, colour.filled()));
            chart
                .draw_series(of(Origin::Seed).map(|p| Cross::new(p, 6, colour.stroke_width(2))))
                .ok()?
                .label(format!("seed cases, {}", dimension(d).to_uppercase()))
                .legend(move |(x, y)| Cross::new((x + 9, y), 6, colour.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .ok()?;
        root.present().ok()?;
    }
    Some(svg)
}
