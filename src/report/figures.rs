//! SVG figures (plotters): per case, each live contract column (and each contact gap) over time
//! for the closed form and the engines, so a reader sees what the error tables measure.

use crate::comparison;
use crate::contract::{self, History};
use crate::scene::Scene;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

/// Engines drawn, with their colours, in drawing order (the closed form last, on top).
const DRAWN: [(&str, RGBColor); 6] = [
    ("rapier_f64_default", RGBColor(200, 160, 0)),
    ("rapier_f64", RGBColor(214, 39, 40)),
    ("explicit", RGBColor(31, 119, 180)),
    ("explicit_small", RGBColor(44, 160, 44)),
    ("reference", RGBColor(148, 103, 189)),
    ("analytic", RGBColor(0, 0, 0)),
];

/// Width of the legend column on the right of every panel (outside the data).
const LEGEND_WIDTH: u32 = 240;

/// The unit of a contract column, in the cases' consistent units (N, m, kg, s, rad).
pub fn unit(column: &str) -> &'static str {
    match column {
        "t" => "s",
        "contact_force" => "N",
        c if c.starts_with('r') => "rad",
        c if c.starts_with('u') => "m",
        c if c.starts_with('v') => "m/s",
        c if c.starts_with('e') || c.starts_with('w') => "J",
        _ => "",
    }
}

/// A tick label: at most 3 significant digits, trailing zeros dropped, and a value within
/// 1e-6 of the axis span of zero printed as 0 (no round-off noise such as `-1.388e-17`).
pub fn tick(y: f64, span: f64) -> String {
    if y.abs() <= 1e-6 * span.abs() || y == 0.0 {
        return "0".into();
    }
    let a = y.abs();
    if (1e-3..1e4).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        let text = format!("{y:.decimals$}");
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            text
        }
    } else {
        let text = format!("{y:.2e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let mantissa = if mantissa.contains('.') {
            mantissa.trim_end_matches('0').trim_end_matches('.')
        } else {
            mantissa
        };
        format!("{mantissa}e{exponent}")
    }
}

/// One engine's line in a panel: name, colour, (t, value) points.
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

/// `out/figures/<case>.svg`.
pub fn figure_path(out: &Path, case: &str) -> PathBuf {
    out.join("figures").join(format!("{case}.svg"))
}

