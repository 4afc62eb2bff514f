//! The scene as a mechanism with finite rotation and rigid, persistent contact, written from
//! Newton–Euler's equations (not from the explicit engine's force assembly).
//!
//! # Coordinates
//!
//! Positions: each free node (a *particle*, ground nodes included) has its position p; each
//! body its reference node's position x and a unit quaternion q (body frame = world frame at
//! t = 0). A material point at r₀ from the reference node (at t = 0) is at x + R r₀.
//!
//! Velocities: the full velocity u stacks ṗ (3 per particle) and, per body, the reference
//! node's velocity v and the world angular velocity ω (6 per body). The DOFs a step leaves free
//! span the columns of T (unit frame axes: a particle's translations, a body's translations and
//! rotations; in 2D z and the rotations about x and y are always held), and u = T w: the state
//! integrates w, so held DOFs stay where they are exactly.
//!
//! # Equations
//!
//! A body of mass m, centre of mass at c = R c₀ from O and inertia J_O = R I_O Rᵀ about O obeys
//!
//!   m (a + α × c) = F − m ω × (ω × c),   m c × a + J_O α = M_O − ω × (J_O ω),
//!
//! so its mass block is [[m 1, −m[c]×], [m[c]×, J_O]]; a particle's is m 1. Springs and dashpots
//! of the three kinds act as the scene says (grounded: along a node's frame axis or about a
//! rotation axis; fixed direction: along a constant global direction; axial: along the current
//! line joining the nodes); loads are global forces at nodes, constant or their force times their
//! amplitude at the time t of the evaluation (linear between the table's points). A force f at a
//! body point p adds f to F and (p − x) × f to M_O.
//!
//! A closed contact pair is a constraint: the node keeps its distance to the surface,
//! g = g₀ (a plane: g = n·(p_N − a) with n = R n₀ and a = x + R r_f; a solid: the signed
//! distance φ(Rᵀ(p_N − x)), whose curvature adds ṡᵀHṡ to Ġu). Its velocity row G gives
//! ġ = n·ṗ_N − n·v − ((p_N − x) × n)·ω, and g̈ = G u̇ + Ġu with
//! Ġu = (ω × n)·(ṗ_N − v) − ω·((ṗ_N − v) × n + (p_N − x) × (ω × n)). With A = TᵀMT, b = Tᵀf and
//! B = GT, each evaluation solves
//!
//!   [[A, −Bᵀ], [B, 0]] [ẇ; λ] = [b; −Ġu],
//!
//! λ being the contact forces (on the node λ n: compressive positive). A pair with friction adds
//! its stuck node's tangential rows, or its sliding node's friction to its normal's column
//! ([`friction`]).
//!
//! A body's node N carrying a ball of radius ρ touches a plane at P = p_N − ρ n; its gap is
//! g − ρ, and its rows are those of the relative velocity of the slave body's material point at
//! P ([`touch`]): v_s + ω_s × (P − x_s) takes ṗ's place, P − x the node's arm on the master.

mod friction;
mod touch;

use crate::engines::EngineError;
use crate::scene::{
    Attachment, Connection, ContactPair, ContactState, Dimension, Dof, Element, Friction, NodeId,
    PointLoad, Scene, Solid, Step, Surface, surface_distance,
};
pub use friction::Grip;
use nalgebra::{DMatrix, DVector, Matrix3, Quaternion, UnitQuaternion, Vector3};
use touch::Slave;

/// Where a node lives in the coordinates.
#[derive(Debug, Clone, Copy)]
enum Place {
    /// A free node: particle index.
    Particle(usize),
    /// A point of a body, at `r0` from its reference node at t = 0.
    Body(usize, Vector3<f64>),
}

/// A body's constant data.
#[derive(Debug, Clone)]
struct Body {
    node: NodeId,
    mass: f64,
    centre: Vector3<f64>,
    inertia: Matrix3<f64>,
}

/// A contact pair's constant data.
#[derive(Debug, Clone)]
struct Contact {
    name: String,
    /// The node: a particle, or a body's node carrying a ball.
    slave: Slave,
    body: usize,
    /// The surface in the body frame, its reference node at the origin.
    surface: Surface,
    /// The gap (the ball's radius taken off) a closed contact keeps: the initial one for a pair closed at t = 0 (zero to
    /// the validation's round-off), zero for one that closes later.
    level: f64,
    /// Coefficient of restitution.
    restitution: f64,
    /// Closed at t = 0.
    closed: bool,
    /// Coulomb friction, if any.
    friction: Option<Friction>,
}

