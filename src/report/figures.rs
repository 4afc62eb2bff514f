//! SVG figures (plotters): per case, each live contract column (and each contact gap) over time
//! for the closed form and the engines, so a reader sees what the error tables measure.

#[cfg(feature = "figures")]
use crate::comparison;
#[cfg(feature = "figures")]
use crate::contract::{self, History};
#[cfg(feature = "figures")]
use crate::report::format::tick;
#[cfg(feature = "figures")]
use crate::report::palette;
#[cfg(feature = "figures")]
use crate::scene::Scene;
#[cfg(feature = "figures")]
use plotters::prelude::*;
#[cfg(feature = "figures")]
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

#[cfg(feature = "figures")]
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

#[cfg(feature = "figures")]
/// One engine's line in a panel: name, colour, (t, value) points.
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

/// `out/figures/<case>.svg`.
pub fn figure_path(out: &Path, case: &str) -> PathBuf {
    out.join("figures").join(format!("{case}.svg"))
}

#[cfg(feature = "figures")]
/// Drawn, in drawing order: the exact solutions first (thick, grey, underneath), then every
/// engine.
const DRAWN: [&str; 8] = [
    "analytic",
    "reference",
    "rapier_f64_default",
    "rapier_f32_default",
    "rapier_f64",
    "rapier_f32",
    "explicit_small",
    "explicit",
];

