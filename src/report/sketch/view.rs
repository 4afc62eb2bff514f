//! The projection of a scene onto the sketch plane, and the scale that fits the geometry and
//! every symbol drawn at a fixed pixel size into the drawing area.

use super::geometry::{V2, v2};
use super::{AREA, FACE_LENGTH, GROUNDED_LENGTH, LOAD_LENGTH, VELOCITY_LENGTH};
use crate::scene::{Connection, Dof, Node, NodeId, Scene};
use nalgebra::Vector3;

/// The projection from the scene to pixels: world axes `a` (right) and `b` (up).
pub(super) struct View {
    pub(super) a: usize,
    pub(super) b: usize,
    /// Pixels per length unit.
    pub(super) scale: f64,
    /// Pixel position of the world origin.
    pub(super) origin: V2,
}

impl View {
    /// A world point in pixels.
    pub(super) fn px(&self, p: &Vector3<f64>) -> V2 {
        self.origin + v2(p[self.a], -p[self.b]) * self.scale
    }
    /// A world direction on screen: unit, or `None` when it is (nearly) out of the plane.
    pub(super) fn dir(&self, d: &Vector3<f64>) -> Option<V2> {
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
    pub(super) fn handedness(&self) -> f64 {
        if self.b == self.a + 1 { 1.0 } else { -1.0 }
    }
    /// The world axis out of the sketch plane.
    pub(super) fn normal_axis(&self) -> usize {
        3 - self.a - self.b
    }
}

/// The two world axes drawn: x and y, unless the scene's x–y extent is degenerate and its z
/// extent is not (then the two of largest extent).
pub(super) fn axes(points: &[Vector3<f64>]) -> (usize, usize) {
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
pub(super) fn fit(
    a: usize,
    b: usize,
    reach: &[(Vector3<f64>, V2)],
    world: &[Vector3<f64>],
) -> View {
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

/// The screen direction of a node's translational DOF (its frame column), or a diagonal when
/// the DOF is out of the sketch plane.
pub(super) fn ground_direction(view: &View, n: &Node, dof: Dof) -> V2 {
    let axis: Vector3<f64> = n.frame.column(dof.axis()).into_owned();
    view.dir(&axis).unwrap_or(v2(
        std::f64::consts::FRAC_1_SQRT_2,
        -std::f64::consts::FRAC_1_SQRT_2,
    ))
}

/// What reaches beyond the geometry by a fixed number of pixels: each world point with the
/// pixel offsets of the labels, grounded elements, arrows and faces drawn from it, on screen
/// as `proto` (the sketch's axes at any scale) shows them.
pub(super) fn reach(
    scene: &Scene,
    world: &[Vector3<f64>],
    proto: &View,
) -> Vec<(Vector3<f64>, V2)> {
    let node = |i: NodeId| scene.nodes.get(i);
    let mut reach: Vec<(Vector3<f64>, V2)> = Vec::new();
    for p in world {
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
            let d = ground_direction(proto, n, dof);
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
    reach
}
