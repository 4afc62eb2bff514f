//! The scaling study's files: `DIR/scaling.csv` (one row per engine and N) and
//! `DIR/figures/scaling.svg` (ns per increment against N, log–log, with each engine's fitted
//! exponent and the memory-bandwidth limit).

use crate::report::format::{csv_finite as number, csv_table};
use crate::run::scaling::{RETIMINGS, Study, fitted_exponent};
#[cfg(feature = "figures")]
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The CSV's columns, in order.
pub const COLUMNS: [&str; 10] = [
    "engine",
    "n",
    "steps",
    "ns_per_step",
    "ns_per_dof_step",
    "peak_rss_bytes",
    "scene_rss_bytes",
    "error",
    "limit_ns_per_dof_step",
    "predicted_error",
];

/// Smallest N the fitted exponent uses: below it a step's fixed costs (the loop, the output
/// rows' bookkeeping) are not negligible against the per-DOF work.
pub const FIT_FROM_N: usize = 1000;

/// `DIR/scaling.csv`.
pub fn csv_path(out: &Path) -> PathBuf {
    out.join("scaling.csv")
}

/// `DIR/figures/scaling.svg`.
pub fn figure_path(out: &Path) -> PathBuf {
    out.join("figures").join("scaling.svg")
}

/// The study as CSV text (numbers in Rust's shortest round-trip form; nothing non-finite).
pub fn csv(study: &Study) -> String {
    let rows = study.points.iter().map(|p| {
        vec![
            p.engine.clone(),
            p.n.to_string(),
            p.steps.to_string(),
            number(p.ns_per_step),
            number(p.ns_per_dof_step),
            p.peak_rss_bytes.to_string(),
            p.scene_rss_bytes.to_string(),
            number(p.error),
            number(p.limit_ns_per_dof_step),
            number(p.predicted_error),
        ]
    });
    csv_table(&COLUMNS, rows)
}

/// The study as a text table: one row per point, then the points not run and the fitted
/// exponents.
pub fn table(study: &Study) -> String {
    let mut s = format!(
        "{:<12} {:>9} {:>7} {:>14} {:>10} {:>10} {:>10} {:>12} {:>7} {:>7} {:>10} {:>10}\n",
        "engine",
        "n",
        "steps",
        "ns/increment",
        "ns/DOF",
        "limit",
        "ratio",
        "peak RSS",
        "B/DOF",
        "scene",
        "error",
        "predicted"
    );
    // A difference of two timed runs that noise left unresolved (NaN) says so.
    let shown = |x: f64, decimals: usize| {
        if x.is_finite() {
            format!("{x:.decimals$}")
        } else {
            "unresolved".to_string()
        }
    };
    for p in &study.points {
        s += &format!(
            "{:<12} {:>9} {:>7} {:>14} {:>10} {:>10} {:>10} {:>9.1} MB {:>7.0} {:>7.0} {:>10.3e} {:>10.3e}\n",
            p.engine,
            p.n,
            p.steps,
            shown(p.ns_per_step, 0),
            shown(p.ns_per_dof_step, 2),
            shown(p.limit_ns_per_dof_step, 2),
            shown(p.ns_per_dof_step / p.limit_ns_per_dof_step, 2),
            p.peak_rss_bytes as f64 / 1e6,
            p.peak_rss_bytes as f64 / p.n as f64,
            p.scene_rss_bytes as f64 / p.n as f64,
            p.error,
            p.predicted_error
        );
    }
    if study.points.iter().any(|p| !p.ns_per_step.is_finite()) {
        s += &format!(
            "unresolved: after {RETIMINGS} retimings the longer of the two runs was still not slower than the shorter: noise from other work on the machine\n"
        );
    }
    for k in &study.skipped {
        s += &format!("{} at N = {}: not run: {}\n", k.engine, k.n, k.reason);
    }
    for (engine, slope) in exponents(study) {
        s += &format!("{engine}: fitted exponent {slope:.3} over N >= {FIT_FROM_N}\n");
    }
    s
}

/// Each engine's fitted exponent of ns per increment against N over N ≥ [`FIT_FROM_N`].
pub fn exponents(study: &Study) -> Vec<(String, f64)> {
    let mut engines: Vec<&str> = study.points.iter().map(|p| p.engine.as_str()).collect();
    engines.dedup();
    engines
        .into_iter()
        .filter_map(|e| {
            let pts: Vec<(f64, f64)> = study
                .points
                .iter()
                .filter(|p| p.engine == e && p.n >= FIT_FROM_N)
                .map(|p| (p.n as f64, p.ns_per_step))
                .collect();
            Some((e.to_string(), fitted_exponent(&pts)?.0))
        })
        .collect()
}

