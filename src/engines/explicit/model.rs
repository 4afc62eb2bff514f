//! The scene compiled into the force terms it actually has.
//!
//! Compilation resolves every element end to a [`Point`] (ground, particle or body material
//! point) once, so the time loop does no name look-ups and no work for absent effects. The
//! `FINITE` const parameter selects finite rotation (`explicit`) or the benchmark's
//! small-rotation idealisation (`explicit_small`); it is resolved at compile time.

use super::blocks::{
    Advance, Axial, AxialStore, BlockSchedule, GROUND, LineSpring, axis_of, line_spring_forces,
    step_blocks,
};
use super::space::SharedSolid;
use super::space::{BodyInertia, BodyOperator, BodySolve, Lin, Space, compensated_add};
use crate::scene::{
    Attachment, BoundaryCondition, Connection, ContactPair, ContactState, Dof, Scene, Step,
    StepKind, Surface, surface_distance,
};
use std::marker::PhantomData;

/// Where an element end or a load acts.
#[derive(Debug, Clone, Copy)]
pub enum Point<S: Space> {
    /// A fixed point of space.
    Ground(S::V),
    /// A particle (free node), by index.
    Particle(usize),
    /// A material point of a body: offset `rho` from the reference node at t = 0.
    Body {
        /// Body index.
        body: usize,
        /// Offset from the reference node in the body frame (= world frame at t = 0).
        rho: S::V,
    },
}

impl<S: Space> Point<S> {
    /// A particle's index (`Some(Some(i))`), the ground (`Some(None)`), or None for a body's
    /// point: an element end as the particle-only paths see it.
    fn particle_or_ground(&self) -> Option<Option<usize>> {
        match self {
            Point::Particle(i) => Some(Some(*i)),
            Point::Ground(_) => Some(None),
            Point::Body { .. } => None,
        }
    }
}

/// Configuration, as displacements from t = 0 (so round-off is relative to the motion, not to
/// the coordinates: the penalty multiplies position errors by k_p).
#[derive(Debug, Clone)]
pub struct Config<S: Space> {
    /// Particle displacements.
    pub u: Vec<S::V>,
    /// Reference node displacements.
    pub bu: Vec<S::V>,
    /// Body orientations (finite rotation).
    pub br: Vec<S::R>,
    /// The rounding carry of each orientation's components (compensated summation of the
    /// increments' turns).
    pub br_carry: Vec<S::Carry>,
    /// Body rotation vectors (small rotation).
    pub bth: Vec<S::W>,
    /// Mass properties of each body at this configuration (centre in world axes, inertia in
    /// the body's axes with the orientation), kept in step with `br` by every method that
    /// rotates a body (finite rotation; the unrotated ones under small rotation).
    pub inertia: Vec<BodyInertia<S>>,
}

/// Velocities or accelerations of every particle and body.
#[derive(Debug, Clone)]
pub struct Rates<S: Space> {
    /// Particles.
    pub p: Vec<S::V>,
    /// Body reference nodes.
    pub b: Vec<S::V>,
    /// Body angular.
    pub w: Vec<S::W>,
}

impl<S: Space> Rates<S> {
    /// All zero.
    pub fn zeros(particles: usize, bodies: usize) -> Self {
        Self {
            p: vec![S::V::zero(); particles],
            b: vec![S::V::zero(); bodies],
            w: vec![S::W::zero(); bodies],
        }
    }
    /// `self + s · other`.
    pub fn plus(&self, s: f64, other: &Self) -> Self {
        Self {
            p: self
                .p
                .iter()
                .zip(&other.p)
                .map(|(a, b)| *a + *b * s)
                .collect(),
            b: self
                .b
                .iter()
                .zip(&other.b)
                .map(|(a, b)| *a + *b * s)
                .collect(),
            w: self
                .w
                .iter()
                .zip(&other.w)
                .map(|(a, b)| *a + *b * s)
                .collect(),
        }
    }
    /// In place: `self = a + s · b`.
    pub fn set_plus(&mut self, a: &Self, s: f64, b: &Self) {
        for (o, (x, y)) in self.p.iter_mut().zip(a.p.iter().zip(&b.p)) {
            *o = *x + *y * s;
        }
        for (o, (x, y)) in self.b.iter_mut().zip(a.b.iter().zip(&b.b)) {
            *o = *x + *y * s;
        }
        for (o, (x, y)) in self.w.iter_mut().zip(a.w.iter().zip(&b.w)) {
            *o = *x + *y * s;
        }
    }
    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.p.iter().chain(&self.b).all(|a| a.dot(a).is_finite())
            && self.w.iter().all(|a| a.dot(a).is_finite())
    }
    /// Largest Euclidean norm of any particle's, body's or angular difference, and the largest
    /// such norm of `self` (square roots taken once, of the maxima).
    pub fn max_difference(&self, other: &Self) -> (f64, f64) {
        let mut d: f64 = 0.0;
        let mut m: f64 = 0.0;
        for (a, b) in self
            .p
            .iter()
            .zip(&other.p)
            .chain(self.b.iter().zip(&other.b))
        {
            let e = *a - *b;
            d = d.max(e.dot(&e));
            m = m.max(a.dot(a));
        }
        for (a, b) in self.w.iter().zip(&other.w) {
            let e = *a - *b;
            d = d.max(e.dot(&e));
            m = m.max(a.dot(a));
        }
        (d.sqrt(), m.sqrt())
    }
}

/// Forces on particles and wrenches on bodies (about their reference nodes), plus what the
/// same pass measured.
#[derive(Debug, Clone)]
pub struct Forces<S: Space> {
    /// Particle forces.
    pub p: Vec<S::V>,
    /// Body forces.
    pub b: Vec<S::V>,
    /// Body moments about the reference node.
    pub m: Vec<S::W>,
    /// Elastic energy of springs and penalty.
    pub elastic: f64,
    /// Dissipation power of dashpots.
    pub dissipation: f64,
    /// Normal force per contact pair (compressive positive).
    pub contact: Vec<f64>,
}

impl<S: Space> Forces<S> {
    fn zeros(particles: usize, bodies: usize, contacts: usize) -> Self {
        Self {
            p: vec![S::V::zero(); particles],
            b: vec![S::V::zero(); bodies],
            m: vec![S::W::zero(); bodies],
            elastic: 0.0,
            dissipation: 0.0,
            contact: vec![0.0; contacts],
        }
    }
    /// Reset to zero, keeping the allocation.
    pub fn clear(&mut self) {
        fill_zero(&mut self.p, S::V::zero());
        fill_zero(&mut self.b, S::V::zero());
        fill_zero(&mut self.m, S::W::zero());
        fill_zero(&mut self.contact, 0.0);
        self.elastic = 0.0;
        self.dissipation = 0.0;
    }
}

/// Set every element of `xs` to `zero`, through an opaque copy of it, so that the compiler
/// does not turn the loop into a `memset` call. This machine's `memset` clears a short slice with
/// one masked AVX-512 store, and a masked store does not forward to the loads that follow: the
/// force pass that adds into the cleared forces waits for it to retire (the hottest
/// instruction of `springs_grounded_a`'s increment; `BENCHMARKS.md`).
#[inline(always)]
pub fn fill_zero<T: Copy>(xs: &mut [T], zero: T) {
    let zero = std::hint::black_box(zero);
    for x in xs {
        *x = zero;
    }
}

/// How contact is evaluated.
#[derive(Debug, Clone, Copy)]
pub enum ContactMode<'a> {
    /// Penalty, compression only (the simulation).
    Unilateral,
    /// Penalty acting in tension too (the linearisation about a closed contact).
    Bilateral,
    /// No contact force (the structure alone).
    Off,
    /// Given normal forces instead of the penalty (the consistent start).
    Given(&'a [f64]),
}

