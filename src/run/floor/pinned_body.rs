//! The arithmetic floor of a rigid-body increment: a 2D body turning about a pin, with springs
//! of fixed direction from its points to the ground, constant loads on its points, and one
//! particle that slides along x on a spring, pressed against a face of the body by a penalty
//! (rigid2d_pin_lumped and rigid2d_pin_surface), written out by hand with the state in heap
//! slices: one pass over the body's springs, the particle's springs, the contact pairs and the
//! loads, then the update of the turn and of the particle.
//!
//! It is the same scheme as the explicit engine's (central differences, finite rotation, a
//! unilateral penalty) with the same arithmetic for the motion: the particle's displacement
//! summed with a compensated (Kahan) addition, the orientation kept as its versine and sine,
//! turned by the increment's angle from the first two terms of their series, each summed with
//! its carry and brought back to unit norm. It leaves out what is not the scheme: the contact
//! starts from zero penetration (the engine starts it where the rigid model is), and nothing
//! is checked or recorded (rows, energy, the work of impacts). So it is a floor to time the
//! engine against, not its answer to round-off: `tests/floor.rs` holds it to the case's exact
//! solution at the case's tolerance.

use super::{compensated_add, holds, one_body};
use crate::scene::{Attachment, Connection, Dimension, Dof, Scene, Surface};
use nalgebra::Vector2;
use std::hint::black_box;

/// A spring from a body point to the ground along x: (point relative to the pin, stiffness).
pub type PointSpring = (Vector2<f64>, f64);

/// A pinned body as the floor needs it: every point relative to the pin, at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct PinnedBody {
    /// Inertia about the pin (kg·m²).
    pub inertia: f64,
    /// Initial angular velocity (rad/s).
    pub angular: f64,
    /// Springs from body points to the ground along x: (point, stiffness).
    pub body_springs: Vec<PointSpring>,
    /// Loads on body points: (point, force).
    pub loads: Vec<(Vector2<f64>, Vector2<f64>)>,
    /// The particle: its position, mass, initial velocity along x and the stiffness of its
    /// springs to the ground along x.
    pub particle: (Vector2<f64>, f64, f64, f64),
    /// The face the particle touches: a point and the outward normal, on the body.
    pub face: (Vector2<f64>, Vector2<f64>),
    /// Penalty stiffness (N/m).
    pub penalty: f64,
    /// Duration of the dynamic step (s).
    pub duration: f64,
}

/// The state after a run: the turn, and the particle's displacement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinnedState {
    /// Rotation of the body (rad).
    pub angle: f64,
    /// Displacement of the particle along x (m).
    pub displacement: f64,
}

impl PinnedBody {
    /// The pinned body a scene describes, when it is exactly that: 2D, one body whose
    /// reference node is held in both translations and free to turn, one particle held in uy,
    /// springs of fixed direction x from a body point or the particle to a held node, one plane
    /// contact between the particle and the body, loads on body points, one dynamic step, no
    /// dashpots, the identity frame everywhere.
    pub fn of(scene: &Scene) -> Option<Self> {
        let (body, contact, step, duration) = one_body(scene, Dimension::Two)?;
        let held = |node: usize, dof: Dof| holds(step, node, dof);
        let pin = body.reference;
        let particle = contact.node;
        let on_body = |n: usize| scene.nodes[n].attachment != Attachment::Free;
        let ground = |n: usize| held(n, Dof::Translation(0)) && held(n, Dof::Translation(1));
        if !ground(pin)
            || held(pin, Dof::Rotation(2))
            || on_body(particle)
            || !held(particle, Dof::Translation(1))
            || held(particle, Dof::Translation(0))
            || scene
                .nodes
                .iter()
                .any(|n| n.frame != nalgebra::Matrix3::identity())
            || scene
                .nodes
                .iter()
                .enumerate()
                .any(|(i, n)| n.mass > 0.0 && !on_body(i) && i != particle)
        {
            return None;
        }
        let origin = scene.nodes[pin].position;
        let relative = |n: usize| {
            let p = scene.nodes[n].position - origin;
            Vector2::new(p.x, p.y)
        };
        let (body_springs, particle_stiffness) =
            Self::springs(scene, particle, &relative, &ground, &on_body)?;
        let mut loads = Vec::new();
        for load in &scene.loads {
            if !on_body(load.node) {
                return None;
            }
            loads.push((
                relative(load.node),
                Vector2::new(load.force.x, load.force.y),
            ));
        }
        let Surface::Plane { point, normal } = contact.surface else {
            return None;
        };
        let initial = |n: usize| scene.initial_velocities.iter().find(|v| v.node == n);
        let angular = initial(pin).map_or(0.0, |v| v.angular.z);
        let speed = initial(particle).map_or(0.0, |v| v.velocity.x);
        let face_point = point - origin;
        Some(PinnedBody {
            inertia: body.inertia[(2, 2)],
            angular,
            body_springs,
            loads,
            particle: (
                relative(particle),
                scene.nodes[particle].mass,
                speed,
                particle_stiffness,
            ),
            face: (
                Vector2::new(face_point.x, face_point.y),
                Vector2::new(normal.x, normal.y),
            ),
            penalty: scene.penalty_stiffness(scene.settings.penalty),
            duration,
        })
    }