/// The mechanism: constant data of a scene, and its equations.
#[derive(Debug, Clone)]
pub struct Mechanism {
    dimension: Dimension,
    places: Vec<Place>,
    particles: Vec<NodeId>,
    particle_mass: Vec<f64>,
    bodies: Vec<Body>,
    springs: Vec<Element>,
    dashpots: Vec<Element>,
    loads: Vec<PointLoad>,
    contacts: Vec<Contact>,
    /// Whether any pair has friction.
    frictional: bool,
    /// Whether any load has an amplitude.
    ramped: bool,
    initial: Vec<Vector3<f64>>,
    frames: Vec<Matrix3<f64>>,
}

/// Positions of the mechanism, unpacked.
#[derive(Debug, Clone)]
pub struct Placement {
    /// Particle positions.
    pub particles: Vec<Vector3<f64>>,
    /// Body reference node positions.
    pub origins: Vec<Vector3<f64>>,
    /// Body orientations (unit).
    pub orientations: Vec<UnitQuaternion<f64>>,
}

/// What one evaluation of the equations gives.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Time derivative of the free velocity coordinates.
    pub acceleration: DVector<f64>,
    /// Contact forces, compressive positive, per pair.
    pub contact: Vec<f64>,
    /// Friction force on each pair's node (tangential; zero for a pair without a grip); empty
    /// in a scene without friction.
    pub friction: Vec<Vector3<f64>>,
    /// Power of the friction of the sliding pairs, μ_k λ_n d·v_t summed (dissipated: ≥ 0).
    pub dissipation: f64,
}

fn refused<T>(what: impl Into<String>) -> Result<T, EngineError> {
    Err(EngineError::Unsupported(format!(
        "reference: {}",
        what.into()
    )))
}

/// What pair `c`'s node is: a free node (touching with itself), or a node of another body than
/// the face's carrying a ball against a plane.
fn slave(c: &ContactPair, place: Place) -> Result<Slave, EngineError> {
    match place {
        Place::Particle(i) if !c.rolls() => Ok(Slave::Particle(i)),
        Place::Body(body, offset) if c.rolls() && body != c.body && c.plane().is_some() => {
            Ok(Slave::Ball {
                body,
                offset,
                radius: c.node_radius,
            })
        }
        _ => refused(format!(
            "contact `{}`: the reference slaves a free node without a ball, or a node of \
             another body than the face's carrying a ball against a plane",
            c.name
        )),
    }
}

fn skew(c: &Vector3<f64>) -> Matrix3<f64> {
    c.cross_matrix()
}

/// Rotation of `q` about a unit axis (the twist angle, in (−π, π]).
pub fn twist(q: &UnitQuaternion<f64>, axis: &Vector3<f64>) -> f64 {
    2.0 * q.imag().dot(axis).atan2(q.w)
}

impl Mechanism {
    /// The mechanism of a scene, or why the reference cannot solve it.
    pub fn new(scene: &Scene) -> Result<Self, EngineError> {
        let mut places = Vec::with_capacity(scene.nodes.len());
        let mut particles = Vec::new();
        for (id, node) in scene.nodes.iter().enumerate() {
            let frame = node.frame;
            if (frame.transpose() * frame - Matrix3::identity()).amax() > 1e-9 {
                return refused(format!(
                    "node `{}`: its frame is not orthonormal",
                    node.name
                ));
            }
            places.push(match node.attachment {
                Attachment::Free => {
                    particles.push(id);
                    Place::Particle(particles.len() - 1)
                }
                Attachment::Reference(b) | Attachment::OnBody(b) => {
                    let origin = scene.nodes[scene.bodies[b].reference].position;
                    Place::Body(b, node.position - origin)
                }
            });
        }
        let particle_mass = particles.iter().map(|&i| scene.nodes[i].mass).collect();
        let bodies = scene
            .bodies
            .iter()
            .map(|b| Body {
                node: b.reference,
                mass: b.mass,
                centre: b.centre_offset,
                inertia: match scene.dimension {
                    // Only I_zz is used in 2D: the rotations about x and y are held.
                    Dimension::Two => Matrix3::from_diagonal(&Vector3::new(
                        b.inertia[(2, 2)],
                        b.inertia[(2, 2)],
                        b.inertia[(2, 2)],
                    )),
                    Dimension::Three => b.inertia,
                },
            })
            .collect();
        let mut contacts = Vec::new();
        for c in &scene.contacts {
            let slave = slave(c, places[c.node])?;
            let origin = scene.nodes[scene.bodies[c.body].reference].position;
            let surface = match &c.surface {
                Surface::Plane { point, normal } => Surface::Plane {
                    point: point - origin,
                    normal: *normal,
                },
                Surface::Solid { solid, centre } => Surface::Solid {
                    solid: solid.clone(),
                    centre: centre - origin,
                },
            };
            let closed = c.initially == ContactState::Closed;
            if c.friction.is_some() && !closed {
                return refused(format!(
                    "contact `{}`: with friction, a pair must start closed (the tangential \
                     impulse of an impact is not modelled)",
                    c.name
                ));
            }
            contacts.push(Contact {
                name: c.name.clone(),
                slave,
                body: c.body,
                surface,
                level: if closed {
                    c.gap_at(&scene.nodes[c.node].position).0
                } else {
                    0.0
                },
                restitution: c.restitution,
                closed,
                friction: c.friction,
            });
        }
        for e in scene.springs.iter().chain(&scene.dashpots) {
            if let Connection::Grounded {
                node,
                dof: Dof::Rotation(_),
            } = e.connection
                && !matches!(scene.nodes[node].attachment, Attachment::Reference(_))
            {
                return refused(format!(
                    "element `{}`: a rotation of a node that is not a body's reference",
                    e.name
                ));
            }
        }
        Ok(Self {
            dimension: scene.dimension,
            places,
            particles,
            particle_mass,
            bodies,
            springs: scene.springs.clone(),
            dashpots: scene.dashpots.clone(),
            loads: scene.loads.clone(),
            ramped: scene.has_amplitudes(),
            frictional: contacts.iter().any(|c| c.friction.is_some()),
            contacts,
            initial: scene.nodes.iter().map(|n| n.position).collect(),
            frames: scene.nodes.iter().map(|n| n.frame).collect(),
        })
    }

