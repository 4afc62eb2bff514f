//! A closed pair's kinematics at its contact point: what touches (a particle, or a ball rigid
//! with a body), the point it touches the master body at, and the velocity rows there.
//!
//! A particle touches with itself: the contact point P is the node p, its velocity ṗ. A body's
//! node N carrying a ball of radius ρ touches a plane at P = p_N − ρ n (n the plane's outward
//! normal, turning with the master body), and the slave body's material point there moves at
//! v_s + ω_s × (P − x_s). Either way the relative velocity at P is
//!
//!   V = Ṗ_s − v − ω × (P − x),
//!
//! Ṗ_s the slave's material velocity at P, v, ω, x the master body's. Its normal part is the
//! gap's rate (n·(ω_s × n) = 0: the ball's spin does not move P along n), its tangential part
//! the slip. For a direction e turning with the master body (ė = ω × e), d/dt (e·V) is the row
//! of e·V on u̇ plus
//!
//!   (ω × e)·V + e·(ω_s × (Ṗ − v_s)) − e·(ω × (Ṗ − v)),
//!
//! Ṗ the contact point's own rate: ṗ for a particle (no ω_s), v_s + ω_s × (p_N − x_s) − ρ ω × n
//! for a ball ([`Touch::rate`]).

use super::{Mechanism, Placement, add_row, row_rate};
use crate::scene::{Dimension, surface_distance};
use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};

/// What a contact pair's node is.
#[derive(Debug, Clone, Copy)]
pub(super) enum Slave {
    /// A free node: particle index.
    Particle(usize),
    /// A node of a body carrying a ball rigid with it.
    Ball {
        /// The body.
        body: usize,
        /// The node from the body's reference node at t = 0.
        offset: Vector3<f64>,
        /// The ball's radius.
        radius: f64,
    },
}

impl Slave {
    /// The ball's radius; 0 for a particle.
    pub(super) fn radius(&self) -> f64 {
        match *self {
            Slave::Particle(_) => 0.0,
            Slave::Ball { radius, .. } => radius,
        }
    }
}

/// The slave side of a closed pair at a placement and velocity.
#[derive(Debug, Clone, Copy)]
enum Side {
    /// A particle: u's column of its ṗ.
    Particle(usize),
    /// A body's ball.
    Ball {
        /// u's column of the body's v (ω_s follows).
        column: usize,
        /// P − x_s.
        arm: Vector3<f64>,
        /// p_N − x_s.
        node_arm: Vector3<f64>,
        /// ω_s.
        w: Vector3<f64>,
        /// ρ.
        radius: f64,
    },
}

/// A closed pair's kinematics at a placement and velocity.
pub(super) struct Touch {
    side: Side,
    /// u's column of the master body's v (ω follows).
    body: usize,
    pub(super) rot: UnitQuaternion<f64>,
    /// P − x.
    arm: Vector3<f64>,
    /// Ṗ_s − v.
    relative: Vector3<f64>,
    /// ω.
    w: Vector3<f64>,
    /// The surface's unit outward normal at the node (world).
    normal: Vector3<f64>,
    /// The unit tangents (world): one in 2D (in the plane), two in 3D.
    pub(super) tangents: Vec<Vector3<f64>>,
}

impl Touch {
    /// The tangential part of a vector.
    pub(super) fn tangential(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.tangents
            .iter()
            .fold(Vector3::zeros(), |s, t| s + t * t.dot(v))
    }

    /// The relative velocity at the contact point, V = Ṗ_s − v − ω × (P − x).
    pub(super) fn slip(&self) -> Vector3<f64> {
        self.relative - self.w.cross(&self.arm)
    }

    /// The surface's unit outward normal (world).
    pub(super) fn normal(&self) -> Vector3<f64> {
        self.normal
    }

    /// Add the row of e·V (on u) to row `row` of `g`.
    pub(super) fn add_row(&self, g: &mut DMatrix<f64>, row: usize, e: &Vector3<f64>) {
        match self.side {
            Side::Particle(column) => add_row(g, row, e, &self.arm, column, self.body),
            Side::Ball { column, arm, .. } => {
                let spin = arm.cross(e);
                let moment = self.arm.cross(e);
                for a in 0..3 {
                    g[(row, column + a)] += e[a];
                    g[(row, column + 3 + a)] += spin[a];
                    g[(row, self.body + a)] -= e[a];
                    g[(row, self.body + 3 + a)] -= moment[a];
                }
            }
        }
    }

