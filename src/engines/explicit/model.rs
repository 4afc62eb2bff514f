//! The scene compiled into the force terms it actually has.
//!
//! Compilation resolves every element end to a [`Point`] (ground, particle or body material
//! point) once, so the time loop does no name look-ups and no work for absent effects. The
//! `FINITE` const parameter selects finite rotation (`explicit`) or the benchmark's
//! small-rotation idealisation (`explicit_small`); it is resolved at compile time.

use super::axis::{LineSprings, ParticleKernel};
use super::body_solve::BodyOperator;
use super::space::{BodyInertia, Lin, Space};
pub use super::state::{Config, ContactMode, Counters, Forces, Rates, Vectors, fill_zero};
use crate::scene::{
    Amplitude, Attachment, Connection, ContactPair, ContactState, Dof, Element, Friction,
    PointLoad, Scene, StepKind, Surface,
};

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
    pub(super) fn particle_or_ground(&self) -> Option<Option<usize>> {
        match self {
            Point::Particle(i) => Some(Some(*i)),
            Point::Ground(_) => Some(None),
            Point::Body { .. } => None,
        }
    }
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
    /// From end a to end b at t = 0.
    pub(super) span0: S::V,
    pub(super) length0: f64,
    pub(super) c: f64,
}

/// A spring of fixed direction whose ends are particles or the ground: the bulk of a large
/// scene, stored apart from the general two-point elements in the compact form the force pass
/// streams through (32 bytes in 2D, 40 in 3D, against a [`TwoPoint`]'s 120 or 152).
#[derive(Debug, Clone, Copy)]
pub(super) struct LineSpring<S: Space> {
    /// Particle at end a, or [`GROUND`].
    pub(super) a: u32,
    /// Particle at end b, or [`GROUND`].
    pub(super) b: u32,
    /// Unit direction.
    pub(super) direction: S::V,
    /// Stiffness.
    pub(super) c: f64,
}

/// A [`LineSpring`] end that does not move.
pub(super) const GROUND: u32 = u32::MAX;

impl<S: Space> LineSpring<S> {
    /// The spring as a general two-point element's ends (for the passes that are not on the
    /// increment's path: the stable increment's bound).
    pub(super) fn ends(&self) -> [Point<S>; 2] {
        [self.a, self.b].map(|i| {
            if i == GROUND {
                Point::Ground(S::V::zero())
            } else {
                Point::Particle(i as usize)
            }
        })
    }
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
    /// The slave: a particle (it touches with its node), or a body's material point whose
    /// ball of [`Contact::radius`] touches (a body rolling on a plane face).
    pub(super) slave: Point<S>,
    /// The radius of the slave's ball (0 for a particle): the pair touches at the node less
    /// this along the outward normal.
    pub(super) radius: f64,
    pub(super) body: usize,
    /// A solid's centre relative to the reference node (body frame) and its parry shape; `None`
    /// for a plane.
    pub(super) solid: Option<(S::V, S::Shape)>,
    /// Contact dashpot (sized for the pair's restitution; 0 when elastic).
    pub(super) damping: f64,
    /// One over the mass the normal force moves ([`contact_mass`]).
    pub(super) inverse_mass: f64,
    /// The gap at t = 0 of a pair that starts open: the linearisation's penalty is unstressed
    /// there (0 for a closed pair).
    pub(super) open_gap: f64,
    /// A face point relative to the reference node (body frame).
    pub(super) face: S::V,
    /// Outward normal (body frame).
    pub(super) normal: S::V,
    /// The contact node's offset from the reference node at t = 0 (small-rotation arm).
    pub(super) arm0: S::V,
    /// The node's gap at t = 0 (small rotation: the constant part of the linearised gap).
    pub(super) gap0: f64,
    /// Coulomb friction ([`super::friction`]); `None`: frictionless.
    pub(super) friction: Option<Friction>,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Load<S: Space> {
    pub(super) point: Point<S>,
    pub(super) force: S::V,
}

/// A particle's constant data.
#[derive(Debug, Clone, Copy)]
pub struct Particle {
    /// Scene node.
    pub node: usize,
    /// Mass.
    pub mass: f64,
    /// Its frame's axes (DOF directions), as an index into [`Model::frames`].
    pub frame: u32,
}

/// A body's constant data.
#[derive(Debug, Clone)]
pub struct Body<S: Space> {
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
    /// The distinct sets of held directions (orthonormal) the particles take, indexed like
    /// `motions` (a particle's set is [`Constraints::particle_held`]).
    pub held_sets: Vec<Vec<S::V>>,
    /// The distinct projections the particles' accelerations take (a few, whatever the number
    /// of particles).
    pub motions: Vec<Motion<S::V>>,
    /// Each particle's projection, as an index into `motions` (4 bytes per particle streamed
    /// by the time loop instead of a projection's 40 or 56).
    pub particle_motion: Vec<u32>,
    /// The kernel that steps the particles ([`super::axis`]).
    pub particle_kernel: ParticleKernel,
    /// Under [`ParticleKernel::Along`], where some particle is held along every coordinate
    /// axis: each particle's inverse mass along the axis, 0 for a held one (a finite force
    /// then moves it by nothing, as its projection gives). Empty otherwise: the model's
    /// inverse masses.
    pub along_inverse_masses: Vec<f64>,
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
    /// - at a dynamic step's start, under finite rotation in 3D, for such a body turning about
    ///   one free axis ([`Model::form_turning_operators`]).
    ///
    /// `None` for every other body under finite rotation (formed at every increment from the
    /// configuration's mass properties), among them some whose operator happens not to change
    /// either, such as a 3D body with every rotation held.
    pub body_operators: Vec<Option<BodyOperator<S>>>,
}

impl<S: Space> Constraints<S> {
    /// The directions held on particle `i`.
    #[inline]
    pub fn particle_held(&self, i: usize) -> &[S::V] {
        &self.held_sets[self.particle_motion[i] as usize]
    }