    /// Length of the full velocity u.
    pub fn velocity_len(&self) -> usize {
        3 * self.particles.len() + 6 * self.bodies.len()
    }

    /// Length of the position part of the state.
    pub fn position_len(&self) -> usize {
        3 * self.particles.len() + 7 * self.bodies.len()
    }

    /// Whether a load varies in time (has an amplitude).
    pub fn varies_in_time(&self) -> bool {
        self.ramped
    }

    /// Number of contact pairs.
    pub fn contact_count(&self) -> usize {
        self.contacts.len()
    }

    /// The positions at t = 0.
    pub fn initial_placement(&self) -> Placement {
        Placement {
            particles: self.particles.iter().map(|&i| self.initial[i]).collect(),
            origins: self.bodies.iter().map(|b| self.initial[b.node]).collect(),
            orientations: vec![UnitQuaternion::identity(); self.bodies.len()],
        }
    }

    /// Positions into the first `position_len` entries of a state.
    pub fn pack(&self, placement: &Placement, state: &mut [f64]) {
        let mut k = 0;
        for p in &placement.particles {
            state[k..k + 3].copy_from_slice(p.as_slice());
            k += 3;
        }
        for (x, q) in placement.origins.iter().zip(&placement.orientations) {
            state[k..k + 3].copy_from_slice(x.as_slice());
            state[k + 3..k + 7].copy_from_slice(q.as_vector().as_slice());
            k += 7;
        }
    }

    /// Positions from the first `position_len` entries of a state (quaternions normalised).
    pub fn unpack(&self, state: &[f64]) -> Placement {
        let mut particles = Vec::with_capacity(self.particles.len());
        let mut k = 0;
        for _ in &self.particles {
            particles.push(Vector3::from_column_slice(&state[k..k + 3]));
            k += 3;
        }
        let mut origins = Vec::with_capacity(self.bodies.len());
        let mut orientations = Vec::with_capacity(self.bodies.len());
        for _ in &self.bodies {
            origins.push(Vector3::from_column_slice(&state[k..k + 3]));
            // Stored as (i, j, k, w), nalgebra's coordinate order.
            let q = Quaternion::new(state[k + 6], state[k + 3], state[k + 4], state[k + 5]);
            orientations.push(UnitQuaternion::from_quaternion(q));
            k += 7;
        }
        Placement {
            particles,
            origins,
            orientations,
        }
    }