/// Work counters: they prove what a run did and did not evaluate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Position-dependent force passes.
    pub force_evaluations: u64,
    /// Contact pair evaluations.
    pub contact_evaluations: u64,
    /// Dashpot passes.
    pub damping_evaluations: u64,
    /// Body orientation updates.
    pub rotation_updates: u64,
    /// Rigid-body acceleration solves (one per load solved against a body's factorisation).
    pub body_solves: u64,
    /// Increments stepped block by block of springs ([`Model::step_by_blocks`],
    /// [`Model::step_axial`]).
    pub block_increments: u64,
    /// Of those, the increments stepped on the one-dimensional store ([`Model::step_axial`]).
    pub axial_increments: u64,
    /// Increments stepped as the recurrence of a small affine step
    /// ([`AffineStep`](super::affine::AffineStep)).
    pub affine_increments: u64,
    /// Increments stepped with one turning body's state in locals
    /// ([`TurningStep`](super::turning::TurningStep)).
    pub turning_increments: u64,
    /// Of those, the increments that carried the body's turn about its axis
    /// ([`TurningStep`](super::turning::TurningStep)'s arithmetic about the axis, the same to
    /// round-off; the others are the general path's bit for bit).
    pub about_axis_increments: u64,
    /// Axial elements held on their lines in a dynamic step ([`Model::with_lines_held`]: they
    /// act along fixed lines, a spring while its ends keep their order), summed over the
    /// dynamic steps.
    pub held_lines: u64,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Grounded<S: Space> {
    pub(super) point: Point<S>,
    /// Translation direction (None for a rotational DOF).
    pub(super) direction: Option<S::V>,
    /// Rotation axis and body (rotational DOF at a reference node).
    pub(super) rotation: Option<(usize, S::W)>,
    pub(super) c: f64,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct TwoPoint<S: Space> {
    pub(super) a: Point<S>,
    pub(super) b: Point<S>,
    /// Fixed direction, or for axial elements the initial unit direction.
    pub(super) direction: S::V,
    pub(super) axial: bool,
    /// An axial element whose line cannot turn in the current step
    /// ([`Model::with_lines_held`]): a spring acts along `direction` while its ends keep their
    /// order along it; a dashpot is then no longer `axial`.
    pub(super) line_held: bool,
    /// From end a to end b at t = 0.
    pub(super) span0: S::V,
    pub(super) length0: f64,
    pub(super) c: f64,
}

/// Where a contact node is relative to its solid (see [`Model::solid_positions`]).
#[derive(Debug, Clone, Copy)]
pub struct SolidPosition<S: Space> {
    /// Position relative to the solid's centre, in its axes.
    pub local: S::V,
    /// Signed gap.
    pub gap: f64,
    /// Outward normal at the nearest surface point (solid's axes).
    pub normal: S::V,
}

#[derive(Debug, Clone)]
pub(super) struct Contact<S: Space> {
    pub(super) particle: usize,
    pub(super) body: usize,
    /// A solid's centre relative to the reference node (body frame) and its parry shape; `None`
    /// for a plane.
    pub(super) solid: Option<(S::V, SharedSolid<S>)>,
    /// Contact dashpot (sized for the pair's restitution; 0 when elastic).
    pub(super) damping: f64,
    /// The gap at t = 0 of a pair that starts open: the linearisation's penalty is unstressed
    /// there (0 for a closed pair).
    pub(super) open_gap: f64,
    /// A face point relative to the reference node (body frame).
    pub(super) face: S::V,
    /// Outward normal (body frame).
    pub(super) normal: S::V,
    /// The contact node's offset from the reference node at t = 0 (small-rotation arm).
    pub(super) arm0: S::V,
    /// Gap at t = 0 (small rotation: the constant part of the linearised gap).
    pub(super) gap0: f64,
}

impl<S: Space> Contact<S> {
    /// A plane pair's signed gap (negative: penetration) and outward normal under finite
    /// rotation, at its body's orientation `r`, with `relative` the node's displacement less
    /// the body's reference node's: the time loop's and [`TurningStep`]'s as the general path
    /// (one arithmetic; its turn about the axis forms the same gap to round-off).
    ///
    /// [`TurningStep`]: super::turning::TurningStep
    #[inline(always)]
    pub(super) fn plane_gap(&self, r: &S::R, relative: S::V) -> (f64, S::V) {
        let n = S::rotate(r, &self.normal);
        (n.dot(&self.face_to_node(r, relative)), n)
    }

    /// From the face point to the node (finite rotation), summed from small parts (the offset
    /// at t = 0, the displacements, the face point's turn) so that a penalty stiffness does
    /// not multiply the cancellation of body-sized positions.
    #[inline(always)]
    fn face_to_node(&self, r: &S::R, relative: S::V) -> S::V {
        (self.arm0 - self.face) + relative - S::turned(r, &self.face)
    }

    /// From the body's reference node to the node (finite rotation), with `relative` as in
    /// [`Contact::plane_gap`].
    #[inline(always)]
    pub(super) fn arm(&self, relative: S::V) -> S::V {
        self.arm0 + relative
    }
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Load<S: Space> {
    pub(super) point: Point<S>,
    pub(super) force: S::V,
}

/// A particle's constant data.
#[derive(Debug, Clone)]
pub struct Particle<S: Space> {
    /// Scene node.
    pub node: usize,
    /// Mass.
    pub mass: f64,
    /// 1 / mass.
    pub inverse_mass: f64,
    /// Position at t = 0.
    pub x0: S::V,
    /// Frame axes (DOF directions).
    pub axes: Vec<S::V>,
}

/// A body's constant data.
#[derive(Debug, Clone)]
pub struct Body<S: Space> {
    /// Scene body index.
    pub index: usize,
    /// Reference node.
    pub node: usize,
    /// Reference position at t = 0.
    pub x0: S::V,
    /// Mass properties at t = 0 (body frame = world frame).
    pub inertia: BodyInertia<S>,
    /// Translation axes of the reference node's frame.
    pub axes: Vec<S::V>,
    /// Rotation axes of the reference node's frame.
    pub rot_axes: Vec<S::W>,
}

/// The boundary conditions of one step, compiled.
#[derive(Debug, Clone)]
pub struct Constraints<S: Space> {
    /// Held directions per particle (orthonormal).
    pub particle_held: Vec<Vec<S::V>>,
    /// The distinct projections the particles' accelerations take (a few, whatever the number
    /// of particles).
    pub motions: Vec<Motion<S::V>>,
    /// Each particle's projection, as an index into `motions` (4 bytes per particle streamed
    /// by the time loop instead of a projection's 40 or 56).
    pub particle_motion: Vec<u32>,
    /// `particle_motion` as runs of consecutive particles that share a projection: the end
    /// of each run (exclusive) and its index into `motions`.
    pub motion_runs: Vec<(u32, u32)>,
    /// Held translation axes per body.
    pub body_held_t: Vec<Vec<S::V>>,
    /// Held rotation axes per body.
    pub body_held_r: Vec<Vec<S::W>>,
    /// Free rotation axes per body (orthonormal complement of the held ones).
    pub body_free_r: Vec<Vec<S::W>>,
    /// Prescribed values: (target, value) applied at the start of a static step.
    pub prescribed: Vec<(Target<S>, f64)>,
    /// Bodies whose rotation can change in this step.
    pub rotating: Vec<bool>,
    /// Bodies whose centripetal or gyroscopic terms act on a free DOF in this step.
    pub velocity_terms: Vec<bool>,
    /// Per body, its solve's operator where it does not change during the step, formed once
    /// instead of at every increment:
    /// - here, under small rotations (a body keeps its reference mass properties), and under
    ///   finite rotation in the plane for a body pinned at its reference node or with its mass
    ///   centre there (the operator is then the inertia about the one axis, which turning
    ///   leaves as it is);
    /// - at the start of each dynamic step, at the orientation the step starts from, for a 3D
    ///   body under finite rotation that turns about one free axis, pinned or with its mass
    ///   centre at the node ([`Model::fix_single_axis_operators`]; the same up to the rounding
    ///   of the orientation's update).
    ///
    /// `None` for every other body under finite rotation (formed at every increment from the
    /// configuration's mass properties), among them some whose operator happens not to change
    /// either, such as a 3D body with every rotation held.
    pub body_operators: Vec<Option<BodyOperator<S>>>,
}

impl<S: Space> Constraints<S> {
    /// Whether any velocity-dependent term acts (dashpots aside).
    pub fn any_velocity_terms(&self) -> bool {
        self.velocity_terms.iter().any(|x| *x)
    }

    /// The solve of body `b` at mass properties `inertia` under this step's constraints, with
    /// the step's operator where it has one ([`Constraints::body_operators`]).
    #[inline(always)]
    pub fn body_solve<'a>(&'a self, inertia: &'a BodyInertia<S>, b: usize) -> BodySolve<'a, S> {
        let (held_t, free_r) = (&self.body_held_t[b], &self.body_free_r[b]);
        match self.body_operators[b] {
            Some(operator) => BodySolve::with(inertia, held_t, free_r, operator),
            None => BodySolve::new(inertia, held_t, free_r),
        }
    }
}

/// How a particle's acceleration is projected onto its free directions in a step.
#[derive(Debug, Clone, Copy)]
pub enum Motion<V: Lin> {
    /// No direction held.
    Free,
    /// Every direction held.
    Held,
    /// One direction held (unit): the component along it removed.
    Across(V),
    /// Two orthonormal directions held (3D): both components removed.
    AcrossTwo(V, V),
}

impl<V: Lin> Motion<V> {
    /// The projection that removes the `held` directions of a space of `dim` dimensions.
    fn of(held: &[V], dim: usize) -> Self {
        match held {
            [] => Motion::Free,
            _ if held.len() == dim => Motion::Held,
            [d] => Motion::Across(*d),
            [d, e] => Motion::AcrossTwo(*d, *e),
            _ => Motion::Held,
        }
    }

    /// `a` with its held components removed (in the order they were held).
    #[inline]
    pub fn project(&self, a: V) -> V {
        match self {
            Motion::Free => a,
            Motion::Held => V::zero(),
            Motion::Across(d) => a - *d * d.dot(&a),
            Motion::AcrossTwo(d, e) => {
                let a = a - *d * d.dot(&a);
                a - *e * e.dot(&a)
            }
        }
    }
}

/// A generalised DOF: a free direction of a particle or a body.
#[derive(Debug, Clone, Copy)]
pub enum Target<S: Space> {
    /// Particle translation along a unit direction.
    Particle(usize, S::V),
    /// Body reference translation along a unit direction.
    Translation(usize, S::V),
    /// Body rotation about a unit axis.
    Rotation(usize, S::W),
}

/// A dashpot whose ends are particles or the ground, as the centred velocity solve sees it:
/// its rate is `d·(v_b − v_a)` (an absent end does not move) and its force on the ends is
/// `−c·rate` times `(−d at a, +d at b)`.
#[derive(Debug, Clone, Copy)]
pub struct ParticleDashpot<S: Space> {
    /// Damping coefficient.
    pub c: f64,
    /// Particle at end a (None: the ground).
    pub a: Option<usize>,
    /// Particle at end b (None: the ground).
    pub b: Option<usize>,
    /// Line of action.
    pub line: DashpotLine<S>,
}

/// Where a [`ParticleDashpot`]'s line of action comes from.
#[derive(Debug, Clone, Copy)]
pub enum DashpotLine<S: Space> {
    /// A fixed direction (grounded dashpots, and two-point ones that do not turn).
    Fixed(S::V),
    /// A two-point dashpot that turns with its nodes: its line at each configuration is
    /// [`Model::dashpot_span`] of `dashpot`, times `scale` (one over its length at t = 0, so
    /// that the line stays near unit length in a scene of any size).
    TwoPoint {
        /// Index of the two-point dashpot.
        dashpot: usize,
        /// One over its length at t = 0.
        scale: f64,
    },
}

/// A spring whose force is affine in the displacements: it acts along a fixed line, between
/// particles or a particle and the ground (what [`AffineStep`](super::affine::AffineStep)
/// steps).
#[derive(Debug, Clone, Copy)]
pub struct AffineSpring<S: Space> {
    /// Particle at end a (None: the ground).
    pub a: Option<usize>,
    /// Particle at end b (None: the ground).
    pub b: Option<usize>,
    /// Unit line: the stretch is `direction·(u_b − u_a)`, the force on end a
    /// `c·stretch·direction` and on end b its opposite.
    pub direction: S::V,
    /// Stiffness.
    pub c: f64,
    /// An axial spring held on its line ([`Model::with_lines_held`]): its length at t = 0. It
    /// takes the line's force only while that length plus its stretch stays positive.
    pub held_length: Option<f64>,
}

/// The compiled scene.
#[derive(Debug, Clone)]
pub struct Model<S: Space, const FINITE: bool> {
    /// Particles (free nodes).
    pub particles: Vec<Particle<S>>,
    /// Rigid bodies.
    pub bodies: Vec<Body<S>>,
    pub(super) grounded_springs: Vec<Grounded<S>>,
    grounded_dashpots: Vec<Grounded<S>>,
    pub(super) springs: Vec<TwoPoint<S>>,
    /// The springs that are [`LineSpring`]s, compact.
    pub(super) line_springs: Vec<LineSpring<S::V>>,
    /// Indices in `springs` of the others (body ends, or axial under finite rotation).
    pub(super) other_springs: Vec<usize>,
    dashpots: Vec<TwoPoint<S>>,
    pub(super) contacts: Vec<Contact<S>>,
    /// 1 / mass per particle (apart, so the time loop streams 8 bytes per particle).
    inverse_masses: Vec<f64>,
    pub(super) loads: Vec<Load<S>>,
    /// Where the scene is particles, springs along fixed lines and loads only: the order of
    /// [`Model::step_by_blocks`].
    block_schedule: Option<BlockSchedule>,
    /// Where such a scene's springs all lie along one coordinate axis: the scene on that axis
    /// ([`Model::step_axial`]).
    axial: Option<Axial>,
    /// Penalty stiffness.
    pub penalty: f64,
    /// Node → point.
    pub points: Vec<Point<S>>,
    _space: PhantomData<S>,
}

/// The [`Axial`] form of a scene that steps by blocks, where every line spring and every
/// grounded spring on a particle lies along one coordinate axis (the first line spring's, or
/// without line springs the first grounded spring's); the loads on particles keep their
/// component along it.
fn axial<S: Space>(
    line_springs: &[LineSpring<S::V>],
    grounded: &[Grounded<S>],
    loads: &[Load<S>],
) -> Option<Axial> {
    let grounded: Vec<(usize, S::V, f64)> = grounded
        .iter()
        .filter_map(|g| match (g.point, g.direction) {
            (Point::Particle(i), Some(d)) => Some((i, d, g.c)),
            _ => None,
        })
        .collect();
    let axis = line_springs
        .first()
        .map(|s| s.direction)
        .or(grounded.first().map(|g| g.1))
        .and_then(|d| axis_of::<S>(&d))?;
    let along = |d: &S::V| (axis_of::<S>(d) == Some(axis)).then(|| S::v3(d)[axis]);
    let springs = line_springs
        .iter()
        .map(|s| {
            Some(LineSpring {
                a: s.a,
                b: s.b,
                direction: along(&s.direction)?,
                c: s.c,
            })
        })
        .collect::<Option<Vec<_>>>()?;
    let grounded = grounded
        .iter()
        .map(|(i, d, c)| Some((*i, along(d)?, *c)))
        .collect::<Option<Vec<_>>>()?;
    let on_particles = loads.iter().filter_map(|l| match l.point {
        Point::Particle(i) => Some((i, S::v3(&l.force))),
        _ => None,
    });
    Some(Axial {
        axis,
        springs,
        grounded,
        loads: on_particles.clone().map(|(i, f)| (i, f[axis])).collect(),
        loads_on_axis: on_particles
            .clone()
            .all(|(_, f)| (0..3).all(|j| j == axis || f[j] == 0.0)),
    })
}

/// The contact dashpot of a pair: c = 2ζ√(k_p m), with ζ the damping ratio whose linear
/// spring–dashpot impact rebounds with the pair's restitution e (e = exp(−ζπ/√(1 − ζ²)), so
/// ζ = −ln e / √(π² + ln² e); e = 0: critical, ζ = 1) and m the node's mass, or its reduced
/// mass with the body's when the body is not held in every DOF of every dynamic step.
fn contact_damping(scene: &Scene, c: &ContactPair, penalty: f64) -> f64 {
    let e = c.restitution;
    if e >= 1.0 {
        return 0.0;
    }
    let zeta = if e <= 0.0 {
        1.0
    } else {
        -e.ln() / (std::f64::consts::PI.powi(2) + e.ln().powi(2)).sqrt()
    };
    let node = scene.nodes[c.node].mass;
    let body = &scene.bodies[c.body];
    let every = Dof::all(scene.dimension, true);
    let held = scene
        .steps
        .iter()
        .filter(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .all(|s| {
            every.iter().all(|d| {
                s.conditions
                    .iter()
                    .any(|b| b.node == body.reference && b.dof == *d && b.value.is_none())
            })
        });
    let mass = if held {
        node
    } else {
        node * body.mass / (node + body.mass)
    };
    2.0 * zeta * (penalty * mass).sqrt()
}

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Compile a scene with penalty stiffness `penalty`.
    pub fn compile(scene: &Scene, penalty: f64) -> Self {
        let mut particles = Vec::new();
        let mut bodies: Vec<Body<S>> = Vec::new();
        let axes = |frame: &nalgebra::Matrix3<f64>| -> Vec<S::V> {
            (0..S::DIM)
                .map(|i| S::v(&frame.column(i).into_owned()))
                .collect()
        };
        let rot_axes = |frame: &nalgebra::Matrix3<f64>| -> Vec<S::W> {
            (3 - S::ROT..3)
                .map(|i| S::w(&frame.column(i).into_owned()))
                .collect()
        };
        for (bi, b) in scene.bodies.iter().enumerate() {
            let node = &scene.nodes[b.reference];
            bodies.push(Body {
                index: bi,
                node: b.reference,
                x0: S::v(&node.position),
                inertia: BodyInertia {
                    mass: b.mass,
                    centre: S::v(&b.centre_offset),
                    inertia: S::inertia(&b.inertia),
                    orientation: None,
                },
                axes: axes(&node.frame),
                rot_axes: rot_axes(&node.frame),
            });
        }
        // A node is ground when it has no mass and every step holds all its DOFs.
        let all = Dof::all(scene.dimension, false);
        let mask = |d: &Dof| 1u8 << all.iter().position(|x| x == d).unwrap_or(7);
        let full: u8 = all.iter().map(mask).fold(0, |a, b| a | b);
        let mut fixed = vec![true; scene.nodes.len()];
        let mut held = vec![0u8; scene.nodes.len()];
        for s in &scene.steps {
            held.iter_mut().for_each(|h| *h = 0);
            for c in s.conditions.iter().filter(|c| c.value.is_none()) {
                held[c.node] |= mask(&c.dof);
            }
            for (f, h) in fixed.iter_mut().zip(&held) {
                *f &= *h & full == full;
            }
        }
        for (f, n) in fixed.iter_mut().zip(&scene.nodes) {
            *f &= n.attachment == Attachment::Free && n.mass == 0.0;
        }
        let mut points = Vec::with_capacity(scene.nodes.len());
        for (i, n) in scene.nodes.iter().enumerate() {
            let x = S::v(&n.position);
            points.push(match n.attachment {
                Attachment::Free if fixed[i] => Point::Ground(x),
                Attachment::Free => {
                    particles.push(Particle {
                        node: i,
                        mass: n.mass,
                        inverse_mass: 1.0 / n.mass,
                        x0: x,
                        axes: axes(&n.frame),
                    });
                    Point::Particle(particles.len() - 1)
                }
                Attachment::Reference(b) => Point::Body {
                    body: b,
                    rho: S::V::zero(),
                },
                Attachment::OnBody(b) => Point::Body {
                    body: b,
                    rho: x - bodies[b].x0,
                },
            });
        }
        let x0 = |node: usize| S::v(&scene.nodes[node].position);
        let grounded = |list: &[crate::scene::Element]| -> Vec<Grounded<S>> {
            list.iter()
                .filter_map(|e| match e.connection {
                    Connection::Grounded { node, dof } => {
                        let frame = &scene.nodes[node].frame;
                        let (direction, rotation) = match dof {
                            Dof::Translation(i) => {
                                (Some(S::v(&frame.column(i).into_owned())), None)
                            }
                            Dof::Rotation(i) => {
                                let Attachment::Reference(b) = scene.nodes[node].attachment else {
                                    unreachable!("validated: rotations only at reference nodes")
                                };
                                (None, Some((b, S::w(&frame.column(i).into_owned()))))
                            }
                        };
                        Some(Grounded {
                            point: points[node],
                            direction,
                            rotation,
                            c: e.coefficient,
                        })
                    }
                    _ => None,
                })
                .collect()
        };
        let two_point = |list: &[crate::scene::Element]| -> Vec<TwoPoint<S>> {
            list.iter()
                .filter_map(|e| {
                    let (nodes, direction, axial) = match &e.connection {
                        Connection::FixedDirection { nodes, direction } => {
                            (*nodes, S::v(direction), false)
                        }
                        Connection::Axial { nodes } => {
                            let d = x0(nodes[1]) - x0(nodes[0]);
                            (*nodes, d * (1.0 / d.dot(&d).sqrt()), true)
                        }
                        Connection::Grounded { .. } => return None,
                    };
                    let span0 = x0(nodes[1]) - x0(nodes[0]);
                    Some(TwoPoint {
                        a: points[nodes[0]],
                        b: points[nodes[1]],
                        direction,
                        axial,
                        line_held: false,
                        span0,
                        length0: span0.dot(&span0).sqrt(),
                        c: e.coefficient,
                    })
                })
                .collect()
        };
        let contacts: Vec<Contact<S>> = scene
            .contacts
            .iter()
            .map(|c| {
                let Point::Particle(particle) = points[c.node] else {
                    unreachable!("validated: contact nodes are free nodes with mass")
                };
                let origin = bodies[c.body].x0;
                let arm0 = x0(c.node) - origin;
                let (face, normal, solid) = match &c.surface {
                    Surface::Plane { point, normal } => (S::v(point) - origin, S::v(normal), None),
                    Surface::Solid { solid, centre } => (
                        S::v(centre) - origin,
                        S::V::zero(),
                        Some((S::v(centre) - origin, S::solid(solid))),
                    ),
                };
                let (gap0, _) = surface_distance(&c.surface, &scene.nodes[c.node].position);
                Contact {
                    particle,
                    body: c.body,
                    solid,
                    damping: contact_damping(scene, c, penalty),
                    open_gap: match c.initially {
                        ContactState::Open => gap0,
                        ContactState::Closed => 0.0,
                    },
                    face,
                    normal,
                    arm0,
                    gap0: normal.dot(&(arm0 - face)),
                }
            })
            .collect();
        let loads: Vec<Load<S>> = scene
            .loads
            .iter()
            .map(|l| Load {
                point: points[l.node],
                force: S::v(&l.force),
            })
            .collect();
        let springs = two_point(&scene.springs);
        let end = |p: &Point<S>| match p {
            Point::Particle(i) => u32::try_from(*i).ok().filter(|i| *i != GROUND),
            Point::Ground(_) => Some(GROUND),
            Point::Body { .. } => None,
        };
        let mut line_springs = Vec::new();
        let mut other_springs = Vec::new();
        for (k, s) in springs.iter().enumerate() {
            match (end(&s.a), end(&s.b)) {
                (Some(a), Some(b)) if !(s.axial && FINITE) => line_springs.push(LineSpring {
                    a,
                    b,
                    direction: s.direction,
                    c: s.c,
                }),
                _ => other_springs.push(k),
            }
        }
        let grounded_springs = grounded(&scene.springs);
        let grounded_dashpots = grounded(&scene.dashpots);
        let dashpots = two_point(&scene.dashpots);
        let loaded: Option<Vec<usize>> = loads
            .iter()
            .filter_map(|l| match l.point {
                Point::Particle(i) => Some(Some(i)),
                Point::Ground(_) => None,
                Point::Body { .. } => Some(None),
            })
            .collect();
        let block_schedule = loaded
            .filter(|_| {
                particles.len() < GROUND as usize
                    && bodies.is_empty()
                    && other_springs.is_empty()
                    && contacts.is_empty()
                    && grounded_dashpots.is_empty()
                    && dashpots.is_empty()
                    && grounded_springs
                        .iter()
                        .all(|g| g.rotation.is_none() && !matches!(g.point, Point::Body { .. }))
            })
            .map(|loaded| BlockSchedule::of(particles.len(), &line_springs, &loaded));
        let axial = block_schedule
            .as_ref()
            .and_then(|_| axial(&line_springs, &grounded_springs, &loads));
        Model {
            inverse_masses: particles.iter().map(|p| p.inverse_mass).collect(),
            particles,
            bodies,
            grounded_springs,
            grounded_dashpots,
            springs,
            line_springs,
            other_springs,
            dashpots,
            contacts,
            loads,
            block_schedule,
            axial,
            penalty,
            points,
            _space: PhantomData,
        }
    }

    /// Every spring as an [`AffineSpring`], when the scene has no body and no contact and every
    /// spring acts along a fixed line between particles or a particle and the ground (an axial
    /// spring under finite rotation only where its step holds it on its line); None otherwise.
    /// Grounded springs on the ground alone are left out (they never act).
    pub fn affine_springs(&self) -> Option<Vec<AffineSpring<S>>> {
        if !self.bodies.is_empty() || !self.contacts.is_empty() {
            return None;
        }
        let mut out = Vec::new();
        for s in &self.grounded_springs {
            if s.rotation.is_some() {
                return None;
            }
            match (s.point, s.direction) {
                (Point::Particle(i), Some(direction)) => out.push(AffineSpring {
                    a: None,
                    b: Some(i),
                    direction,
                    c: s.c,
                    held_length: None,
                }),
                (Point::Body { .. }, _) => return None,
                _ => {}
            }
        }
        let at = |i: u32| (i != GROUND).then_some(i as usize);
        for s in &self.line_springs {
            out.push(AffineSpring {
                a: at(s.a),
                b: at(s.b),
                direction: s.direction,
                c: s.c,
                held_length: None,
            });
        }
        for s in self.other_springs.iter().map(|k| &self.springs[*k]) {
            let turning = s.axial && FINITE;
            if turning && !s.line_held {
                return None;
            }
            out.push(AffineSpring {
                a: s.a.particle_or_ground()?,
                b: s.b.particle_or_ground()?,
                direction: s.direction,
                c: s.c,
                held_length: turning.then_some(s.length0),
            });
        }
        Some(out)
    }

    /// Whether the scene has dashpots.
    pub fn has_dashpots(&self) -> bool {
        !self.grounded_dashpots.is_empty()
            || !self.dashpots.is_empty()
            || self.has_contact_dashpots()
    }

    /// Number of contact pairs.
    pub fn contact_count(&self) -> usize {
        self.contacts.len()
    }

    /// The configuration at t = 0.
    pub fn initial_config(&self) -> Config<S> {
        Config {
            u: vec![S::V::zero(); self.particles.len()],
            bu: vec![S::V::zero(); self.bodies.len()],
            br: vec![S::identity(); self.bodies.len()],
            br_carry: vec![S::Carry::default(); self.bodies.len()],
            bth: vec![S::W::zero(); self.bodies.len()],
            inertia: self.bodies.iter().map(|b| b.inertia).collect(),
        }
    }

    /// Zero rates shaped like the model.
    pub fn zero_rates(&self) -> Rates<S> {
        Rates::zeros(self.particles.len(), self.bodies.len())
    }

    /// Zero forces shaped like the model.
    pub fn zero_forces(&self) -> Forces<S> {
        Forces::zeros(self.particles.len(), self.bodies.len(), self.contacts.len())
    }

    /// Body-frame offset `rho` as a world arm from the reference node.
    #[inline]
    pub fn arm(&self, cfg: &Config<S>, body: usize, rho: &S::V) -> S::V {
        if FINITE {
            S::rotate(&cfg.br[body], rho)
        } else {
            *rho
        }
    }

    /// Current displacement of a point from its position at t = 0.
    #[inline]
    pub fn displacement(&self, cfg: &Config<S>, p: &Point<S>) -> S::V {
        match p {
            Point::Ground(_) => S::V::zero(),
            Point::Particle(i) => cfg.u[*i],
            Point::Body { body, rho } => {
                if FINITE {
                    cfg.bu[*body] + S::turned(&cfg.br[*body], rho)
                } else {
                    cfg.bu[*body] + S::cross(&cfg.bth[*body], rho)
                }
            }
        }
    }

    /// Current velocity of a point.
    #[inline]
    pub fn velocity(&self, cfg: &Config<S>, vel: &Rates<S>, p: &Point<S>) -> S::V {
        match p {
            Point::Ground(_) => S::V::zero(),
            Point::Particle(i) => vel.p[*i],
            Point::Body { body, rho } => {
                vel.b[*body] + S::cross(&vel.w[*body], &self.arm(cfg, *body, rho))
            }
        }
    }

    #[inline(always)]
    fn apply(&self, cfg: &Config<S>, p: &Point<S>, f: S::V, out: &mut Forces<S>) {
        match p {
            Point::Ground(_) => {}
            Point::Particle(i) => out.p[*i] += f,
            Point::Body { body, rho } => {
                out.b[*body] += f;
                out.m[*body] += S::moment(&self.arm(cfg, *body, rho), &f);
            }
        }
    }

    /// Rotation of a body about a unit axis.
    pub fn rotation_about(&self, cfg: &Config<S>, body: usize, axis: &S::W) -> f64 {
        if FINITE {
            S::twist(&cfg.br[body], axis)
        } else {
            cfg.bth[body].dot(axis)
        }
    }

    /// Signed gap of a contact pair (negative: penetration) and the current outward normal.
    #[inline(always)]
    pub fn gap(&self, cfg: &Config<S>, k: usize) -> (f64, S::V) {
        let c = &self.contacts[k];
        let relative = cfg.u[c.particle] - cfg.bu[c.body];
        if let Some((centre, shape)) = &c.solid {
            let (d, n) = S::solid_gap(shape, &self.local(cfg, k, centre));
            return (d, self.to_world(cfg, c.body, &n));
        }
        if FINITE {
            c.plane_gap(&cfg.br[c.body], relative)
        } else {
            let th = &cfg.bth[c.body];
            let d = c.gap0 + c.normal.dot(&relative) - c.normal.dot(&S::cross(th, &c.arm0));
            (d, c.normal)
        }
    }

    /// The size of the terms a plane contact's gap sums under small rotation (the gap at
    /// t = 0, the node's motion relative to the body's reference node, the turn of its arm):
    /// the gap's rounding is a few ulps of it. Only for a plane contact under small rotation
    /// (it reads the rotation vector, not the orientation).
    pub fn gap_size(&self, cfg: &Config<S>, k: usize) -> f64 {
        let c = &self.contacts[k];
        let relative = cfg.u[c.particle] - cfg.bu[c.body];
        let turn = S::cross(&cfg.bth[c.body], &c.arm0);
        c.gap0.abs() + relative.dot(&relative).sqrt() + turn.dot(&turn).sqrt()
    }

    /// A contact node's position relative to its solid's centre, in the body frame (small
    /// rotation: Rᵀ ≈ 1 − [θ]×).
    #[inline]
    fn local(&self, cfg: &Config<S>, k: usize, centre: &S::V) -> S::V {
        let c = &self.contacts[k];
        let arm = c.arm0 + (cfg.u[c.particle] - cfg.bu[c.body]);
        if FINITE {
            S::unrotate(&cfg.br[c.body], &arm) - *centre
        } else {
            arm - S::cross(&cfg.bth[c.body], &arm) - *centre
        }
    }

    /// A body-frame direction in the world (small rotation: R ≈ 1 + [θ]×).
    #[inline]
    fn to_world(&self, cfg: &Config<S>, body: usize, x: &S::V) -> S::V {
        if FINITE {
            S::rotate(&cfg.br[body], x)
        } else {
            *x + S::cross(&cfg.bth[body], x)
        }
    }

    /// From the body's reference node to a contact node (small rotation: at t = 0).
    #[inline]
    fn contact_arm(&self, cfg: &Config<S>, k: usize) -> S::V {
        let c = &self.contacts[k];
        if FINITE {
            c.arm(cfg.u[c.particle] - cfg.bu[c.body])
        } else {
            c.arm0
        }
    }

    /// Rate of a contact's gap along the normal `n`: the node's velocity relative to the body
    /// point it passes, n·(ṗ − v − ω × (p − x)) (any surface: the normal's own turning moves
    /// the gap only at second order).
    #[inline]
    fn normal_rate(&self, cfg: &Config<S>, vel: &Rates<S>, k: usize, n: &S::V) -> f64 {
        let c = &self.contacts[k];
        let (i, b) = (c.particle, c.body);
        n.dot(&(vel.p[i] - vel.b[b] - S::cross(&vel.w[b], &self.contact_arm(cfg, k))))
    }

    /// Whether the scene has contacts with solids (parry shapes).
    pub fn has_solids(&self) -> bool {
        self.contacts.iter().any(|c| c.solid.is_some())
    }

    /// Whether every contact pair is closed at t = 0 (what the consistent start assumes: it
    /// carries the rigid model's persistent contact forces).
    pub fn closed_only(&self) -> bool {
        self.contacts.iter().all(|c| c.open_gap == 0.0)
    }

    /// Whether any contact pair has a dashpot.
    pub fn has_contact_dashpots(&self) -> bool {
        self.contacts.iter().any(|c| c.damping > 0.0)
    }

    /// Each solid contact's node position in the solid's frame, its gap and the outward
    /// normal there (for [`Model::through_solid`]); planes get `None`.
    pub fn solid_positions(&self, cfg: &Config<S>, out: &mut Vec<Option<SolidPosition<S>>>) {
        out.clear();
        for (k, c) in self.contacts.iter().enumerate() {
            out.push(c.solid.as_ref().map(|(centre, shape)| {
                let local = self.local(cfg, k, centre);
                let (gap, normal) = S::solid_gap(shape, &local);
                SolidPosition { local, gap, normal }
            }));
        }
    }

    /// The first solid contact whose node went through its solid between two sets of
    /// [`Model::solid_positions`] one increment apart: its nearest side turned over (the
    /// normal there reversed) while it was inside before or after, so it passed the solid's
    /// middle and the penalty now pushes it out of the far side; or it crossed the solid
    /// within the increment, outside before and after. A node sliding on a surface turns its
    /// normal smoothly and is never taken for one. Returns the pair and the distance moved
    /// relative to the solid in the increment.
    pub fn through_solid(
        &self,
        before: &[Option<SolidPosition<S>>],
        after: &[Option<SolidPosition<S>>],
    ) -> Option<(usize, f64)> {
        for (k, c) in self.contacts.iter().enumerate() {
            let (Some(a), Some(b), Some((_, shape))) = (&before[k], &after[k], &c.solid) else {
                continue;
            };
            let turned = b.normal.dot(&a.normal) < 0.0;
            let outside = a.gap >= 0.0 && b.gap >= 0.0;
            if turned && (!outside || S::crosses(shape, &a.local, &b.local)) {
                let moved = b.local - a.local;
                return Some((k, moved.dot(&moved).sqrt()));
            }
        }
        None
    }

    /// Pair `k`'s [`Contact::face_to_node`] at configuration `cfg` (finite rotation).
    #[inline(always)]
    fn face_to_node(&self, cfg: &Config<S>, k: usize) -> S::V {
        let c = &self.contacts[k];
        c.face_to_node(&cfg.br[c.body], cfg.u[c.particle] - cfg.bu[c.body])
    }

    /// Position-dependent forces: springs, contact, loads. Fills `out` (cleared first), with
    /// the elastic energy.
    pub fn forces(
        &self,
        cfg: &Config<S>,
        mode: ContactMode,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        self.forces_with::<true>(cfg, mode, out, counters);
    }

    /// [`Model::forces`], with the elastic energy summed only when `ENERGY` (an increment that
    /// writes no row does not read it; the sum is a chain of dependent additions, one per
    /// element, that would otherwise set the pace of a large scene's force pass). The forces
    /// are the same either way, bit for bit; without `ENERGY`, `out.elastic` is 0.
    pub fn forces_with<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        mode: ContactMode,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        out.clear();
        counters.force_evaluations += 1;
        let mut elastic = self.grounded_spring_forces::<ENERGY>(cfg, out);
        elastic =
            line_spring_forces::<S::V, ENERGY>(&self.line_springs, &cfg.u, &mut out.p, elastic);
        for s in self.other_springs.iter().map(|k| &self.springs[*k]) {
            let stretch = self.displacement(cfg, &s.b) - self.displacement(cfg, &s.a);
            let along = s.direction.dot(&stretch);
            // A spring held to its line takes the line's force while its span along the line,
            // length0 + along, stays positive: there it is the turning force to round-off.
            let turns = s.axial && FINITE && !(s.line_held && along > -s.length0);
            let (e, dir) = if turns {
                let l = s.span0 + stretch;
                let square = l.dot(&l);
                // 1/|l| as |l|·(1/|l|²): the square root and the division run side by side
                // instead of one after the other on the increment's chain.
                let len = square.sqrt();
                (len - s.length0, l * (len * (1.0 / square)))
            } else {
                (along, s.direction)
            };
            if ENERGY {
                elastic += 0.5 * s.c * e * e;
            }
            let f = dir * (s.c * e);
            self.apply(cfg, &s.a, f, out);
            self.apply(cfg, &s.b, -f, out);
        }
        if !self.contacts.is_empty() && !matches!(mode, ContactMode::Off) {
            for (k, c) in self.contacts.iter().enumerate() {
                counters.contact_evaluations += 1;
                let (d, n) = self.gap(cfg, k);
                let f = match mode {
                    ContactMode::Unilateral => self.penalty * (-d).max(0.0),
                    ContactMode::Bilateral => -self.penalty * (d - c.open_gap),
                    ContactMode::Given(f) => f[k],
                    ContactMode::Off => unreachable!(),
                };
                if ENERGY && !matches!(mode, ContactMode::Given(_)) {
                    elastic += 0.5 * f * f / self.penalty;
                }
                out.contact[k] = f;
                out.p[c.particle] += n * f;
                out.b[c.body] -= n * f;
                out.m[c.body] -= S::moment(&self.contact_arm(cfg, k), &n) * f;
            }
        }
        self.apply_loads(cfg, out);
        out.elastic = elastic;
    }

    /// Add the grounded springs' forces to `out`; their elastic energy (0 unless `ENERGY`).
    /// Always inlined, as are [`Model::apply_loads`] and `line_spring_forces`: the force pass
    /// keeps the shape it had before they were split out (with this one called instead, the
    /// time loop ran `rigid2d_pin_lumped` in 112 ns instead of 55: code layout,
    /// `BENCHMARKS.md`).
    #[inline(always)]
    fn grounded_spring_forces<const ENERGY: bool>(
        &self,
        cfg: &Config<S>,
        out: &mut Forces<S>,
    ) -> f64 {
        let mut elastic = 0.0;
        for s in &self.grounded_springs {
            if let Some(d) = s.direction {
                let u = d.dot(&self.displacement(cfg, &s.point));
                if ENERGY {
                    elastic += 0.5 * s.c * u * u;
                }
                self.apply(cfg, &s.point, d * (-s.c * u), out);
            }
            if let Some((b, axis)) = s.rotation {
                let angle = self.rotation_about(cfg, b, &axis);
                if ENERGY {
                    elastic += 0.5 * s.c * angle * angle;
                }
                out.m[b] -= axis * (s.c * angle);
            }
        }
        elastic
    }

    /// Add the loads to `out`.
    #[inline(always)]
    fn apply_loads(&self, cfg: &Config<S>, out: &mut Forces<S>) {
        for l in &self.loads {
            self.apply(cfg, &l.point, l.force, out);
        }
    }

    /// Whether [`Model::step_by_blocks`] applies: particles, springs along fixed lines
    /// ([`LineSpring`]s, and grounded springs on particles) and loads only; no bodies,
    /// contacts, dashpots or springs whose direction turns.
    pub fn can_step_by_blocks(&self) -> bool {
        self.block_schedule.is_some()
    }

    /// One increment of a scene where [`Model::can_step_by_blocks`], block by block of line
    /// springs: after the grounded springs, a block's forces (those of [`Model::forces_with`],
    /// without the energy) are summed into `pending`, then the particles whose force is
    /// complete are advanced as in [`Model::step`] (see [`BlockSchedule`]). Each particle's
    /// force is summed in the same order and advanced with the same arithmetic, so the result
    /// is [`Model::forces_with`] then [`Model::step`] bit for bit. What is saved is the
    /// separate pass that clears the force array (the update resets each entry instead), and
    /// reading every particle's data from memory a second time in a scene larger than the
    /// cache.
    ///
    /// `pending` is zero on entry and zero again on return.
    ///
    /// Never inlined: inlined into the time loop, it changed how the loop keeps its other
    /// paths' values on the stack, and the 2D rigid cases, which never come here, took twice
    /// as long (`BENCHMARKS.md`, code layout; measured before the tenth round found byte-equal
    /// copies of one binary at twice each other's time, which may explain it instead).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub fn step_by_blocks(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        vel: &mut Rates<S>,
        held: &Constraints<S>,
        pending: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        let schedule = self
            .block_schedule
            .as_ref()
            .expect("Model::step_by_blocks is called only where Model::can_step_by_blocks");
        counters.block_increments += 1;
        counters.force_evaluations += 1;
        self.grounded_spring_forces::<false>(cfg, pending);
        let n = self.particles.len();
        let mut advance = Advance {
            u: &mut cfg.u[..n],
            carry: &mut carry.p[..n],
            v: &mut vel.p[..n],
            f: &mut pending.p[..n],
            inverse: &self.inverse_masses[..n],
            motion_runs: &held.motion_runs,
            motions: &held.motions,
            h,
        };
        // Loads act on particles or the ground only in the last block (see `BlockSchedule`):
        // the sum of `Model::apply`, in the same order.
        let loads = |f: &mut [S::V]| {
            for l in &self.loads {
                if let Point::Particle(i) = l.point {
                    f[i] += l.force;
                }
            }
        };
        step_blocks(schedule, &self.line_springs, loads, &mut advance);
    }

    /// The store [`Model::step_axial`] steps for one step under `held`: where the scene steps
    /// by blocks, its springs lie along one coordinate axis, and every particle either moves
    /// along that axis only or is held (see `AxialStore::of`).
    pub fn axial_store(&self, held: &Constraints<S>) -> Option<AxialStore> {
        AxialStore::of(self.axial.as_ref()?, held, self.particles.len())
    }

    /// [`Model::step_by_blocks`] on the one-dimensional `store` (loaded from `cfg`, `carry` and
    /// `vel` at its first increment after each [`AxialStore::write_back`]): the same
    /// sums in the same order on the axis components, so the same result to the bit (up to
    /// the sign of a zero), at half the bytes per particle and spring in 2D. False, and nothing
    /// done, where a particle's velocity or rounding carry lies off the axis (it would move
    /// off it).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub fn step_axial(
        &self,
        store: &mut AxialStore,
        cfg: &Config<S>,
        carry: &Rates<S>,
        h: f64,
        vel: &Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) -> bool {
        let (Some(axial), Some(schedule)) = (&self.axial, &self.block_schedule) else {
            return false;
        };
        let n = self.particles.len();
        if !store.load::<S>(&cfg.u[..n], &carry.p[..n], &vel.p[..n]) {
            return false;
        }
        counters.block_increments += 1;
        counters.axial_increments += 1;
        counters.force_evaluations += 1;
        store.step(
            axial,
            schedule,
            &self.inverse_masses[..n],
            &held.motion_runs,
            h,
        );
        true
    }

    /// Add dashpot forces at velocities `vel` to `out`, and their dissipation power.
    pub fn damping(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        let mut directions = Vec::new();
        self.dashpot_directions(cfg, &mut directions);
        self.damping_along(cfg, &directions, vel, out, counters);
    }

    /// This model for a dynamic step under `held` that starts from `cfg`, where every axial
    /// element whose line cannot turn in the step ([`Model::line_cannot_turn`]) acts along
    /// that fixed line: a dashpot always (its force, c (d·Δv) d for a unit d along its span,
    /// does not change when d reverses), a spring while its ends keep their order along the
    /// line (once they pass each other its turning force differs, and it takes that).
    /// There the fixed line is the turning line to round-off, and the increment needs no
    /// square root or division for it. None where no element is held to its line, and
    /// always under small rotations, where no element turns.
    pub fn with_lines_held(&self, cfg: &Config<S>, held: &Constraints<S>) -> Option<Self> {
        if !FINITE {
            return None;
        }
        let held_to_line = |list: &[TwoPoint<S>]| -> Vec<bool> {
            list.iter()
                .map(|s| s.axial && self.line_cannot_turn(s, self.span(cfg, s), held))
                .collect()
        };
        let (springs, dashpots) = (held_to_line(&self.springs), held_to_line(&self.dashpots));
        if !springs.iter().chain(&dashpots).any(|h| *h) {
            return None;
        }
        let mut model = self.clone();
        for (s, h) in model.springs.iter_mut().zip(springs) {
            s.line_held = h;
        }
        for (s, h) in model.dashpots.iter_mut().zip(dashpots) {
            s.line_held = h;
            s.axial &= !h;
        }
        Some(model)
    }

    /// How many axial elements act along fixed lines in this model (none but in a step's
    /// [`Model::with_lines_held`]).
    pub fn held_lines(&self) -> usize {
        self.springs
            .iter()
            .chain(&self.dashpots)
            .filter(|s| s.line_held)
            .count()
    }

    /// Whether two-point element `s`, whose span from end a to end b is `span` where a step
    /// under `held` starts, keeps its line of action through the step: each end is the
    /// ground or a particle free to move only along the element's initial direction, and the
    /// span lies along that direction, pointing the same way, to round-off. Then the span stays on
    /// the line; the rounding of the projections moves it off by ulps of the displacements.
    fn line_cannot_turn(&self, s: &TwoPoint<S>, span: S::V, held: &Constraints<S>) -> bool {
        // Orthogonality of unit directions formed by the scene's frames, to round-off.
        const ACROSS: f64 = 4.0 * f64::EPSILON;
        let line = s.direction;
        let on_line = |p: &Point<S>| match *p {
            Point::Ground(_) => true,
            Point::Body { .. } => false,
            Point::Particle(i) => match held.motions[held.particle_motion[i] as usize] {
                Motion::Held => true,
                Motion::Free => false,
                Motion::Across(d) => S::DIM == 2 && d.dot(&line).abs() <= ACROSS,
                Motion::AcrossTwo(d, e) => {
                    d.dot(&line).abs() <= ACROSS && e.dot(&line).abs() <= ACROSS
                }
            },
        };
        let along = line.dot(&span);
        let off = span - line * along;
        on_line(&s.a)
            && on_line(&s.b)
            && along > 0.0
            && off.dot(&off) <= (8.0 * f64::EPSILON * along).powi(2)
    }

    /// The line of action of every two-point dashpot at `cfg` (axial ones turn with their
    /// nodes under finite rotation), for [`Model::damping_along`]: a configuration's
    /// directions serve every velocity iterate of an increment.
    pub fn dashpot_directions(&self, cfg: &Config<S>, out: &mut Vec<S::V>) {
        out.clear();
        out.extend(self.dashpots.iter().enumerate().map(|(k, s)| {
            if s.axial && FINITE {
                let l = self.dashpot_span(cfg, k);
                l * (1.0 / l.dot(&l).sqrt())
            } else {
                s.direction
            }
        }));
    }

    /// The vector from end a to end b of two-point dashpot `k` at `cfg`: its line of action,
    /// not normalised.
    #[inline(always)]
    pub fn dashpot_span(&self, cfg: &Config<S>, k: usize) -> S::V {
        self.span(cfg, &self.dashpots[k])
    }

    /// The vector from end a to end b of two-point element `s` at `cfg`.
    #[inline(always)]
    fn span(&self, cfg: &Config<S>, s: &TwoPoint<S>) -> S::V {
        s.span0 + (self.displacement(cfg, &s.b) - self.displacement(cfg, &s.a))
    }

    /// Every dashpot as a [`ParticleDashpot`], when every one acts between particles or a
    /// particle and the ground along a line (no body end, no rotational dashpot, no contact
    /// dashpot); None otherwise. Dashpots on the ground alone are left out (they never act).
    pub fn particle_dashpots(&self) -> Option<Vec<ParticleDashpot<S>>> {
        if self.contacts.iter().any(|c| c.damping != 0.0) {
            return None;
        }
        let mut out = Vec::new();
        for s in &self.grounded_dashpots {
            let (Some(d), None) = (s.direction, s.rotation) else {
                return None;
            };
            if let Some(b) = s.point.particle_or_ground()?
                && s.c != 0.0
            {
                out.push(ParticleDashpot {
                    c: s.c,
                    a: None,
                    b: Some(b),
                    line: DashpotLine::Fixed(d),
                });
            }
        }
        for (k, s) in self.dashpots.iter().enumerate() {
            let (a, b) = (s.a.particle_or_ground()?, s.b.particle_or_ground()?);
            if (a.is_some() || b.is_some()) && s.c != 0.0 {
                // Only an axial dashpot under finite rotation turns with its nodes
                // (`Model::dashpot_directions`); every other keeps its direction.
                let line = if s.axial && FINITE {
                    DashpotLine::TwoPoint {
                        dashpot: k,
                        scale: 1.0 / s.length0,
                    }
                } else {
                    DashpotLine::Fixed(s.direction)
                };
                out.push(ParticleDashpot { c: s.c, a, b, line });
            }
        }
        Some(out)
    }

    /// `P M⁻¹ f` for particle `i` under the step's constraints: the acceleration a force `f`
    /// gives it.
    #[inline]
    pub fn particle_response(&self, held: &Constraints<S>, i: usize, f: S::V) -> S::V {
        held.motions[held.particle_motion[i] as usize].project(f * self.inverse_masses[i])
    }

    /// [`Model::damping`] with the two-point dashpots' directions given (from
    /// [`Model::dashpot_directions`] at the same `cfg`).
    pub fn damping_along(
        &self,
        cfg: &Config<S>,
        directions: &[S::V],
        vel: &Rates<S>,
        out: &mut Forces<S>,
        counters: &mut Counters,
    ) {
        counters.damping_evaluations += 1;
        let mut power = 0.0;
        for s in &self.grounded_dashpots {
            if let Some(d) = s.direction {
                let rate = d.dot(&self.velocity(cfg, vel, &s.point));
                power += s.c * rate * rate;
                self.apply(cfg, &s.point, d * (-s.c * rate), out);
            }
            if let Some((b, axis)) = s.rotation {
                let rate = vel.w[b].dot(&axis);
                power += s.c * rate * rate;
                out.m[b] -= axis * (s.c * rate);
            }
        }
        for (s, dir) in self.dashpots.iter().zip(directions) {
            let rate = dir.dot(&(self.velocity(cfg, vel, &s.b) - self.velocity(cfg, vel, &s.a)));
            power += s.c * rate * rate;
            let f = *dir * (s.c * rate);
            self.apply(cfg, &s.a, f, out);
            self.apply(cfg, &s.b, -f, out);
        }
        // Contact dashpots act while the node penetrates, against the gap's rate.
        for (k, c) in self.contacts.iter().enumerate() {
            if c.damping == 0.0 {
                continue;
            }
            let (d, n) = self.gap(cfg, k);
            if d >= 0.0 {
                continue;
            }
            let rate = self.normal_rate(cfg, vel, k, &n);
            power += c.damping * rate * rate;
            let f = -c.damping * rate;
            out.contact[k] += f;
            out.p[c.particle] += n * f;
            out.b[c.body] -= n * f;
            out.m[c.body] -= S::moment(&self.contact_arm(cfg, k), &n) * f;
        }
        out.dissipation = power;
    }

    /// Work of the constant loads since configuration `from`.
    pub fn external_work(&self, cfg: &Config<S>, from: &Config<S>) -> f64 {
        self.loads
            .iter()
            .map(|l| {
                l.force
                    .dot(&(self.displacement(cfg, &l.point) - self.displacement(from, &l.point)))
            })
            .sum()
    }

    /// Mass properties of a body at `cfg` (centre in world axes, inertia in the body's axes
    /// with the orientation).
    #[inline]
    pub fn body_inertia<'c>(&self, cfg: &'c Config<S>, b: usize) -> &'c BodyInertia<S> {
        &cfg.inertia[b]
    }

    /// Mass properties of a body at orientation `r` (finite rotation): the centre in world
    /// axes, the inertia with its orientation.
    pub(super) fn oriented(&self, b: usize, r: &S::R) -> BodyInertia<S> {
        let i = &self.bodies[b].inertia;
        BodyInertia {
            mass: i.mass,
            // A body whose mass centre is its reference node (lumped) keeps it there.
            centre: if i.centre == S::V::zero() {
                i.centre
            } else {
                S::rotate(r, &i.centre)
            },
            inertia: i.inertia,
            orientation: Some(*r),
        }
    }

    /// Accelerations from forces, with body angular velocities `omega` for the centripetal and
    /// gyroscopic terms (finite rotation only), honouring the step's held DOFs.
    pub fn accelerations(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        self.accelerate_particles(forces, held, out);
        self.accelerate_bodies(cfg, forces, vel, held, out, counters);
    }

    /// The particles' part of [`Model::accelerations`] (no particle force reads the velocity).
    fn accelerate_particles(&self, forces: &Forces<S>, held: &Constraints<S>, out: &mut Rates<S>) {
        for ((a, f), (inverse_mass, motion)) in out
            .p
            .iter_mut()
            .zip(&forces.p)
            .zip(self.inverse_masses.iter().zip(&held.particle_motion))
        {
            *a = held.motions[*motion as usize].project(*f * *inverse_mass);
        }
    }

    /// Whether every body with centripetal or gyroscopic terms in this step turns about a
    /// single free axis (always so in 2D): then [`Model::centred_single_axis`] applies to a
    /// scene without dashpots.
    pub fn single_axis(&self, held: &Constraints<S>) -> bool {
        (0..self.bodies.len()).all(|b| !held.velocity_terms[b] || held.body_free_r[b].len() == 1)
    }

    /// The accelerations at the centred velocity `v(n) = v(n−½) + (h/2)·a(n)`, solved in
    /// closed form, for a step whose only velocity-dependent forces are the centripetal and
    /// gyroscopic terms of bodies that each turn about one free axis g (no dashpots; see
    /// [`Model::single_axis`]). With ω = s·g those terms are s² times the terms at ω = g, and
    /// the body solve is linear, so a(s) = a₀ + s²·a₁ with a₀ from the forces and a₁ from the
    /// unit-rate terms (two solves), and s solves `(h/2)·q·s² − s + s_h + (h/2)·p = 0`
    /// (p = g·α₀, q = g·α₁, s_h = g·ω(n−½)): the root that tends to `s_h + (h/2)·p` as
    /// h → 0. Where the velocity iteration converges, this is its fixed point, reached without
    /// iterating (it also exists where the iteration would not contract, up to a discriminant
    /// of zero). False, with `out` unfinished, where the roots are not real: no centred velocity
    /// exists there (h·|ω| far past anything stable).
    #[allow(clippy::too_many_arguments)]
    pub fn centred_single_axis(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        v_half: &Rates<S>,
        held: &Constraints<S>,
        h: f64,
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) -> bool {
        self.accelerate_particles(forces, held, out);
        for b in 0..self.bodies.len() {
            let inertia = self.body_inertia(cfg, b);
            let solve = held.body_solve(inertia, b);
            counters.body_solves += 1;
            if !(FINITE && held.velocity_terms[b]) {
                (out.b[b], out.w[b]) = solve.solve(&forces.b[b], &forces.m[b]);
                continue;
            }
            // On the one axis g the solves give α = s·g: s read directly, not as g·α (in 3D
            // two dependent steps fewer on the increment's chain).
            let (a0, p) = solve.solve_on_axis(&forces.b[b], &forces.m[b]);
            let g = held.body_free_r[b][0];
            let unit_force = S::cross(&g, &S::cross(&g, &inertia.centre)) * (-inertia.mass);
            // The gyroscopic moment at ω = g, g × I g, is perpendicular to g, and the solve on
            // the one axis g reads only the moment along it: left out, as in
            // `accelerate_bodies`.
            counters.body_solves += 1;
            let (a1, q) = solve.solve_on_axis(&unit_force, &S::W::zero());
            let beta = 0.5 * h * q;
            let gamma = g.dot(&v_half.w[b]) + 0.5 * h * p;
            let Some(rate) = centred_rate(beta, gamma) else {
                return false;
            };
            let squared = rate * rate;
            out.b[b] = a0 + a1 * squared;
            out.w[b] = g * (p + q * squared);
        }
        true
    }

    /// The bodies' part of [`Model::accelerations`].
    fn accelerate_bodies(
        &self,
        cfg: &Config<S>,
        forces: &Forces<S>,
        vel: &Rates<S>,
        held: &Constraints<S>,
        out: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        for b in 0..self.bodies.len() {
            let inertia = self.body_inertia(cfg, b);
            let mut f = forces.b[b];
            let mut m = forces.m[b];
            if FINITE && held.velocity_terms[b] {
                let w = vel.w[b];
                f -= S::cross(&w, &S::cross(&w, &inertia.centre)) * inertia.mass;
                // ω × I ω is perpendicular to ω: on a body turning about one axis g (ω along
                // g, the held components removed) the solve, which reads only the moment along
                // g, would see round-off of it alone.
                if held.body_free_r[b].len() > 1 {
                    m -= S::gyroscopic(&w, &inertia.apply(&w));
                }
            }
            counters.body_solves += 1;
            let (a, alpha) = held.body_solve(inertia, b).solve(&f, &m);
            out.b[b] = a;
            out.w[b] = alpha;
        }
    }

    /// One increment of a step without velocity-dependent forces, fused: the accelerations
    /// from `forces`, the half-step velocities `vel` advanced in place by `h·a`, and the
    /// configuration advanced by `h·vel`, each particle in one pass over memory. The same
    /// arithmetic in the same order as [`Model::accelerations`], [`Rates::set_plus`] and
    /// [`Model::advance`] in turn, so the result is bit-identical. The particles'
    /// accelerations are not stored (`acc` receives the bodies' only): for the increments that
    /// write no output row and end no step, after which nothing reads them.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        forces: &Forces<S>,
        vel: &mut Rates<S>,
        held: &Constraints<S>,
        acc: &mut Rates<S>,
        counters: &mut Counters,
    ) {
        // Bodies first: their accelerations read the orientation before it moves.
        self.accelerate_bodies(cfg, forces, vel, held, acc, counters);
        for b in 0..self.bodies.len() {
            vel.b[b] += acc.b[b] * h;
            vel.w[b] += acc.w[b] * h;
        }
        let n = self.particles.len();
        let (u, c, v) = (&mut cfg.u[..n], &mut carry.p[..n], &mut vel.p[..n]);
        let (f, inverse) = (&forces.p[..n], &self.inverse_masses[..n]);
        let (motion, motions) = (&held.particle_motion[..n], &held.motions[..]);
        for i in 0..n {
            let a = motions[motion[i] as usize].project(f[i] * inverse[i]);
            v[i] += a * h;
            compensated_add(&mut u[i], &mut c[i], v[i] * h);
        }
        self.advance_bodies(cfg, carry, h, vel, held, counters);
    }

    /// The half-step velocities `vel` advanced in place by `h·acc` and the configuration by
    /// `h·vel`, each particle in one pass over memory: the arithmetic of [`Rates::set_plus`]
    /// and [`Model::advance`] in turn, bit for bit (for an increment that writes no row, after
    /// its accelerations are known).
    #[allow(clippy::too_many_arguments)]
    pub fn advance_by(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        acc: &Rates<S>,
        vel: &mut Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        for b in 0..self.bodies.len() {
            vel.b[b] += acc.b[b] * h;
            vel.w[b] += acc.w[b] * h;
        }
        let n = self.particles.len();
        let (u, c, v, a) = (
            &mut cfg.u[..n],
            &mut carry.p[..n],
            &mut vel.p[..n],
            &acc.p[..n],
        );
        for i in 0..n {
            v[i] += a[i] * h;
            compensated_add(&mut u[i], &mut c[i], v[i] * h);
        }
        self.advance_bodies(cfg, carry, h, vel, held, counters);
    }

    /// Kinetic energy at velocities `vel`.
    pub fn kinetic_energy(&self, cfg: &Config<S>, vel: &Rates<S>) -> f64 {
        let mut e = 0.0;
        for (i, p) in self.particles.iter().enumerate() {
            e += 0.5 * p.mass * vel.p[i].dot(&vel.p[i]);
        }
        for b in 0..self.bodies.len() {
            let (f, m) = self.body_momentum(cfg, b, &vel.b[b], &vel.w[b]);
            e += 0.5 * (vel.b[b].dot(&f) + vel.w[b].dot(&m));
        }
        e
    }

    /// The body mass matrix applied to `(v, ω)`: `(m v + m ω×c, m c×v + I ω)`.
    pub fn body_momentum(&self, cfg: &Config<S>, b: usize, v: &S::V, w: &S::W) -> (S::V, S::W) {
        let i = self.body_inertia(cfg, b);
        (
            (*v + S::cross(w, &i.centre)) * i.mass,
            S::moment(&i.centre, v) * i.mass + i.apply(w),
        )
    }

    /// Advance positions by `h · vel`, rotating only the bodies that can rotate.
    ///
    /// Translations (and small rotations) are summed with Kahan compensation kept in `carry`:
    /// the rounding of `x + h·v` then stays O(ε|x|) instead of growing as ε|x|√N, which matters
    /// because the penalty multiplies position errors by k_p.
    pub fn advance(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        vel: &Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        for ((x, c), v) in cfg.u.iter_mut().zip(carry.p.iter_mut()).zip(&vel.p) {
            compensated_add(x, c, *v * h);
        }
        self.advance_bodies(cfg, carry, h, vel, held, counters);
    }

    /// The bodies' part of [`Model::advance`].
    fn advance_bodies(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        h: f64,
        vel: &Rates<S>,
        held: &Constraints<S>,
        counters: &mut Counters,
    ) {
        for ((x, c), v) in cfg.bu.iter_mut().zip(carry.b.iter_mut()).zip(&vel.b) {
            compensated_add(x, c, *v * h);
        }
        for b in 0..self.bodies.len() {
            if !held.rotating[b] {
                continue;
            }
            counters.rotation_updates += 1;
            if FINITE {
                // The mass properties from the new orientation while it is still in
                // registers, not read back from the configuration just written.
                let r = S::advance_compensated(&cfg.br[b], &mut cfg.br_carry[b], &(vel.w[b] * h));
                cfg.inertia[b] = self.oriented(b, &r);
                cfg.br[b] = r;
            } else {
                compensated_add(&mut cfg.bth[b], &mut carry.w[b], vel.w[b] * h);
            }
        }
    }

    /// Remove velocity components along held directions.
    pub fn enforce(&self, vel: &mut Rates<S>, held: &Constraints<S>) {
        for (v, h) in vel.p.iter_mut().zip(&held.particle_held) {
            for d in h {
                *v -= *d * d.dot(v);
            }
        }
        for b in 0..self.bodies.len() {
            for d in &held.body_held_t[b] {
                let along = d.dot(&vel.b[b]);
                vel.b[b] -= *d * along;
            }
            for g in &held.body_held_r[b] {
                let along = g.dot(&vel.w[b]);
                vel.w[b] -= *g * along;
            }
        }
    }

    /// Compile a step's boundary conditions.
    pub fn constraints(&self, scene: &Scene, step: &Step) -> Constraints<S> {
        let np = self.particles.len();
        let nb = self.bodies.len();
        let mut c = Constraints {
            particle_held: vec![Vec::new(); np],
            motions: Vec::new(),
            particle_motion: Vec::new(),
            motion_runs: Vec::new(),
            body_held_t: vec![Vec::new(); nb],
            body_held_r: vec![Vec::new(); nb],
            body_free_r: vec![Vec::new(); nb],
            prescribed: Vec::new(),
            rotating: vec![false; nb],
            velocity_terms: vec![false; nb],
            body_operators: vec![None; nb],
        };
        for bc in &step.conditions {
            let BoundaryCondition { node, dof, value } = *bc;
            let target = match (self.points[node], dof) {
                (Point::Ground(_), _) => continue,
                (Point::Particle(i), Dof::Translation(k)) => {
                    Target::Particle(i, self.particles[i].axes[k.min(S::DIM - 1)])
                }
                (Point::Body { body, .. }, Dof::Translation(k)) => {
                    Target::Translation(body, self.bodies[body].axes[k.min(S::DIM - 1)])
                }
                (Point::Body { body, .. }, Dof::Rotation(k)) => {
                    Target::Rotation(body, self.bodies[body].rot_axes[k + S::ROT - 3])
                }
                (Point::Particle(_), Dof::Rotation(_)) => unreachable!("validated"),
            };
            match target {
                Target::Particle(i, d) => c.particle_held[i].push(d),
                Target::Translation(b, d) => c.body_held_t[b].push(d),
                Target::Rotation(b, g) => c.body_held_r[b].push(g),
            }
            if let Some(v) = value {
                c.prescribed.push((target, v));
            }
        }
        let _ = scene;
        // The distinct held sets, each with its projection (the last one found is tried first:
        // neighbours usually share theirs; a set not among the first 64 is added again rather
        // than searched for, so a scene of many frames compiles in linear time).
        let mut distinct: Vec<&Vec<S::V>> = Vec::new();
        let mut last = 0;
        c.particle_motion = c
            .particle_held
            .iter()
            .map(|h| {
                if distinct.get(last).is_none_or(|d| *d != h) {
                    last = distinct
                        .iter()
                        .take(64)
                        .position(|d| *d == h)
                        .unwrap_or_else(|| {
                            distinct.push(h);
                            distinct.len() - 1
                        });
                }
                u32::try_from(last).expect("fewer than 2^32 distinct projections")
            })
            .collect();
        c.motions = distinct.iter().map(|h| Motion::of(h, S::DIM)).collect();
        for (i, m) in c.particle_motion.iter().enumerate() {
            let end = u32::try_from(i + 1).expect("fewer than 2^32 particles");
            match c.motion_runs.last_mut() {
                Some((last, motion)) if *motion == *m => *last = end,
                _ => c.motion_runs.push((end, *m)),
            }
        }
        for b in 0..nb {
            c.body_free_r[b] = S::free_rotations(&c.body_held_r[b]);
            let free_r = S::ROT - c.body_held_r[b].len();
            let free_t = S::DIM - c.body_held_t[b].len();
            c.rotating[b] = free_r > 0;
            let centre = self.bodies[b].inertia.centre;
            let offset = centre.dot(&centre) > 0.0;
            c.velocity_terms[b] = FINITE && free_r > 0 && ((offset && free_t > 0) || free_r > 1);
            // Under small rotations the configuration's mass properties are the reference ones
            // throughout (`Model::initial_config`); under finite rotation in the plane the
            // operator reads only the inertia about the axis (g·I g with g unturned, see
            // `BodyInertia::axial`) and, unless pinned, the centre, which stays zero where it
            // starts there (`Model::oriented`): the same operator, bit for bit.
            if !FINITE || (S::ROT == 1 && self.turns_in_place(&c, b)) {
                c.body_operators[b] = Some(BodyOperator::of(
                    &self.bodies[b].inertia,
                    &c.body_held_t[b],
                    &c.body_free_r[b],
                ));
            }
        }
        c
    }

    /// Whether body `b` turns in place under `held`: pinned at its reference node, or with its
    /// mass centre there (which turning leaves there, `Model::oriented`), so that its solve
    /// has no drag terms and, about one free axis, an operator that turning leaves as it is.
    fn turns_in_place(&self, held: &Constraints<S>, b: usize) -> bool {
        held.body_held_t[b].len() == S::DIM || self.bodies[b].inertia.centre == S::V::zero()
    }

    /// For a dynamic step that starts at `cfg`: the operator of every 3D body under finite
    /// rotation that turns about one free axis g and is pinned at its reference node or has its
    /// mass centre there, formed once at `cfg` instead of at every increment.
    ///
    /// Such a body's angular velocity stays along g (its solve returns α along g, and the step
    /// starts with the held components removed), so its orientation over the step is
    /// R = Rot(g, φ)·R₀, and Rᵀg = R₀ᵀg: its operator, g·R I Rᵀg (the drag terms are zero when
    /// pinned, and with the centre at O), does not change (`tests/body_solve.rs` checks the
    /// operator at R₀ against the dense system at any such R; `tests/spin.rs`, a whole run
    /// against `reference`). Formed at each increment it would differ from this one only by
    /// rounding: the orientation's update, and the round-off of ω off g that the step's start
    /// leaves. In the plane [`Model::constraints`] already forms it. Called after the step's
    /// configuration is final (the consistent start forms its own operators before).
    pub fn fix_single_axis_operators(&self, cfg: &Config<S>, held: &mut Constraints<S>) {
        if !FINITE || S::ROT != 3 {
            return;
        }
        for b in 0..self.bodies.len() {
            if held.body_free_r[b].len() == 1 && self.turns_in_place(held, b) {
                held.body_operators[b] = Some(BodyOperator::of(
                    self.body_inertia(cfg, b),
                    &held.body_held_t[b],
                    &held.body_free_r[b],
                ));
            }
        }
    }

    /// Move a configuration along a generalised DOF by `delta`.
    pub fn perturb(&self, cfg: &mut Config<S>, target: &Target<S>, delta: f64) {
        match target {
            Target::Particle(i, d) => cfg.u[*i] += *d * delta,
            Target::Translation(b, d) => cfg.bu[*b] += *d * delta,
            Target::Rotation(b, g) => {
                if FINITE {
                    cfg.br[*b] = S::advance(&cfg.br[*b], &(*g * delta));
                    // The carried rounding belonged to the rotation before the jump.
                    cfg.br_carry[*b] = Default::default();
                    cfg.inertia[*b] = self.oriented(*b, &cfg.br[*b]);
                } else {
                    cfg.bth[*b] += *g * delta;
                }
            }
        }
    }

    /// The generalised force along a DOF.
    pub fn project(&self, forces: &Forces<S>, target: &Target<S>) -> f64 {
        match target {
            Target::Particle(i, d) => d.dot(&forces.p[*i]),
            Target::Translation(b, d) => d.dot(&forces.b[*b]),
            Target::Rotation(b, g) => g.dot(&forces.m[*b]),
        }
    }

    /// The rate of a generalised DOF.
    pub fn rate_along(&self, rates: &Rates<S>, target: &Target<S>) -> f64 {
        match target {
            Target::Particle(i, d) => d.dot(&rates.p[*i]),
            Target::Translation(b, d) => d.dot(&rates.b[*b]),
            Target::Rotation(b, g) => g.dot(&rates.w[*b]),
        }
    }

    /// Unit rates along a DOF.
    pub fn unit_rate(&self, target: &Target<S>) -> Rates<S> {
        let mut r = self.zero_rates();
        match target {
            Target::Particle(i, d) => r.p[*i] = *d,
            Target::Translation(b, d) => r.b[*b] = *d,
            Target::Rotation(b, g) => r.w[*b] = *g,
        }
        r
    }

    /// Generalised mass matrix entry between two DOFs.
    pub fn mass_entry(&self, cfg: &Config<S>, k: &Target<S>, l: &Target<S>) -> f64 {
        let ul = self.unit_rate(l);
        match k {
            Target::Particle(i, d) => self.particles[*i].mass * d.dot(&ul.p[*i]),
            Target::Translation(b, d) => {
                let (f, _) = self.body_momentum(cfg, *b, &ul.b[*b], &ul.w[*b]);
                d.dot(&f)
            }
            Target::Rotation(b, g) => {
                let (_, m) = self.body_momentum(cfg, *b, &ul.b[*b], &ul.w[*b]);
                g.dot(&m)
            }
        }
    }

    /// Upper bounds `(λ, γ)` on the eigenvalues of M⁻¹K and on the row sums of M⁻¹C in the
    /// free DOFs at `cfg`, from the elements alone (Gershgorin: every eigenvalue of M⁻¹K lies
    /// within the largest absolute row sum), without assembling a matrix; O(elements). `None`
    /// for scenes with bodies or contact (they take the assembled linearisation).
    ///
    /// An axial spring's tangent stiffness is `c ddᵀ + (T/L)(I − ddᵀ)`, T its tension; each
    /// entry between unit axes e, f is bounded by `c|e·d||d·f| + (|T|/L)(|e·f| + |e·d||d·f|)`.
    pub fn frequency_bound(&self, cfg: &Config<S>, held: &Constraints<S>) -> Option<(f64, f64)> {
        if !self.bodies.is_empty() || !self.contacts.is_empty() {
            return None;
        }
        let free: Vec<Vec<S::V>> = self
            .particles
            .iter()
            .zip(&held.particle_held)
            .map(|(p, h)| {
                p.axes
                    .iter()
                    .copied()
                    .filter(|a| h.iter().all(|d| d.dot(a).abs() < 0.5))
                    .collect()
            })
            .collect();
        let mut stiffness = vec![0.0; self.particles.len() * S::DIM];
        let mut damping = vec![0.0; self.particles.len() * S::DIM];
        let entry = |e: &S::V, f: &S::V, d: &S::V, c: f64, t: f64| {
            let along = e.dot(d).abs() * d.dot(f).abs();
            c * along + t * (e.dot(f).abs() + along)
        };
        // Add one element's row sums to the rows of its particle ends.
        let add = |rows: &mut Vec<f64>, ends: [&Point<S>; 2], d: &S::V, c: f64, t: f64| {
            for end in ends {
                let Point::Particle(i) = end else { continue };
                for (a, e) in free[*i].iter().enumerate() {
                    let mut sum = 0.0;
                    for other in ends {
                        if let Point::Particle(j) = other {
                            sum += free[*j].iter().map(|f| entry(e, f, d, c, t)).sum::<f64>();
                        }
                    }
                    rows[*i * S::DIM + a] += sum;
                }
            }
        };
        for s in &self.grounded_springs {
            if let Some(d) = s.direction {
                add(
                    &mut stiffness,
                    [&s.point, &Point::Ground(S::V::zero())],
                    &d,
                    s.c,
                    0.0,
                );
            }
        }
        for s in &self.grounded_dashpots {
            if let Some(d) = s.direction {
                add(
                    &mut damping,
                    [&s.point, &Point::Ground(S::V::zero())],
                    &d,
                    s.c,
                    0.0,
                );
            }
        }
        let direction = |s: &TwoPoint<S>| {
            if s.axial && FINITE {
                let l = s.span0 + (self.displacement(cfg, &s.b) - self.displacement(cfg, &s.a));
                let len = l.dot(&l).sqrt();
                (l * (1.0 / len), len)
            } else {
                (s.direction, s.length0)
            }
        };
        for s in &self.springs {
            let (d, len) = direction(s);
            let tension = if s.axial && FINITE {
                (s.c * (len - s.length0) / len).abs()
            } else {
                0.0
            };
            add(&mut stiffness, [&s.a, &s.b], &d, s.c, tension);
        }
        for s in &self.dashpots {
            let (d, _) = direction(s);
            add(&mut damping, [&s.a, &s.b], &d, s.c, 0.0);
        }
        let largest = |rows: &[f64]| {
            rows.iter()
                .enumerate()
                .map(|(r, x)| x / self.particles[r / S::DIM].mass)
                .fold(0.0, f64::max)
        };
        Some((largest(&stiffness), largest(&damping)))
    }

    /// Free generalised DOFs under a step's constraints.
    pub fn free_dofs(&self, held: &Constraints<S>) -> Vec<Target<S>> {
        let mut out = Vec::new();
        let free = |axes: &[S::V], held: &[S::V]| -> Vec<S::V> {
            axes.iter()
                .copied()
                .filter(|a| held.iter().all(|h| h.dot(a).abs() < 0.5))
                .collect()
        };
        for (i, p) in self.particles.iter().enumerate() {
            for d in free(&p.axes, &held.particle_held[i]) {
                out.push(Target::Particle(i, d));
            }
        }
        for (b, body) in self.bodies.iter().enumerate() {
            for d in free(&body.axes, &held.body_held_t[b]) {
                out.push(Target::Translation(b, d));
            }
            for g in &body.rot_axes {
                if held.body_held_r[b].iter().all(|h| h.dot(g).abs() < 0.5) {
                    out.push(Target::Rotation(b, *g));
                }
            }
        }
        out
    }
}

