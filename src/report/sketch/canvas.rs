//! The canvas a sketch is drawn on: shapes in layers, the obstacles they make, the labels
//! placed where they cover least; and the canvas rendered into an SVG document.

use super::geometry::{Rect, V2, point_segment_distance, segment_distance, v2};
use super::{AREA, HEIGHT, WIDTH};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The layers a sketch is drawn in, bottom to top.
pub(super) const BODY_LAYER: u8 = 0;
pub(super) const ELEMENT_LAYER: u8 = 1;
pub(super) const SUPPORT_LAYER: u8 = 2;
pub(super) const NODE_LAYER: u8 = 3;
pub(super) const MARK_LAYER: u8 = 4;
pub(super) const ARROW_LAYER: u8 = 5;
pub(super) const LABEL_LAYER: u8 = 6;
pub(super) const LEGEND_LAYER: u8 = 7;

/// Something drawn that labels and arrows keep clear of.
#[derive(Debug, Clone, Copy)]
enum Obstacle {
    /// A line segment and its half-width.
    Segment(V2, V2, f64),
    /// A disc.
    Disc(V2, f64),
}

/// One drawing primitive, in pixels.
#[derive(Debug, Clone)]
pub(super) enum Shape {
    Line {
        points: Vec<V2>,
        colour: RGBAColor,
        width: u32,
    },
    Fill {
        points: Vec<V2>,
        colour: RGBAColor,
    },
    Circle {
        centre: V2,
        radius: f64,
        colour: RGBAColor,
        filled: bool,
    },
    Text {
        text: String,
        top_left: V2,
        size: f64,
        colour: RGBAColor,
        bold: bool,
    },
}

/// A label still to be placed near its anchor.
#[derive(Debug, Clone)]
pub(super) struct Label {
    pub(super) text: String,
    pub(super) anchor: V2,
    pub(super) size: f64,
    pub(super) colour: RGBColor,
    pub(super) bold: bool,
    /// Preferred directions from the anchor, tried first (pixel units, any length).
    pub(super) prefer: Vec<V2>,
    /// Try the rectangle centred on the anchor first (a body's name inside the body).
    pub(super) centred: bool,
    /// Placement order: lower first.
    pub(super) priority: u8,
}

impl Label {
    pub(super) fn new(
        text: impl Into<String>,
        anchor: V2,
        colour: RGBColor,
        priority: u8,
    ) -> Label {
        Label {
            text: text.into(),
            anchor,
            size: 13.0,
            colour,
            bold: false,
            prefer: Vec::new(),
            centred: false,
            priority,
        }
    }
    pub(super) fn prefer(mut self, dirs: &[V2]) -> Label {
        self.prefer = dirs.iter().filter_map(|d| d.unit()).collect();
        self
    }
}

/// The estimated box of a text in the SVG backend (which writes font-size = size / 1.24;
/// DejaVu Sans averages about 0.6 em per character).
fn text_size(text: &str, size: f64) -> (f64, f64) {
    (0.5 * size * text.chars().count() as f64 + 2.0, 0.84 * size)
}

/// Shapes in layers, the obstacles they make, and the labels still to place.
pub(super) struct Canvas {
    pub(super) shapes: Vec<(u8, Shape)>,
    obstacles: Vec<Obstacle>,
    labels: Vec<Label>,
    placed: Vec<Rect>,
}

impl Canvas {
    pub(super) fn new() -> Canvas {
        Canvas {
            shapes: Vec::new(),
            obstacles: Vec::new(),
            labels: Vec::new(),
            placed: Vec::new(),
        }
    }

    /// A polyline; an obstacle unless `layer` is the legend's.
    pub(super) fn line(&mut self, layer: u8, points: Vec<V2>, colour: RGBColor, width: u32) {
        if layer != LEGEND_LAYER {
            for w in points.windows(2) {
                self.obstacles
                    .push(Obstacle::Segment(w[0], w[1], width as f64 / 2.0 + 0.5));
            }
        }
        self.shapes.push((
            layer,
            Shape::Line {
                points,
                colour: colour.to_rgba(),
                width,
            },
        ));
    }