/// Render a case's figure: one panel per column in `columns` (name and unit) whose values are
/// not all zero, every available engine's history as a line. `histories` pairs engine names
/// with histories.
pub fn render(
    case: &str,
    columns: &[(&str, &str)],
    histories: &[(&str, History)],
) -> Option<String> {
    let live: Vec<(&str, &str)> = columns
        .iter()
        .copied()
        .filter(|(c, _)| {
            histories
                .iter()
                .any(|(_, h)| h.column(c).is_some_and(|v| v.iter().any(|x| *x != 0.0)))
        })
        .collect();
    if live.is_empty() {
        return None;
    }
    let mut svg = String::new();
    {
        let height = 220 * live.len() as u32 + 40;
        let root =
            SVGBackend::with_string(&mut svg, (900 + LEGEND_WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let (title, body) = root.split_vertically(40);
        title.titled(case, ("sans-serif", 22)).ok()?;
        let panels = body.split_evenly((live.len(), 1));
        for (whole, &(column, unit)) in panels.iter().zip(&live) {
            let (panel, legend) = whole.split_horizontally(900);
            let series: Vec<Series> = DRAWN
                .iter()
                .filter_map(|(engine, colour)| {
                    let (_, h) = histories.iter().find(|(e, _)| e == engine)?;
                    let t = h.column("t")?;
                    let v = h.column(column)?;
                    let finite = t
                        .into_iter()
                        .zip(v)
                        .filter(|(t, y)| t.is_finite() && y.is_finite())
                        .collect();
                    Some((*engine, *colour, finite))
                })
                .collect();
            let (t0, t1) = series
                .iter()
                .flat_map(|s| s.2.iter().map(|p| p.0))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t), b.max(t))
                });
            // Scale to the closed form (else the converged reference, else the first engine) so
            // one wild run does not flatten the others; wild values are clipped at the panel
            // edge. A constant scale (the reference's contact force where its impacts are
            // impulses) would clip every engine: then all of them set the range.
            let range = |points: &mut dyn Iterator<Item = f64>| {
                points.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
                    (a.min(y), b.max(y))
                })
            };
            let scale = series
                .iter()
                .find(|s| s.0 == "analytic")
                .or(series.iter().find(|s| s.0 == "reference"))
                .or(series.first())?;
            let (mut lo, mut hi) = range(&mut scale.2.iter().map(|p| p.1));
            if hi <= lo {
                (lo, hi) = range(&mut series.iter().flat_map(|s| s.2.iter().map(|p| p.1)));
            }
            let (lo, hi) = padded(lo, hi)?;
            if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
                return None;
            }
            let mut chart = ChartBuilder::on(&panel)
                .margin(8)
                .x_label_area_size(36)
                .y_label_area_size(80)
                .build_cartesian_2d(t0..t1, lo..hi)
                .ok()?;
            let (x_span, y_span) = (t1 - t0, hi - lo);
            chart
                .configure_mesh()
                .x_desc("t [s]")
                .y_desc(format!("{column} [{unit}]"))
                .x_label_formatter(&|x| tick(*x, x_span))
                .y_label_formatter(&|y| tick(*y, y_span))
                .light_line_style(WHITE)
                .draw()
                .ok()?;
            for (row, (engine, colour, points)) in series.iter().enumerate() {
                let clipped = points.iter().map(|(t, y)| (*t, y.clamp(lo, hi)));
                chart
                    .draw_series(LineSeries::new(clipped, colour.stroke_width(1)))
                    .ok()?;
                // The legend, in its own column right of the data. A run that leaves the
                // closed form's range is clipped at the panel edge, and says so.
                let outside = points.iter().any(|(_, y)| *y < lo || *y > hi);
                legend_entry(&legend, row, *colour, engine, outside)?;
            }
        }
        root.present().ok()?;
    }
    Some(svg)
}

/// One line of a panel's legend (in its own column right of the data): a run that leaves the
/// panel's range is clipped at its edge, and says so.
fn legend_entry<DB: DrawingBackend>(
    legend: &DrawingArea<DB, plotters::coord::Shift>,
    row: usize,
    colour: RGBColor,
    label: &str,
    clipped: bool,
) -> Option<()> {
    let y = 20 + 18 * row as i32;
    legend
        .draw(&PathElement::new([(4, y), (24, y)], colour.stroke_width(2)))
        .ok()?;
    let label = if clipped {
        format!("{label} (clipped)")
    } else {
        label.to_string()
    };
    legend
        .draw(&Text::new(
            label,
            (30, y - 6),
            ("sans-serif", 12).into_font(),
        ))
        .ok()?;
    Some(())
}

/// Errors below this are drawn at it on the log-scale panels (round-off: nothing smaller is
/// meaningful relative to a peak).
pub const LOG_FLOOR: f64 = 1e-16;

/// Errors above this are clipped on the log-scale panels (a run off by ten times the peak has
/// no accuracy left to show).
const LOG_CEILING: f64 = 10.0;

/// A labelled line of a log-scale panel: label, colour, (t, value) points.
type LabelledSeries = (String, RGBColor, Vec<(f64, f64)>);