    /// The free-DOF basis T (velocity_len × free) of a step, and the prescribed values
    /// `(node, dof, value)` it sets.
    pub fn free_basis(&self, step: &Step) -> Result<DMatrix<f64>, EngineError> {
        let held = |node: NodeId, dof: Dof| {
            step.conditions
                .iter()
                .any(|c| c.node == node && c.dof == dof)
        };
        for c in &step.conditions {
            if let Place::Body(b, _) = self.places[c.node]
                && self.bodies[b].node != c.node
            {
                return refused(
                    "a held DOF on a body point that is not the body's reference node".to_string(),
                );
            }
        }
        let planar = self.dimension == Dimension::Two;
        let mut columns: Vec<DVector<f64>> = Vec::new();
        let n = self.velocity_len();
        for (i, &node) in self.particles.iter().enumerate() {
            for axis in 0..3 {
                if (planar && axis == 2) || held(node, Dof::Translation(axis)) {
                    continue;
                }
                let mut c = DVector::zeros(n);
                c.fixed_rows_mut::<3>(3 * i)
                    .copy_from(&self.frames[node].column(axis));
                columns.push(c);
            }
        }
        let base = 3 * self.particles.len();
        for (b, body) in self.bodies.iter().enumerate() {
            let frame = self.frames[body.node];
            for axis in 0..3 {
                if !((planar && axis == 2) || held(body.node, Dof::Translation(axis))) {
                    let mut c = DVector::zeros(n);
                    c.fixed_rows_mut::<3>(base + 6 * b)
                        .copy_from(&frame.column(axis));
                    columns.push(c);
                }
                if !((planar && axis != 2) || held(body.node, Dof::Rotation(axis))) {
                    let mut c = DVector::zeros(n);
                    let direction = if planar {
                        Vector3::z()
                    } else {
                        frame.column(axis).into_owned()
                    };
                    c.fixed_rows_mut::<3>(base + 6 * b + 3)
                        .copy_from(&direction);
                    columns.push(c);
                }
            }
        }
        Ok(if columns.is_empty() {
            DMatrix::zeros(n, 0)
        } else {
            DMatrix::from_columns(&columns)
        })
    }

    /// Set a step's prescribed displacements (along the node's frame axis from its initial
    /// position; a rotation about the frame axis from where the body is).
    pub fn prescribe(&self, step: &Step, placement: &mut Placement) {
        for c in &step.conditions {
            let Some(value) = c.value else { continue };
            let frame = self.frames[c.node];
            let initial = self.initial[c.node];
            match (self.places[c.node], c.dof) {
                (Place::Particle(i), Dof::Translation(a)) => {
                    let e = frame.column(a).into_owned();
                    let p = &mut placement.particles[i];
                    *p += e * (e.dot(&initial) + value - e.dot(p));
                }
                (Place::Body(b, _), Dof::Translation(a)) => {
                    let e = frame.column(a).into_owned();
                    let x = &mut placement.origins[b];
                    *x += e * (e.dot(&initial) + value - e.dot(x));
                }
                (Place::Body(b, _), Dof::Rotation(a)) => {
                    let axis = if self.dimension == Dimension::Two {
                        Vector3::z()
                    } else {
                        frame.column(a).into_owned()
                    };
                    let q = &mut placement.orientations[b];
                    let turn = value - twist(q, &axis);
                    *q = UnitQuaternion::from_scaled_axis(axis * turn) * *q;
                }
                (Place::Particle(_), Dof::Rotation(_)) => {}
            }
        }
    }

    /// Position of a node.
    pub fn position(&self, at: &Placement, node: NodeId) -> Vector3<f64> {
        match self.places[node] {
            Place::Particle(i) => at.particles[i],
            Place::Body(b, r0) => at.origins[b] + at.orientations[b] * r0,
        }
    }

    /// Velocity of a node from the full velocity u.
    pub fn velocity(&self, at: &Placement, u: &DVector<f64>, node: NodeId) -> Vector3<f64> {
        match self.places[node] {
            Place::Particle(i) => u.fixed_rows::<3>(3 * i).into_owned(),
            Place::Body(b, r0) => {
                let k = 3 * self.particles.len() + 6 * b;
                let v = u.fixed_rows::<3>(k).into_owned();
                let w = u.fixed_rows::<3>(k + 3).into_owned();
                v + w.cross(&(at.orientations[b] * r0))
            }
        }
    }

    /// Angular velocity of a body from u.
    pub fn angular(&self, u: &DVector<f64>, body: usize) -> Vector3<f64> {
        u.fixed_rows::<3>(3 * self.particles.len() + 6 * body + 3)
            .into_owned()
    }

    /// Add a force at a node to the generalised force f (on u).
    fn apply(&self, at: &Placement, f: &mut DVector<f64>, node: NodeId, force: Vector3<f64>) {
        match self.places[node] {
            Place::Particle(i) => {
                let mut s = f.fixed_rows_mut::<3>(3 * i);
                s += force;
            }
            Place::Body(b, _) => {
                let k = 3 * self.particles.len() + 6 * b;
                let arm = self.position(at, node) - at.origins[b];
                let mut s = f.fixed_rows_mut::<3>(k);
                s += force;
                let mut m = f.fixed_rows_mut::<3>(k + 3);
                m += arm.cross(&force);
            }
        }
    }

    /// Add a moment about a body's reference node.
    fn apply_moment(&self, f: &mut DVector<f64>, node: NodeId, moment: Vector3<f64>) {
        if let Place::Body(b, _) = self.places[node] {
            let k = 3 * self.particles.len() + 6 * b + 3;
            let mut m = f.fixed_rows_mut::<3>(k);
            m += moment;
        }
    }

