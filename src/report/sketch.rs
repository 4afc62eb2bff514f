//! A sketch of a scene, drawn from the [`Scene`] itself (not from a picture of the source
//! problem): nodes, rigid bodies, springs and dashpots, contact faces, loads, initial velocities
//! and the DOFs held during the run, with a legend and a scale bar, as one SVG document.
//!
//! The scene is projected onto its x–y plane (a 3D scene too; when its x–y extent is degenerate
//! but its z extent is not, onto the two axes of largest extent). Geometry is placed at scale;
//! symbols (grounded elements, supports, arrows) have fixed pixel sizes, and the scale is chosen
//! so that both fit. Labels are placed greedily where they cover no other label, line or node.

use crate::report::format::tick;
use crate::scene::{
    Attachment, BodyId, Connection, Dimension, Dof, Element, NodeId, Scene, Solid, StepKind,
    Surface,
};
use nalgebra::Vector3;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::{Add, Mul, Neg, Sub};

/// Size of the sketch in pixels.
const WIDTH: u32 = 800;
/// Height of the sketch in pixels.
const HEIGHT: u32 = 500;
/// Left edge of the legend column (everything right of it is legend, never drawing).
const LEGEND_X: f64 = 604.0;
/// The drawing area (pixels): between the title and the scale bar, left of the legend.
const AREA: Rect = Rect {
    x0: 14.0,
    y0: 62.0,
    x1: 592.0,
    y1: 466.0,
};
/// Length of a grounded element, from its node to the ground hatch (pixels).
const GROUNDED_LENGTH: f64 = 100.0;
/// Length of a load arrow (pixels).
const LOAD_LENGTH: f64 = 60.0;
/// Length of an initial-velocity arrow (pixels).
const VELOCITY_LENGTH: f64 = 50.0;
/// Length of a contact face segment (pixels).
const FACE_LENGTH: f64 = 84.0;
/// Two-node elements shorter than this (pixels) are drawn as a loop of this length.
const MIN_LINK: f64 = 40.0;
/// Spacing of elements drawn in parallel between the same ends (pixels).
const PARALLEL_SPACING: f64 = 22.0;

const INK: RGBColor = RGBColor(30, 30, 30);
const BODY: RGBColor = RGBColor(31, 119, 180);
const SPRING: RGBColor = RGBColor(140, 86, 75);
const DASHPOT: RGBColor = RGBColor(148, 103, 189);
const CONTACT: RGBColor = RGBColor(230, 120, 0);
const LOAD: RGBColor = RGBColor(214, 39, 40);
const VELOCITY: RGBColor = RGBColor(44, 160, 44);
const SUPPORT: RGBColor = RGBColor(90, 90, 90);

/// A point or direction in pixels (y down).
#[derive(Debug, Clone, Copy, PartialEq)]
struct V2 {
    x: f64,
    y: f64,
}

fn v2(x: f64, y: f64) -> V2 {
    V2 { x, y }
}

impl Add for V2 {
    type Output = V2;
    fn add(self, o: V2) -> V2 {
        v2(self.x + o.x, self.y + o.y)
    }
}

impl Sub for V2 {
    type Output = V2;
    fn sub(self, o: V2) -> V2 {
        v2(self.x - o.x, self.y - o.y)
    }
}

impl Mul<f64> for V2 {
    type Output = V2;
    fn mul(self, k: f64) -> V2 {
        v2(self.x * k, self.y * k)
    }
}

impl Neg for V2 {
    type Output = V2;
    fn neg(self) -> V2 {
        v2(-self.x, -self.y)
    }
}