/// One log-scale panel: named series of (t, value ≥ 0), drawn between [`LOG_FLOOR`] and
/// [`LOG_CEILING`], the legend in its own column.
fn log_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    y_desc: &str,
    series: &[LabelledSeries],
) -> Option<()> {
    let (panel, legend) = area.split_horizontally(900);
    let (t0, t1) = series
        .iter()
        .flat_map(|s| s.2.iter().map(|p| p.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
    if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
        return None;
    }
    // The lower end from the values above the floor (an exact start, error 0, would otherwise
    // stretch the axis down to round-off); anything below it is drawn at it.
    let values = series.iter().flat_map(|s| s.2.iter().map(|p| p.1));
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > LOG_FLOOR)
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let lo = (lo / 2.0).clamp(LOG_FLOOR, LOG_CEILING / 10.0);
    let hi = (hi * 2.0).clamp(lo * 10.0, LOG_CEILING);
    let mut chart = ChartBuilder::on(&panel)
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(80)
        .build_cartesian_2d(t0..t1, (lo..hi).log_scale())
        .ok()?;
    let x_span = t1 - t0;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(y_desc)
        .x_label_formatter(&|x| tick(*x, x_span))
        .y_label_formatter(&|y| tick(*y, 0.0))
        .light_line_style(WHITE)
        .draw()
        .ok()?;
    for (row, (label, colour, points)) in series.iter().enumerate() {
        let clipped = points.iter().any(|(_, y)| *y > hi);
        let drawn = points.iter().map(|(t, y)| (*t, y.clamp(lo, hi)));
        chart
            .draw_series(LineSeries::new(drawn, colour.stroke_width(1)))
            .ok()?;
        legend_entry(&legend, row, *colour, label, clipped)?;
    }
    Some(())
}

/// `out/figures/<case>.sketch.svg` (drawn by [`crate::report::sketch`]).
pub fn sketch_path(out: &Path, case: &str) -> PathBuf {
    out.join("figures").join(format!("{case}.sketch.svg"))
}

/// `out/figures/<case>.errors.svg`.
pub fn errors_figure_path(out: &Path, case: &str) -> PathBuf {
    out.join("figures").join(format!("{case}.errors.svg"))
}