    /// Rotation axis of a grounded rotational element (the node's frame axis; z in 2D).
    fn rotation_axis(&self, node: NodeId, axis: usize) -> Vector3<f64> {
        if self.dimension == Dimension::Two {
            Vector3::z()
        } else {
            self.frames[node].column(axis).into_owned()
        }
    }

    /// Generalised force of the springs, dashpots and loads on u (no inertia terms) at time `t`
    /// (the loads' amplitudes there).
    pub fn applied(
        &self,
        at: &Placement,
        u: &DVector<f64>,
        t: f64,
    ) -> Result<DVector<f64>, EngineError> {
        let mut f = DVector::zeros(self.velocity_len());
        for load in &self.loads {
            self.apply(at, &mut f, load.node, load.force_at(t));
        }
        for (elements, viscous) in [(&self.springs, false), (&self.dashpots, true)] {
            for e in elements {
                let k = e.coefficient;
                match &e.connection {
                    Connection::Grounded {
                        node,
                        dof: Dof::Translation(a),
                    } => {
                        let d = self.frames[*node].column(*a).into_owned();
                        let measure = if viscous {
                            d.dot(&self.velocity(at, u, *node))
                        } else {
                            d.dot(&(self.position(at, *node) - self.initial[*node]))
                        };
                        self.apply(at, &mut f, *node, d * (-k * measure));
                    }
                    Connection::Grounded {
                        node,
                        dof: Dof::Rotation(a),
                    } => {
                        let axis = self.rotation_axis(*node, *a);
                        let Place::Body(b, _) = self.places[*node] else {
                            continue;
                        };
                        let measure = if viscous {
                            axis.dot(&self.angular(u, b))
                        } else {
                            twist(&at.orientations[b], &axis)
                        };
                        self.apply_moment(&mut f, *node, axis * (-k * measure));
                    }
                    Connection::FixedDirection { nodes, direction } => {
                        let [a, b] = *nodes;
                        let measure = if viscous {
                            direction.dot(&(self.velocity(at, u, b) - self.velocity(at, u, a)))
                        } else {
                            direction.dot(
                                &((self.position(at, b) - self.initial[b])
                                    - (self.position(at, a) - self.initial[a])),
                            )
                        };
                        let force = direction * (-k * measure);
                        self.apply(at, &mut f, b, force);
                        self.apply(at, &mut f, a, -force);
                    }
                    Connection::Axial { nodes } => {
                        let [a, b] = *nodes;
                        let line = self.position(at, b) - self.position(at, a);
                        let length = line.norm();
                        if length.is_nan() || length <= 0.0 {
                            return Err(EngineError::Failed(format!(
                                "reference: axial element `{}` has collapsed to zero length",
                                e.name
                            )));
                        }
                        let d = line / length;
                        let measure = if viscous {
                            d.dot(&(self.velocity(at, u, b) - self.velocity(at, u, a)))
                        } else {
                            length - (self.initial[b] - self.initial[a]).norm()
                        };
                        let force = d * (-k * measure);
                        self.apply(at, &mut f, b, force);
                        self.apply(at, &mut f, a, -force);
                    }
                }
            }
        }
        Ok(f)
    }

    /// Mass matrix on u and the velocity-dependent inertia terms (moved to the force side).
    fn inertia(&self, at: &Placement, u: &DVector<f64>) -> (DMatrix<f64>, DVector<f64>) {
        let n = self.velocity_len();
        let mut m = DMatrix::zeros(n, n);
        let mut q = DVector::zeros(n);
        for (i, mass) in self.particle_mass.iter().enumerate() {
            for a in 0..3 {
                m[(3 * i + a, 3 * i + a)] = *mass;
            }
        }
        let base = 3 * self.particles.len();
        for (b, body) in self.bodies.iter().enumerate() {
            let k = base + 6 * b;
            let r = at.orientations[b].to_rotation_matrix();
            let c = r * body.centre;
            let j = r.matrix() * body.inertia * r.matrix().transpose();
            let w = self.angular(u, b);
            m.view_mut((k, k), (3, 3))
                .copy_from(&(Matrix3::identity() * body.mass));
            m.view_mut((k, k + 3), (3, 3))
                .copy_from(&(-skew(&c) * body.mass));
            m.view_mut((k + 3, k), (3, 3))
                .copy_from(&(skew(&c) * body.mass));
            m.view_mut((k + 3, k + 3), (3, 3)).copy_from(&j);
            q.fixed_rows_mut::<3>(k)
                .copy_from(&(-w.cross(&w.cross(&c)) * body.mass));
            q.fixed_rows_mut::<3>(k + 3)
                .copy_from(&(-w.cross(&(j * w))));
        }
        (m, q)
    }