impl<S: Space> Forces<S> {
    /// Copy another force set into this one (same shape).
    pub fn copy_from(&mut self, other: &Self) {
        self.p.copy_from_slice(&other.p);
        self.b.copy_from_slice(&other.b);
        self.m.copy_from_slice(&other.m);
        self.contact.copy_from_slice(&other.contact);
        self.elastic = other.elastic;
        self.dissipation = other.dissipation;
    }
}

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Push a contact node into its face so that its gap becomes `-depth`.
    pub fn set_penetration(&self, cfg: &mut Config<S>, k: usize, depth: f64) {
        let (d, n) = self.gap(cfg, k);
        let i = self.contacts[k].particle;
        cfg.u[i] -= n * (d + depth);
    }

    /// State reached from `(cfg, vel)` after `s` seconds with acceleration `acc` and jerk
    /// `jerk` (third-order Taylor expansion; rotations through the exponential of the
    /// expanded rotation vector). That expansion is exact to third order while ω, α and α̇
    /// share one axis (every shipped case with contact: the contact start is its user). About
    /// changing axes the rotation vector's cubic term also holds ½ ω×α (the first Magnus
    /// commutator), left out here: a third-order error in the turned state, which reaches the
    /// contact start's lead as an O(h²·|ω×α|) error in the gap rate.
    pub fn extrapolate(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        acc: &Rates<S>,
        jerk: &Rates<S>,
        s: f64,
    ) -> (Config<S>, Rates<S>) {
        let (s2, s3) = (0.5 * s * s, s * s * s / 6.0);
        let turn = |b: usize| vel.w[b] * s + acc.w[b] * s2 + jerk.w[b] * s3;
        let cfg = Config {
            u: (0..cfg.u.len())
                .map(|i| cfg.u[i] + vel.p[i] * s + acc.p[i] * s2 + jerk.p[i] * s3)
                .collect(),
            bu: (0..cfg.bu.len())
                .map(|b| cfg.bu[b] + vel.b[b] * s + acc.b[b] * s2 + jerk.b[b] * s3)
                .collect(),
            br: (0..cfg.br.len())
                .map(|b| {
                    if FINITE {
                        S::advance(&cfg.br[b], &turn(b))
                    } else {
                        cfg.br[b]
                    }
                })
                .collect(),
            br_carry: vec![S::Carry::default(); cfg.br.len()],
            bth: (0..cfg.bth.len()).map(|b| cfg.bth[b] + turn(b)).collect(),
            inertia: cfg.inertia.clone(),
        };
        let mut cfg = cfg;
        if FINITE {
            for b in 0..cfg.br.len() {
                cfg.inertia[b] = self.oriented(b, &cfg.br[b]);
            }
        }
        (cfg, vel.plus(s, acc).plus(s2, jerk))
    }

    /// Time derivative of a contact pair's gap.
    pub fn gap_rate(&self, cfg: &Config<S>, vel: &Rates<S>, k: usize) -> f64 {
        let c = &self.contacts[k];
        if c.solid.is_some() {
            let (_, n) = self.gap(cfg, k);
            return self.normal_rate(cfg, vel, k, &n);
        }
        let (i, b) = (c.particle, c.body);
        if FINITE {
            let r = &cfg.br[b];
            let n = S::rotate(r, &c.normal);
            let f = S::rotate(r, &c.face);
            let p_dot = vel.b[b] + S::cross(&vel.w[b], &f);
            S::cross(&vel.w[b], &n).dot(&self.face_to_node(cfg, k)) + n.dot(&(vel.p[i] - p_dot))
        } else {
            c.normal.dot(&(vel.p[i] - vel.b[b])) - c.normal.dot(&S::cross(&vel.w[b], &c.arm0))
        }
    }

    /// Change the contact node's velocity along the face normal so the gap rate becomes `rate`.
    pub fn set_gap_rate(&self, cfg: &Config<S>, vel: &mut Rates<S>, k: usize, rate: f64) {
        let current = self.gap_rate(cfg, vel, k);
        let (_, n) = self.gap(cfg, k);
        vel.p[self.contacts[k].particle] += n * (rate - current);
    }

    /// Second time derivative of a contact pair's gap, exact for the given velocities and
    /// accelerations (finite: the face point and normal rotate with the body). On a solid,
    /// whose curvature parry does not give, it is the central difference of the gap's rate
    /// along the motion extrapolated ±τ, τ small enough that the node moves 1e-6 of the
    /// solid's half thickness relative to the body and the body turns 1e-6 rad (truncation
    /// ~1e-12, round-off ~1e-10 of the rate's scale), and at most `longest` (the increment:
    /// a node at rest on a still solid has no scale of its own).
    pub fn gap_acceleration(
        &self,
        cfg: &Config<S>,
        vel: &Rates<S>,
        acc: &Rates<S>,
        k: usize,
        longest: f64,
    ) -> f64 {
        let c = &self.contacts[k];
        let (i, b) = (c.particle, c.body);
        if let Some((_, shape)) = &c.solid {
            let depth = match shape {
                SharedSolid::Planar(s, _) => s.compute_local_aabb().half_extents().min_element(),
                SharedSolid::Spatial(s, _) => s.compute_local_aabb().half_extents().min_element(),
            };
            // The node's motion relative to the body point it touches: a body carrying the
            // pair fast through space does not shrink τ.
            let arm = self.contact_arm(cfg, k);
            let (w, alpha) = (vel.w[b], acc.w[b]);
            let v = vel.p[i] - vel.b[b] - S::cross(&w, &arm);
            let a =
                acc.p[i] - acc.b[b] - S::cross(&alpha, &arm) - S::cross(&w, &S::cross(&w, &arm));
            let (speed, pace, spin) = (v.dot(&v).sqrt(), a.dot(&a).sqrt(), w.dot(&w).sqrt());
            let tau =
                (1e-6 * (depth / speed).min((depth / pace).sqrt()).min(1.0 / spin)).min(longest);
            let zero = self.zero_rates();
            let rate = |s: f64| {
                let (c, v) = self.extrapolate(cfg, vel, acc, &zero, s);
                self.gap_rate(&c, &v, k)
            };
            return (rate(tau) - rate(-tau)) / (2.0 * tau);
        }
        if FINITE {
            let r = &cfg.br[b];
            let (w, alpha) = (vel.w[b], acc.w[b]);
            let n = S::rotate(r, &c.normal);
            let f = S::rotate(r, &c.face);
            let n_dot = S::cross(&w, &n);
            let n_ddot = S::cross(&alpha, &n) + S::cross(&w, &n_dot);
            let p_dot = vel.b[b] + S::cross(&w, &f);
            let p_ddot = acc.b[b] + S::cross(&alpha, &f) + S::cross(&w, &S::cross(&w, &f));
            n_ddot.dot(&self.face_to_node(cfg, k))
                + n_dot.dot(&(vel.p[i] - p_dot)) * 2.0
                + n.dot(&(acc.p[i] - p_ddot))
        } else {
            c.normal.dot(&(acc.p[i] - acc.b[b])) - c.normal.dot(&S::cross(&acc.w[b], &c.arm0))
        }
    }
}

