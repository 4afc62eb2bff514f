//! The arithmetic floor of a 3D rigid-body increment: a body turning about z, with its
//! reference node held in the rotations about x and y and in y and z, and either sliding along
//! x (rigid3d_slide_surface, rigid3d_slide_lumped: the scene of [`super::SlidingBody`]
//! extruded in z) or pinned, held in x too (rigid3d_pin_surface, rigid3d_pin_lumped: the scene
//! of [`super::PinnedBody`] extruded in z); its mass centre off that node or on it, springs of
//! fixed direction x from its points to the ground, constant loads on its points, and one
//! particle held in y and z, pressed against a face of the body by a penalty. The answer is
//! the 2D twin's; the arithmetic is what a 3D explicit engine must do for it, written out by
//! hand with the state in heap slices. Where no force reads the velocity (the mass centre on
//! the reference node, or the node pinned, so that the centripetal force acts on a held
//! translation alone) the accelerations are formed once per increment without iterating, as
//! the engine forms them; the mass matrix, which a turn about the free axis leaves as it is,
//! is then formed once, as the engine forms its body solve once per step for such a body.
//!
//! What stays 3D, as in the explicit engine's spatial kinematics: the orientation is a unit
//! quaternion, turned each increment by the rotation vector h·ω(n+½) (a 3-vector) as the
//! engine turns it (the increment's half-angle series at these angles, the product written
//! out from the rotation vector, the four components each summed with its carry and pulled
//! back to unit norm in the same increment), and R − 1 is formed from its small parts once per
//! increment; body points, the face's point and normal and the mass centre are turned by
//! R − 1 as 3-vectors; forces, moments, the body's rates and accelerations are 3-vectors; the
//! centripetal force is m ω×(ω×c) with 3-vectors; a sliding body's translation is a 3-vector
//! summed with a compensated addition (a pinned body's is not formed). What exploits that only
//! two of the body's six DOFs are free (one where it is pinned) is what the engine's body solve
//! (`BodyOperator`, one free rotation axis g and the free translations' projector Q) exploits
//! too: the rigid-body equations are eliminated to one pivot,
//! `(g·I g − m w·w) s = g·M − f·w` with `w = Q(g × c)`, then `a = Q f/m − w s` and
//! `α = s g` (Q = 0 where pinned), with g·I g formed from the body-frame inertia through
//! `Rᵀ g` once per increment. The gyroscopic moment ω×(Iω) is left out, as the engine leaves
//! it out on a body turning about one axis: it is perpendicular to ω and so to g, and the solve
//! reads the moment along g only. The particle, held in y and z, moves along x alone, as the
//! engine's particle kernel moves particles that all share one free axis: its position enters
//! the contact as a 3D point, its force is a 3-vector, its state a scalar.
//!
//! The rest is the 2D floors' scheme: the centred velocity in closed form where the iteration
//! would contract by at most ½, otherwise by fixed-point iteration with the engine's stop rule
//! ([`super::sliding_body`]), here over the body's six rates (the engine's measures the
//! particle's too), the start at t = 0 from a(0), the contact from zero
//! penetration, no checks and no records. The rotation increment keeps the series the engine
//! keeps below |h·ω| of 4.5e-4 (one term of the sine's, two of the cosine's) without the
//! engine's test of |h·ω|: the floor is for increments whose turn is that small (at the case's
//! increment |ω| reaches about 37 rad/s and |h·ω| 3.8e-4 when sliding, measured; the benchmark
//! runs at a tenth of it). The angle it reports is the twist of the quaternion about z, formed
//! once after the run. `tests/floor.rs` holds it to the case's exact solution at the case's
//! tolerance and to the 2D floor's end state.

use super::pinned_body::PinnedBody;
use super::sliding_body::{SlidingBody, SlidingState, centred, centred_about_axis, plus};
use super::{compensated_add, condition, one_body};
use crate::scene::{Attachment, DampingTreatment, Dimension, Dof, Scene, Surface};
use nalgebra::{Matrix3, Vector3, Vector4};
use std::hint::black_box;

