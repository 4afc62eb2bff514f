//! A convex polygon (2D) or polyhedron (3D) given by its corners, in closed form: its faces
//! (outward unit normal and offset), its boundary segments (2D: the faces; 3D: the edges), the
//! signed distance of a point to its boundary with the nearest feature, and the same polytope
//! eroded by a radius. Written from the corners alone (no hull library), so the engines that
//! take the shape from parry are checked against an independent geometry.

use nalgebra::{Matrix2, Matrix3, Matrix4, Vector2, Vector3, Vector4};

/// The most corners a polytope may have (face finding is O(n⁴) over them, once per case).
pub const MAX_CORNERS: usize = 32;

/// The least angle, in radians, between two faces that meet at a corner. A corner where the
/// boundary turns by less is nearly straight: a hull library may keep or drop it by round-off
/// (parry merges faces whose normals differ by about 1e-4 rad), and then the engines would
/// not share one shape. A regular polygon of [`MAX_CORNERS`] sides turns by 0.196 rad.
pub const MIN_TURN: f64 = 1e-3;

/// Corners nearer each other than this fraction of the polytope's size are one corner given
/// twice.
const SAME_CORNER: f64 = 1e-6;

/// A face: the points s with `normal · s = offset`, the solid on the side `normal · s < offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// Outward unit normal.
    pub normal: Vector3<f64>,
    /// `normal · s` on the face.
    pub offset: f64,
}

/// The feature of a polytope's boundary nearest a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// Inside a face (or the point is inside the solid: the face it is nearest).
    Face(usize),
    /// Inside a boundary segment (3D: an edge), index into [`Polytope::segments`].
    Segment(usize),
    /// A corner.
    Corner(usize),
}

/// Why corners do not make a convex polytope.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolytopeError {
    /// Too few or too many corners.
    #[error("a convex {what} needs {least} to {MAX_CORNERS} corners, got {got}")]
    Count {
        /// polygon or polyhedron.
        what: &'static str,
        /// The fewest.
        least: usize,
        /// Given.
        got: usize,
    },
    /// The corners span no area (2D) or volume (3D).
    #[error("the corners are {0}: the {1} has no interior")]
    Flat(&'static str, &'static str),
    /// Two corners at one place.
    #[error("corner {index} repeats corner {other}: they are {distance:e} m apart")]
    Repeated {
        /// Index in the list of the later one.
        index: usize,
        /// Index of the earlier one.
        other: usize,
        /// Their distance.
        distance: f64,
    },
    /// A corner where the boundary hardly turns: two faces meeting there are almost one.
    #[error(
        "corner {index} ({x}, {y}, {z}) is almost straight: two faces that meet there turn by {angle:.1e} rad, less than {MIN_TURN:.0e}"
    )]
    Straight {
        /// Index in the list.
        index: usize,
        /// Coordinates.
        x: f64,
        /// Coordinates.
        y: f64,
        /// Coordinates.
        z: f64,
        /// The smallest angle between two faces that meet there.
        angle: f64,
    },
    /// A point that is not a corner of the hull (inside it, or on a face or an edge).
    #[error(
        "corner {index} ({x}, {y}, {z}) is not a corner of the convex hull of the others: it lies inside it, on a face or on an edge"
    )]
    NotCorner {
        /// Index in the list.
        index: usize,
        /// Coordinates.
        x: f64,
        /// Coordinates.
        y: f64,
        /// Coordinates.
        z: f64,
    },
}

/// A convex polygon (z = 0) or polyhedron, relative to its centre.
#[derive(Debug, Clone, PartialEq)]
pub struct Polytope {
    /// Whether it is a polygon in the x–y plane.
    pub planar: bool,
    /// Its corners, as given.
    pub corners: Vec<Vector3<f64>>,
    /// Its faces (2D: its sides).
    pub faces: Vec<Face>,
    /// Its boundary segments as pairs of corner indices (2D: its sides, in the order of
    /// `faces`; 3D: its edges).
    pub segments: Vec<(usize, usize)>,
    /// The radius of the largest ball inside it: how deep a node can go before it is nearer
    /// another face than the one it entered by.
    pub inradius: f64,
}