    /// The springs, all of fixed direction x from a held node: those on body points (with the
    /// point relative to the pin, as `relative` gives it: a 2D or a 3D point) and the
    /// particle's summed stiffness.
    pub(super) fn springs<P>(
        scene: &Scene,
        particle: usize,
        relative: &dyn Fn(usize) -> P,
        ground: &dyn Fn(usize) -> bool,
        on_body: &dyn Fn(usize) -> bool,
    ) -> Option<(Vec<(P, f64)>, f64)> {
        let (mut body_springs, mut particle_stiffness) = (Vec::new(), 0.0);
        for spring in &scene.springs {
            let Connection::FixedDirection { nodes, direction } = spring.connection else {
                return None;
            };
            if direction != nalgebra::Vector3::x() {
                return None;
            }
            let (end, other) = match (ground(nodes[0]), ground(nodes[1])) {
                (false, true) => (nodes[0], nodes[1]),
                (true, false) => (nodes[1], nodes[0]),
                _ => return None,
            };
            if on_body(other) {
                return None;
            }
            if end == particle {
                particle_stiffness += spring.coefficient;
            } else if on_body(end) {
                body_springs.push((relative(end), spring.coefficient));
            } else {
                return None;
            }
        }
        Some((body_springs, particle_stiffness))
    }

    /// The state after `steps` increments of `h`, the state and the element lists in heap
    /// slices of a length the compiler does not know.
    pub fn in_slices(&self, h: f64, steps: u64) -> PinnedState {
        let one = black_box(1usize);
        let (at, mass, speed, stiffness) = self.particle;
        // State: the body's (cos θ − 1, sin θ) and their carries, θ, ω(n−½); the particle's u,
        // its carry, v(n−½).
        let mut heading = vec![Heading::default(); one];
        let mut angle = vec![0.0; one];
        let mut spin = vec![self.angular; one];
        let mut u = vec![0.0; one];
        let mut u_carry = vec![0.0; one];
        let mut v = vec![speed; one];
        let mut moment = vec![0.0; one];
        let mut force = vec![0.0; one];
        let inverse_inertia = vec![1.0 / self.inertia; one];
        let inverse_mass = vec![1.0 / mass; one];
        let particle_springs = vec![stiffness; one];
        let faces = vec![self.face; one];
        let forces = |heading: Heading, u: f64, moment: &mut f64, force: &mut f64| {
            let (c, s) = (1.0 + heading.versine, heading.sine);
            let turn = |p: &Vector2<f64>| Vector2::new(c * p.x - s * p.y, s * p.x + c * p.y);
            *moment = 0.0;
            *force = 0.0;
            for (p, k) in &self.body_springs {
                let q = turn(p);
                let fx = -k * (q.x - p.x);
                *moment -= q.y * fx;
            }
            for k in &particle_springs {
                *force -= k * u;
            }
            let node = Vector2::new(at.x + u, at.y);
            for (point, normal) in &faces {
                let n = turn(normal);
                let gap = (node - turn(point)).dot(&n);
                let f = self.penalty * (-gap).max(0.0);
                *force += n.x * f;
                *moment -= (node.x * n.y - node.y * n.x) * f;
            }
            for (p, f) in &self.loads {
                let q = turn(p);
                *moment += q.x * f.y - q.y * f.x;
            }
        };
        // The half-step velocities from the accelerations at t = 0.
        forces(heading[0], u[0], &mut moment[0], &mut force[0]);
        spin[0] -= 0.5 * h * moment[0] * inverse_inertia[0];
        v[0] -= 0.5 * h * force[0] * inverse_mass[0];
        for _ in 0..steps {
            forces(heading[0], u[0], &mut moment[0], &mut force[0]);
            spin[0] += h * moment[0] * inverse_inertia[0];
            v[0] += h * force[0] * inverse_mass[0];
            let x = h * spin[0];
            heading[0].turn(x);
            angle[0] += x;
            compensated_add(&mut u[0], &mut u_carry[0], h * v[0]);
        }
        PinnedState {
            angle: angle[0],
            displacement: u[0],
        }
    }
}

/// An orientation in 2D as cos θ − 1 and sin θ (the versine keeps its relative precision near
/// θ = 0), each with the carry of its compensated sum.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Heading {
    pub(super) versine: f64,
    pub(super) sine: f64,
    carry: [f64; 2],
}

impl Heading {
    /// Turn by the angle `x` (|x| small: the first two terms of the series of sin and cos − 1),
    /// restoring unit norm by the first-order correction of the excess c² + s² − 1.
    #[inline(always)]
    pub(super) fn turn(&mut self, x: f64) {
        let (v, s) = (self.versine, self.sine);
        let c = 1.0 + v;
        let excess = (2.0 * v + s * s) + v * v;
        let (ds, dc) = (x * (1.0 - x * x / 6.0), x * x * (-0.5 + x * x / 24.0));
        let radial = dc - 0.5 * excess;
        compensated_add(&mut self.versine, &mut self.carry[0], c * radial - s * ds);
        compensated_add(&mut self.sine, &mut self.carry[1], s * radial + c * ds);
    }
}