    /// The projection of particle `i`'s accelerations.
    #[inline]
    pub fn particle_projection(&self, i: usize) -> &Motion<S::V> {
        &self.motions[self.particle_motion[i] as usize]
    }

    /// Whether any velocity-dependent term acts (dashpots aside).
    pub fn any_velocity_terms(&self) -> bool {
        self.velocity_terms.iter().any(|x| *x)
    }

    /// Whether every body whose velocity terms act turns about one free axis: where no
    /// dashpot acts, its centred rate may then be in closed form
    /// ([`Model::centred_bodies_solved`]).
    pub fn velocity_terms_about_one_axis(&self) -> bool {
        let mut terms = self.velocity_terms.iter().zip(&self.body_free_r);
        terms.all(|(reads, free)| !reads || free.len() == 1)
    }

    /// The accelerations of body `b` at mass properties `inertia` under `force` and `moment`
    /// and this step's constraints, with `operator` where one is formed for them, otherwise
    /// the step's operator where it has one ([`Constraints::body_operators`]), otherwise one
    /// formed here.
    #[inline(always)]
    pub fn body_accelerations(
        &self,
        (inertia, b): (&BodyInertia<S>, usize),
        operator: Option<&BodyOperator<S>>,
        force: &S::V,
        moment: &S::W,
    ) -> (S::V, S::W) {
        let held = (
            self.body_held_t[b].as_slice(),
            self.body_free_r[b].as_slice(),
        );
        match operator.or(self.body_operators[b].as_ref()) {
            Some(operator) => operator.solve(inertia, held, force, moment),
            None => BodyOperator::of(inertia, held.0, held.1).solve(inertia, held, force, moment),
        }
    }
}

/// The largest cosine between a held direction and a line for [`Motion::confines_to`] to
/// take them as perpendicular: 45 times the machine epsilon, several times the round-off of
/// forming the two unit vectors from a frame and from two points, so that a hold across the
/// line those points span is found across it; a free direction that leaves the line by more
/// (in 3D by up to √2 times this, one hold off on each side) is not confined to it, and the
/// line is then treated as turning, which is always right.
pub const ACROSS: f64 = 1e-14;

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
    pub(super) fn of(held: &[V], dim: usize) -> Self {
        match held {
            [] => Motion::Free,
            _ if held.len() == dim => Motion::Held,
            [d] => Motion::Across(*d),
            [d, e] => Motion::AcrossTwo(*d, *e),
            _ => Motion::Held,
        }
    }