    /// The generalised row (on u) of e·V.
    pub(super) fn row(&self, e: &Vector3<f64>, n: usize) -> DVector<f64> {
        let mut g = DMatrix::zeros(1, n);
        self.add_row(&mut g, 0, e);
        g.row(0).transpose()
    }

    /// The velocity terms of d/dt (e·V) for a direction e turning with the master body (see
    /// the module's doc): for a ball, the particle's terms with Ṗ_s for ṗ, less e·(ω × (Ṗ − Ṗ_s))
    /// with Ṗ − Ṗ_s = ρ (ω_s − ω) × n, plus e·(ω_s × (Ṗ − v_s)).
    pub(super) fn rate(&self, e: &Vector3<f64>) -> f64 {
        let particle = row_rate(e, &self.w, &self.relative, &self.arm);
        let Side::Ball {
            node_arm,
            w: spin,
            radius,
            ..
        } = self.side
        else {
            return particle;
        };
        let drift = (spin - self.w).cross(&self.normal) * radius;
        let moving = spin.cross(&node_arm) - self.w.cross(&self.normal) * radius;
        particle - e.dot(&self.w.cross(&drift)) + e.dot(&spin.cross(&moving))
    }
}

impl Mechanism {
    /// Pair `k`'s node position (world): the particle, or the body point.
    pub(super) fn node_position(&self, at: &Placement, k: usize) -> Vector3<f64> {
        match self.contacts[k].slave {
            Slave::Particle(i) => at.particles[i],
            Slave::Ball { body, offset, .. } => at.origins[body] + at.orientations[body] * offset,
        }
    }

    /// Pair `k`'s unit tangents at its node (world): the one in the plane in 2D, two in 3D,
    /// fixed in the body frame (functions of the surface's normal there).
    pub(super) fn tangents(&self, at: &Placement, k: usize) -> Vec<Vector3<f64>> {
        let c = &self.contacts[k];
        let rot = at.orientations[c.body];
        let local = rot.inverse() * (self.node_position(at, k) - at.origins[c.body]);
        let (_, n0) = surface_distance(&c.surface, &local);
        match self.dimension {
            Dimension::Two => vec![rot * Vector3::new(-n0.y, n0.x, 0.0)],
            Dimension::Three => {
                let t1 = n0.cross(&Vector3::ith(n0.iamin(), 1.0)).normalize();
                vec![rot * t1, rot * n0.cross(&t1)]
            }
        }
    }