/// The free translation of a sliding body and of the particle: along x.
const SLIDE: Vector3<f64> = Vector3::new(1.0, 0.0, 0.0);

/// The body's free rotation axis: z.
const AXIS: Vector3<f64> = Vector3::new(0.0, 0.0, 1.0);

/// The springs' fixed direction: x.
const ALONG: Vector3<f64> = Vector3::new(1.0, 0.0, 0.0);

/// A body turning about z in 3D, sliding along x or pinned, as the floor needs it: every point
/// relative to the reference node, at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct TurningBody3d {
    /// Mass (kg).
    pub mass: f64,
    /// Mass centre relative to the reference node (m): zero where the body is lumped.
    pub centre: Vector3<f64>,
    /// Inertia about the reference node, in the body's axes (kg·m²).
    pub inertia: Matrix3<f64>,
    /// Whether the reference node slides along x (otherwise it is pinned: held in every
    /// translation).
    pub slides: bool,
    /// Initial velocity of the reference node (m/s) and angular velocity (rad/s), along the
    /// free DOFs.
    pub velocity: (Vector3<f64>, Vector3<f64>),
    /// Springs from body points to the ground along x: (point, stiffness).
    pub body_springs: Vec<(Vector3<f64>, f64)>,
    /// Loads on body points: (point, force).
    pub loads: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// The particle: its position, mass, initial velocity along x and the stiffness of its
    /// springs to the ground along x.
    pub particle: (Vector3<f64>, f64, f64, f64),
    /// The face the particle touches: a point and the outward normal, on the body.
    pub face: (Vector3<f64>, Vector3<f64>),
    /// Penalty stiffness (N/m).
    pub penalty: f64,
    /// Duration of the dynamic step (s).
    pub duration: f64,
}

/// What the force pass gives: the force and the moment about the reference node on the body,
/// and the force on the particle.
#[derive(Debug, Clone, Copy, Default)]
struct Load {
    force: Vector3<f64>,
    moment: Vector3<f64>,
    particle: Vector3<f64>,
}

/// The body's rates: the reference node's velocity, then the angular velocity.
type Rates = [f64; 6];

/// A 3D orientation as the engine keeps it: the unit quaternion's coordinates (i, j, k, w)
/// with the carries of their compensated sums, and R − 1 formed from them.
#[derive(Debug, Clone, Copy)]
struct Orientation {
    coords: Vector4<f64>,
    carry: [f64; 4],
    /// R − 1 = 2w [v]× + 2 [v]×², from the small parts (w, v).
    turn: Matrix3<f64>,
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation {
            coords: Vector4::new(0.0, 0.0, 0.0, 1.0),
            carry: [0.0; 4],
            turn: Matrix3::zeros(),
        }
    }
}

impl Orientation {
    /// Turn by the rotation vector `d` (world axes, |d| < 4.5e-4): q ← q + dq with
    /// `dq = ½p − (excess/2)·q + t·p + w·q`, p = (0, d) ⊗ q, w = cos(|d|/2) − 1 and
    /// t = sin(|d|/2)/|d| − ½ from their series, each component summed with its carry; then
    /// R − 1 from the new quaternion.
    #[inline(always)]
    fn turn(&mut self, d: &Vector3<f64>) {
        let y = d.norm_squared();
        let (w, t) = (y * (-1.0 / 8.0 + y * (1.0 / 384.0)), y * (-1.0 / 48.0));
        let q = self.coords;
        let excess = (q.norm_squared() - 1.0) - 2.0 * q.dot(&Vector4::from(self.carry));
        let (v, s) = (Vector3::new(q.x, q.y, q.z), q.w);
        let c = d.cross(&v);
        let p = Vector4::new(s * d.x + c.x, s * d.y + c.y, s * d.z + c.z, -d.dot(&v));
        let dq = (p * 0.5 - q * (0.5 * excess)) + (p * t + q * w);
        for i in 0..4 {
            compensated_add(&mut self.coords[i], &mut self.carry[i], dq[i]);
        }
        self.turn = small_parts(&self.coords);
    }