/// Below this |z| the series of [`centred_rate`] stops at z³: the first term left out, 14 z⁴,
/// is under 2.2e-17, a fifth of an ulp of the sum or less (the sum is about 1; its ulp is
/// 1.1e-16 just below 1, 2.2e-16 from 1 up).
const CATALAN_FOUR: f64 = 3.5e-5;

/// Below this |z| the series stops at z⁵: the first term left out, 132 z⁶, is under 1.6e-17.
const CATALAN_SIX: f64 = 7e-4;

/// The root `s = 2γ / (1 + √(1 − 4βγ))` of `β s² − s + γ = 0` that tends to γ as β → 0;
/// None where the roots are not real (4βγ > 1, or NaN) or not finite.
///
/// With z = βγ the root is γ·C(z), C(z) = 2/(1 + √(1 − 4z)) = Σ Cₙ zⁿ (the Catalan numbers
/// 1, 1, 2, 5, 14, 42, …). At the rates explicit runs take z is small (of order h·|ω|), and the
/// series' first terms, evaluated in pairs (Estrin), give C(z) to round-off in a shorter chain
/// of dependent operations than the square root and the division of the closed form, which sit
/// on the time loop's critical path. Beyond [`CATALAN_SIX`], the closed form.
#[inline]
pub fn centred_rate(beta: f64, gamma: f64) -> Option<f64> {
    let z = beta * gamma;
    let magnitude = z.abs();
    if magnitude < CATALAN_SIX {
        let z2 = z * z;
        let low = (1.0 + z) + z2 * (2.0 + 5.0 * z);
        let c = if magnitude < CATALAN_FOUR {
            low
        } else {
            low + (z2 * z2) * (14.0 + 42.0 * z)
        };
        return Some(gamma * c);
    }
    let discriminant = 1.0 - 4.0 * z;
    // Negative or NaN: no real root; infinite: no finite one.
    if !(discriminant >= 0.0 && discriminant.is_finite()) {
        return None;
    }
    Some(2.0 * gamma / (1.0 + discriminant.sqrt()))
}