impl Polytope {
    /// The polytope whose corners are `corners` (every one of them must be a corner of their
    /// convex hull). `planar`: a polygon in the x–y plane (z ignored).
    pub fn new(corners: &[Vector3<f64>], planar: bool) -> Result<Polytope, PolytopeError> {
        let (what, least) = if planar {
            ("polygon", 3)
        } else {
            ("polyhedron", 4)
        };
        if corners.len() < least || corners.len() > MAX_CORNERS {
            return Err(PolytopeError::Count {
                what,
                least,
                got: corners.len(),
            });
        }
        let corners: Vec<Vector3<f64>> = corners
            .iter()
            .map(|c| {
                if planar {
                    Vector3::new(c.x, c.y, 0.0)
                } else {
                    *c
                }
            })
            .collect();
        // The diameter: every tolerance below is relative to it.
        let size = corners
            .iter()
            .flat_map(|a| corners.iter().map(move |b| (a - b).norm()))
            .fold(0.0_f64, f64::max)
            .max(f64::MIN_POSITIVE);
        for (index, c) in corners.iter().enumerate() {
            if let Some((other, distance)) = corners[..index]
                .iter()
                .map(|b| (c - b).norm())
                .enumerate()
                .find(|(_, d)| *d <= SAME_CORNER * size)
            {
                return Err(PolytopeError::Repeated {
                    index,
                    other,
                    distance,
                });
            }
        }
        let eps = 1e-9 * size;
        // A face's candidate normal is a length (2D: a side) or an area (3D: a cross product).
        let least_normal = if planar { eps } else { eps * size };
        let mut faces: Vec<Face> = Vec::new();
        let mut consider = |normal: Vector3<f64>, at: &Vector3<f64>| {
            let length = normal.norm();
            if length <= least_normal {
                return;
            }
            let mut n = normal / length;
            let side: Vec<f64> = corners.iter().map(|c| n.dot(&(c - at))).collect();
            if side.iter().all(|d| *d <= eps) {
            } else if side.iter().all(|d| *d >= -eps) {
                n = -n;
            } else {
                return;
            }
            if faces.iter().any(|f| f.normal.dot(&n) > 1.0 - 1e-12) {
                return;
            }
            faces.push(Face {
                normal: n,
                offset: n.dot(at),
            });
        };
        let n = corners.len();
        if planar {
            for i in 0..n {
                for j in i + 1..n {
                    let d = corners[j] - corners[i];
                    consider(Vector3::new(d.y, -d.x, 0.0), &corners[i]);
                }
            }
        } else {
            for i in 0..n {
                for j in i + 1..n {
                    for k in j + 1..n {
                        let normal = (corners[j] - corners[i]).cross(&(corners[k] - corners[i]));
                        consider(normal, &corners[i]);
                    }
                }
            }
        }
        let on = |f: &Face, c: &Vector3<f64>| (f.normal.dot(c) - f.offset).abs() <= eps;
        // Flat: every corner on one face (and, for a polyhedron, its mirror).
        if faces.len() < least || faces.iter().any(|f| corners.iter().all(|c| on(f, c))) {
            return Err(PolytopeError::Flat(
                if planar { "collinear" } else { "coplanar" },
                what,
            ));
        }
        for (index, c) in corners.iter().enumerate() {
            let incident: Vec<&Face> = faces.iter().filter(|f| on(f, c)).collect();
            if incident.len() < if planar { 2 } else { 3 } {
                return Err(PolytopeError::NotCorner {
                    index,
                    x: c.x,
                    y: c.y,
                    z: c.z,
                });
            }
            let angle = incident
                .iter()
                .enumerate()
                .flat_map(|(i, f)| {
                    incident[i + 1..].iter().map(move |g| {
                        f.normal
                            .cross(&g.normal)
                            .norm()
                            .atan2(f.normal.dot(&g.normal))
                    })
                })
                .fold(f64::INFINITY, f64::min);
            if angle < MIN_TURN {
                return Err(PolytopeError::Straight {
                    index,
                    x: c.x,
                    y: c.y,
                    z: c.z,
                    angle,
                });
            }
        }
        let on_face = |f: &Face| (0..n).filter(|&i| on(f, &corners[i])).collect::<Vec<_>>();
        let mut segments = Vec::new();
        if planar {
            for f in &faces {
                let ends = on_face(f);
                segments.push((ends[0], ends[1]));
            }
        } else {
            for (a, f) in faces.iter().enumerate() {
                for g in &faces[a + 1..] {
                    let both: Vec<usize> = on_face(f)
                        .into_iter()
                        .filter(|&i| on(g, &corners[i]))
                        .collect();
                    if let [i, j] = both[..] {
                        segments.push((i, j));
                    }
                }
            }
        }
        let inradius = inradius(&faces, planar);
        Ok(Polytope {
            planar,
            corners,
            faces,
            segments,
            inradius,
        })
    }