    /// The twist about the unit axis `g` (rad), from the carried quaternion.
    fn twist(&self, g: &Vector3<f64>) -> f64 {
        let q = self.coords - Vector4::from(self.carry);
        2.0 * Vector3::new(q.x, q.y, q.z).dot(g).atan2(q.w)
    }
}

/// R − 1 of the unit quaternion `q` (i, j, k, w), from its small parts so that the entries
/// keep their relative precision near the identity.
#[inline(always)]
fn small_parts(q: &Vector4<f64>) -> Matrix3<f64> {
    let (x2, y2, z2) = (2.0 * q.x, 2.0 * q.y, 2.0 * q.z);
    let (xx, yy, zz) = (q.x * x2, q.y * y2, q.z * z2);
    let (xy, xz, yz) = (q.x * y2, q.x * z2, q.y * z2);
    let (wx, wy, wz) = (q.w * x2, q.w * y2, q.w * z2);
    Matrix3::new(
        -(yy + zz),
        xy - wz,
        xz + wy,
        xy + wz,
        -(xx + zz),
        yz - wx,
        xz - wy,
        yz + wx,
        -(xx + yy),
    )
}

/// The body's mass properties at an orientation, as the solve for (a, α) needs them, with
/// the free translation `slide` (Q = slide slideᵀ: SLIDE, or zero where pinned) and the free
/// axis g = AXIS.
#[derive(Debug, Clone, Copy)]
struct MassMatrix {
    /// m (the mass) and the mass centre in world axes.
    mass: f64,
    centre: Vector3<f64>,
    slide: Vector3<f64>,
    /// w = Q(g × c).
    drag: Vector3<f64>,
    inverse_mass: f64,
    /// 1/(g·I g − m w·w), I in world axes.
    inverse: f64,
}

impl MassMatrix {
    /// At `orientation`, for `body` of mass 1/`inverse_mass`.
    #[inline(always)]
    fn at(body: &TurningBody3d, inverse_mass: f64, orientation: &Orientation) -> Self {
        let t = &orientation.turn;
        let centre = body.centre + t * body.centre;
        let slide = if body.slides { SLIDE } else { Vector3::zeros() };
        let drag = slide * slide.dot(&AXIS.cross(&centre));
        // g in the body's axes: Rᵀ g = g + (R − 1)ᵀ g.
        let u = AXIS + t.tr_mul(&AXIS);
        let axial = u.dot(&(body.inertia * u));
        MassMatrix {
            mass: body.mass,
            centre,
            slide,
            drag,
            inverse_mass,
            inverse: 1.0 / (axial - body.mass * drag.dot(&drag)),
        }
    }

    /// The accelerations (a, α) under `load` of a body whose mass centre is its reference
    /// node or which is pinned: no drag, and the centripetal force, if any, on a held
    /// translation, so a = Q f/m and α = (g·M / g·I g) g.
    #[inline(always)]
    fn accelerations_in_place(&self, load: &Load) -> Rates {
        let s = AXIS.dot(&load.moment) * self.inverse;
        let a = self.slide * (self.slide.dot(&load.force) * self.inverse_mass);
        let alpha = AXIS * s;
        [a.x, a.y, a.z, alpha.x, alpha.y, alpha.z]
    }

    /// The accelerations (a, α) under `load` at the rates `rates` (the centripetal force
    /// from their angular velocity).
    #[inline(always)]
    fn accelerations(&self, load: &Load, rates: &Rates) -> Rates {
        let spin = Vector3::new(rates[3], rates[4], rates[5]);
        let f = load.force - spin.cross(&spin.cross(&self.centre)) * self.mass;
        let s = (AXIS.dot(&load.moment) - f.dot(&self.drag)) * self.inverse;
        let a = self.slide * (self.slide.dot(&f) * self.inverse_mass) - self.drag * s;
        let alpha = AXIS * s;
        [a.x, a.y, a.z, alpha.x, alpha.y, alpha.z]
    }
}