#[cfg(feature = "figures")]
/// The engines of `histories` in drawing order: those of [`DRAWN`] in its order, then any
/// other (a user's engine, in black) in the order given.
fn drawing_order<'a>(histories: &'a [(&'a str, History)]) -> Vec<&'a str> {
    let known = DRAWN
        .iter()
        .copied()
        .filter(|e| histories.iter().any(|(h, _)| h == e));
    let others = histories
        .iter()
        .map(|(e, _)| *e)
        .filter(|e| !DRAWN.contains(e));
    known.chain(others).collect()
}

#[cfg(feature = "figures")]
/// Height of the one legend, under the title.
const LEGEND_HEIGHT: u32 = 50;

#[cfg(feature = "figures")]
/// Markers per line: each engine's at its own times, so that lines which agree and overlap
/// still show every engine.
const MARKERS: usize = 8;

#[cfg(feature = "figures")]
/// A line's width: the exact solutions thick, under the engines.
fn stroke(engine: &str) -> u32 {
    match engine {
        "analytic" => 7,
        "reference" => 4,
        _ => 2,
    }
}

#[cfg(feature = "figures")]
/// The runs of consecutive points within [lo, hi] (a run that leaves the range is broken
/// there, not drawn along the frame).
fn within(points: &[(f64, f64)], lo: f64, hi: f64) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for &(t, y) in points {
        if (lo..=hi).contains(&y) {
            if let Some(r) = runs.last_mut() {
                r.push((t, y));
            }
        } else if runs.last().is_some_and(|r| !r.is_empty()) {
            runs.push(Vec::new());
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

/// How far, in pixels, a dropped point of a drawn line may lie from the line drawn instead: a
/// quarter pixel, below what the SVG's whole-pixel coordinates resolve.
pub const DRAWN_TOLERANCE: f64 = 0.25;

/// The points of a polyline that show at the figure's resolution (Ramer–Douglas–Peucker): a
/// point is dropped where the line between the points kept on either side passes within
/// `tolerance` pixels of it. `scale` turns a data difference into pixels along each axis. A
/// history of thousands of rows draws as the few hundred points that bend it; a line with a
/// non-finite point is kept whole.
pub fn simplified(points: &[(f64, f64)], scale: (f64, f64), tolerance: f64) -> Vec<(f64, f64)> {
    let n = points.len();
    let finite = points.iter().all(|p| p.0.is_finite() && p.1.is_finite());
    if n < 3 || !finite || !(scale.0.is_finite() && scale.1.is_finite()) {
        return points.to_vec();
    }
    let pixel = |i: usize| (points[i].0 * scale.0, points[i].1 * scale.1);
    let mut keep = vec![false; n];
    (keep[0], keep[n - 1]) = (true, true);
    let mut spans = vec![(0, n - 1)];
    while let Some((a, b)) = spans.pop() {
        let ((ax, ay), (bx, by)) = (pixel(a), pixel(b));
        let (dx, dy) = (bx - ax, by - ay);
        let length = dx.hypot(dy);
        let distance = |i: usize| {
            let (x, y) = pixel(i);
            if length > 0.0 {
                ((x - ax) * dy - (y - ay) * dx).abs() / length
            } else {
                (x - ax).hypot(y - ay)
            }
        };
        let farthest = (a + 1..b)
            .map(|i| (distance(i), i))
            .max_by(|p, q| p.0.total_cmp(&q.0));
        if let Some((_, i)) = farthest.filter(|(d, _)| *d > tolerance) {
            keep[i] = true;
            spans.push((a, i));
            spans.push((i, b));
        }
    }
    points
        .iter()
        .zip(keep)
        .filter_map(|(p, k)| k.then_some(*p))
        .collect()
}

#[cfg(feature = "figures")]
/// The pixels per data unit of a chart's x and y axes (`x` and `y` the spans drawn).
fn pixels_per_unit<DB: DrawingBackend, X: Ranged, Y: Ranged>(
    chart: &ChartContext<DB, Cartesian2d<X, Y>>,
    (x, y): (f64, f64),
) -> (f64, f64) {
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    (
        f64::from(xs.end - xs.start) / x,
        f64::from(ys.end - ys.start) / y,
    )
}

#[cfg(feature = "figures")]
/// Render a case's figure: one panel per column in `columns` (name and unit) whose values are
/// not all zero, every available engine's history as a line (the exact solutions thick and
/// grey underneath, each engine with markers at its own times), one legend under the title.
/// `histories` pairs engine names with histories.
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
    let drawn = drawing_order(histories);
    let mut leaves: Vec<&str> = Vec::new();
    let mut svg = String::new();
    {
        let height = 220 * live.len() as u32 + 40 + LEGEND_HEIGHT;
        let root = SVGBackend::with_string(&mut svg, (1000, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let (title, rest) = root.split_vertically(40);
        let (legend, body) = rest.split_vertically(LEGEND_HEIGHT);
        title.titled(case, ("sans-serif", 22)).ok()?;
        let panels = body.split_evenly((live.len(), 1));
        for (panel, &(column, unit)) in panels.iter().zip(&live) {
            let series: Vec<Series> = drawn
                .iter()
                .filter_map(|engine| {
                    let (_, h) = histories.iter().find(|(e, _)| e == engine)?;
                    let t = h.column("t")?;
                    let v = h.column(column)?;
                    let finite = t
                        .into_iter()
                        .zip(v)
                        .filter(|(t, y)| t.is_finite() && y.is_finite())
                        .collect();
                    Some((*engine, palette::engine(engine), finite))
                })
                .collect();
            for e in panel_lines(panel, column, unit, &series)? {
                if !leaves.contains(&e) {
                    leaves.push(e);
                }
            }
        }
        for (i, engine) in drawn.iter().enumerate() {
            let x = 20 + 240 * (i % 4) as i32;
            let y = 14 + 22 * (i / 4) as i32;
            let colour = palette::engine(engine);
            legend
                .draw(&PathElement::new(
                    [(x, y), (x + 28, y)],
                    colour.stroke_width(stroke(engine)),
                ))
                .ok()?;
            if !palette::is_exact(engine) {
                legend
                    .draw(&Circle::new((x + 14, y), 4, colour.filled()))
                    .ok()?;
            }
            let label = if leaves.contains(engine) {
                format!("{engine} (leaves the range)")
            } else {
                engine.to_string()
            };
            legend
                .draw(&Text::new(
                    label,
                    (x + 36, y - 7),
                    ("sans-serif", 13).into_font(),
                ))
                .ok()?;
        }
        root.present().ok()?;
    }
    Some(svg)
}

#[cfg(feature = "figures")]
/// One panel: its axes scaled to the exact solution, each series drawn where it is within
/// them. Returns the engines that leave the range.
fn panel_lines<'a, DB: DrawingBackend>(
    panel: &DrawingArea<DB, plotters::coord::Shift>,
    column: &str,
    unit: &str,
    series: &[Series<'a>],
) -> Option<Vec<&'a str>> {
    let (t0, t1) = series
        .iter()
        .flat_map(|s| s.2.iter().map(|p| p.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
    // Scale to the closed form (else the converged reference, else the first engine) so one
    // wild run does not flatten the others. A constant scale (the reference's contact force
    // where its impacts are impulses) would leave out every engine: then all of them set it.
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
    let mut chart = ChartBuilder::on(panel)
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
        .max_light_lines(0)
        .draw()
        .ok()?;
    let mut leaves = Vec::new();
    let engines = series
        .iter()
        .filter(|s| !palette::is_exact(s.0))
        .count()
        .max(1);
    let mut k = 0;
    let scale = pixels_per_unit(&chart, (x_span, y_span));
    for (engine, colour, points) in series {
        for run in within(points, lo, hi) {
            let run = simplified(&run, scale, DRAWN_TOLERANCE);
            chart
                .draw_series(LineSeries::new(run, colour.stroke_width(stroke(engine))))
                .ok()?;
        }
        if points.iter().any(|(_, y)| *y < lo || *y > hi) {
            leaves.push(*engine);
        }
        if palette::is_exact(engine) || points.is_empty() {
            continue;
        }
        // Markers at this engine's own fraction of each of MARKERS intervals.
        let n = points.len();
        let marks = (0..MARKERS).filter_map(|m| {
            let i = (m * engines + k) * n / (MARKERS * engines);
            let (t, y) = *points.get(i)?;
            (lo..=hi).contains(&y).then_some((t, y))
        });
        chart
            .draw_series(marks.map(|p| Circle::new(p, 4, colour.filled())))
            .ok()?;
        k += 1;
    }
    Some(leaves)
}

#[cfg(feature = "figures")]
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

#[cfg(feature = "figures")]
/// Errors above this are clipped on the log-scale panels (a run off by ten times the peak has
/// no accuracy left to show).
const LOG_CEILING: f64 = 10.0;

#[cfg(feature = "figures")]
/// A labelled line of a log-scale panel: label, colour, (t, value) points.
type LabelledSeries = (String, RGBColor, Vec<(f64, f64)>);

#[cfg(feature = "figures")]
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
        .max_light_lines(0)
        .draw()
        .ok()?;
    // The log axis is linear in log10: lines are simplified there and drawn back.
    let decades = hi.log10() - lo.log10();
    let scale = pixels_per_unit(&chart, (x_span, decades));
    for (row, (label, colour, points)) in series.iter().enumerate() {
        let clipped = points.iter().any(|(_, y)| *y > hi);
        let logged: Vec<(f64, f64)> = points
            .iter()
            .map(|(t, y)| (*t, y.clamp(lo, hi).log10()))
            .collect();
        let drawn = simplified(&logged, scale, DRAWN_TOLERANCE);
        let drawn = drawn.into_iter().map(|(t, e)| (t, 10f64.powf(e)));
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

#[cfg(feature = "figures")]
/// Render a case's error figure: per live contract column, each engine's error against the
/// exact solution of its own model ([`comparison::baseline`]) over time, over the column's
/// peak, on a log scale (the rows the comparison measures: valid rows, a contact force from the
/// first increment on); a last panel the energy balance error of each engine that keeps one,
/// over the largest energy it exchanges (`comparison::energy_scale`).
pub fn render_errors(scene: &Scene, histories: &[(&str, History)]) -> Option<String> {
    let find = |name: &str| histories.iter().find(|(e, _)| *e == name).map(|(_, h)| h);
    let mut panels: Vec<(String, Vec<LabelledSeries>)> = Vec::new();
    for column in contract::columns(scene.family) {
        // A displacement whose exact solution is zero is read over the scene's extent, as the
        // comparison reads it; another column without a peak is not drawn.
        let over_extent = std::cell::Cell::new(false);
        let series: Vec<_> = drawing_order(histories)
            .into_iter()
            .filter_map(|engine| {
                let colour = palette::engine(engine);
                let against = comparison::baseline(engine)?;
                let (run, exact) = (find(engine)?, find(against)?);
                let (t, y, x) = (run.column("t")?, run.column(column)?, exact.column(column)?);
                let n = comparison::valid_rows(exact).min(y.len()).min(x.len());
                let peak = match comparison::peak(&x[..n]) {
                    p if p > comparison::round_off(scene, column) => p,
                    _ if comparison::unit(scene, column) == "m" => {
                        over_extent.set(true);
                        comparison::scene_scale(scene, column)
                    }
                    _ => return None,
                };
                if peak == 0.0 {
                    return None;
                }
                let first = comparison::first_compared_row(scene, column).min(n);
                let points = (first..n)
                    .map(|i| (t[i], ((y[i] - x[i]).abs() / peak).max(LOG_FLOOR)))
                    .filter(|p| p.1.is_finite())
                    .collect();
                Some((format!("{engine} vs {against}"), colour, points))
            })
            .collect();
        // A held DOF every engine holds exactly has nothing to draw.
        let all_exact = series
            .iter()
            .all(|(_, _, points): &LabelledSeries| points.iter().all(|p| p.1 <= LOG_FLOOR));
        let nothing_to_draw = series.is_empty() || (over_extent.get() && all_exact);
        if !nothing_to_draw {
            let of = if over_extent.get() {
                format!("|error| in {column} / extent")
            } else {
                format!("|error| / peak of {column}")
            };
            panels.push((of, series));
        }
    }
    let balance: Vec<_> = drawing_order(histories)
        .into_iter()
        .filter_map(|engine| {
            let colour = palette::engine(engine);
            let h = find(engine)?;
            let (t, b) = (h.column("t")?, h.column(contract::E_BALANCE)?);
            let scale = comparison::energy_scale(h)?;
            (scale > 0.0).then(|| {
                let points = t
                    .into_iter()
                    .zip(b)
                    .map(|(t, b)| (t, (b.abs() / scale).max(LOG_FLOOR)))
                    .filter(|p| p.1.is_finite())
                    .collect();
                (engine.to_string(), colour, points)
            })
        })
        .collect();
    if !balance.is_empty() {
        panels.push(("|energy balance| / largest energy".into(), balance));
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

#[cfg(feature = "figures")]
/// The budget's parts, with their colours.
const PARTS: [(&str, RGBColor); 4] = [
    ("model_form", RGBColor(120, 120, 120)),
    ("time_step", palette::BLUE),
    ("penalty", palette::ORANGE),
    ("solver", palette::PURPLE),
];

/// One row of the budget figure: its label, the four parts' norms (model form, time step,
/// penalty, solver) of the run's worst column, and that column's total.
pub struct BudgetBar {
    /// `case / engine (column)`.
    pub label: String,
    /// The parts' norms, in [`PARTS`] order.
    pub parts: [f64; 4],
    /// The total's norm.
    pub total: f64,
}

#[cfg(feature = "figures")]
/// Render a family's budget as a dot plot on a log scale: one row per case and engine, a dot
/// per part (its norm over the column's peak) and a black bar for the total, so that a part of
/// 1e-16 sits sixteen decades left of one of 1.
pub fn render_budget(family: &str, bars: &[BudgetBar]) -> Option<String> {
    if bars.is_empty() {
        return None;
    }
    const ROW: i32 = 18;
    const TOP: i32 = 70;
    let (label_w, axis_x, axis_w) = (380, 400, 560);
    let values = bars
        .iter()
        .flat_map(|b| b.parts.iter().chain([&b.total]))
        .filter(|v| **v > 0.0 && v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
    if !(lo.is_finite() && hi > 0.0) {
        return None;
    }
    let (d0, d1) = (
        lo.max(LOG_FLOOR).log10().floor() as i32,
        hi.log10()
            .ceil()
            .max(lo.max(LOG_FLOOR).log10().floor() + 1.0) as i32,
    );
    let x_of = |v: f64| -> i32 {
        let l = v.max(10f64.powi(d0)).log10();
        axis_x + ((l - d0 as f64) / (d1 - d0) as f64 * axis_w as f64).round() as i32
    };
    let height = (TOP + ROW * bars.len() as i32 + 60) as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, height)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let font = |size| ("sans-serif", size).into_font();
        root.draw(&Text::new(
            format!(
                "Discrepancy budget, {family}: each source's largest value over the column's \
                 peak (worst column per run)"
            ),
            (10, 8),
            font(16),
        ))
        .ok()?;
        for (k, (name, colour)) in PARTS.iter().enumerate() {
            let x = axis_x + 110 * k as i32;
            root.draw(&Circle::new((x + 7, 47), 5, colour.filled()))
                .ok()?;
            root.draw(&Text::new(name.replace('_', " "), (x + 16, 41), font(12)))
                .ok()?;
        }
        let x = axis_x + 440;
        root.draw(&PathElement::new(
            [(x + 7, 40), (x + 7, 54)],
            BLACK.stroke_width(3),
        ))
        .ok()?;
        root.draw(&Text::new("total", (x + 16, 41), font(12)))
            .ok()?;
        let bottom = TOP + ROW * bars.len() as i32;
        for d in d0..=d1 {
            let x = x_of(10f64.powi(d));
            let grid = if d % 4 == 0 {
                RGBColor(200, 200, 200)
            } else {
                RGBColor(235, 235, 235)
            };
            root.draw(&PathElement::new([(x, TOP), (x, bottom)], grid))
                .ok()?;
        }
        for (i, bar) in bars.iter().enumerate() {
            let y = TOP + ROW * i as i32 + ROW / 2;
            let right = TextStyle::from(font(11)).pos(Pos::new(HPos::Right, VPos::Center));
            root.draw(&Text::new(bar.label.clone(), (label_w, y), right))
                .ok()?;
            for (part, (_, colour)) in bar.parts.iter().zip(PARTS) {
                if *part > 0.0 && part.is_finite() {
                    root.draw(&Circle::new((x_of(*part), y), 4, colour.filled()))
                        .ok()?;
                }
            }
            if bar.total > 0.0 && bar.total.is_finite() {
                let x = x_of(bar.total);
                root.draw(&PathElement::new(
                    [(x, y - 6), (x, y + 6)],
                    BLACK.stroke_width(2),
                ))
                .ok()?;
            }
        }
        // Axis: decades.
        root.draw(&PathElement::new(
            [(axis_x, bottom + 4), (axis_x + axis_w, bottom + 4)],
            BLACK,
        ))
        .ok()?;
        let step = if d1 - d0 > 8 { 2 } else { 1 };
        for d in (d0..=d1).filter(|d| (d - d0) % step == 0) {
            let x = x_of(10f64.powi(d));
            root.draw(&PathElement::new([(x, bottom + 4), (x, bottom + 9)], BLACK))
                .ok()?;
            root.draw(&Text::new(
                format!("1e{d}"),
                (x - 12, bottom + 12),
                font(11),
            ))
            .ok()?;
        }
        root.draw(&Text::new(
            "value over the column's peak (log scale; a part below 1e-16 drawn at 1e-16)",
            (axis_x + 40, bottom + 30),
            font(12),
        ))
        .ok()?;
        root.present().ok()?;
    }
    Some(svg)
}

#[cfg(feature = "figures")]
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

#[cfg(feature = "figures")]
#[cfg(test)]
mod tests {
    use super::*;

    /// The distance in pixels from `p` to the polyline `line` (segment by segment).
    fn distance_to(line: &[(f64, f64)], p: (f64, f64), scale: (f64, f64)) -> f64 {
        let px = |q: (f64, f64)| (q.0 * scale.0, q.1 * scale.1);
        let (x, y) = px(p);
        line.windows(2)
            .map(|w| {
                let ((ax, ay), (bx, by)) = (px(w[0]), px(w[1]));
                let (dx, dy) = (bx - ax, by - ay);
                let s = (((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
                (x - ax - s * dx).hypot(y - ay - s * dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// A straight line keeps its ends alone; a damped oscillation of 2001 rows on an 800 × 200
    /// pixel panel keeps every row within the tolerance of the line drawn, with far fewer
    /// points; a line with a NaN is kept whole.
    #[test]
    fn lines_are_simplified_within_a_quarter_pixel() {
        let straight: Vec<(f64, f64)> = (0..1000).map(|i| (i as f64, 2.0 * i as f64)).collect();
        assert_eq!(simplified(&straight, (1.0, 1.0), 0.25).len(), 2);
        let rows: Vec<(f64, f64)> = (0..=2000)
            .map(|i| {
                let t = i as f64 * 1e-3;
                (t, (-0.5 * t).exp() * (20.0 * t).cos())
            })
            .collect();
        let scale = (800.0 / 2.0, 200.0 / 2.0);
        let drawn = simplified(&rows, scale, DRAWN_TOLERANCE);
        assert!(
            drawn.len() < rows.len() / 4,
            "{} of {}",
            drawn.len(),
            rows.len()
        );
        assert_eq!((drawn[0], drawn[drawn.len() - 1]), (rows[0], rows[2000]));
        let worst = rows
            .iter()
            .map(|p| distance_to(&drawn, *p, scale))
            .fold(0.0, f64::max);
        assert!(worst <= DRAWN_TOLERANCE, "{worst}");
        let mut broken = rows.clone();
        broken[7].1 = f64::NAN;
        assert_eq!(
            simplified(&broken, scale, DRAWN_TOLERANCE).len(),
            rows.len()
        );
    }

    #[test]
    fn columns_have_their_units() {
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