/// Render a case's error figure: per live contract column, each engine's error against the
/// exact solution of its own model ([`comparison::baseline`]) over time, over the column's
/// peak, on a log scale (the rows the comparison measures: valid rows, a contact force from the
/// first increment on); a last panel the energy balance error of each engine that keeps one,
/// over its largest kinetic + elastic energy.
pub fn render_errors(scene: &Scene, histories: &[(&str, History)]) -> Option<String> {
    let find = |name: &str| histories.iter().find(|(e, _)| *e == name).map(|(_, h)| h);
    let mut panels: Vec<(String, Vec<LabelledSeries>)> = Vec::new();
    for column in contract::columns(scene.family) {
        let series: Vec<_> = DRAWN
            .iter()
            .filter_map(|(engine, colour)| {
                let against = comparison::baseline(engine)?;
                let (run, exact) = (find(engine)?, find(against)?);
                let (t, y, x) = (run.column("t")?, run.column(column)?, exact.column(column)?);
                let n = comparison::valid_rows(exact).min(y.len()).min(x.len());
                let peak = comparison::peak(&x[..n]);
                if peak == 0.0 {
                    return None;
                }
                let first = comparison::first_compared_row(scene, column).min(n);
                let points = (first..n)
                    .map(|i| (t[i], ((y[i] - x[i]).abs() / peak).max(LOG_FLOOR)))
                    .filter(|p| p.1.is_finite())
                    .collect();
                Some((format!("{engine} vs {against}"), *colour, points))
            })
            .collect();
        if !series.is_empty() {
            panels.push((format!("|error| / peak of {column}"), series));
        }
    }
    let balance: Vec<_> = DRAWN
        .iter()
        .filter_map(|(engine, colour)| {
            let h = find(engine)?;
            let (t, b) = (h.column("t")?, h.column(contract::E_BALANCE)?);
            let (k, e) = (
                h.column(contract::E_KINETIC)?,
                h.column(contract::E_ELASTIC)?,
            );
            let scale = k.iter().zip(&e).fold(0.0f64, |m, (k, e)| m.max(k + e));
            (scale > 0.0).then(|| {
                let points = t
                    .into_iter()
                    .zip(b)
                    .map(|(t, b)| (t, (b.abs() / scale).max(LOG_FLOOR)))
                    .filter(|p| p.1.is_finite())
                    .collect();
                (engine.to_string(), *colour, points)
            })
        })
        .collect();
    if !balance.is_empty() {
        panels.push(("|energy balance| / peak energy".into(), balance));
    }
    if panels.is_empty() {
        return None;
    }
    let mut svg = String::new();
    {
        let height = 220 * panels.len() as u32 + 60;
        let root =
            SVGBackend::with_string(&mut svg, (900 + LEGEND_WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let (title, body) = root.split_vertically(60);
        title
            .titled(
                &format!(
                    "{}: error against the exact solution of each engine's own model \
                     (log scale; smaller values drawn at the lower edge)",
                    scene.id
                ),
                ("sans-serif", 16),
            )
            .ok()?;
        for (area, (desc, series)) in body.split_evenly((panels.len(), 1)).iter().zip(&panels) {
            log_panel(area, desc, series)?;
        }
        root.present().ok()?;
    }
    Some(svg)
}

/// `out/figures/budget-<family>.svg`.
pub fn budget_figure_path(out: &Path, family: &str) -> PathBuf {
    out.join("figures").join(format!("budget-{family}.svg"))
}

/// The budget's parts, with their colours, in stacking order.
const PARTS: [(&str, RGBColor); 4] = [
    ("model_form", RGBColor(150, 150, 150)),
    ("time_step", RGBColor(31, 119, 180)),
    ("penalty", RGBColor(255, 127, 14)),
    ("solver", RGBColor(214, 39, 40)),
];

/// One bar of the budget figure: its label, the four parts' norms (model form, time step,
/// penalty, solver) of the run's worst column, and that column's total.
pub struct BudgetBar {
    /// `case / engine (column)`.
    pub label: String,
    /// The parts' norms, in [`PARTS`] order.
    pub parts: [f64; 4],
    /// The total's norm.
    pub total: f64,
}

/// Render a family's budget: one horizontal bar per case and engine, each part's share of the
/// sum of the parts' norms (the norms are maxima over time, so they need not add up to the
/// total's; the shares show which source dominates), the total's norm printed at its end.
pub fn render_budget(family: &str, bars: &[BudgetBar]) -> Option<String> {
    if bars.is_empty() {
        return None;
    }
    const ROW: i32 = 18;
    const TOP: i32 = 70;
    let (label_w, bar_x, bar_w) = (380, 390, 440);
    let height = (TOP + ROW * bars.len() as i32 + 50) as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let font = |size| ("sans-serif", size).into_font();
        root.draw(&Text::new(
            format!("Discrepancy budget, {family}: share of each source (worst column per run)"),
            (10, 8),
            font(18),
        ))
        .ok()?;
        for (k, (name, colour)) in PARTS.iter().enumerate() {
            let x = bar_x + 110 * k as i32;
            root.draw(&Rectangle::new([(x, 40), (x + 14, 54)], colour.filled()))
                .ok()?;
            root.draw(&Text::new(name.to_string(), (x + 18, 41), font(12)))
                .ok()?;
        }
        root.draw(&Text::new(
            "total error / peak".to_string(),
            (bar_x + bar_w + 12, 41),
            font(12),
        ))
        .ok()?;
        for (i, bar) in bars.iter().enumerate() {
            let y = TOP + ROW * i as i32;
            let right = TextStyle::from(font(11)).pos(Pos::new(HPos::Right, VPos::Top));
            root.draw(&Text::new(bar.label.clone(), (label_w, y + 3), right))
                .ok()?;
            let sum: f64 = bar.parts.iter().sum();
            let mut x = bar_x as f64;
            if sum > 0.0 && sum.is_finite() {
                for (part, (_, colour)) in bar.parts.iter().zip(PARTS) {
                    let w = bar_w as f64 * part / sum;
                    root.draw(&Rectangle::new(
                        [
                            (x.round() as i32, y + 2),
                            ((x + w).round() as i32, y + ROW - 2),
                        ],
                        colour.filled(),
                    ))
                    .ok()?;
                    x += w;
                }
            }
            root.draw(&Text::new(
                crate::report::markdown::sci(bar.total),
                (bar_x + bar_w + 12, y + 3),
                font(11),
            ))
            .ok()?;
        }
        // Axis: share in per cent.
        let y = TOP + ROW * bars.len() as i32 + 4;
        root.draw(&PathElement::new([(bar_x, y), (bar_x + bar_w, y)], BLACK))
            .ok()?;
        for k in 0..=4 {
            let x = bar_x + bar_w * k / 4;
            root.draw(&PathElement::new([(x, y), (x, y + 5)], BLACK))
                .ok()?;
            root.draw(&Text::new(format!("{}", 25 * k), (x - 8, y + 8), font(11)))
                .ok()?;
        }
        root.draw(&Text::new(
            "share of the parts' norms [%]".to_string(),
            (bar_x + bar_w / 2 - 80, y + 24),
            font(12),
        ))
        .ok()?;
        root.present().ok()?;
    }
    Some(svg)
}

/// A value range widened by 15 % (at least 1e-9 of its magnitude, at least 1e-12), or `None`
/// when it is empty or not finite: the figure is skipped rather than drawn on a degenerate
/// axis.
fn padded(lo: f64, hi: f64) -> Option<(f64, f64)> {
    if !(lo.is_finite() && hi.is_finite() && hi >= lo) {
        return None;
    }
    let magnitude = lo.abs().max(hi.abs());
    let pad = 0.15 * (hi - lo).max(1e-9 * magnitude).max(1e-12);
    let (lo, hi) = (lo - pad, hi + pad);
    (lo.is_finite() && hi.is_finite() && hi > lo).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_have_three_significant_digits_and_no_round_off_noise() {
        assert_eq!(tick(-1.388e-17, 0.3), "0");
        assert_eq!(tick(0.05, 0.3), "0.05");
        assert_eq!(tick(0.125, 0.3), "0.125");
        assert_eq!(tick(-0.2, 0.3), "-0.2");
        assert_eq!(tick(250_000.0, 3e5), "2.5e5");
        assert_eq!(tick(1.2345e-5, 1e-4), "1.23e-5");
        assert_eq!(tick(37.0, 100.0), "37");
        assert_eq!(unit("contact_force"), "N");
        assert_eq!(unit("rz"), "rad");
        assert_eq!(unit("ux_node"), "m");
        assert_eq!(unit("v_end"), "m/s");
    }

    #[test]
    fn degenerate_and_non_finite_ranges_are_skipped_or_widened() {
        assert_eq!(padded(f64::NAN, 1.0), None);
        assert_eq!(padded(0.0, f64::INFINITY), None);
        assert_eq!(padded(1.0, 0.0), None);
        let (lo, hi) = padded(1e30, 1e30).unwrap();
        assert!(lo < 1e30 && hi > 1e30);
        let (lo, hi) = padded(0.0, 0.0).unwrap();
        assert!(lo < 0.0 && hi > 0.0);
        assert!(padded(f64::MAX, f64::MAX).is_none());
    }

    #[test]
    fn a_history_of_nan_draws_no_figure_and_does_not_hang() {
        let h = History {
            columns: vec!["t".into(), "u_end".into()],
            rows: (0..5).map(|i| vec![f64::from(i), f64::NAN]).collect(),
        };
        assert!(render("c", &[("u_end", "m")], &[("explicit", h)]).is_none());
    }
}
