//! The frame around a sketch: its title, a legend of the symbols it uses, a scale bar and a
//! note of the DOFs held out of the sketch plane.

use super::canvas::{Canvas, LEGEND_LAYER, Shape};
use super::geometry::{V2, v2};
use super::symbols::{Kind, centre_of_mass, element_symbol, support_legend};
use super::view::View;
use super::{AREA, BODY, CONTACT, HEIGHT, INK, LEGEND_X, LOAD, Present, SUPPORT, VELOCITY, WIDTH};
use crate::report::format::tick;
use crate::scene::Scene;
use plotters::prelude::*;

/// A legend row: its text and how its symbol is drawn at a point.
type LegendRow = (&'static str, Box<dyn Fn(&mut Canvas, V2)>);

/// Title, legend, scale bar and the note of DOFs held out of the sketch plane.
pub(super) fn frame(
    canvas: &mut Canvas,
    scene: &Scene,
    view: &View,
    present: &Present,
    out_of_plane: &[String],
) {
    title(canvas, scene);
    legend(canvas, legend_rows(present));
    scale_bar(canvas, view);
    out_of_plane_note(canvas, out_of_plane);
}

/// The scene's id, and its title below it.
fn title(canvas: &mut Canvas, scene: &Scene) {
    let l = LEGEND_LAYER;
    let mut title = Shape::Text {
        text: scene.id.clone(),
        top_left: v2(14.0, 8.0),
        size: 24.0,
        colour: INK.to_rgba(),
        bold: true,
    };
    canvas.shapes.push((l, title.clone()));
    let subtitle = shorten(&scene.title, 130);
    if let Shape::Text {
        text,
        top_left,
        size,
        colour,
        bold,
    } = &mut title
    {
        *text = subtitle;
        *top_left = v2(14.0, 36.0);
        *size = 14.0;
        *colour = SUPPORT.to_rgba();
        *bold = false;
    }
    canvas.shapes.push((l, title));
}

/// The legend's rows: only the symbols the sketch uses.
fn legend_rows(present: &Present) -> Vec<LegendRow> {
    let mut rows: Vec<LegendRow> = Vec::new();
    if present.node {
        rows.push((
            "node",
            Box::new(|c: &mut Canvas, p: V2| c.circle(LEGEND_LAYER, p, 4.0, INK, false)),
        ));
    }
    if present.mass {
        rows.push((
            "node with point mass",
            Box::new(|c: &mut Canvas, p: V2| c.circle(LEGEND_LAYER, p, 5.0, INK, true)),
        ));
    }
    if present.body {
        rows.extend(body_rows());
    }
    rows.extend(element_rows(present));
    rows.extend(arrow_rows(present));
    rows.extend(support_rows(present));
    rows
}

/// The legend's rows for the springs, dashpots and contact faces the sketch draws.
fn element_rows(present: &Present) -> Vec<LegendRow> {
    let mut rows: Vec<LegendRow> = Vec::new();
    if present.spring {
        rows.push((
            "spring",
            Box::new(|c: &mut Canvas, p: V2| {
                element_symbol(
                    c,
                    LEGEND_LAYER,
                    Kind::Spring,
                    p - v2(16.0, 0.0),
                    p + v2(16.0, 0.0),
                )
            }),
        ));
    }
    if present.dashpot {
        rows.push((
            "dashpot",
            Box::new(|c: &mut Canvas, p: V2| {
                element_symbol(
                    c,
                    LEGEND_LAYER,
                    Kind::Dashpot,
                    p - v2(16.0, 0.0),
                    p + v2(16.0, 0.0),
                )
            }),
        ));
    }
    if present.contact {
        rows.push((
            "contact face, normal",
            Box::new(|c: &mut Canvas, p: V2| {
                c.line(
                    LEGEND_LAYER,
                    vec![p + v2(-6.0, -9.0), p + v2(-6.0, 9.0)],
                    CONTACT,
                    4,
                );
                c.arrow(
                    LEGEND_LAYER,
                    p + v2(-4.0, 0.0),
                    p + v2(14.0, 0.0),
                    CONTACT,
                    2,
                );
            }),
        ));
    }
    rows
}

/// The legend's rows for the loads and initial velocities the sketch draws.
fn arrow_rows(present: &Present) -> Vec<LegendRow> {
    let mut rows: Vec<LegendRow> = Vec::new();
    if present.load {
        rows.push((
            "load (magnitude)",
            Box::new(|c: &mut Canvas, p: V2| {
                c.arrow(LEGEND_LAYER, p - v2(16.0, 0.0), p + v2(16.0, 0.0), LOAD, 3)
            }),
        ));
    }
    if present.velocity {
        rows.push((
            "initial velocity",
            Box::new(|c: &mut Canvas, p: V2| {
                c.arrow(
                    LEGEND_LAYER,
                    p - v2(16.0, 0.0),
                    p + v2(16.0, 0.0),
                    VELOCITY,
                    2,
                )
            }),
        ));
    }
    rows
}

/// The legend's rows for the supports the sketch draws.
fn support_rows(present: &Present) -> Vec<LegendRow> {
    let mut rows: Vec<LegendRow> = Vec::new();
    if present.pin {
        rows.push((
            "held (pin)",
            Box::new(|c: &mut Canvas, p: V2| support_legend(c, p, false)),
        ));
    }
    if present.roller {
        rows.push((
            "held along triangle axis",
            Box::new(|c: &mut Canvas, p: V2| support_legend(c, p, true)),
        ));
    }
    rows
}

/// The legend's rows for a rigid body: its outline, its reference node, its centre of mass.
fn body_rows() -> Vec<LegendRow> {
    let mut rows: Vec<LegendRow> = Vec::new();
    rows.push((
        "rigid body (its nodes)",
        Box::new(|c: &mut Canvas, p: V2| {
            let pts = vec![
                p + v2(-14.0, -7.0),
                p + v2(14.0, -7.0),
                p + v2(14.0, 7.0),
                p + v2(-14.0, 7.0),
            ];
            c.fill(LEGEND_LAYER, pts.clone(), BODY.mix(0.13));
            let mut closed = pts.clone();
            closed.push(pts[0]);
            c.line(LEGEND_LAYER, closed, BODY, 2);
        }),
    ));
    rows.push((
        "reference node",
        Box::new(|c: &mut Canvas, p: V2| {
            let r = 7.0;
            c.line(
                LEGEND_LAYER,
                vec![
                    p + v2(-r, -r),
                    p + v2(r, -r),
                    p + v2(r, r),
                    p + v2(-r, r),
                    p + v2(-r, -r),
                ],
                BODY,
                2,
            );
        }),
    ));
    rows.push((
        "centre of mass",
        Box::new(|c: &mut Canvas, p: V2| centre_of_mass(c, LEGEND_LAYER, p)),
    ));
    rows
}

/// The legend: a box right of the drawing, headed "Legend", one row per symbol.
fn legend(canvas: &mut Canvas, rows: Vec<LegendRow>) {
    let l = LEGEND_LAYER;
    let x = LEGEND_X;
    let mut y = 70.0;
    // Supports are taller than the other symbols.
    let row = |text: &str| if text.starts_with("held") { 38.0 } else { 26.0 };
    let height = 22.0 + rows.iter().map(|(t, _)| row(t)).sum::<f64>();
    let boxed = vec![
        v2(x, y - 22.0),
        v2(WIDTH as f64 - 6.0, y - 22.0),
        v2(WIDTH as f64 - 6.0, y - 22.0 + height),
        v2(x, y - 22.0 + height),
        v2(x, y - 22.0),
    ];
    canvas.line(l, boxed, RGBColor(180, 180, 180), 1);
    canvas.text(l, "Legend", v2(x + 8.0, y - 17.0), 13.0, SUPPORT);
    y += 8.0;
    for (text, symbol) in rows {
        let h = row(text);
        let mid = y + (h - 26.0) / 2.0;
        symbol(canvas, v2(x + 24.0, mid));
        canvas.text(l, text, v2(x + 46.0, mid - 6.0), 13.0, INK);
        y += h;
    }
}

/// Scale bar: a round length of about 100 px, and the sketch plane named beside it.
fn scale_bar(canvas: &mut Canvas, view: &View) {
    let l = LEGEND_LAYER;
    let target = 100.0 / view.scale;
    if target.is_finite() && target > 0.0 {
        let p10 = 10f64.powf(target.log10().floor());
        let length = [5.0, 2.0, 1.0]
            .into_iter()
            .map(|m| m * p10)
            .find(|len| *len <= target)
            .unwrap_or(p10);
        let w = length * view.scale;
        let (x0, y0) = (AREA.x0 + 8.0, HEIGHT as f64 - 18.0);
        canvas.line(l, vec![v2(x0, y0), v2(x0 + w, y0)], INK, 2);
        for xe in [x0, x0 + w] {
            canvas.line(l, vec![v2(xe, y0 - 5.0), v2(xe, y0 + 5.0)], INK, 2);
        }
        canvas.text(
            l,
            format!("{} m", tick(length, length)),
            v2(x0 + w + 8.0, y0 - 7.0),
            13.0,
            INK,
        );
        let axis = ["x", "y", "z"];
        canvas.text(
            l,
            format!("sketch plane {}–{}", axis[view.a], axis[view.b]),
            v2(x0 + w + 70.0, y0 - 7.0),
            12.0,
            SUPPORT,
        );
    }
}

/// The note of DOFs held out of the sketch plane, if any, under the drawing.
fn out_of_plane_note(canvas: &mut Canvas, out_of_plane: &[String]) {
    let l = LEGEND_LAYER;
    if !out_of_plane.is_empty() {
        let note = shorten(
            &format!("held out of plane: {}", out_of_plane.join("; ")),
            62,
        );
        canvas.text(
            l,
            note,
            v2(LEGEND_X - 8.0 - 0.5 * 12.0 * 38.0, HEIGHT as f64 - 25.0),
            12.0,
            SUPPORT,
        );
    }
}

/// At most `n` characters, with an ellipsis when cut.
fn shorten(text: &str, n: usize) -> String {
    if text.chars().count() <= n {
        text.to_string()
    } else {
        text.chars().take(n - 1).collect::<String>() + "…"
    }
}