    /// A dashed straight line.
    pub(super) fn dashed(&mut self, layer: u8, a: V2, b: V2, colour: RGBColor) {
        let len = (b - a).norm();
        let Some(u) = (b - a).unit() else { return };
        let mut t = 0.0;
        while t < len {
            let e = (t + 5.0).min(len);
            self.line(layer, vec![a + u * t, a + u * e], colour, 1);
            t += 9.0;
        }
    }

    pub(super) fn fill(&mut self, layer: u8, points: Vec<V2>, colour: RGBAColor) {
        self.shapes.push((layer, Shape::Fill { points, colour }));
    }

    pub(super) fn circle(
        &mut self,
        layer: u8,
        centre: V2,
        radius: f64,
        colour: RGBColor,
        filled: bool,
    ) {
        if layer != LEGEND_LAYER {
            self.obstacles.push(Obstacle::Disc(centre, radius + 1.0));
        }
        self.shapes.push((
            layer,
            Shape::Circle {
                centre,
                radius,
                colour: colour.to_rgba(),
                filled,
            },
        ));
    }

    pub(super) fn text(
        &mut self,
        layer: u8,
        text: impl Into<String>,
        top_left: V2,
        size: f64,
        colour: RGBColor,
    ) {
        self.shapes.push((
            layer,
            Shape::Text {
                text: text.into(),
                top_left,
                size,
                colour: colour.to_rgba(),
                bold: false,
            },
        ));
    }

    /// A straight arrow with a filled head at `tip`.
    pub(super) fn arrow(&mut self, layer: u8, tail: V2, tip: V2, colour: RGBColor, width: u32) {
        let Some(u) = (tip - tail).unit() else { return };
        let head = 10.0;
        let base = tip - u * head;
        self.line(layer, vec![tail, base + u * 1.0], colour, width);
        self.fill(
            layer,
            vec![tip, base + u.perp() * 4.5, base - u.perp() * 4.5],
            colour.to_rgba(),
        );
    }

    /// How many obstacles the segment ab comes within `clearance` of.
    pub(super) fn hits(&self, a: V2, b: V2, clearance: f64) -> usize {
        self.obstacles
            .iter()
            .filter(|o| match **o {
                Obstacle::Segment(c, d, w) => segment_distance(a, b, c, d) < w + clearance,
                Obstacle::Disc(c, r) => point_segment_distance(c, a, b) < r + clearance,
            })
            .count()
    }

    pub(super) fn label(&mut self, label: Label) {
        self.labels.push(label);
    }

    /// What a label at `rect` would cover: other labels weigh most, then lines and nodes;
    /// outside the drawing area is not allowed.
    fn cost(&self, rect: &Rect) -> f64 {
        if !rect.inside(&AREA) {
            return f64::INFINITY;
        }
        let labels = self.placed.iter().filter(|p| p.overlaps(rect, 9.0)).count();
        let things = self
            .obstacles
            .iter()
            .filter(|o| match **o {
                Obstacle::Segment(a, b, w) => rect.distance_to_segment(a, b) < w + 1.5,
                Obstacle::Disc(c, r) => rect.distance_to_point(c) < r + 1.5,
            })
            .count();
        100.0 * labels as f64 + 10.0 * things as f64
    }