impl TurningBody3d {
    /// The turning body a scene describes, when it is exactly that: 3D, one body whose
    /// reference node is held in uy, uz, rx and ry, free to turn about z, and free along x
    /// (sliding: rigid3d_slide_surface, rigid3d_slide_lumped) or held there too (pinned:
    /// rigid3d_pin_surface, rigid3d_pin_lumped), with its mass centre off that node or on it
    /// (where it is on it or the node is pinned, the accelerations are formed once per
    /// increment without iterating); one particle held in uy and uz and free along x; springs
    /// of fixed direction x from a body point or the particle to a node held in every
    /// translation; one plane contact between the particle and the body, without a contact
    /// dashpot; loads on body points; initial velocities on the reference node and the particle
    /// only; one dynamic step; no dashpots; the centred velocity; the identity frame everywhere.
    pub fn of(scene: &Scene) -> Option<Self> {
        if scene.settings.damping != DampingTreatment::Centred {
            return None;
        }
        let (body, contact, step, duration) = one_body(scene, Dimension::Three)?;
        let condition = |node: usize, dof: Dof| condition(step, node, dof);
        let held = |node: usize, dof: Dof| condition(node, dof).is_some_and(|c| c.value.is_none());
        let free = |node: usize, dof: Dof| condition(node, dof).is_none();
        let (reference, particle) = (body.reference, contact.node);
        let on_body = |n: usize| scene.nodes[n].attachment != Attachment::Free;
        let ground = |n: usize| (0..3).all(|k| held(n, Dof::Translation(k)));
        let sliding = |n: usize| {
            held(n, Dof::Translation(1))
                && held(n, Dof::Translation(2))
                && free(n, Dof::Translation(0))
        };
        let slides = sliding(reference);
        if !(slides || ground(reference))
            || !held(reference, Dof::Rotation(0))
            || !held(reference, Dof::Rotation(1))
            || !free(reference, Dof::Rotation(2))
            || on_body(particle)
            || !sliding(particle)
            || contact.restitution != 1.0
            || !SlidingBody::plain(scene, particle, reference)
        {
            return None;
        }
        let origin = scene.nodes[reference].position;
        let relative = |n: usize| scene.nodes[n].position - origin;
        let (body_springs, particle_stiffness) =
            PinnedBody::springs(scene, particle, &relative, &ground, &on_body)?;
        let mut loads = Vec::new();
        for load in &scene.loads {
            if !on_body(load.node) {
                return None;
            }
            loads.push((relative(load.node), load.force));
        }
        let Surface::Plane { point, normal } = contact.surface else {
            return None;
        };
        let initial = |n: usize| scene.initial_velocities.iter().find(|v| v.node == n);
        let (speed, angular) =
            initial(reference).map_or((Vector3::zeros(), Vector3::zeros()), |v| {
                let along = if slides { SLIDE.dot(&v.velocity) } else { 0.0 };
                (SLIDE * along, AXIS * AXIS.dot(&v.angular))
            });
        Some(TurningBody3d {
            mass: body.mass,
            centre: body.centre_offset,
            inertia: body.inertia,
            slides,
            velocity: (speed, angular),
            body_springs,
            loads,
            particle: (
                relative(particle),
                scene.nodes[particle].mass,
                initial(particle).map_or(0.0, |v| v.velocity.x),
                particle_stiffness,
            ),
            face: (point - origin, normal),
            penalty: scene.penalty_stiffness(scene.settings.penalty),
            duration,
        })
    }