    /// Signed distance from `s` to the boundary (negative inside), the outward unit normal
    /// there, and the nearest feature. Inside, the nearest face; outside, the nearest point of
    /// a face, a segment or a corner.
    pub fn distance(&self, s: &Vector3<f64>) -> (f64, Vector3<f64>, Feature) {
        let s = if self.planar {
            Vector3::new(s.x, s.y, 0.0)
        } else {
            *s
        };
        let height = |f: &Face| f.normal.dot(&s) - f.offset;
        let (deepest, d) = self
            .faces
            .iter()
            .enumerate()
            .map(|(i, f)| (i, height(f)))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        if d <= 0.0 {
            return (d, self.faces[deepest].normal, Feature::Face(deepest));
        }
        let size = self.corners.iter().fold(0.0_f64, |m, c| m.max(c.norm()));
        let eps = 1e-12 * size;
        let mut best = (f64::INFINITY, Vector3::zeros(), Feature::Face(deepest));
        for (i, f) in self.faces.iter().enumerate() {
            let h = height(f);
            if h <= 0.0 {
                continue;
            }
            let foot = s - f.normal * h;
            let within = self
                .faces
                .iter()
                .enumerate()
                .all(|(j, g)| j == i || g.normal.dot(&foot) - g.offset <= eps);
            if within && h < best.0 {
                best = (h, f.normal, Feature::Face(i));
            }
        }
        for (k, &(a, b)) in self.segments.iter().enumerate() {
            let (p, q) = (self.corners[a], self.corners[b]);
            let along = q - p;
            let t = (along.dot(&(s - p)) / along.norm_squared()).clamp(0.0, 1.0);
            let near = p + along * t;
            let gap = (s - near).norm();
            if gap < best.0 && gap > 0.0 {
                let feature = if t == 0.0 {
                    Feature::Corner(a)
                } else if t == 1.0 {
                    Feature::Corner(b)
                } else if self.planar {
                    Feature::Face(k)
                } else {
                    Feature::Segment(k)
                };
                best = (gap, (s - near) / gap, feature);
            }
        }
        best
    }

    /// The projector onto the directions along which `feature` extends: a face's plane (its
    /// curvature is zero), an edge's direction, nothing at a corner; a polygon also extends
    /// along z. The Hessian of the signed distance at distance ρ outside is (I − P − n nᵀ)/ρ.
    pub fn extends(&self, feature: Feature) -> Matrix3<f64> {
        let z = if self.planar {
            Matrix3::from_diagonal(&Vector3::z())
        } else {
            Matrix3::zeros()
        };
        match feature {
            Feature::Face(i) => {
                Matrix3::identity() - self.faces[i].normal * self.faces[i].normal.transpose()
            }
            Feature::Segment(k) => {
                let (a, b) = self.segments[k];
                let e = (self.corners[b] - self.corners[a]).normalize();
                e * e.transpose() + z
            }
            Feature::Corner(_) => z,
        }
    }

