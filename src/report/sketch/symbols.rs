//! The symbols a sketch draws with: springs and dashpots (alone or in parallel), grounds,
//! supports, the centre of mass and a spin arrow.

use super::canvas::{ARROW_LAYER, Canvas, ELEMENT_LAYER, LEGEND_LAYER, SUPPORT_LAYER};
use super::geometry::{V2, v2};
use super::{DASHPOT, INK, MIN_LINK, PARALLEL_SPACING, SPRING, SUPPORT, VELOCITY};
use plotters::prelude::*;

/// Which element symbol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    Spring,
    Dashpot,
}

impl Kind {
    /// The colour the element is drawn in.
    pub(super) fn colour(self) -> RGBColor {
        match self {
            Kind::Spring => SPRING,
            Kind::Dashpot => DASHPOT,
        }
    }
}

/// A zig-zag from a to b (leads of 15 % at each end).
pub(super) fn zigzag(a: V2, b: V2) -> Vec<V2> {
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
pub(super) fn dashpot(canvas: &mut Canvas, layer: u8, a: V2, b: V2, colour: RGBColor) {
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

/// An element's symbol from a to b: a zig-zag (spring) or a dashpot.
pub(super) fn element_symbol(canvas: &mut Canvas, layer: u8, kind: Kind, a: V2, b: V2) {
    match kind {
        Kind::Spring => canvas.line(layer, zigzag(a, b), SPRING, 2),
        Kind::Dashpot => dashpot(canvas, layer, a, b, DASHPOT),
    }
}

/// Hatch of a ground: a line across `dir` at `at`, with short ticks on the far side.
pub(super) fn ground(canvas: &mut Canvas, layer: u8, at: V2, dir: V2, half: f64) {
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
pub(super) fn parallel(
    canvas: &mut Canvas,
    p0: V2,
    p1: V2,
    group: &[(Kind, &str)],
) -> Vec<(V2, V2)> {
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
pub(super) fn link(
    canvas: &mut Canvas,
    p0: V2,
    p1: V2,
    out: V2,
    group: &[(Kind, &str)],
) -> Vec<(V2, V2)> {
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

/// The side (of those offered, in preference order) where a support at `p` crosses least.
pub(super) fn best_side(canvas: &Canvas, p: V2, sides: &[V2]) -> V2 {
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
pub(super) fn support(canvas: &mut Canvas, p: V2, side: V2, roller: bool) {
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
pub(super) fn centre_of_mass(canvas: &mut Canvas, layer: u8, c: V2) {
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
pub(super) fn spin_arrow(canvas: &mut Canvas, p: V2, ccw: bool, gap: V2) -> V2 {
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

/// The legend's support symbol, pointing down.
pub(super) fn support_legend(canvas: &mut Canvas, p: V2, roller: bool) {
    let mut sub = Canvas::new();
    support(&mut sub, p - v2(0.0, 14.0), v2(0.0, 1.0), roller);
    for (_, s) in sub.shapes {
        canvas.shapes.push((LEGEND_LAYER, s));
    }
}