#[cfg(feature = "figures")]
/// The figure: ns per increment against N, log–log, one marked line per engine (legend: its
/// fitted exponent), and the streaming limit × N as a dashed line; the legend sits lower right,
/// below the lines (every line rises to the right).
pub fn render(study: &Study) -> Option<String> {
    let finite = |x: f64| x.is_finite() && x > 0.0;
    let points: Vec<_> = study
        .points
        .iter()
        .filter(|p| finite(p.ns_per_step) && finite(p.limit_ns_per_dof_step))
        .collect();
    if points.is_empty() {
        return None;
    }
    let ys = points
        .iter()
        .flat_map(|p| [p.ns_per_step, p.limit_ns_per_dof_step * p.n as f64]);
    let (lo, hi) = ys.fold((f64::INFINITY, 0.0f64), |(a, b), y| (a.min(y), b.max(y)));
    let (n0, n1) = points.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.n as f64), b.max(p.n as f64))
    });
    let exponents = exponents(study);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 620)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Cost of one increment against chain size (one thread)",
                ("sans-serif", 22),
            )
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(
                (n0 / 2.0..n1 * 2.0).log_scale(),
                (lo / 3.0..hi * 3.0).log_scale(),
            )
            .ok()?;
        chart
            .configure_mesh()
            .x_desc("N, masses in the chain (free DOFs)")
            .y_desc("wall time per increment [ns]")
            .x_label_formatter(&|x| power_of_ten(*x))
            .y_label_formatter(&|y| power_of_ten(*y))
            .draw()
            .ok()?;
        let colours = [RGBColor(31, 119, 180), RGBColor(214, 39, 40)];
        let mut engines: Vec<&str> = points.iter().map(|p| p.engine.as_str()).collect();
        engines.dedup();
        for (k, engine) in engines.iter().enumerate() {
            let colour = colours[k % colours.len()];
            let line: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.engine == *engine)
                .map(|p| (p.n as f64, p.ns_per_step))
                .collect();
            let mut label = match exponents.iter().find(|(e, _)| e == engine) {
                Some((_, slope)) => {
                    format!("{engine}: fitted exponent {slope:.2} (N ≥ {FIT_FROM_N})")
                }
                None => format!("{engine}: too few points to fit"),
            };
            if let Some(skip) = study.skipped.iter().find(|s| s.engine == *engine) {
                label += &format!(
                    "; N ≥ {} not run (the study's {:.0} s)",
                    skip.n,
                    crate::run::scaling::STUDY_SECONDS
                );
            }
            chart
                .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                .ok()?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(line.iter().map(|p| Circle::new(*p, 4, colour.filled())))
                .ok()?;
        }
        // The limit, measured at every N of the explicit engine.
        let limit: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.engine == engines[0])
            .map(|p| (p.n as f64, p.limit_ns_per_dof_step * p.n as f64))
            .collect();
        let grey = RGBColor(90, 90, 90);
        chart
            .draw_series(DashedLineSeries::new(limit, 6, 4, grey.stroke_width(2)))
            .ok()?
            .label("memory-bandwidth limit: streaming loop, 48 bytes per DOF")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], grey.stroke_width(2)));
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

#[cfg(feature = "figures")]
/// Tick label for a log axis: exact powers of ten as 10 with a superscript exponent, other
/// values with 2 significant figures.
fn power_of_ten(x: f64) -> String {
    let k = x.log10();
    if (k - k.round()).abs() < 1e-9 {
        const SUPERSCRIPT: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
        let k = k.round() as i32;
        let digits: String = k
            .unsigned_abs()
            .to_string()
            .chars()
            .map(|c| SUPERSCRIPT[c.to_digit(10).unwrap_or(0) as usize])
            .collect();
        format!("10{}{digits}", if k < 0 { "⁻" } else { "" })
    } else {
        format!("{x:.2}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::scaling::Point;

    fn point(engine: &str, n: usize, ns: f64) -> Point {
        Point {
            engine: engine.into(),
            n,
            steps: 100,
            repeats: 1,
            ns_per_step: ns,
            ns_per_dof_step: ns / n as f64,
            peak_rss_bytes: 1,
            scene_rss_bytes: 1,
            error: 1e-3,
            predicted_error: 1e-3,
            limit_ns_per_dof_step: 1.0,
        }
    }

    #[test]
    fn the_fitted_exponent_of_a_power_law_is_its_power() {
        // ns = 3 N^1.5 exactly: the fit must return 1.5 to round-off.
        let study = Study {
            points: [10, 1000, 10_000, 100_000]
                .into_iter()
                .map(|n| point("explicit", n, 3.0 * (n as f64).powf(1.5)))
                .collect(),
            skipped: Vec::new(),
        };
        let e = exponents(&study);
        assert_eq!(e.len(), 1);
        assert!((e[0].1 - 1.5).abs() < 1e-12, "{e:?}");
    }

    #[test]
    fn an_unresolved_point_is_said_and_left_out_of_the_fit() {
        let mut points: Vec<Point> = [1000, 10_000, 100_000]
            .into_iter()
            .map(|n| point("explicit", n, 2.0 * n as f64))
            .collect();
        points.push(point("explicit", 1_000_000, f64::NAN));
        let study = Study {
            points,
            skipped: Vec::new(),
        };
        let text = table(&study);
        let last = text.lines().nth(4).unwrap();
        assert!(
            last.contains("1000000") && last.contains("unresolved"),
            "{text}"
        );
        // ns = 2 N over the resolved points: exponent 1.
        let e = exponents(&study);
        assert!((e[0].1 - 1.0).abs() < 1e-12, "{e:?}");
        assert!(csv(&study).lines().nth(4).unwrap().contains(",,"));
    }

    #[test]
    fn the_csv_has_the_issue_columns_and_one_row_per_point() {
        let study = Study {
            points: vec![
                point("explicit", 10, 100.0),
                point("rapier_f64", 10, 5000.0),
            ],
            skipped: Vec::new(),
        };
        let text = csv(&study);
        let mut lines = text.lines();
        assert_eq!(
            lines.next().unwrap(),
            "engine,n,steps,ns_per_step,ns_per_dof_step,peak_rss_bytes,scene_rss_bytes,error,limit_ns_per_dof_step,predicted_error"
        );
        assert_eq!(lines.count(), 2);
        assert!(render(&study).is_some());
    }
}