    /// Which contacts are closed at t = 0.
    pub fn initially_closed(&self) -> Vec<bool> {
        self.contacts.iter().map(|c| c.closed).collect()
    }

    /// Coefficient of restitution of contact `k`.
    pub fn restitution(&self, k: usize) -> f64 {
        self.contacts[k].restitution
    }

    /// Pair `k`'s signed distance from its node to its surface (negative: penetrating).
    pub fn distance(&self, at: &Placement, k: usize) -> f64 {
        let c = &self.contacts[k];
        let local =
            at.orientations[c.body].inverse() * (self.node_position(at, k) - at.origins[c.body]);
        surface_distance(&c.surface, &local).0 - c.slave.radius()
    }

    /// Each contact's gap above the level it closes at (negative: penetrating), the velocity
    /// rows G (on u) and Ġu of the closed (`active`) contacts: each one's normal row, in pair
    /// order, then the tangential rows of the stuck ones ([`Grip::Stick`]; `grips` empty: none).
    ///
    /// With s = Rᵀ(p − x) the node in the body frame and φ(s) the signed distance to the
    /// surface (closed-form geometry, less a ball's radius ρ), ġ = n·V with n = R ∇φ and V the
    /// relative velocity at the contact point ([`touch`]), for any surface; g̈ = G u̇ + Ġu adds
    /// to the plane's terms the surface's curvature, ṡᵀ H ṡ with H the Hessian of φ (a ball
    /// touches a plane only: H = 0).
    pub fn constraints(
        &self,
        at: &Placement,
        u: &DVector<f64>,
        active: &[bool],
        grips: &[Grip],
    ) -> (Vec<f64>, DMatrix<f64>, DVector<f64>) {
        let n = self.velocity_len();
        let normals = active.iter().filter(|a| **a).count();
        let rows = if self.frictional {
            normals + self.stick_rows(active, grips)
        } else {
            normals
        };
        let mut gaps = Vec::with_capacity(self.contacts.len());
        let mut g = DMatrix::zeros(rows, n);
        let mut gdot_u = DVector::zeros(rows);
        let mut row = 0;
        for (k, (c, closed)) in self.contacts.iter().zip(active).enumerate() {
            let rot = at.orientations[c.body];
            let local = rot.inverse() * (self.node_position(at, k) - at.origins[c.body]);
            let phi = surface_distance(&c.surface, &local).0;
            gaps.push(phi - c.slave.radius() - c.level);
            if !closed {
                continue;
            }
            let touch = self.touch(at, u, k);
            let normal = touch.normal();
            touch.add_row(&mut g, row, &normal);
            let sliding = rot.inverse() * touch.slip();
            gdot_u[row] =
                touch.rate(&normal) + sliding.dot(&(curvature(&c.surface, &local) * sliding));
            row += 1;
        }
        if rows > normals {
            self.add_stick_rows(at, u, (active, grips), &mut g, &mut gdot_u, normals);
        }
        (gaps, g, gdot_u)
    }

    /// Rate of contact `k`'s gap, n·V (V the relative velocity at the contact point).
    pub fn gap_rate(&self, at: &Placement, u: &DVector<f64>, k: usize) -> f64 {
        let touch = self.touch(at, u, k);
        touch.normal().dot(&touch.slip())
    }