    /// The corners of this polytope with every face moved inward by `radius` (the solid a
    /// ball of that radius rolls over to trace this one, corners rounded): the points where
    /// `dimension` of the moved faces meet inside all the others. `None` if nothing is left.
    pub fn eroded(&self, radius: f64) -> Option<Vec<Vector3<f64>>> {
        let moved: Vec<Face> = self
            .faces
            .iter()
            .map(|f| Face {
                normal: f.normal,
                offset: f.offset - radius,
            })
            .collect();
        let size = self.corners.iter().fold(0.0_f64, |m, c| m.max(c.norm()));
        let eps = 1e-9 * size.max(radius);
        let inside = |p: &Vector3<f64>| moved.iter().all(|f| f.normal.dot(p) - f.offset <= eps);
        let mut points: Vec<Vector3<f64>> = Vec::new();
        let mut keep = |p: Vector3<f64>| {
            if inside(&p) && !points.iter().any(|q| (q - p).norm() <= eps) {
                points.push(p);
            }
        };
        let m = moved.len();
        for i in 0..m {
            for j in i + 1..m {
                if self.planar {
                    let a = Matrix2::new(
                        moved[i].normal.x,
                        moved[i].normal.y,
                        moved[j].normal.x,
                        moved[j].normal.y,
                    );
                    if let Some(p) = a
                        .lu()
                        .solve(&Vector2::new(moved[i].offset, moved[j].offset))
                    {
                        keep(Vector3::new(p.x, p.y, 0.0));
                    }
                    continue;
                }
                for k in j + 1..m {
                    let a = Matrix3::from_rows(&[
                        moved[i].normal.transpose(),
                        moved[j].normal.transpose(),
                        moved[k].normal.transpose(),
                    ]);
                    if a.determinant().abs() < 1e-12 {
                        continue;
                    }
                    if let Some(p) = a.lu().solve(&Vector3::new(
                        moved[i].offset,
                        moved[j].offset,
                        moved[k].offset,
                    )) {
                        keep(p);
                    }
                }
            }
        }
        (points.len() > if self.planar { 2 } else { 3 }).then_some(points)
    }

    /// The outline of its shadow on the x–y plane, counter-clockwise (for sketches): the
    /// convex hull of the corners' (x, y) by Andrew's monotone chain.
    pub fn outline(&self) -> Vec<Vector3<f64>> {
        let mut points: Vec<Vector3<f64>> = self
            .corners
            .iter()
            .map(|c| Vector3::new(c.x, c.y, 0.0))
            .collect();
        points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        let turn = |o: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>| {
            (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
        };
        let mut hull: Vec<Vector3<f64>> = Vec::new();
        for pass in [points.clone(), points.into_iter().rev().collect()] {
            let start = hull.len();
            for p in pass {
                while hull.len() >= start + 2
                    && turn(&hull[hull.len() - 2], &hull[hull.len() - 1], &p) <= 0.0
                {
                    hull.pop();
                }
                hull.push(p);
            }
            hull.pop();
        }
        hull
    }
}

/// The radius of the largest ball inside the faces' half-spaces (their Chebyshev centre): the
/// best of the points equidistant from `dimension + 1` faces that lie inside all of them.
fn inradius(faces: &[Face], planar: bool) -> f64 {
    let m = faces.len();
    let mut best = 0.0_f64;
    // Round-off relative to the faces' distances from the origin (the polytope's size).
    let scale = faces
        .iter()
        .fold(f64::MIN_POSITIVE, |m, f| m.max(f.offset.abs()));
    let fits = |c: &Vector3<f64>, r: f64| {
        faces
            .iter()
            .all(|f| f.normal.dot(c) + r <= f.offset + 1e-12 * scale)
    };
    for i in 0..m {
        for j in i + 1..m {
            for k in j + 1..m {
                if planar {
                    let rows = [faces[i], faces[j], faces[k]];
                    let a = Matrix3::from_fn(|r, c| match c {
                        0 => rows[r].normal.x,
                        1 => rows[r].normal.y,
                        _ => 1.0,
                    });
                    let b = Vector3::from_fn(|r, _| rows[r].offset);
                    if let Some(x) = a.lu().solve(&b) {
                        let c = Vector3::new(x[0], x[1], 0.0);
                        if x[2] > best && fits(&c, x[2]) {
                            best = x[2];
                        }
                    }
                    continue;
                }
                for l in k + 1..m {
                    let rows = [faces[i], faces[j], faces[k], faces[l]];
                    let a = Matrix4::from_fn(|r, c| if c < 3 { rows[r].normal[c] } else { 1.0 });
                    let b = Vector4::from_fn(|r, _| rows[r].offset);
                    if let Some(x) = a.lu().solve(&b) {
                        let c = Vector3::new(x[0], x[1], x[2]);
                        if x[3] > best && fits(&c, x[3]) {
                            best = x[3];
                        }
                    }
                }
            }
        }
    }
    best
}