    /// The forces at the orientation, the body's translation `x` and the particle's
    /// displacement `u` along x: one pass over each list.
    #[inline(always)]
    fn forces(&self, lists: &Lists, orientation: &Orientation, x: &Vector3<f64>, u: f64) -> Load {
        let t = &orientation.turn;
        let mut load = Load::default();
        for (p, k) in &self.body_springs {
            let moved = t * p;
            let f = ALONG * (-k * ALONG.dot(&(x + moved)));
            load.force += f;
            load.moment += (p + moved).cross(&f);
        }
        for k in &lists.particle_springs {
            load.particle -= ALONG * (k * u);
        }
        // The particle relative to the reference node.
        let node = self.particle.0 + SLIDE * u - x;
        for (point, normal) in &lists.faces {
            let n = normal + t * normal;
            let gap = (node - (point + t * point)).dot(&n);
            let f = n * (self.penalty * (-gap).max(0.0));
            load.particle += f;
            load.force -= f;
            load.moment -= node.cross(&f);
        }
        for (p, f) in &self.loads {
            load.force += f;
            load.moment += (p + t * p).cross(f);
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
        // State: the body's orientation (quaternion, carries, R − 1), its translation and
        // carry, its rates at n − ½ and accelerations at n − 1; the particle's u, its carry,
        // v(n−½).
        let mut orientation = vec![Orientation::default(); one];
        let (mut x, mut x_carry) = (vec![Vector3::zeros(); one], vec![Vector3::zeros(); one]);
        let (v0, w0) = self.velocity;
        let mut rates: Vec<Rates> = vec![[v0.x, v0.y, v0.z, w0.x, w0.y, w0.z]; one];
        let mut acc: Vec<Rates> = vec![[0.0; 6]; one];
        let (mut u, mut u_carry) = (vec![0.0; one], vec![0.0; one]);
        let mut v = vec![speed; one];
        let mut load = vec![Load::default(); one];
        let inverse_mass = vec![1.0 / mass; one];
        let inverse_body_mass = vec![1.0 / self.mass; one];
        // t = 0: the accelerations at the initial velocities, and v(−½) = v(0) − (h/2)·a(0), so
        // that the first increment's kick gives v(½) = v(0) + (h/2)·a(0).
        load[0] = self.forces(&lists, &orientation[0], &x[0], u[0]);
        let matrix = MassMatrix::at(self, inverse_body_mass[0], &orientation[0]);
        acc[0] = matrix.accelerations(&load[0], &rates[0]);
        rates[0] = plus(rates[0], -0.5 * h, acc[0]);
        v[0] -= 0.5 * h * SLIDE.dot(&load[0].particle) * inverse_mass[0];
        // A body whose mass centre is its reference node (lumped) feels no centripetal force,
        // a pinned body feels it on its held translation alone, and turning about g leaves
        // g·I g as it is: the mass matrix formed once (as the engine forms its body solve once
        // per step for a body turning in place), and the accelerations, which then do not read
        // the velocity, once per increment, without iterating.
        let in_place = self.centre == Vector3::zeros() || !self.slides;
        let mut passes = 0;
        for _ in 0..steps {
            load[0] = self.forces(&lists, &orientation[0], &x[0], u[0]);
            if in_place {
                acc[0] = matrix.accelerations_in_place(&load[0]);
                passes += 1;
            } else {
                let matrix = MassMatrix::at(self, inverse_body_mass[0], &orientation[0]);
                let at = |guess: &Rates| matrix.accelerations(&load[0], guess);
                // ω about g = z is the last rate.
                let unit_spin = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
                let per_square = matrix.accelerations(&Load::default(), &unit_spin);
                let responses = (at(&[0.0; 6]), per_square);
                let (a, taken) = match centred_about_axis(responses, rates[0], 5, h) {
                    Some(a) => (a, 2),
                    None => centred(at, rates[0], acc[0], h),
                };
                (acc[0], passes) = (a, passes + taken);
            }
            rates[0] = plus(rates[0], h, acc[0]);
            v[0] += h * SLIDE.dot(&load[0].particle) * inverse_mass[0];
            let r = rates[0];
            orientation[0].turn(&(Vector3::new(r[3], r[4], r[5]) * h));
            if self.slides {
                let dx = Vector3::new(r[0], r[1], r[2]) * h;
                for k in 0..3 {
                    compensated_add(&mut x[0][k], &mut x_carry[0][k], dx[k]);
                }
            }
            compensated_add(&mut u[0], &mut u_carry[0], h * v[0]);
        }
        SlidingState {
            angle: orientation[0].twist(&AXIS),
            translation: SLIDE.dot(&x[0]),
            displacement: u[0],
            passes,
        }
    }
}

/// The element lists the floor keeps in slices: the particle's springs, the contact faces.
struct Lists {
    particle_springs: Vec<f64>,
    faces: Vec<(Vector3<f64>, Vector3<f64>)>,
}