    /// Accelerations of the free coordinates, contact forces and friction at a placement and
    /// velocity, with the closed pairs `active` and their `grips`, at time `t` (the loads'
    /// amplitudes there).
    pub fn evaluate(
        &self,
        at: &Placement,
        basis: &DMatrix<f64>,
        w: &DVector<f64>,
        active: &[bool],
        grips: &[Grip],
        t: f64,
    ) -> Result<Evaluation, EngineError> {
        if basis.ncols() == 0 {
            // Nothing is free to move: no acceleration, and a held node's contact force is a
            // reaction this model does not resolve (the closed pairs report none).
            return Ok(Evaluation {
                acceleration: DVector::zeros(0),
                contact: vec![0.0; active.len()],
                friction: if self.frictional {
                    vec![Vector3::zeros(); active.len()]
                } else {
                    Vec::new()
                },
                dissipation: 0.0,
            });
        }
        let u = basis * w;
        let (mass, inertial) = self.inertia(at, &u);
        let force = self.applied(at, &u, t)? + inertial;
        let (_, g, gdot_u) = self.constraints(at, &u, active, grips);
        let nf = basis.ncols();
        let nc = g.nrows();
        let mut kkt = DMatrix::zeros(nf + nc, nf + nc);
        let a = basis.transpose() * &mass * basis;
        let b = &g * basis;
        kkt.view_mut((0, 0), (nf, nf)).copy_from(&a);
        kkt.view_mut((0, nf), (nf, nc)).copy_from(&(-b.transpose()));
        kkt.view_mut((nf, 0), (nc, nf)).copy_from(&b);
        let slips = if self.frictional {
            self.slip_columns(at, &u, active, grips)
        } else {
            Vec::new()
        };
        for slip in &slips {
            // The normal force λ_n also pushes μ_k λ_n against the slip.
            let mut column = kkt.view_mut((0, nf + slip.row), (nf, 1));
            column += basis.transpose() * &slip.generalized * slip.mu;
        }
        let mut rhs = DVector::zeros(nf + nc);
        rhs.rows_mut(0, nf).copy_from(&(basis.transpose() * force));
        rhs.rows_mut(nf, nc).copy_from(&(-gdot_u));
        let solution = kkt.lu().solve(&rhs).ok_or_else(|| {
            EngineError::Unsupported(
                "reference: the mass matrix of the free DOFs (with the contact constraints) is \
                 singular: a free DOF without mass, or a contact that fixes nothing"
                    .into(),
            )
        })?;
        let normals = active.iter().filter(|a| **a).count();
        let normal_forces = solution.rows(nf, normals);
        let mut closed = normal_forces.iter().copied();
        let contact: Vec<f64> = active
            .iter()
            .map(|a| {
                if *a {
                    closed.next().unwrap_or(0.0)
                } else {
                    0.0
                }
            })
            .collect();
        let (friction, dissipation) = if self.frictional {
            let sticking = solution.rows(nf + normals, nc - normals);
            self.friction_forces(at, (active, grips), &contact, sticking.as_slice(), &slips)
        } else {
            (Vec::new(), 0.0)
        };
        Ok(Evaluation {
            acceleration: solution.rows(0, nf).into_owned(),
            contact,
            friction,
            dissipation,
        })
    }

    /// Rate of the positions from the full velocity: ṗ, ẋ = v, q̇ = ½ (0, ω) q.
    pub fn position_rate(&self, at: &Placement, u: &DVector<f64>, out: &mut [f64]) {
        let mut k = 0;
        for i in 0..self.particles.len() {
            out[k..k + 3].copy_from_slice(u.fixed_rows::<3>(3 * i).as_slice());
            k += 3;
        }
        let base = 3 * self.particles.len();
        for (b, q) in at.orientations.iter().enumerate() {
            let v = u.fixed_rows::<3>(base + 6 * b);
            let w = self.angular(u, b);
            out[k..k + 3].copy_from_slice(v.as_slice());
            let rate = Quaternion::from_imag(w) * q.quaternion() * 0.5;
            out[k + 3..k + 7].copy_from_slice(rate.as_vector().as_slice());
            k += 7;
        }
    }

    /// The full velocity of the scene's initial velocities (a body's from its reference node).
    pub fn initial_velocity(&self, scene: &Scene) -> DVector<f64> {
        let mut u = DVector::zeros(self.velocity_len());
        let base = 3 * self.particles.len();
        for iv in &scene.initial_velocities {
            match self.places[iv.node] {
                Place::Particle(i) => u.fixed_rows_mut::<3>(3 * i).copy_from(&iv.velocity),
                Place::Body(b, _) => {
                    u.fixed_rows_mut::<3>(base + 6 * b).copy_from(&iv.velocity);
                    u.fixed_rows_mut::<3>(base + 6 * b + 3)
                        .copy_from(&iv.angular);
                }
            }
        }
        u
    }

    /// The free velocity closest to u (in the kinetic-energy norm) that satisfies the closed
    /// contacts' constraints: the projection on T, then the impulse that makes ġ = 0 (and a
    /// stuck node's tangential relative velocity 0).
    pub fn admissible(
        &self,
        at: &Placement,
        basis: &DMatrix<f64>,
        u: &DVector<f64>,
        (active, grips): (&[bool], &[Grip]),
    ) -> Result<DVector<f64>, EngineError> {
        let w = basis.transpose() * u;
        self.impact(at, basis, &w, (active, grips), None)
    }

