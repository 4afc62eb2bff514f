//! Plane geometry in pixels: points and directions, rectangles, distances, convex hulls.

use std::ops::{Add, Mul, Neg, Sub};

/// A point or direction in pixels (y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct V2 {
    pub(super) x: f64,
    pub(super) y: f64,
}

/// A point or direction in pixels.
pub(super) fn v2(x: f64, y: f64) -> V2 {
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
    pub(super) fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    pub(super) fn dot(self, o: V2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    pub(super) fn cross(self, o: V2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Rotated a quarter turn (in pixel coordinates).
    pub(super) fn perp(self) -> V2 {
        v2(-self.y, self.x)
    }
    pub(super) fn unit(self) -> Option<V2> {
        let n = self.norm();
        (n > 1e-9 && n.is_finite()).then(|| self * (1.0 / n))
    }
    pub(super) fn pixel(self) -> (i32, i32) {
        (self.x.round() as i32, self.y.round() as i32)
    }
}

/// An axis-aligned rectangle in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Rect {
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) x1: f64,
    pub(super) y1: f64,
}

impl Rect {
    pub(super) fn centred(c: V2, w: f64, h: f64) -> Rect {
        Rect {
            x0: c.x - w / 2.0,
            y0: c.y - h / 2.0,
            x1: c.x + w / 2.0,
            y1: c.y + h / 2.0,
        }
    }
    pub(super) fn overlaps(&self, o: &Rect, pad: f64) -> bool {
        self.x0 < o.x1 + pad && o.x0 < self.x1 + pad && self.y0 < o.y1 + pad && o.y0 < self.y1 + pad
    }
    pub(super) fn inside(&self, outer: &Rect) -> bool {
        self.x0 >= outer.x0 && self.x1 <= outer.x1 && self.y0 >= outer.y0 && self.y1 <= outer.y1
    }
    pub(super) fn contains(&self, p: V2) -> bool {
        p.x >= self.x0 && p.x <= self.x1 && p.y >= self.y0 && p.y <= self.y1
    }
    pub(super) fn distance_to_point(&self, p: V2) -> f64 {
        let dx = (self.x0 - p.x).max(p.x - self.x1).max(0.0);
        let dy = (self.y0 - p.y).max(p.y - self.y1).max(0.0);
        dx.hypot(dy)
    }
    pub(super) fn corners(&self) -> [V2; 4] {
        [
            v2(self.x0, self.y0),
            v2(self.x1, self.y0),
            v2(self.x1, self.y1),
            v2(self.x0, self.y1),
        ]
    }
    pub(super) fn distance_to_segment(&self, a: V2, b: V2) -> f64 {
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

/// Distance from `p` to the segment ab.
pub(super) fn point_segment_distance(p: V2, a: V2, b: V2) -> f64 {
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
pub(super) fn segment_distance(a: V2, b: V2, c: V2, d: V2) -> f64 {
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

/// Convex hull (counter-clockwise in pixel coordinates) of a set of points.
pub(super) fn hull(points: &[V2]) -> Vec<V2> {
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

/// Area of a polygon (either orientation).
pub(super) fn polygon_area(p: &[V2]) -> f64 {
    (0..p.len())
        .map(|i| p[i].cross(p[(i + 1) % p.len()]))
        .sum::<f64>()
        .abs()
        / 2.0
}

/// Whether `p` is inside a convex polygon (on its edge counts as inside).
pub(super) fn inside_polygon(p: V2, poly: &[V2]) -> bool {
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