    /// Pair `k`'s kinematics at its contact point.
    pub(super) fn touch(&self, at: &Placement, u: &DVector<f64>, k: usize) -> Touch {
        let c = &self.contacts[k];
        let base = 3 * self.particles.len();
        let body = base + 6 * c.body;
        let rot = at.orientations[c.body];
        let x = at.origins[c.body];
        let p = self.node_position(at, k);
        let (_, n0) = surface_distance(&c.surface, &(rot.inverse() * (p - x)));
        let normal = rot * n0;
        let v = u.fixed_rows::<3>(body);
        let (side, arm, relative) = match c.slave {
            Slave::Particle(i) => (Side::Particle(3 * i), p - x, u.fixed_rows::<3>(3 * i) - v),
            Slave::Ball {
                body: b, radius, ..
            } => {
                let column = base + 6 * b;
                let point = p - normal * radius;
                let slave_arm = point - at.origins[b];
                let spin = u.fixed_rows::<3>(column + 3).into_owned();
                let material = u.fixed_rows::<3>(column) + spin.cross(&slave_arm);
                let side = Side::Ball {
                    column,
                    arm: slave_arm,
                    node_arm: p - at.origins[b],
                    w: spin,
                    radius,
                };
                (side, point - x, material - v)
            }
        };
        Touch {
            side,
            body,
            rot,
            arm,
            relative,
            w: u.fixed_rows::<3>(body + 3).into_owned(),
            normal,
            tangents: self.tangents(at, k),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Mechanism, Placement};
    use nalgebra::{DVector, UnitQuaternion, Vector3};
    use std::path::Path;

    /// friction_roll_3d with two more pairs: a node of the ball off its centre carrying a ball
    /// of radius 0.2 against a face turned 37° about z, and a particle against the top face
    /// (the velocities are set in the test: the steps' holds do not enter).
    fn mechanism() -> Mechanism {
        let mut text = std::fs::read_to_string("cases/friction/friction_roll_3d.toml").unwrap();
        text.push_str(
            r#"
[[nodes]]
id = "N"
at = [0.1, 0.6, 0.2]
body = "ball"

[[nodes]]
id = "P"
at = [1.0, 1.0, 1.0]

[[masses]]
node = "P"
mass = 1.0

[[contacts]]
id = "side"
node = "N"
node_radius = 0.2
body = "block"
face_point = [0.0, -2.0, 0.0]
face_normal = [0.6, 0.8, 0.0]
initially = "open"

[[contacts]]
id = "dot"
node = "P"
body = "block"
face_point = [0.0, 0.0, 0.0]
face_normal = [0.0, 1.0, 0.0]
initially = "open"
"#,
        );
        let scene = crate::case::parse(&text, Path::new("cases/friction/friction_roll_3d.toml"))
            .unwrap_or_else(|e| panic!("{e}"));
        Mechanism::new(&scene).unwrap()
    }

    /// The placement `at` moved for time `t` at the constant full velocity `u` (each body
    /// turning at its constant world ω: R(t) = exp([ω] t) R).
    fn moved(m: &Mechanism, at: &Placement, u: &DVector<f64>, t: f64) -> Placement {
        let mut p = at.clone();
        for (i, x) in p.particles.iter_mut().enumerate() {
            *x += u.fixed_rows::<3>(3 * i) * t;
        }
        let base = 3 * m.particles.len();
        for (b, (x, q)) in p.origins.iter_mut().zip(&mut p.orientations).enumerate() {
            *x += u.fixed_rows::<3>(base + 6 * b) * t;
            let w: Vector3<f64> = u.fixed_rows::<3>(base + 6 * b + 3).into_owned();
            *q = UnitQuaternion::from_scaled_axis(w * t) * *q;
        }
        p
    }

    /// [`Touch::rate`] is d/dt (e·V) for e the normal and the tangents, turning with the master
    /// body, at constant velocities (u̇ = 0: the row's part vanishes) with both bodies turning,
    /// against a 4th-order central difference of e·V along the motion (h = 1e-3: truncation
    /// ~h⁴ f⁽⁵⁾ ~ 1e-11, round-off ~1e-16/h ~ 1e-13, over rates of order 10).
    #[test]
    fn the_rate_is_the_derivative_of_the_relative_velocity_along_the_motion() {
        let m = mechanism();
        let mut at = m.initial_placement();
        at.orientations[0] = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.2, 0.5));
        at.orientations[1] = UnitQuaternion::from_scaled_axis(Vector3::new(-0.4, 0.7, 0.1));
        at.origins[0] += Vector3::new(0.1, -0.2, 0.05);
        let u = DVector::from_fn(m.velocity_len(), |i, _| 1.5 * (1.7 * i as f64 + 0.3).sin());
        let h = 1e-3;
        for k in 0..m.contact_count() {
            let touch = m.touch(&at, &u, k);
            let directions: Vec<usize> = (0..=touch.tangents.len()).collect();
            for d in directions {
                let along = |t: f64| {
                    let moved = m.touch(&moved(&m, &at, &u, t), &u, k);
                    let e = if d == 0 {
                        moved.normal()
                    } else {
                        moved.tangents[d - 1]
                    };
                    e.dot(&moved.slip())
                };
                let numeric = (8.0 * (along(h) - along(-h)) - (along(2.0 * h) - along(-2.0 * h)))
                    / (12.0 * h);
                let e = if d == 0 {
                    touch.normal()
                } else {
                    touch.tangents[d - 1]
                };
                let rate = touch.rate(&e);
                println!("pair {k}, direction {d}: rate {rate:.12} against {numeric:.12}");
                assert!((rate - numeric).abs() < 1e-9, "pair {k}, direction {d}");
            }
        }
    }
}