    /// The free velocity after an impact: the impulse along the closed contacts' rows that
    /// leaves their ġ = 0 and, for `striking = Some((k, e))`, turns contact k's approach rate
    /// ġ⁻ into −e ġ⁻ (Newton's law of restitution; k need not be closed). Frictionless, so the
    /// impulse acts along the normals only and the kinetic energy changes by the factor the
    /// law prescribes. A stuck pair's tangential rows are held too: with `striking` none, this
    /// is the projection that sticks a node (the solver strikes no pair while a pair with
    /// friction is closed: that impulse would need Coulomb's law).
    pub fn impact(
        &self,
        at: &Placement,
        basis: &DMatrix<f64>,
        w: &DVector<f64>,
        (active, grips): (&[bool], &[Grip]),
        striking: Option<(usize, f64)>,
    ) -> Result<DVector<f64>, EngineError> {
        let mut rows = active.to_vec();
        if let Some((k, _)) = striking {
            rows[k] = true;
        }
        if !rows.iter().any(|r| *r) || basis.ncols() == 0 {
            return Ok(w.clone());
        }
        let full = basis * w;
        let (mass, _) = self.inertia(at, &full);
        let (_, g, _) = self.constraints(at, &full, &rows, grips);
        let a = basis.transpose() * mass * basis;
        let b = g * basis;
        let singular =
            || EngineError::Unsupported("reference: singular mass or constraint matrix".into());
        let a_inv = a.try_inverse().ok_or_else(singular)?;
        let s = &b * &a_inv * b.transpose();
        let rate = &b * w;
        let mut target = DVector::zeros(rate.len());
        if let Some((k, e)) = striking {
            let row = rows[..k].iter().filter(|r| **r).count();
            target[row] = -e * rate[row];
        }
        let impulse = s.lu().solve(&(rate - target)).ok_or_else(singular)?;
        Ok(w - a_inv * b.transpose() * impulse)
    }
}

/// Set row `row` of G to direction `e` at a pair's node (u's columns `particle` for ṗ and
/// `body` for the body's v and ω): the row of e·(ṗ − v − ω × (p − x)), `arm` = p − x.
fn add_row(
    g: &mut DMatrix<f64>,
    row: usize,
    e: &Vector3<f64>,
    arm: &Vector3<f64>,
    particle: usize,
    body: usize,
) {
    let moment = arm.cross(e);
    for a in 0..3 {
        g[(row, particle + a)] += e[a];
        g[(row, body + a)] -= e[a];
        g[(row, body + 3 + a)] -= moment[a];
    }
}

/// The velocity terms of d/dt [e·(ṗ − v − ω × (p − x))] for a direction e that turns with the
/// body (ė = ω × e): (ω × e)·(ṗ − v) − ω·((ṗ − v) × e + (p − x) × (ω × e)), `relative` =
/// ṗ − v.
fn row_rate(
    e: &Vector3<f64>,
    w: &Vector3<f64>,
    relative: &Vector3<f64>,
    arm: &Vector3<f64>,
) -> f64 {
    let we = w.cross(e);
    we.dot(relative) - w.dot(&(relative.cross(e) + arm.cross(&we)))
}

/// Hessian of a surface's signed distance at `s` (body frame, relative to the reference
/// node): zero on a plane and on a cuboid's or polytope's faces; (P − n nᵀ)/ρ at distance ρ
/// from a ball's centre, a capsule's axis or a cuboid's or polytope's edge or corner, P
/// projecting out the directions along which the nearest feature extends.
fn curvature(surface: &Surface, s: &Vector3<f64>) -> Matrix3<f64> {
    let Surface::Solid { solid, centre } = surface else {
        return Matrix3::zeros();
    };
    let s = s - centre;
    let round = |d: Vector3<f64>, extends: Matrix3<f64>| {
        let rho = d.norm();
        if rho == 0.0 {
            return Matrix3::zeros();
        }
        let n = d / rho;
        (Matrix3::identity() - extends - n * n.transpose()) / rho
    };
    match *solid {
        Solid::Convex { ref polytope } => {
            let (gap, normal, feature) = polytope.distance(&s);
            if gap <= 0.0 {
                return Matrix3::zeros();
            }
            round(normal * gap, polytope.extends(feature))
        }
        Solid::Ball { .. } => round(s, Matrix3::zeros()),
        Solid::Capsule { half_height, .. } => {
            let along = if s.y.abs() < half_height {
                Matrix3::from_diagonal(&Vector3::y())
            } else {
                Matrix3::zeros()
            };
            round(
                s - Vector3::new(0.0, s.y.clamp(-half_height, half_height), 0.0),
                along,
            )
        }
        Solid::Cuboid { half_extents: h } => {
            let outside = Vector3::from_fn(|i, _| s[i].abs() > h[i] && h[i] > 0.0);
            if !outside.iter().any(|o| *o) {
                return Matrix3::zeros();
            }
            let d = Vector3::from_fn(|i, _| {
                if outside[i] {
                    s[i] - s[i].signum() * h[i]
                } else {
                    0.0
                }
            });
            let extends =
                Matrix3::from_diagonal(&Vector3::from_fn(
                    |i, _| {
                        if outside[i] { 0.0 } else { 1.0 }
                    },
                ));
            round(d, extends)
        }
    }
}
