//! The arithmetic floor of a sliding rigid body's increment, whose forces read the velocity where
//! its mass centre is off its reference node: a 2D body that slides along x and turns, with springs
//! of fixed direction from its points to the ground, constant loads on its points, and one particle
//! that slides along x on a spring, pressed against a face of the body by a penalty
//! (rigid2d_slide_surface), written out by hand with the state in heap slices: one pass over the
//! body's springs, the particle's springs, the contact pairs and the loads, then the centred
//! velocity, then the update of the body and of the particle. The same body with its mass centre on
//! its reference node (rigid2d_slide_lumped) has no force that reads the velocity: its
//! accelerations are formed once per increment from a mass matrix formed once, as the engine forms
//! them.
//!
//! It is the same scheme as the explicit engine's (central differences, finite rotation, a
//! unilateral penalty). With the mass centre off the reference node the centripetal force
//! m ω²c reads the angular velocity at time n, so the body's accelerations come from the
//! centred velocity `v(n) = v(n−½) + (h/2)·a(v(n))`, found as the engine finds it: the
//! accelerations are those at rest plus ω² times those under the unit centripetal force, so
//! ω(n) is the root of a quadratic, taken in closed form ([`centred_about_axis`]) where the
//! fixed-point iteration would contract by at most ½, and otherwise iterated from
//! `v(n−½) + (h/2)·a(n−1)` and stopped by the engine's rule (the change within 1e-14 of the
//! largest rate, or within that of the fixed point by the contraction bound after a
//! contracting pass). Each solve of the body's 2×2 mass matrix about the reference node gives
//! the acceleration along x and the angular acceleration; the part of it that depends on the
//! heading is formed once per increment. The start at t = 0 is
//! the engine's: a(0) at the initial velocities, then `v(½) = v(0) + (h/2)·a(0)`. The motion
//! keeps the engine's arithmetic: translations summed with a compensated (Kahan) addition, the
//! orientation kept as its versine and sine and turned as [`super::PinnedBody`] turns it. Only
//! the rates the velocity reaches are iterated (the body's), and the stop rule measures them
//! alone (the engine's measures every rate, the particle's too).
//!
//! It leaves out what is not the scheme: the contact starts from zero penetration (the engine
//! starts it where the rigid model is, and the penalty mode then rings), an iteration that
//! does not converge in 100
//! passes is taken as it stands (the engine refuses the run), and nothing is checked or
//! recorded (rows, energy, the work of impacts). So it is a floor to time the engine against,
//! not its answer to round-off: `tests/floor.rs` holds it to the case's exact solution at the
//! case's tolerance.

use super::pinned_body::{Heading, PinnedBody, PointSpring};
use super::{compensated_add, condition, one_body};
use crate::scene::{Attachment, DampingTreatment, Dimension, Dof, Scene, Surface};
use nalgebra::Vector2;
use std::hint::black_box;

/// Passes of the centred velocity iteration, at most (the engine's limit).
const MAX_PASSES: usize = 100;

/// The iteration stops when the body's rates are within this fraction of the largest of them
/// from their fixed point (the engine's tolerance).
const VELOCITY_TOLERANCE: f64 = 1e-14;

/// A body sliding along x and turning, as the floor needs it: every point relative to the
/// reference node, at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct SlidingBody {
    /// Mass (kg).
    pub mass: f64,
    /// Mass centre relative to the reference node (m): zero where the body is lumped.
    pub centre: Vector2<f64>,
    /// Inertia about the reference node (kg·m²).
    pub inertia: f64,
    /// Initial velocity of the reference node along x (m/s) and angular velocity (rad/s).
    pub velocity: (f64, f64),
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

/// The state after a run: the turn, the translation of the reference node, and the particle's
/// displacement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingState {
    /// Rotation of the body (rad).
    pub angle: f64,
    /// Displacement of the reference node along x (m).
    pub translation: f64,
    /// Displacement of the particle along x (m).
    pub displacement: f64,
    /// Acceleration passes over the run (one per increment where no force reads the velocity,
    /// more where the centred velocity is iterated).
    pub passes: u64,
}

/// What the force pass gives: the force along x and the moment about the reference node on
/// the body, and the force along x on the particle.
#[derive(Debug, Clone, Copy, Default)]
struct Load {
    force: f64,
    moment: f64,
    particle: f64,
}

/// The body's rates along its free DOFs: along x of the reference node, and about z.
type Rates = [f64; 2];