/// Below this |z| the series of [`centred_square_factor`] stops at z³: the first term left out,
/// 42 z⁴, is under 1.7e-17, a fifth of an ulp of the sum or less.
const SQUARE_FOUR: f64 = 2.5e-5;

/// Below this |z| that series stops at z⁵: the first term left out, 429 z⁶, is under 2.1e-17.
const SQUARE_SIX: f64 = 6e-4;

/// The factor C(z)² that turns γ² into the square s² = γ²·C(z)² of [`centred_rate`]'s root
/// s = γ·C(z), for a step that needs only s² (the centripetal terms) and multiplies it by
/// factors of its own: those can take γ² before the factor is ready, so the chain of dependent
/// operations from γ is shorter than the root's and its square's. With z = βγ and
/// C(z) = 1 + z·C(z)², C(z)² = (C(z) − 1)/z = Σ Cₙ₊₁ zⁿ (1, 2, 5, 14, 42, 132, …); the series'
/// coefficients times z are formed as (k·β)·γ, from β, which is ready before γ, each fused
/// with the constant it is added to. From γ the factor takes three or four steps (βγ, z², z⁴
/// beyond [`SQUARE_FOUR`], the last fused step).
/// Beyond [`SQUARE_SIX`], (2/(1 + √(1 − 4z)))². None where [`centred_rate`] is.
#[inline(always)]
pub fn centred_square_factor(beta: f64, gamma: f64) -> Option<f64> {
    let z = beta * gamma;
    let magnitude = z.abs();
    if magnitude < SQUARE_SIX {
        let z2 = z * z;
        let low = z2.mul_add(
            (14.0 * beta).mul_add(gamma, 5.0),
            (2.0 * beta).mul_add(gamma, 1.0),
        );
        return Some(if magnitude < SQUARE_FOUR {
            low
        } else {
            (z2 * z2).mul_add((132.0 * beta).mul_add(gamma, 42.0), low)
        });
    }
    let discriminant = 1.0 - 4.0 * z;
    // As in `centred_rate`: negative or NaN, no real root; infinite, no finite one.
    if !(discriminant >= 0.0 && discriminant.is_finite()) {
        return None;
    }
    let c = 2.0 / (1.0 + discriminant.sqrt());
    Some(c * c)
}