    /// Place every label, in priority order, at the first free spot near its anchor (or the
    /// least covered one), and draw it on a light backing.
    pub(super) fn place_labels(&mut self) {
        let mut labels = std::mem::take(&mut self.labels);
        labels.sort_by_key(|l| l.priority);
        let compass: Vec<V2> = (0..8)
            .map(|k| {
                let a = std::f64::consts::FRAC_PI_4 * k as f64 - std::f64::consts::FRAC_PI_4;
                v2(a.cos(), a.sin())
            })
            .collect();
        for label in labels {
            let (w, h) = text_size(&label.text, label.size);
            let w = if label.bold { 1.15 * w } else { w };
            let mut candidates = Vec::new();
            if label.centred {
                candidates.push(Rect::centred(label.anchor, w, h));
            }
            for d in [5.0, 10.0, 17.0, 26.0, 38.0, 52.0, 70.0, 92.0] {
                for dir in label.prefer.iter().chain(&compass) {
                    let c = label.anchor + v2(dir.x * (d + w / 2.0), dir.y * (d + h / 2.0));
                    candidates.push(Rect::centred(c, w, h));
                }
            }
            let mut best: Option<(f64, Rect)> = None;
            for (k, rect) in candidates.iter().enumerate() {
                let cost = self.cost(rect) + 1e-3 * k as f64;
                if best.is_none_or(|(c, _)| cost < c) {
                    best = Some((cost, *rect));
                }
                if cost < 1.0 {
                    break;
                }
            }
            let rect = match best {
                Some((c, r)) if c.is_finite() => r,
                _ => {
                    // Nowhere inside the area: clamp the first candidate into it.
                    let mut r = candidates[0];
                    let dx = (AREA.x0 - r.x0).max(0.0) - (r.x1 - AREA.x1).max(0.0);
                    let dy = (AREA.y0 - r.y0).max(0.0) - (r.y1 - AREA.y1).max(0.0);
                    r = Rect {
                        x0: r.x0 + dx,
                        x1: r.x1 + dx,
                        y0: r.y0 + dy,
                        y1: r.y1 + dy,
                    };
                    r
                }
            };
            self.placed.push(rect);
            self.fill(
                LABEL_LAYER,
                vec![
                    v2(rect.x0 - 1.0, rect.y0 - 1.0),
                    v2(rect.x1 + 1.0, rect.y0 - 1.0),
                    v2(rect.x1 + 1.0, rect.y1 + 1.0),
                    v2(rect.x0 - 1.0, rect.y1 + 1.0),
                ],
                WHITE.mix(0.75),
            );
            self.shapes.push((
                LABEL_LAYER,
                Shape::Text {
                    text: label.text,
                    top_left: v2(rect.x0 + 1.0, rect.y0),
                    size: label.size,
                    colour: label.colour.to_rgba(),
                    bold: label.bold,
                },
            ));
        }
    }
}

/// Render the canvas, layer by layer, into an SVG document.
pub(super) fn draw(mut canvas: Canvas) -> Option<String> {
    canvas.shapes.sort_by_key(|(layer, _)| *layer);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).ok()?;
        let pix = |pts: &[V2]| pts.iter().map(|p| p.pixel()).collect::<Vec<_>>();
        for (_, shape) in &canvas.shapes {
            match shape {
                Shape::Line {
                    points,
                    colour,
                    width,
                } => root
                    .draw(&PathElement::new(pix(points), colour.stroke_width(*width)))
                    .ok()?,
                Shape::Fill { points, colour } => root
                    .draw(&Polygon::new(pix(points), colour.filled()))
                    .ok()?,
                Shape::Circle {
                    centre,
                    radius,
                    colour,
                    filled,
                } => {
                    let style = if *filled {
                        colour.filled()
                    } else {
                        colour.stroke_width(2)
                    };
                    root.draw(&Circle::new(centre.pixel(), radius.round() as i32, style))
                        .ok()?
                }
                Shape::Text {
                    text,
                    top_left,
                    size,
                    colour,
                    bold,
                } => {
                    let font = if *bold {
                        ("sans-serif", *size, FontStyle::Bold).into_font()
                    } else {
                        ("sans-serif", *size).into_font()
                    };
                    let style = TextStyle::from(font)
                        .color(colour)
                        .pos(Pos::new(HPos::Left, VPos::Top));
                    root.draw(&Text::new(text.clone(), top_left.pixel(), style))
                        .ok()?
                }
            }
        }
        root.present().ok()?;
    }
    Some(svg)
}