    /// True when every direction this projection leaves free is along the unit vector `u`
    /// (or none is): a particle under it moves on the line through it along `u`. A held
    /// direction counts as across `u` when its cosine with `u` is at most [`ACROSS`].
    pub fn confines_to(&self, u: V) -> bool {
        let across = |d: &V| d.dot(&u).abs() <= ACROSS;
        match self {
            Motion::Free => false,
            Motion::Held => true,
            Motion::Across(d) => V::DIM == 2 && across(d),
            Motion::AcrossTwo(d, e) => V::DIM == 3 && across(d) && across(e),
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

/// The compiled scene.
#[derive(Debug, Clone)]
pub struct Model<S: Space, const FINITE: bool> {
    /// Particles (free nodes).
    pub particles: Vec<Particle>,
    /// The distinct frames the particles' DOFs are taken in (axes per frame).
    pub frames: Vec<Vec<S::V>>,
    /// Rigid bodies.
    pub bodies: Vec<Body<S>>,
    pub(super) grounded_springs: Vec<Grounded<S>>,
    pub(super) grounded_dashpots: Vec<Grounded<S>>,
    /// Springs of fixed direction between particles or a particle and the ground.
    pub(super) line_springs: LineSprings<S>,
    /// Every other two-point spring (axial, or with an end on a body).
    pub(super) springs: Vec<TwoPoint<S>>,
    pub(super) dashpots: Vec<TwoPoint<S>>,
    pub(super) contacts: Vec<Contact<S>>,
    /// 1 / mass per particle (apart, so the time loop streams 8 bytes per particle).
    pub(super) inverse_masses: Vec<f64>,
    pub(super) loads: Vec<Load<S>>,
    /// Loads scaled by an amplitude in time ([`super::ramps`]).
    pub(super) ramped_loads: Vec<(Load<S>, Amplitude)>,
    /// Penalty stiffness.
    pub penalty: f64,
    /// Node → point.
    pub points: Vec<Point<S>>,
    /// Whether any dashpot acts (grounded, two-point or on a contact pair): read by every pass
    /// of the centred velocity, so kept rather than found again.
    dashpots_act: bool,
}

/// The springs of fixed direction between particles or a particle and the ground, in their
/// compact form, and the others as they are (each list in the scene's order), taken one by one
/// so that a large scene never holds every spring in the general form.
fn line_springs<S: Space>(
    springs: impl Iterator<Item = TwoPoint<S>>,
) -> (Vec<LineSpring<S>>, Vec<TwoPoint<S>>) {
    let end = |p: &Point<S>| match p {
        Point::Ground(_) => Some(GROUND),
        Point::Particle(i) => u32::try_from(*i).ok().filter(|i| *i != GROUND),
        Point::Body { .. } => None,
    };
    let (mut line, mut other) = (Vec::new(), Vec::new());
    line.reserve_exact(springs.size_hint().1.unwrap_or(0));
    for s in springs {
        match (s.axial, end(&s.a), end(&s.b)) {
            (false, Some(a), Some(b)) => line.push(LineSpring {
                a,
                b,
                direction: s.direction,
                c: s.c,
            }),
            _ => other.push(s),
        }
    }
    (line, other)
}

/// The contact dashpot of a pair: c = 2ζ√(k_p m), with ζ the damping ratio whose linear
/// spring–dashpot impact rebounds with the pair's restitution e (e = exp(−ζπ/√(1 − ζ²)), so
/// ζ = −ln e / √(π² + ln² e); e = 0: critical, ζ = 1) and m the pair's [`contact_mass`].
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
    2.0 * zeta * (penalty * contact_mass(scene, c)).sqrt()
}

/// The mass a pair's normal force moves: the node's (for a node of a body, the body's), or its
/// reduced mass with the face's body when that body is not held in every DOF of every dynamic
/// step (the bodies' turning left out).
fn contact_mass(scene: &Scene, c: &ContactPair) -> f64 {
    let node = match scene.nodes[c.node].attachment {
        Attachment::Free => scene.nodes[c.node].mass,
        Attachment::Reference(b) | Attachment::OnBody(b) => scene.bodies[b].mass,
    };
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
    if held {
        node
    } else {
        node * body.mass / (node + body.mass)
    }
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
        for b in &scene.bodies {
            let node = &scene.nodes[b.reference];
            bodies.push(Body {
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
        let mut frames: Vec<Vec<S::V>> = Vec::new();
        particles.reserve_exact(fixed.iter().filter(|f| !**f).count());
        for (i, n) in scene.nodes.iter().enumerate() {
            let x = S::v(&n.position);
            points.push(match n.attachment {
                Attachment::Free if fixed[i] => Point::Ground(x),
                Attachment::Free => {
                    let frame = axes(&n.frame);
                    // Neighbours usually share a frame: the last one is tried first.
                    if frames.last() != Some(&frame) {
                        frames.push(frame);
                    }
                    particles.push(Particle {
                        node: i,
                        mass: n.mass,
                        frame: u32::try_from(frames.len() - 1).expect("fewer than 2^32 frames"),
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
        let grounded = |list: &[Element]| -> Vec<Grounded<S>> {
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
        let two_point = |e: &Element| -> Option<TwoPoint<S>> {
            let (nodes, direction, axial) = match &e.connection {
                Connection::FixedDirection { nodes, direction } => (*nodes, S::v(direction), false),
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
                span0,
                length0: span0.dot(&span0).sqrt(),
                c: e.coefficient,
            })
        };
        let contacts: Vec<Contact<S>> = scene
            .contacts
            .iter()
            .map(|c| {
                let slave = points[c.node];
                debug_assert!(
                    !matches!(slave, Point::Ground(_)),
                    "validated: contact nodes have mass or belong to a body"
                );
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
                let (gap0, _) = c.gap_at(&scene.nodes[c.node].position);
                Contact {
                    slave,
                    radius: c.node_radius,
                    body: c.body,
                    solid,
                    damping: contact_damping(scene, c, penalty),
                    inverse_mass: 1.0 / contact_mass(scene, c),
                    open_gap: match c.initially {
                        ContactState::Open => gap0,
                        ContactState::Closed => 0.0,
                    },
                    face,
                    normal,
                    arm0,
                    gap0: normal.dot(&(arm0 - face)),
                    friction: c.friction,
                }
            })
            .collect();
        let load = |l: &PointLoad| Load {
            point: points[l.node],
            force: S::v(&l.force),
        };
        let loads: Vec<Load<S>> = scene
            .loads
            .iter()
            .filter(|l| l.amplitude.is_none())
            .map(load)
            .collect();
        let ramped_loads = scene
            .loads
            .iter()
            .filter_map(|l| Some((load(l), l.amplitude.clone()?)))
            .collect();
        let (line_springs, springs) = line_springs(scene.springs.iter().filter_map(two_point));
        let grounded_springs = grounded(&scene.springs);
        let grounded_dashpots = grounded(&scene.dashpots);
        let dashpots: Vec<_> = scene.dashpots.iter().filter_map(two_point).collect();
        let dashpots_act = !grounded_dashpots.is_empty()
            || !dashpots.is_empty()
            || contacts.iter().any(|c| c.damping > 0.0);
        Model {
            inverse_masses: particles.iter().map(|p| 1.0 / p.mass).collect(),
            particles,
            frames,
            bodies,
            grounded_springs,
            grounded_dashpots,
            line_springs: LineSprings::new(line_springs),
            springs,
            dashpots,
            contacts,
            loads,
            ramped_loads,
            penalty,
            points,
            dashpots_act,
        }
    }

    /// Whether the scene has dashpots.
    #[inline]
    pub fn has_dashpots(&self) -> bool {
        self.dashpots_act
    }

    /// The axes of particle `i`'s frame.
    #[inline]
    pub fn particle_axes(&self, i: usize) -> &[S::V] {
        &self.frames[self.particles[i].frame as usize]
    }

    /// The configuration at t = 0.
    pub fn initial_config(&self) -> Config<S> {
        Config {
            u: Vectors::zeros(self.particles.len()),
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
            Point::Particle(i) => cfg.u.get(*i),
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
            Point::Particle(i) => vel.p.get(*i),
            Point::Body { body, rho } => {
                vel.b[*body] + S::cross(&vel.w[*body], &self.arm(cfg, *body, rho))
            }
        }
    }

    #[inline(always)]
    pub(super) fn apply(&self, cfg: &Config<S>, p: &Point<S>, f: S::V, out: &mut Forces<S>) {
        match p {
            Point::Ground(_) => {}
            Point::Particle(i) => out.add_particle(*i, f),
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
        match self.contacts[k].slave {
            Point::Particle(i) => self.gap_at(cfg, k, cfg.u.get(i)),
            _ => self.touch_gap(cfg, k),
        }
    }

    /// The signed distance of pair `k`'s node, displaced by `u`, from its surface, and the
    /// current outward normal: the gap of a node that touches with itself.
    #[inline(always)]
    pub(super) fn gap_at(&self, cfg: &Config<S>, k: usize, u: S::V) -> (f64, S::V) {
        let c = &self.contacts[k];
        if let Some((centre, shape)) = &c.solid {
            let (d, n) = S::solid_gap(shape, &self.local_at(cfg, k, u, centre));
            return (d, self.to_world(cfg, c.body, &n));
        }
        if FINITE {
            let n = S::rotate(&cfg.br[c.body], &c.normal);
            (n.dot(&self.face_to_node_at(cfg, k, u)), n)
        } else {
            let (th, relative) = (&cfg.bth[c.body], u - cfg.bu[c.body]);
            let d = c.gap0 + c.normal.dot(&relative) - c.normal.dot(&S::cross(th, &c.arm0));
            (d, c.normal)
        }
    }

    /// A contact node's position relative to its solid's centre, in the body frame (small
    /// rotation: Rᵀ ≈ 1 − [θ]×).
    #[inline(always)]
    pub(super) fn local(&self, cfg: &Config<S>, k: usize, centre: &S::V) -> S::V {
        let u = self.node_displacement(cfg, &self.contacts[k].slave);
        self.local_at(cfg, k, u, centre)
    }

    /// [`Model::local`] with the node displaced by `u`.
    #[inline(always)]
    pub(super) fn local_at(&self, cfg: &Config<S>, k: usize, u: S::V, centre: &S::V) -> S::V {
        let c = &self.contacts[k];
        let arm = c.arm0 + (u - cfg.bu[c.body]);
        if FINITE {
            S::unrotate(&cfg.br[c.body], &arm) - *centre
        } else {
            arm - S::cross(&cfg.bth[c.body], &arm) - *centre
        }
    }

    /// A body-frame direction in the world (small rotation: R ≈ 1 + [θ]×).
    #[inline]
    pub(super) fn to_world(&self, cfg: &Config<S>, body: usize, x: &S::V) -> S::V {
        if FINITE {
            S::rotate(&cfg.br[body], x)
        } else {
            *x + S::cross(&cfg.bth[body], x)
        }
    }

    /// From the body's reference node to a contact node (small rotation: at t = 0); a ball
    /// touches [`Contact::radius`] from it ([`Model::touch_arm`]).
    #[inline(always)]
    pub(super) fn contact_arm(&self, cfg: &Config<S>, k: usize) -> S::V {
        let c = &self.contacts[k];
        if FINITE {
            self.arm_at(cfg, k, self.node_displacement(cfg, &c.slave))
        } else {
            c.arm0
        }
    }

    /// [`Model::contact_arm`] with the node displaced by `u`.
    #[inline(always)]
    pub(super) fn arm_at(&self, cfg: &Config<S>, k: usize, u: S::V) -> S::V {
        let c = &self.contacts[k];
        if FINITE {
            c.arm0 + (u - cfg.bu[c.body])
        } else {
            c.arm0
        }
    }

    /// Rate of a contact's gap along the normal `n`: the node's velocity relative to the body
    /// point it passes, n·(ṗ − v − ω × (p − x)) (any surface: the normal's own turning moves
    /// the gap only at second order; a ball's spin moves its contact point across `n`).
    #[inline]
    pub(super) fn normal_rate(&self, cfg: &Config<S>, vel: &Rates<S>, k: usize, n: &S::V) -> f64 {
        let c = &self.contacts[k];
        let (p, b) = (self.node_velocity(cfg, vel, &c.slave), c.body);
        n.dot(&(p - vel.b[b] - S::cross(&vel.w[b], &self.contact_arm(cfg, k))))
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

    /// From plane pair `k`'s face point to its node at `cfg` (finite rotation), summed from
    /// small parts (the offset at t = 0, the displacements, the face point's turn) so that a
    /// penalty stiffness does not multiply the cancellation of body-sized positions.
    #[inline(always)]
    pub(super) fn face_to_node(&self, cfg: &Config<S>, k: usize) -> S::V {
        let u = self.node_displacement(cfg, &self.contacts[k].slave);
        self.face_to_node_at(cfg, k, u)
    }

    /// [`Model::face_to_node`] with the node displaced by `u`.
    #[inline(always)]
    pub(super) fn face_to_node_at(&self, cfg: &Config<S>, k: usize, u: S::V) -> S::V {
        let c = &self.contacts[k];
        let relative = u - cfg.bu[c.body];
        (c.arm0 - c.face) + relative - S::turned(&cfg.br[c.body], &c.face)
    }
}