/// The body's mass matrix about the reference node at a heading, as the solve for (a, α)
/// needs it. With the centre c in world axes and the reference node held in y, the equations
/// `m a − m c_y α = f`, `−m c_y a + I α = M` (the centripetal force m ω²c_x added to f) give
/// `α = (M + c_y f)/(I − m c_y²)` and `a = f/m + c_y α`.
#[derive(Debug, Clone, Copy)]
struct MassMatrix {
    /// m c_x: the centripetal force along x per ω².
    pull: f64,
    /// c_y.
    lever: f64,
    inverse_mass: f64,
    /// 1/(I − m c_y²).
    inverse: f64,
}

impl MassMatrix {
    /// At `heading`, for `body` of mass 1/`inverse_mass`.
    fn at(body: &SlidingBody, inverse_mass: f64, heading: &Heading) -> Self {
        let (c, s) = (1.0 + heading.versine, heading.sine);
        let (x, y) = (body.centre.x, body.centre.y);
        let (cx, cy) = (c * x - s * y, s * x + c * y);
        MassMatrix {
            pull: body.mass * cx,
            lever: cy,
            inverse_mass,
            inverse: 1.0 / (body.inertia - body.mass * cy * cy),
        }
    }

    /// The accelerations (a, α) under `load` of a body whose mass centre is its reference
    /// node: (f/m, M/I).
    #[inline(always)]
    fn lumped_accelerations(&self, load: &Load) -> Rates {
        [load.force * self.inverse_mass, load.moment * self.inverse]
    }

    /// The accelerations (a, α) under `load` at angular velocity `spin`.
    #[inline(always)]
    fn accelerations(&self, load: &Load, spin: f64) -> Rates {
        let f = load.force + self.pull * (spin * spin);
        let alpha = (load.moment + self.lever * f) * self.inverse;
        [f * self.inverse_mass + self.lever * alpha, alpha]
    }
}