impl V2 {
    fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    fn dot(self, o: V2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    fn cross(self, o: V2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Rotated a quarter turn (in pixel coordinates).
    fn perp(self) -> V2 {
        v2(-self.y, self.x)
    }
    fn unit(self) -> Option<V2> {
        let n = self.norm();
        (n > 1e-9 && n.is_finite()).then(|| self * (1.0 / n))
    }
    fn pixel(self) -> (i32, i32) {
        (self.x.round() as i32, self.y.round() as i32)
    }
}

/// An axis-aligned rectangle in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Rect {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Rect {
    fn centred(c: V2, w: f64, h: f64) -> Rect {
        Rect {
            x0: c.x - w / 2.0,
            y0: c.y - h / 2.0,
            x1: c.x + w / 2.0,
            y1: c.y + h / 2.0,
        }
    }
    fn overlaps(&self, o: &Rect, pad: f64) -> bool {
        self.x0 < o.x1 + pad && o.x0 < self.x1 + pad && self.y0 < o.y1 + pad && o.y0 < self.y1 + pad
    }
    fn inside(&self, outer: &Rect) -> bool {
        self.x0 >= outer.x0 && self.x1 <= outer.x1 && self.y0 >= outer.y0 && self.y1 <= outer.y1
    }
    fn contains(&self, p: V2) -> bool {
        p.x >= self.x0 && p.x <= self.x1 && p.y >= self.y0 && p.y <= self.y1
    }
    fn distance_to_point(&self, p: V2) -> f64 {
        let dx = (self.x0 - p.x).max(p.x - self.x1).max(0.0);
        let dy = (self.y0 - p.y).max(p.y - self.y1).max(0.0);
        dx.hypot(dy)
    }
    fn corners(&self) -> [V2; 4] {
        [
            v2(self.x0, self.y0),
            v2(self.x1, self.y0),
            v2(self.x1, self.y1),
            v2(self.x0, self.y1),
        ]
    }
    fn distance_to_segment(&self, a: V2, b: V2) -> f64 {
        if self.contains(a) || self.contains(b) {
            return 0.0;
        }
        let c = self.corners();
        let mut d = self.distance_to_point(a).min(self.distance_to_point(b));
        for k in 0..4 {
            d = d.min(segment_distance(a, b, c[k], c[(k + 1) % 4]));
        }
        d
    }
}

fn point_segment_distance(p: V2, a: V2, b: V2) -> f64 {
    let ab = b - a;
    let len2 = ab.dot(ab);
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// Distance between segments ab and cd (zero when they cross).
fn segment_distance(a: V2, b: V2, c: V2, d: V2) -> f64 {
    let (d1, d2) = ((b - a).cross(c - a), (b - a).cross(d - a));
    let (d3, d4) = ((d - c).cross(a - c), (d - c).cross(b - c));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    point_segment_distance(a, c, d)
        .min(point_segment_distance(b, c, d))
        .min(point_segment_distance(c, a, b))
        .min(point_segment_distance(d, a, b))
}

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
enum Shape {
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
struct Label {
    text: String,
    anchor: V2,
    size: f64,
    colour: RGBColor,
    bold: bool,
    /// Preferred directions from the anchor, tried first (pixel units, any length).
    prefer: Vec<V2>,
    /// Try the rectangle centred on the anchor first (a body's name inside the body).
    centred: bool,
    /// Placement order: lower first.
    priority: u8,
}

impl Label {
    fn new(text: impl Into<String>, anchor: V2, colour: RGBColor, priority: u8) -> Label {
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
    fn prefer(mut self, dirs: &[V2]) -> Label {
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
struct Canvas {
    shapes: Vec<(u8, Shape)>,
    obstacles: Vec<Obstacle>,
    labels: Vec<Label>,
    placed: Vec<Rect>,
}

impl Canvas {
    fn new() -> Canvas {
        Canvas {
            shapes: Vec::new(),
            obstacles: Vec::new(),
            labels: Vec::new(),
            placed: Vec::new(),
        }
    }

    /// A polyline; an obstacle unless `layer` is the legend's.
    fn line(&mut self, layer: u8, points: Vec<V2>, colour: RGBColor, width: u32) {
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
    fn dashed(&mut self, layer: u8, a: V2, b: V2, colour: RGBColor) {
        let len = (b - a).norm();
        let Some(u) = (b - a).unit() else { return };
        let mut t = 0.0;
        while t < len {
            let e = (t + 5.0).min(len);
            self.line(layer, vec![a + u * t, a + u * e], colour, 1);
            t += 9.0;
        }
    }

    fn fill(&mut self, layer: u8, points: Vec<V2>, colour: RGBAColor) {
        self.shapes.push((layer, Shape::Fill { points, colour }));
    }

    fn circle(&mut self, layer: u8, centre: V2, radius: f64, colour: RGBColor, filled: bool) {
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

    fn text(
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
    fn arrow(&mut self, layer: u8, tail: V2, tip: V2, colour: RGBColor, width: u32) {
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
    fn hits(&self, a: V2, b: V2, clearance: f64) -> usize {
        self.obstacles
            .iter()
            .filter(|o| match **o {
                Obstacle::Segment(c, d, w) => segment_distance(a, b, c, d) < w + clearance,
                Obstacle::Disc(c, r) => point_segment_distance(c, a, b) < r + clearance,
            })
            .count()
    }

    fn label(&mut self, label: Label) {
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
    fn place_labels(&mut self) {
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

const BODY_LAYER: u8 = 0;
const ELEMENT_LAYER: u8 = 1;
const SUPPORT_LAYER: u8 = 2;
const NODE_LAYER: u8 = 3;
const MARK_LAYER: u8 = 4;
const ARROW_LAYER: u8 = 5;
const LABEL_LAYER: u8 = 6;
const LEGEND_LAYER: u8 = 7;

/// The projection from the scene to pixels: world axes `a` (right) and `b` (up).
struct View {
    a: usize,
    b: usize,
    /// Pixels per length unit.
    scale: f64,
    /// Pixel position of the world origin.
    origin: V2,
}

impl View {
    fn px(&self, p: &Vector3<f64>) -> V2 {
        self.origin + v2(p[self.a], -p[self.b]) * self.scale
    }
    /// A world direction on screen: unit, or `None` when it is (nearly) out of the plane.
    fn dir(&self, d: &Vector3<f64>) -> Option<V2> {
        let n = d.norm();
        let s = v2(d[self.a], -d[self.b]);
        if n > 0.0 && s.norm() > 1e-6 * n {
            s.unit()
        } else {
            None
        }
    }
    /// +1 when a positive rotation about the out-of-plane axis turns counter-clockwise on
    /// screen, −1 otherwise.
    fn handedness(&self) -> f64 {
        if self.b == self.a + 1 { 1.0 } else { -1.0 }
    }
    fn normal_axis(&self) -> usize {
        3 - self.a - self.b
    }
}

/// The two world axes drawn: x and y, unless the scene's x–y extent is degenerate and its z
/// extent is not (then the two of largest extent).
fn axes(points: &[Vector3<f64>]) -> (usize, usize) {
    let mut span = [0.0f64; 3];
    let mut size = 1.0f64;
    for i in 0..3 {
        let lo = points.iter().map(|p| p[i]).fold(f64::INFINITY, f64::min);
        let hi = points
            .iter()
            .map(|p| p[i])
            .fold(f64::NEG_INFINITY, f64::max);
        if hi >= lo {
            span[i] = hi - lo;
            size = size.max(lo.abs()).max(hi.abs());
        }
    }
    let tol = 1e-9 * size;
    if span[0].min(span[1]) > tol || span[2] <= span[0].min(span[1]).max(tol) {
        return (0, 1);
    }
    let mut order = [0, 1, 2];
    order.sort_by(|i, j| span[*j].total_cmp(&span[*i]));
    (order[0].min(order[1]), order[0].max(order[1]))
}

/// Choose the scale and origin so that every reach (a world point plus a pixel offset) lies in
/// the drawing area: the largest scale that fits, at most the one that fills the area with the
/// world extent alone.
fn fit(a: usize, b: usize, reach: &[(Vector3<f64>, V2)], world: &[Vector3<f64>]) -> View {
    let (w, h) = (AREA.x1 - AREA.x0 - 8.0, AREA.y1 - AREA.y0 - 8.0);
    let coords = |i: usize| world.iter().map(move |p| p[i]);
    let span = |i: usize| {
        let lo = coords(i).fold(f64::INFINITY, f64::min);
        let hi = coords(i).fold(f64::NEG_INFINITY, f64::max);
        if hi >= lo { hi - lo } else { 0.0 }
    };
    let size = world
        .iter()
        .map(|p| p[a].abs().max(p[b].abs()))
        .fold(1.0, f64::max);
    let tol = 1e-9 * size;
    let (sa, sb) = (span(a), span(b));
    let s_max = match (sa > tol, sb > tol) {
        (true, true) => (w / sa).min(h / sb),
        (true, false) => w / sa,
        (false, true) => h / sb,
        (false, false) => 0.5 * w.min(h) / size,
    };
    let ranges = |s: f64| {
        let mut r = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for (p, d) in reach {
            let (x, y) = (s * p[a] + d.x, -s * p[b] + d.y);
            r = [r[0].min(x), r[1].max(x), r[2].min(y), r[3].max(y)];
        }
        r
    };
    let fits = |s: f64| {
        let r = ranges(s);
        r[1] - r[0] <= w && r[3] - r[2] <= h
    };
    let scale = if fits(s_max) {
        s_max
    } else if fits(0.0) {
        let (mut lo, mut hi) = (0.0, s_max);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if fits(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    } else {
        0.2 * s_max
    };
    let scale = if scale > 0.0 && scale.is_finite() {
        scale
    } else {
        s_max.max(1e-300)
    };
    let r = ranges(scale);
    let centre = v2(0.5 * (AREA.x0 + AREA.x1), 0.5 * (AREA.y0 + AREA.y1));
    let origin = if r[0].is_finite() && r[2].is_finite() {
        centre - v2(0.5 * (r[0] + r[1]), 0.5 * (r[2] + r[3]))
    } else {
        centre
    };
    View {
        a,
        b,
        scale,
        origin,
    }
}

/// Convex hull (counter-clockwise in pixel coordinates) of a set of points.
fn hull(points: &[V2]) -> Vec<V2> {
    let mut p: Vec<V2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup_by(|a, b| (*a - *b).norm() < 0.5);
    if p.len() < 3 {
        return p;
    }
    let mut lower: Vec<V2> = Vec::new();
    for q in &p {
        while lower.len() >= 2
            && (lower[lower.len() - 1] - lower[lower.len() - 2]).cross(*q - lower[lower.len() - 2])
                <= 0.0
        {
            lower.pop();
        }
        lower.push(*q);
    }
    let mut upper: Vec<V2> = Vec::new();
    for q in p.iter().rev() {
        while upper.len() >= 2
            && (upper[upper.len() - 1] - upper[upper.len() - 2]).cross(*q - upper[upper.len() - 2])
                <= 0.0
        {
            upper.pop();
        }
        upper.push(*q);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

fn polygon_area(p: &[V2]) -> f64 {
    (0..p.len())
        .map(|i| p[i].cross(p[(i + 1) % p.len()]))
        .sum::<f64>()
        .abs()
        / 2.0
}

fn inside_polygon(p: V2, poly: &[V2]) -> bool {
    if poly.len() < 3 {
        return false;
    }
    let mut sign = 0.0;
    for i in 0..poly.len() {
        let c = (poly[(i + 1) % poly.len()] - poly[i]).cross(p - poly[i]);
        if c.abs() < 1e-9 {
            continue;
        }
        if sign == 0.0 {
            sign = c.signum();
        } else if c.signum() != sign {
            return false;
        }
    }
    true
}

/// Which element symbol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Spring,
    Dashpot,
}

impl Kind {
    fn colour(self) -> RGBColor {
        match self {
            Kind::Spring => SPRING,
            Kind::Dashpot => DASHPOT,
        }
    }
}

/// A zig-zag from a to b (leads of 15 % at each end).
fn zigzag(a: V2, b: V2) -> Vec<V2> {
    let len = (b - a).norm();
    let Some(u) = (b - a).unit() else {
        return vec![a, b];
    };
    let n = u.perp();
    let lead = (0.15 * len).min(12.0);
    let waves = ((len - 2.0 * lead) / 6.0).round().clamp(4.0, 40.0) as usize;
    let step = (len - 2.0 * lead) / waves as f64;
    let mut pts = vec![a, a + u * lead];
    for k in 0..waves {
        let side = if k % 2 == 0 { 6.0 } else { -6.0 };
        pts.push(a + u * (lead + step * (k as f64 + 0.5)) + n * side);
    }
    pts.push(b - u * lead);
    pts.push(b);
    pts
}

/// A dashpot from a to b: rod, open cylinder, piston and rod.
fn dashpot(canvas: &mut Canvas, layer: u8, a: V2, b: V2, colour: RGBColor) {
    let len = (b - a).norm();
    let Some(u) = (b - a).unit() else { return };
    let n = u.perp();
    let r = 7.0;
    let cup = (0.5 * len).min(26.0);
    let c0 = a + u * (0.5 * len - 0.6 * cup);
    let c1 = c0 + u * cup;
    canvas.line(layer, vec![a, c0], colour, 2);
    canvas.line(
        layer,
        vec![c1 + n * r, c0 + n * r, c0 - n * r, c1 - n * r],
        colour,
        2,
    );
    let p = c0 + u * (0.55 * cup);
    canvas.line(layer, vec![p + n * (r - 2.5), p - n * (r - 2.5)], colour, 3);
    canvas.line(layer, vec![p, b], colour, 2);
}

fn element_symbol(canvas: &mut Canvas, layer: u8, kind: Kind, a: V2, b: V2) {
    match kind {
        Kind::Spring => canvas.line(layer, zigzag(a, b), SPRING, 2),
        Kind::Dashpot => dashpot(canvas, layer, a, b, DASHPOT),
    }
}

/// Hatch of a ground: a line across `dir` at `at`, with short ticks on the far side.
fn ground(canvas: &mut Canvas, layer: u8, at: V2, dir: V2, half: f64) {
    let n = dir.perp();
    canvas.line(layer, vec![at + n * half, at - n * half], SUPPORT, 2);
    let ticks = ((2.0 * half) / 6.0).floor().max(2.0) as usize;
    for k in 0..=ticks {
        let p = at + n * (-half + 2.0 * half * k as f64 / ticks as f64);
        canvas.line(layer, vec![p, p + dir * 6.0 - n * 5.0], SUPPORT, 1);
    }
}

/// Elements in parallel from `p0` to `p1` (pixels): centred side by side, joined by bars at
/// both ends. Returns each element's mid point and its side (for its label).
fn parallel(canvas: &mut Canvas, p0: V2, p1: V2, group: &[(Kind, &str)]) -> Vec<(V2, V2)> {
    let len = (p1 - p0).norm();
    let u = (p1 - p0).unit().unwrap_or(v2(1.0, 0.0));
    let n = u.perp();
    let k = group.len();
    let lead = if k > 1 { (0.18 * len).min(18.0) } else { 0.0 };
    let offset = |j: usize| (j as f64 - (k as f64 - 1.0) / 2.0) * PARALLEL_SPACING;
    let (a, b) = (p0 + u * lead, p1 - u * lead);
    if k > 1 {
        canvas.line(ELEMENT_LAYER, vec![p0, a], INK, 2);
        canvas.line(ELEMENT_LAYER, vec![b, p1], INK, 2);
        let (lo, hi) = (offset(0), offset(k - 1));
        canvas.line(ELEMENT_LAYER, vec![a + n * lo, a + n * hi], INK, 2);
        canvas.line(ELEMENT_LAYER, vec![b + n * lo, b + n * hi], INK, 2);
    }
    group
        .iter()
        .enumerate()
        .map(|(j, (kind, _))| {
            let o = offset(j);
            element_symbol(canvas, ELEMENT_LAYER, *kind, a + n * o, b + n * o);
            let side = if o < 0.0 { -n } else { n };
            ((a + b) * 0.5 + n * o, side)
        })
        .collect()
}

/// The ends of an element group between two nodes, as drawn: straight between the nodes, or,
/// when they are closer than [`MIN_LINK`] pixels, a loop out along `out` and back.
fn link(canvas: &mut Canvas, p0: V2, p1: V2, out: V2, group: &[(Kind, &str)]) -> Vec<(V2, V2)> {
    if (p1 - p0).norm() >= MIN_LINK {
        return parallel(canvas, p0, p1, group);
    }
    let n = out.perp();
    let lift = 16.0 + PARALLEL_SPACING * (group.len() as f64 - 1.0) / 2.0;
    let length = 70.0;
    let a = p0 - n * lift;
    let b = a + out * length;
    let c = p1 + out * length;
    canvas.line(ELEMENT_LAYER, vec![p0, a], INK, 1);
    let mids = parallel(canvas, a, b, group);
    canvas.line(ELEMENT_LAYER, vec![b, c], INK, 1);
    canvas.dashed(ELEMENT_LAYER, c, p1, INK);
    mids
}

/// The conditions holding during the run: those of the first dynamic step (else the last).
fn run_conditions(scene: &Scene) -> Vec<crate::scene::BoundaryCondition> {
    scene
        .steps
        .iter()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .or(scene.steps.last())
        .map(|s| s.conditions.clone())
        .unwrap_or_default()
}

/// The nodes of a body: its reference node and the nodes on it.
fn body_nodes(scene: &Scene, body: BodyId) -> Vec<NodeId> {
    scene
        .nodes
        .iter()
        .enumerate()
        .filter(|(i, n)| match n.attachment {
            Attachment::Reference(b) => b == body || scene.bodies[body].reference == *i,
            Attachment::OnBody(b) => b == body,
            Attachment::Free => scene.bodies[body].reference == *i,
        })
        .map(|(i, _)| i)
        .collect()
}

/// Which legend entries the scene needs.
#[derive(Default)]
struct Present {
    node: bool,
    mass: bool,
    body: bool,
    spring: bool,
    dashpot: bool,
    contact: bool,
    load: bool,
    velocity: bool,
    pin: bool,
    roller: bool,
}

/// Points on a contact surface's outline in the x–y plane through its anchor (a plane: its
/// point only).
fn outline(surface: &Surface) -> Vec<Vector3<f64>> {
    let Surface::Solid { solid, centre } = surface else {
        return vec![surface.anchor()];
    };
    let centre = *centre;
    let arc = |at: Vector3<f64>, radius: f64, from: f64, to: f64| {
        (0..=16).map(move |i| {
            let a = from + (to - from) * f64::from(i) / 16.0;
            at + Vector3::new(a.cos(), a.sin(), 0.0) * radius
        })
    };
    let pi = std::f64::consts::PI;
    match *solid {
        Solid::Convex { ref polytope } => polytope.outline().iter().map(|c| centre + c).collect(),
        Solid::Ball { radius } => arc(centre, radius, 0.0, 2.0 * pi).take(16).collect(),
        Solid::Cuboid { half_extents: h } => [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
            .iter()
            .map(|(x, y)| centre + Vector3::new(x * h.x, y * h.y, 0.0))
            .collect(),
        Solid::Capsule {
            half_height,
            radius,
        } => {
            let up = Vector3::new(0.0, half_height, 0.0);
            arc(centre + up, radius, 0.0, pi)
                .chain(arc(centre - up, radius, pi, 2.0 * pi))
                .collect()
        }
    }
}

/// A sketch of a scene drawn from the `Scene` itself: nodes (filled where they carry a point
/// mass), rigid bodies (outline of their nodes, reference node and centre of mass), springs and
/// dashpots, contact faces, loads, initial velocities and the DOFs held during the run, with a
/// title, a legend and a scale bar. An SVG document of about 800×500 px; `None` if the scene
/// has no nodes.
pub fn render(scene: &Scene) -> Option<String> {
    if scene.nodes.is_empty() {
        return None;
    }
    let com = |b: &crate::scene::RigidBody| {
        scene
            .nodes
            .get(b.reference)
            .map(|r| r.position + b.centre_offset)
    };
    let node = |i: NodeId| scene.nodes.get(i);
    let mut world: Vec<Vector3<f64>> = scene.nodes.iter().map(|n| n.position).collect();
    world.extend(scene.contacts.iter().flat_map(|c| outline(&c.surface)));
    world.extend(scene.bodies.iter().filter_map(com));
    let (a, b) = axes(&world);
    let proto = View {
        a,
        b,
        scale: 1.0,
        origin: v2(0.0, 0.0),
    };

    // What reaches beyond the geometry by a fixed number of pixels.
    let mut reach: Vec<(Vector3<f64>, V2)> = Vec::new();
    for p in &world {
        for d in [
            v2(34.0, 24.0),
            v2(-34.0, -24.0),
            v2(34.0, -24.0),
            v2(-34.0, 24.0),
        ] {
            reach.push((*p, d));
        }
    }
    let grounded = scene.springs.iter().chain(&scene.dashpots);
    for e in grounded {
        if let Connection::Grounded { node: i, dof } = e.connection
            && let Some(n) = node(i)
        {
            let d = ground_direction(&proto, n, dof);
            reach.push((n.position, -d * (GROUNDED_LENGTH + 18.0)));
        }
    }
    for l in &scene.loads {
        if let (Some(n), Some(d)) = (node(l.node), proto.dir(&l.force)) {
            reach.push((n.position, d * (LOAD_LENGTH + 24.0)));
            reach.push((n.position, -d * (LOAD_LENGTH + 24.0)));
        }
    }
    for v in &scene.initial_velocities {
        if let (Some(n), Some(d)) = (node(v.node), proto.dir(&v.velocity)) {
            reach.push((n.position, d * (VELOCITY_LENGTH + 24.0)));
        }
    }
    for c in &scene.contacts {
        if let Some((point, normal)) = c.plane()
            && let Some(nd) = proto.dir(&normal)
        {
            let t = nd.perp();
            for s in [-1.0, 1.0] {
                reach.push((point, t * (s * FACE_LENGTH / 2.0) + nd * 30.0));
            }
        }
    }
    let view = fit(a, b, &reach, &world);
    let px = |i: NodeId| node(i).map(|n| view.px(&n.position));

    let mut canvas = Canvas::new();
    let mut present = Present::default();
    let mut hulls: Vec<Vec<V2>> = Vec::new();

    // Rigid bodies: the outline of their nodes (and contact face points), lightly filled.
    for (k, body) in scene.bodies.iter().enumerate() {
        present.body = true;
        let mut pts: Vec<V2> = body_nodes(scene, k).into_iter().filter_map(px).collect();
        pts.extend(
            scene
                .contacts
                .iter()
                .filter(|c| c.body == k)
                .flat_map(|c| outline(&c.surface))
                .map(|p| view.px(&p)),
        );
        let mut outline = hull(&pts);
        if outline.len() < 3 || polygon_area(&outline) < 40.0 {
            // Degenerate (a point or a line): a rounded band around it.
            let ring: Vec<V2> = outline
                .iter()
                .flat_map(|p| {
                    (0..16).map(move |j| {
                        let t = std::f64::consts::TAU * j as f64 / 16.0;
                        *p + v2(t.cos(), t.sin()) * 12.0
                    })
                })
                .collect();
            outline = hull(&ring);
        }
        if outline.len() >= 3 {
            canvas.fill(BODY_LAYER, outline.clone(), BODY.mix(0.13));
            let mut closed = outline.clone();
            closed.push(outline[0]);
            canvas.line(BODY_LAYER, closed, BODY, 2);
            let centroid =
                outline.iter().fold(v2(0.0, 0.0), |s, p| s + *p) * (1.0 / outline.len() as f64);
            let mut label = Label::new(body.name.clone(), centroid, BODY, 0);
            label.bold = true;
            label.size = 15.0;
            label.centred = true;
            canvas.label(label);
            hulls.push(outline);
        }
    }

    // Springs and dashpots between two nodes, grouped by their (unordered) pair of nodes.
    let elements: Vec<(Kind, &Element)> = scene
        .springs
        .iter()
        .map(|e| (Kind::Spring, e))
        .chain(scene.dashpots.iter().map(|e| (Kind::Dashpot, e)))
        .collect();
    let mut pairs: Vec<Pair> = Vec::new();
    let mut grounds: Vec<(NodeId, Dof, Group)> = Vec::new();
    for (kind, e) in &elements {
        match kind {
            Kind::Spring => present.spring = true,
            Kind::Dashpot => present.dashpot = true,
        }
        match &e.connection {
            Connection::FixedDirection { nodes, direction } => {
                add_pair(&mut pairs, *nodes, *direction, *kind, &e.name)
            }
            Connection::Axial { nodes } => {
                let d = match (node(nodes[0]), node(nodes[1])) {
                    (Some(p), Some(q)) => q.position - p.position,
                    _ => Vector3::x(),
                };
                add_pair(&mut pairs, *nodes, d, *kind, &e.name)
            }
            Connection::Grounded { node: i, dof } => {
                match grounds.iter_mut().find(|g| g.0 == *i && g.1 == *dof) {
                    Some(g) => g.2.push((*kind, &e.name)),
                    None => grounds.push((*i, *dof, vec![(*kind, &e.name)])),
                }
            }
        }
    }
    for (nodes, direction, group) in &pairs {
        let (Some(p0), Some(p1)) = (px(nodes[0]), px(nodes[1])) else {
            continue;
        };
        let out = view.dir(direction).unwrap_or(v2(1.0, 0.0));
        let mids = link(&mut canvas, p0, p1, out, group);
        for ((kind, name), (mid, side)) in group.iter().zip(mids) {
            canvas.label(Label::new(*name, mid, kind.colour(), 2).prefer(&[side, -side]));
        }
    }
    for (i, dof, group) in &grounds {
        let Some(n) = node(*i) else { continue };
        let p = view.px(&n.position);
        match dof {
            Dof::Translation(_) => {
                let d = ground_direction(&view, n, *dof);
                let g = p - d * GROUNDED_LENGTH;
                let mids = parallel(&mut canvas, p, g, group);
                let half = 12.0 + PARALLEL_SPACING * (group.len() as f64 - 1.0) / 2.0;
                ground(&mut canvas, SUPPORT_LAYER, g, -d, half);
                for ((kind, name), (mid, side)) in group.iter().zip(mids) {
                    canvas.label(Label::new(*name, mid, kind.colour(), 2).prefer(&[side, -side]));
                }
            }
            Dof::Rotation(_) => {
                // A torsional element: a coil round the node, grounded below it.
                for (j, (kind, name)) in group.iter().enumerate() {
                    let r0 = 9.0 + 8.0 * j as f64;
                    let coil: Vec<V2> = (0..=40)
                        .map(|s| {
                            let t = 1.5 * std::f64::consts::TAU * s as f64 / 40.0;
                            p + v2(t.cos(), t.sin()) * (r0 + 6.0 * s as f64 / 40.0)
                        })
                        .collect();
                    let end = *coil.last().unwrap_or(&p);
                    canvas.line(ELEMENT_LAYER, coil, kind.colour(), 2);
                    let g = end + v2(0.0, 18.0);
                    canvas.line(ELEMENT_LAYER, vec![end, g], kind.colour(), 2);
                    ground(&mut canvas, SUPPORT_LAYER, g, v2(0.0, 1.0), 9.0);
                    canvas.label(Label::new(format!("{name} ({dof})"), g, kind.colour(), 2));
                }
            }
        }
    }

    // Held DOFs during the run: a ground symbol per held translation in the plane.
    let conditions = run_conditions(scene);
    let mut out_of_plane: Vec<String> = Vec::new();
    let mut support_sides: Vec<(NodeId, V2)> = Vec::new();
    for (i, n) in scene.nodes.iter().enumerate() {
        let held: Vec<Dof> = conditions
            .iter()
            .filter(|c| c.node == i)
            .map(|c| c.dof)
            .collect();
        if held.is_empty() {
            continue;
        }
        let p = view.px(&n.position);
        let mut dirs: Vec<V2> = Vec::new();
        let mut elsewhere: Vec<String> = Vec::new();
        let mut rotation = Vec::new();
        for dof in &held {
            let axis: Vector3<f64> = n.frame.column(dof.axis()).into_owned();
            let in_plane = v2(axis[view.a], axis[view.b]).norm() > 0.5 * axis.norm();
            let on_screen = view.dir(&axis).filter(|_| in_plane);
            match (dof, on_screen) {
                (Dof::Translation(_), Some(d)) => dirs.push(d),
                (Dof::Translation(_), None) => elsewhere.push(dof.to_string()),
                (Dof::Rotation(_), None) => rotation.push(dof.to_string()),
                (Dof::Rotation(_), Some(_)) => elsewhere.push(dof.to_string()),
            }
        }
        if scene.dimension == Dimension::Three && !elsewhere.is_empty() {
            out_of_plane.push(format!("{} {}", n.name, elsewhere.join(" ")));
        }
        let both = dirs.len() >= 2 && dirs.iter().any(|d| d.cross(dirs[0]).abs() > 0.3);
        if both {
            present.pin = true;
            let sides = [v2(0.0, 1.0), v2(-1.0, 0.0), v2(1.0, 0.0), v2(0.0, -1.0)];
            let side = best_side(&canvas, p, &sides);
            support(&mut canvas, p, side, false);
            support_sides.push((i, side));
        } else if let Some(d) = dirs.first() {
            present.roller = true;
            // Below, or right, rather than above or left, when both are free.
            let d = if d.y < -1e-9 || (d.y.abs() <= 1e-9 && d.x < 0.0) {
                -*d
            } else {
                *d
            };
            let side = best_side(&canvas, p, &[d, -d]);
            support(&mut canvas, p, side, true);
            support_sides.push((i, side));
        }
        for r in rotation {
            canvas.label(Label::new(format!("{r} held"), p, SUPPORT, 4));
        }
    }

    // Contact faces: a segment across the normal, with a short normal arrow.
    for c in &scene.contacts {
        present.contact = true;
        let Some((point, normal)) = c.plane() else {
            // A solid: its outline in the sketch plane, named at its centre.
            let mut ring: Vec<V2> = outline(&c.surface).iter().map(|p| view.px(p)).collect();
            ring.push(ring[0]);
            canvas.line(ELEMENT_LAYER, ring, CONTACT, 3);
            canvas.label(Label::new(c.name.clone(), view.px(&c.anchor()), CONTACT, 3));
            continue;
        };
        let fp = view.px(&point);
        let Some(nd) = view.dir(&normal) else {
            canvas.circle(ELEMENT_LAYER, fp, 4.0, CONTACT, false);
            canvas.label(Label::new(
                format!("{} (face ⟂ sketch)", c.name),
                fp,
                CONTACT,
                3,
            ));
            continue;
        };
        let t = nd.perp();
        // Centred on the face point, or mostly on one side of it where the other is taken.
        let (e0, e1) = [(0.5, 0.5), (0.1, 0.9), (0.9, 0.1)]
            .into_iter()
            .map(|(lo, hi)| (fp - t * (lo * FACE_LENGTH), fp + t * (hi * FACE_LENGTH)))
            .min_by_key(|(e0, e1)| {
                let gap = 9.0;
                let part = |e: V2| {
                    let u = (e - fp).unit().unwrap_or(t);
                    if (e - fp).norm() > gap {
                        canvas.hits(fp + u * gap, e, 2.0)
                    } else {
                        0
                    }
                };
                part(*e0) + part(*e1)
            })
            .unwrap_or((fp, fp));
        canvas.line(ELEMENT_LAYER, vec![e0, e1], CONTACT, 4);
        let base = [0.7, 0.3]
            .into_iter()
            .flat_map(|s| [e0 + (e1 - e0) * s, e1 + (e0 - e1) * s])
            .min_by_key(|q| canvas.hits(*q + nd * 4.0, *q + nd * 24.0, 2.0))
            .unwrap_or(fp);
        canvas.arrow(ARROW_LAYER, base + nd * 2.0, base + nd * 24.0, CONTACT, 2);
        canvas.label(Label::new(c.name.clone(), (e0 + e1) * 0.5, CONTACT, 3).prefer(&[-nd, nd]));
    }

    // Nodes: open circles, filled where they carry a point mass.
    for n in &scene.nodes {
        let p = view.px(&n.position);
        if n.mass > 0.0 {
            present.mass = true;
            canvas.circle(NODE_LAYER, p, 5.0, INK, true);
        } else {
            present.node = true;
            canvas.circle(NODE_LAYER, p, 4.0, WHITE, true);
            canvas.circle(NODE_LAYER, p, 4.0, INK, false);
        }
        let mut label = Label::new(n.name.clone(), p, INK, 1);
        label.size = 13.0;
        canvas.label(label.prefer(&[v2(1.0, -1.0), v2(-1.0, -1.0)]));
    }
    // Reference nodes (a square) and centres of mass (the quartered circle).
    for body in &scene.bodies {
        if let Some(p) = px(body.reference) {
            let r = 8.0;
            canvas.line(
                MARK_LAYER,
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
        }
        if let Some(c) = com(body) {
            centre_of_mass(&mut canvas, MARK_LAYER, view.px(&c));
        }
    }

    // Loads: arrows of fixed length along the force, labelled with the magnitude.
    for l in &scene.loads {
        present.load = true;
        let Some(p) = px(l.node) else { continue };
        let magnitude = l.force.norm();
        let text = format!("F = {} N", tick(magnitude, magnitude));
        match view.dir(&l.force) {
            Some(d) => {
                let candidates = [
                    (p + d * 7.0, p + d * (LOAD_LENGTH + 7.0)),
                    (p - d * (LOAD_LENGTH + 7.0), p - d * 7.0),
                ];
                let (tail, tip) = candidates
                    .into_iter()
                    .min_by_key(|(t, h)| {
                        let inside = hulls.iter().any(|o| inside_polygon((*t + *h) * 0.5, o));
                        canvas.hits(*t, *h, 3.0) + usize::from(inside)
                    })
                    .unwrap_or(candidates[0]);
                canvas.arrow(ARROW_LAYER, tail, tip, LOAD, 3);
                let far = if (tail - p).norm() > (tip - p).norm() {
                    tail
                } else {
                    tip
                };
                canvas.label(Label::new(text, far, LOAD, 3).prefer(&[
                    d.perp(),
                    -d.perp(),
                    far - p,
                ]));
            }
            None => canvas.label(Label::new(format!("{text} (⟂ sketch)"), p, LOAD, 3)),
        }
    }

    // Initial velocities: arrows (beside the node when the line is taken) and ω as a curved
    // arrow about the node.
    for iv in &scene.initial_velocities {
        let Some(p) = px(iv.node) else { continue };
        let speed = iv.velocity.norm();
        if speed > 0.0 {
            present.velocity = true;
            let text = format!("v = {} m/s", tick(speed, speed));
            match view.dir(&iv.velocity) {
                Some(d) => {
                    let (tail, tip) = [0.0, 13.0, -13.0, 24.0, -24.0]
                        .into_iter()
                        .map(|o| {
                            let s = p + d.perp() * o;
                            (s + d * 7.0, s + d * (VELOCITY_LENGTH + 7.0))
                        })
                        .min_by_key(|(t, h)| canvas.hits(*t + d * 3.0, *h, 3.0))
                        .unwrap_or((p, p + d * VELOCITY_LENGTH));
                    canvas.arrow(ARROW_LAYER, tail, tip, VELOCITY, 2);
                    canvas.label(Label::new(text, tip, VELOCITY, 3).prefer(&[
                        d,
                        d.perp(),
                        -d.perp(),
                    ]));
                }
                None => canvas.label(Label::new(format!("{text} (⟂ sketch)"), p, VELOCITY, 3)),
            }
        }
        let normal = view.normal_axis();
        let spin = iv.angular[normal] * view.handedness();
        let tilt = (0..3)
            .filter(|i| *i != normal)
            .map(|i| iv.angular[i].abs())
            .fold(0.0, f64::max);
        if spin != 0.0 {
            present.velocity = true;
            let w = iv.angular[normal].abs();
            let axis = ["x", "y", "z"][normal];
            let gap = support_sides
                .iter()
                .find(|(n, _)| *n == iv.node)
                .map_or(v2(0.0, 1.0), |(_, s)| *s);
            let top = spin_arrow(&mut canvas, p, spin > 0.0, gap);
            canvas.label(
                Label::new(format!("ω{axis} = {} rad/s", tick(w, w)), top, VELOCITY, 3).prefer(&[
                    v2(0.0, -1.0),
                    v2(1.0, -1.0),
                    v2(-1.0, -1.0),
                ]),
            );
        }
        if tilt > 0.0 {
            let w = iv.angular;
            canvas.label(Label::new(
                format!(
                    "ω = ({}, {}, {}) rad/s",
                    tick(w[0], tilt),
                    tick(w[1], tilt),
                    tick(w[2], tilt)
                ),
                p,
                VELOCITY,
                3,
            ));
        }
    }

    canvas.place_labels();
    frame(&mut canvas, scene, &view, &present, &out_of_plane);
    draw(canvas)
}

/// Elements drawn together (in parallel): their kinds and names.
type Group<'a> = Vec<(Kind, &'a str)>;
/// Elements between one pair of nodes: the nodes, the first one's direction, the elements.
type Pair<'a> = ([NodeId; 2], Vector3<f64>, Group<'a>);
/// A legend row: its text and how its symbol is drawn at a point.
type LegendRow<'a> = (&'a str, Box<dyn Fn(&mut Canvas, V2) + 'a>);

/// Add an element to the group of its pair of nodes (either order).
fn add_pair<'a>(
    pairs: &mut Vec<Pair<'a>>,
    nodes: [NodeId; 2],
    direction: Vector3<f64>,
    kind: Kind,
    name: &'a str,
) {
    let same = |p: &[NodeId; 2]| *p == nodes || *p == [nodes[1], nodes[0]];
    match pairs.iter_mut().find(|(p, _, _)| same(p)) {
        Some(g) => g.2.push((kind, name)),
        None => pairs.push((nodes, direction, vec![(kind, name)])),
    }
}

/// The screen direction of a node's translational DOF (its frame column), or a diagonal when
/// the DOF is out of the sketch plane.
fn ground_direction(view: &View, n: &crate::scene::Node, dof: Dof) -> V2 {
    let axis: Vector3<f64> = n.frame.column(dof.axis()).into_owned();
    view.dir(&axis).unwrap_or(v2(
        std::f64::consts::FRAC_1_SQRT_2,
        -std::f64::consts::FRAC_1_SQRT_2,
    ))
}

/// The side (of those offered, in preference order) where a support at `p` crosses least.
fn best_side(canvas: &Canvas, p: V2, sides: &[V2]) -> V2 {
    sides
        .iter()
        .copied()
        .min_by_key(|s| {
            let n = s.perp();
            let tip = p + *s * 27.0;
            canvas.hits(p + *s * 7.0, tip + n * 10.0, 1.0)
                + canvas.hits(p + *s * 7.0, tip - n * 10.0, 1.0)
        })
        .unwrap_or(v2(0.0, 1.0))
}

/// A support at `p` on `side`: a triangle with a hatched ground (pin), with rollers between
/// them when only the translation along `side` is held.
fn support(canvas: &mut Canvas, p: V2, side: V2, roller: bool) {
    let n = side.perp();
    let apex = p + side * 5.5;
    let base = p + side * 19.0;
    canvas.line(
        SUPPORT_LAYER,
        vec![apex, base + n * 8.0, base - n * 8.0, apex],
        SUPPORT,
        2,
    );
    if roller {
        for s in [-4.5, 4.5] {
            canvas.circle(
                SUPPORT_LAYER,
                base + side * 3.5 + n * s,
                3.0,
                SUPPORT,
                false,
            );
        }
        ground(canvas, SUPPORT_LAYER, base + side * 7.5, side, 12.0);
    } else {
        ground(canvas, SUPPORT_LAYER, base, side, 12.0);
    }
}

/// The centre-of-mass symbol: a circle with two opposite quarters filled.
fn centre_of_mass(canvas: &mut Canvas, layer: u8, c: V2) {
    let r = 6.0;
    canvas.circle(layer, c, r, WHITE, true);
    for q in [0.0, std::f64::consts::PI] {
        let mut pts = vec![c];
        pts.extend((0..=8).map(|k| {
            let t = q + std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
            c + v2(t.cos(), -t.sin()) * r
        }));
        canvas.fill(layer, pts, INK.to_rgba());
    }
    canvas.circle(layer, c, r, INK, false);
}

/// A curved arrow about `p` (counter-clockwise on screen when `ccw`), open towards `gap` (a
/// support's side); returns its top point.
fn spin_arrow(canvas: &mut Canvas, p: V2, ccw: bool, gap: V2) -> V2 {
    let r = 24.0;
    let sweep = 1.45 * std::f64::consts::PI;
    // Screen angle (counter-clockwise, y up) of the gap's centre.
    let middle = (-gap.y).atan2(gap.x);
    let at = |t: f64| p + v2(t.cos(), -t.sin()) * r;
    let (first, sign) = if ccw {
        (middle + 0.275 * std::f64::consts::PI, 1.0)
    } else {
        (middle - 0.275 * std::f64::consts::PI, -1.0)
    };
    let angle = |k: f64| first + sign * sweep * k;
    let pts: Vec<V2> = (0..=36).map(|k| at(angle(k as f64 / 36.0))).collect();
    canvas.line(ARROW_LAYER, pts, VELOCITY, 2);
    let end = angle(1.0);
    let tangent = v2(-end.sin(), -end.cos()) * sign;
    let tip = at(end) + tangent * 4.0;
    let base = tip - tangent * 10.0;
    canvas.fill(
        ARROW_LAYER,
        vec![
            tip,
            base + tangent.perp() * 4.5,
            base - tangent.perp() * 4.5,
        ],
        VELOCITY.to_rgba(),
    );
    p + v2(0.0, -r)
}

/// Title, legend, scale bar and the note of DOFs held out of the sketch plane.
fn frame(
    canvas: &mut Canvas,
    scene: &Scene,
    view: &View,
    present: &Present,
    out_of_plane: &[String],
) {
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

    // Legend: only the symbols the sketch uses.
    let x = LEGEND_X;
    let mut y = 70.0;
    let mut rows: Vec<LegendRow> = Vec::new();
    if present.node {
        rows.push((
            "node",
            Box::new(|c: &mut Canvas, p: V2| c.circle(l, p, 4.0, INK, false)),
        ));
    }
    if present.mass {
        rows.push((
            "node with point mass",
            Box::new(|c: &mut Canvas, p: V2| c.circle(l, p, 5.0, INK, true)),
        ));
    }
    if present.body {
        rows.push((
            "rigid body (its nodes)",
            Box::new(|c: &mut Canvas, p: V2| {
                let pts = vec![
                    p + v2(-14.0, -7.0),
                    p + v2(14.0, -7.0),
                    p + v2(14.0, 7.0),
                    p + v2(-14.0, 7.0),
                ];
                c.fill(l, pts.clone(), BODY.mix(0.13));
                let mut closed = pts.clone();
                closed.push(pts[0]);
                c.line(l, closed, BODY, 2);
            }),
        ));
        rows.push((
            "reference node",
            Box::new(|c: &mut Canvas, p: V2| {
                let r = 7.0;
                c.line(
                    l,
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
            Box::new(|c: &mut Canvas, p: V2| centre_of_mass(c, l, p)),
        ));
    }
    if present.spring {
        rows.push((
            "spring",
            Box::new(|c: &mut Canvas, p: V2| {
                element_symbol(c, l, Kind::Spring, p - v2(16.0, 0.0), p + v2(16.0, 0.0))
            }),
        ));
    }
    if present.dashpot {
        rows.push((
            "dashpot",
            Box::new(|c: &mut Canvas, p: V2| {
                element_symbol(c, l, Kind::Dashpot, p - v2(16.0, 0.0), p + v2(16.0, 0.0))
            }),
        ));
    }
    if present.contact {
        rows.push((
            "contact face, normal",
            Box::new(|c: &mut Canvas, p: V2| {
                c.line(l, vec![p + v2(-6.0, -9.0), p + v2(-6.0, 9.0)], CONTACT, 4);
                c.arrow(l, p + v2(-4.0, 0.0), p + v2(14.0, 0.0), CONTACT, 2);
            }),
        ));
    }
    if present.load {
        rows.push((
            "load (magnitude)",
            Box::new(|c: &mut Canvas, p: V2| {
                c.arrow(l, p - v2(16.0, 0.0), p + v2(16.0, 0.0), LOAD, 3)
            }),
        ));
    }
    if present.velocity {
        rows.push((
            "initial velocity",
            Box::new(|c: &mut Canvas, p: V2| {
                c.arrow(l, p - v2(16.0, 0.0), p + v2(16.0, 0.0), VELOCITY, 2)
            }),
        ));
    }
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

    // Scale bar: a round length of about 100 px.
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

/// The legend's support symbol, pointing down.
fn support_legend(canvas: &mut Canvas, p: V2, roller: bool) {
    let mut sub = Canvas::new();
    support(&mut sub, p - v2(0.0, 14.0), v2(0.0, 1.0), roller);
    for (_, s) in sub.shapes {
        canvas.shapes.push((LEGEND_LAYER, s));
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

/// Render the canvas, layer by layer, into an SVG document.
fn draw(mut canvas: Canvas) -> Option<String> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    fn seeds() -> Vec<Scene> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
        let paths: Vec<PathBuf> = crate::case::discover(&dir).expect("cases directory");
        assert!(!paths.is_empty(), "no seed cases in {}", dir.display());
        paths
            .iter()
            .map(|p| crate::case::load(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
            .collect()
    }

    #[test]
    fn every_seed_case_sketches_with_every_named_part() {
        for scene in seeds() {
            let svg = render(&scene).unwrap_or_else(|| panic!("{}: no sketch", scene.id));
            assert!(svg.starts_with("<svg"), "{}: not an SVG document", scene.id);
            assert!(svg.contains(&scene.id), "{}: no title", scene.id);
            let names = scene
                .springs
                .iter()
                .chain(&scene.dashpots)
                .map(|e| &e.name)
                .chain(scene.contacts.iter().map(|c| &c.name))
                .chain(scene.bodies.iter().map(|b| &b.name))
                .chain(scene.nodes.iter().map(|n| &n.name));
            for name in names {
                assert!(
                    svg.contains(&format!(">\n{name}\n</text>")),
                    "{}: {name} is not labelled",
                    scene.id
                );
            }
        }
    }

    #[test]
    fn small_and_degenerate_scenes_render_without_panicking() {
        for scene in seeds() {
            // One node, nothing else.
            let mut one = scene.clone();
            one.nodes.truncate(1);
            one.nodes[0].attachment = Attachment::Free;
            one.bodies.clear();
            one.springs.clear();
            one.dashpots.clear();
            one.contacts.clear();
            one.loads.clear();
            one.initial_velocities.clear();
            one.steps.clear();
            assert!(
                render(&one).is_some_and(|s| s.starts_with("<svg")),
                "{}",
                scene.id
            );
            // Every node at one point (coincident nodes, zero extent).
            let mut point = scene.clone();
            for n in &mut point.nodes {
                n.position = Vector3::new(0.5, 0.5, 0.0);
            }
            for c in &mut point.contacts {
                if let Surface::Plane { point, .. } = &mut c.surface {
                    *point = Vector3::new(0.5, 0.5, 0.0);
                }
            }
            assert!(render(&point).is_some(), "{}", scene.id);
            // The scene turned into the x–z plane: drawn in x–z.
            let mut turned = scene.clone();
            let swap = |v: &mut Vector3<f64>| v.swap_rows(1, 2);
            for n in &mut turned.nodes {
                swap(&mut n.position);
            }
            for c in &mut turned.contacts {
                if let Surface::Plane { point, normal } = &mut c.surface {
                    swap(point);
                    swap(normal);
                }
            }
            for l in &mut turned.loads {
                swap(&mut l.force);
            }
            for b in &mut turned.bodies {
                swap(&mut b.centre_offset);
            }
            for v in &mut turned.initial_velocities {
                swap(&mut v.velocity);
                swap(&mut v.angular);
            }
            let svg = render(&turned).expect("turned scene");
            let flat = |i: usize| {
                turned
                    .nodes
                    .iter()
                    .all(|n| n.position[i] == turned.nodes[0].position[i])
            };
            if flat(1) && !flat(2) {
                assert!(svg.contains("sketch plane x–z"), "{}", scene.id);
            }
        }
        let mut empty = seeds().remove(0);
        empty.nodes.clear();
        assert!(render(&empty).is_none());
    }

    /// Writes every seed case's sketch to `/tmp/sketch/<id>.svg` (for looking at them).
    #[test]
    #[ignore]
    fn write_seed_sketches() {
        let out = Path::new("/tmp/sketch");
        std::fs::create_dir_all(out).unwrap();
        for scene in seeds() {
            let svg = render(&scene).unwrap();
            std::fs::write(out.join(format!("{}.svg", scene.id)), svg).unwrap();
        }
    }
}