impl SlidingBody {
    /// The sliding body a scene describes, when it is exactly that: 2D, one body whose
    /// reference node is held in uy and free along x and to turn, with its mass centre off
    /// that node (rigid2d_slide_surface) or on it (rigid2d_slide_lumped, where no force reads
    /// the velocity and the accelerations are formed once per increment, as the engine forms
    /// them); one particle held in uy and free along x; springs of fixed direction x from
    /// a body point or the particle to a held node; one plane contact between the particle and
    /// the body, without a contact dashpot; loads on body points; initial velocities on the
    /// reference node and the particle only; one dynamic step; no dashpots; the centred
    /// velocity; the identity frame everywhere.
    pub fn of(scene: &Scene) -> Option<Self> {
        if scene.settings.damping != DampingTreatment::Centred {
            return None;
        }
        let (body, contact, step, duration) = one_body(scene, Dimension::Two)?;
        let condition = |node: usize, dof: Dof| condition(step, node, dof);
        let held = |node: usize, dof: Dof| condition(node, dof).is_some_and(|c| c.value.is_none());
        let free = |node: usize, dof: Dof| condition(node, dof).is_none();
        let (reference, particle) = (body.reference, contact.node);
        let on_body = |n: usize| scene.nodes[n].attachment != Attachment::Free;
        let ground = |n: usize| held(n, Dof::Translation(0)) && held(n, Dof::Translation(1));
        let centre = Vector2::new(body.centre_offset.x, body.centre_offset.y);
        if !held(reference, Dof::Translation(1))
            || !free(reference, Dof::Translation(0))
            || !free(reference, Dof::Rotation(2))
            || on_body(particle)
            || !held(particle, Dof::Translation(1))
            || !free(particle, Dof::Translation(0))
            || contact.restitution != 1.0
            || !Self::plain(scene, particle, reference)
        {
            return None;
        }
        let origin = scene.nodes[reference].position;
        let relative = |n: usize| {
            let p = scene.nodes[n].position - origin;
            Vector2::new(p.x, p.y)
        };
        let (body_springs, particle_stiffness) =
            PinnedBody::springs(scene, particle, &relative, &ground, &on_body)?;
        let mut loads = Vec::new();
        for load in &scene.loads {
            if !on_body(load.node) {
                return None;
            }
            let force = Vector2::new(load.force.x, load.force.y);
            loads.push((relative(load.node), force));
        }
        let Surface::Plane { point, normal } = contact.surface else {
            return None;
        };
        let initial = |n: usize| scene.initial_velocities.iter().find(|v| v.node == n);
        let (speed, angular) =
            initial(reference).map_or((0.0, 0.0), |v| (v.velocity.x, v.angular.z));
        let face_point = point - origin;
        Some(SlidingBody {
            mass: body.mass,
            centre,
            inertia: body.inertia[(2, 2)],
            velocity: (speed, angular),
            body_springs,
            loads,
            particle: (
                relative(particle),
                scene.nodes[particle].mass,
                initial(particle).map_or(0.0, |v| v.velocity.x),
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

    /// Whether the nodes are as the floor takes them: the identity frame everywhere, no mass
    /// off the body but the particle's, initial velocities only on the reference node and the
    /// particle.
    pub(super) fn plain(scene: &Scene, particle: usize, reference: usize) -> bool {
        let nodes = scene.nodes.iter().enumerate();
        nodes
            .clone()
            .all(|(_, n)| n.frame == nalgebra::Matrix3::identity())
            && nodes
                .clone()
                .all(|(i, n)| n.mass == 0.0 || n.attachment != Attachment::Free || i == particle)
            && scene
                .initial_velocities
                .iter()
                .all(|v| v.node == reference || v.node == particle)
    }

    /// The forces at the heading, the body's translation `x` and the particle's displacement
    /// `u`: one pass over each list.
    #[inline(always)]
    fn forces(&self, lists: &Lists, heading: &Heading, x: f64, u: f64) -> Load {
        let (c, s) = (1.0 + heading.versine, heading.sine);
        let turn = |p: &Vector2<f64>| Vector2::new(c * p.x - s * p.y, s * p.x + c * p.y);
        let mut load = Load::default();
        for (p, k) in &self.body_springs {
            let q = turn(p);
            let fx = -k * (x + (q.x - p.x));
            load.force += fx;
            load.moment -= q.y * fx;
        }
        for k in &lists.particle_springs {
            load.particle -= k * u;
        }
        // The particle relative to the reference node.
        let at = self.particle.0;
        let node = Vector2::new(at.x + (u - x), at.y);
        for (point, normal) in &lists.faces {
            let n = turn(normal);
            let gap = (node - turn(point)).dot(&n);
            let f = self.penalty * (-gap).max(0.0);
            load.particle += n.x * f;
            load.force -= n.x * f;
            load.moment -= (node.x * n.y - node.y * n.x) * f;
        }
        for (p, f) in &self.loads {
            let q = turn(p);
            load.force += f.x;
            load.moment += q.x * f.y - q.y * f.x;
        }
        load
    }

    /// The state after `steps` increments of `h`, the state and the element lists in heap
    /// slices of a length the compiler does not know.
    pub fn in_slices(&self, h: f64, steps: u64) -> SlidingState {
        let one = black_box(1usize);
        let (_, mass, speed, stiffness) = self.particle;
        let lists = Lists {
            particle_springs: vec![stiffness; one],
            faces: vec![self.face; one],
        };
        // State: the body's (cos θ − 1, sin θ) and their carries, θ, its translation and carry,
        // its rates at n − ½ and accelerations at n − 1; the particle's u, its carry, v(n−½).
        let mut heading = vec![Heading::default(); one];
        let mut angle = vec![0.0; one];
        let (mut x, mut x_carry) = (vec![0.0; one], vec![0.0; one]);
        let mut rates = vec![[self.velocity.0, self.velocity.1]; one];
        let mut acc = vec![[0.0; 2]; one];
        let (mut u, mut u_carry) = (vec![0.0; one], vec![0.0; one]);
        let mut v = vec![speed; one];
        let mut load = vec![Load::default(); one];
        let inverse_mass = vec![1.0 / mass; one];
        let inverse_body_mass = vec![1.0 / self.mass; one];
        // t = 0: the accelerations at the initial velocities, and v(−½) = v(0) − (h/2)·a(0), so
        // that the first increment's kick gives v(½) = v(0) + (h/2)·a(0).
        load[0] = self.forces(&lists, &heading[0], x[0], u[0]);
        let matrix = MassMatrix::at(self, inverse_body_mass[0], &heading[0]);
        acc[0] = matrix.accelerations(&load[0], rates[0][1]);
        rates[0] = plus(rates[0], -0.5 * h, acc[0]);
        v[0] -= 0.5 * h * load[0].particle * inverse_mass[0];
        // A body whose mass centre is its reference node (lumped) feels no centripetal force
        // and its mass matrix does not turn with it: formed once, and the accelerations, which
        // then do not read the velocity, once per increment, without iterating.
        let lumped = self.centre == Vector2::zeros();
        let mut passes = 0;
        for _ in 0..steps {
            load[0] = self.forces(&lists, &heading[0], x[0], u[0]);
            if lumped {
                acc[0] = matrix.lumped_accelerations(&load[0]);
                passes += 1;
            } else {
                let matrix = MassMatrix::at(self, inverse_body_mass[0], &heading[0]);
                let at = |guess: &Rates| matrix.accelerations(&load[0], guess[1]);
                let responses = (at(&[0.0; 2]), matrix.accelerations(&Load::default(), 1.0));
                let (a, taken) = match centred_about_axis(responses, rates[0], 1, h) {
                    Some(a) => (a, 2),
                    None => centred(at, rates[0], acc[0], h),
                };
                (acc[0], passes) = (a, passes + taken);
            }
            rates[0] = plus(rates[0], h, acc[0]);
            v[0] += h * load[0].particle * inverse_mass[0];
            let turn = h * rates[0][1];
            heading[0].turn(turn);
            angle[0] += turn;
            compensated_add(&mut x[0], &mut x_carry[0], h * rates[0][0]);
            compensated_add(&mut u[0], &mut u_carry[0], h * v[0]);
        }
        SlidingState {
            angle: angle[0],
            translation: x[0],
            displacement: u[0],
            passes,
        }
    }
}

/// The element lists the floor keeps in slices: the particle's springs, the contact faces.
struct Lists {
    particle_springs: Vec<f64>,
    faces: Vec<(Vector2<f64>, Vector2<f64>)>,
}

/// `a + s·b`.
#[inline(always)]
pub(super) fn plus<const N: usize>(a: [f64; N], s: f64, b: [f64; N]) -> [f64; N] {
    std::array::from_fn(|k| a[k] + s * b[k])
}

/// The largest of `f(k)` over the `N` components.
#[inline(always)]
fn largest<const N: usize>(f: impl Fn(usize) -> f64) -> f64 {
    (1..N).fold(f(0), |m, k| m.max(f(k)))
}

/// The accelerations at the centred velocity where they read the rates through the square of
/// one alone, ω, the rate about the body's one free axis (index `spin`): with `at_rest` the
/// accelerations at ω = 0 and `per_square` those per ω², ω(n) solves ω = C + k·ω² with
/// C = ω(n−½) + (h/2)·at_rest[spin] and k = (h/2)·per_square[spin], whose root near C is
/// 2C/(1 + √(1 − 4kC)). Taken as the engine takes it, where the iteration would contract by at
/// most ½ there (the square root within [½, 3/2]); `None` elsewhere, where the caller
/// iterates ([`centred`]).
#[inline(always)]
pub(super) fn centred_about_axis<const N: usize>(
    (at_rest, per_square): ([f64; N], [f64; N]),
    half: [f64; N],
    spin: usize,
    h: f64,
) -> Option<[f64; N]> {
    let s = 0.5 * h;
    let (c, k) = (half[spin] + s * at_rest[spin], s * per_square[spin]);
    let root = (1.0 - 4.0 * k * c).sqrt();
    if !(0.5..=1.5).contains(&root) {
        return None;
    }
    let w = 2.0 * c / (1.0 + root);
    Some(plus(at_rest, w * w, per_square))
}

/// The accelerations at the centred velocity `v(n) = v(n−½) + (h/2)·a(v(n))`, by fixed-point
/// iteration from `v(n−½) + (h/2)·a(n−1)` (`half`, `previous`): each pass the accelerations
/// `accelerations` gives at the guess, then the guess they give. The iteration contracts by ρ
/// per pass, so the guess just made is within ρ/(1−ρ)·change of the fixed point; it stops
/// where the change is within the tolerance of the largest rate, or, after a contracting pass
/// (ρ < ½), where that bound is: change² ≤ tolerance·(previous change − change). Returns the
/// last pass's accelerations and the passes taken.
#[inline(always)]
pub(super) fn centred<const N: usize>(
    accelerations: impl Fn(&[f64; N]) -> [f64; N],
    half: [f64; N],
    previous: [f64; N],
    h: f64,
) -> ([f64; N], u64) {
    let mut guess = plus(half, 0.5 * h, previous);
    let mut acc = previous;
    let mut previous_change = 0.0;
    let mut passes = 0;
    for _ in 0..MAX_PASSES {
        passes += 1;
        acc = accelerations(&guess);
        let next = plus(half, 0.5 * h, acc);
        let change = largest::<N>(|k| (next[k] - guess[k]).abs());
        let tolerance = VELOCITY_TOLERANCE * largest::<N>(|k| next[k].abs());
        let contracting = 2.0 * change < previous_change;
        let bound_met = change * change <= tolerance * (previous_change - change);
        previous_change = change;
        guess = next;
        if change <= tolerance || (contracting && bound_met) {
            break;
        }
    }
    (acc, passes)
}
