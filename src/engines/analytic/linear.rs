//! A general exact solver for linear scenes without contact: particles, springs and dashpots of
//! the three kinds, constant point loads and rigid bodies under small rotation, in 2D and 3D.
//!
//! It is written from the equations of motion, independently of the central-difference engine, so that
//! the two cross-check each other on every linear scene (and the hand-derived forms of
//! [`super::springs`] cross-check this one).
//!
//! # Model
//!
//! The linearised (small-rotation) model: a body point at offset ρ from the body's reference
//! node O (at t = 0) displaces by u_O + θ × ρ, with θ the body's rotation vector; every frame
//! axis, element direction and load keeps its initial orientation, and an axial element acts
//! along the initial line joining its nodes.
//!
//! # Generalised coordinates
//!
//! A node is *ground* if it is free, massless and held (or prescribed to 0) in every
//! translation in every step; it carries no coordinates and never moves. The coordinates q are
//!
//! - for each other free node (a particle): its displacement along each translational frame
//!   axis e₀, e₁ (, e₂);
//! - for each body: the displacements of its reference node along its frame axes and its
//!   rotations about the frame axes a (2D: one, about z; 3D: three).
//!
//! A body's material points carry no coordinates. The displacement of any node is u = J q
//! (J is 3 × n): a particle's columns are its frame axes; for a body point at ρ the translation
//! columns are the reference node's frame axes e and the rotation column of axis a is a × ρ;
//! a ground node has J = 0. The body's rotation vector is θ = R q, R having the column a for
//! each rotation coordinate.
//!
//! # Equations
//!
//! The kinetic energy of a body of mass m, centre of mass at c from O and inertia I_O about O
//! is ½ [u̇_O; θ̇]ᵀ M_b [u̇_O; θ̇] with M_b = [[m 1, −m[c]×], [m[c]×, I_O]] (since
//! Σ mᵢ u̇·(θ̇ × ρᵢ) = u̇ᵀ(−m[c]×)θ̇); that of a particle is ½ m |J q̇|². Hence
//!
//!   M q̈ + C q̇ + K q = Q,
//!   M = Σ_particles m JᵀJ + Σ_bodies [T; R]ᵀ M_b [T; R]   (T: the reference node's J),
//!   K = Σ_springs k gᵀg,   C = Σ_dashpots c gᵀg,   Q = Σ_loads J_Pᵀ F,
//!
//! where g (1 × n) is the element's elongation per unit q:
//!
//! - fixed-direction and axial elements between A and B: g = dᵀ(J_B − J_A), d the (initial)
//!   unit direction;
//! - grounded on a translation: g = eᵀJ_node with e the node's frame axis;
//! - grounded on a rotation of a reference node: g = aᵀR with a the frame axis.
//!
//! # Steps
//!
//! Steps are taken in order from q = 0, q̇ = 0.
//!
//! - Static (takes no time): the DOFs the step holds keep their values, the prescribed ones
//!   are set to their value (a displacement along that frame axis from t = 0), and the rest
//!   solve K_ff q_f = Q_f − K_fp q_p (a singular K_ff is an error). Velocities are untouched.
//! - Dynamic: the scene's initial velocities (translational and, at a reference node, angular)
//!   are projected on the coordinates at the start of the first dynamic step; the held DOFs
//!   are frozen (q̇_h = 0) and the free ones obey M_ff q̈_f + C_ff q̇_f + K_ff q_f =
//!   Q_f − K_fh q_h. With the augmented state s = (q_f, q̇_f, 1) this is ṡ = A s,
//!
//!   A = [[0, 1, 0], [−M_ff⁻¹K_ff, −M_ff⁻¹C_ff, M_ff⁻¹(Q_f − K_fh q_h)], [0, 0, 0]],
//!
//!   solved exactly as s(t) = exp(A (t − t₀)) s(t₀) from the step's start t₀ for each output
//!   time in the step. Output times run over the dynamic steps only; a time on the boundary of
//!   two steps is reported by the later one (after its held velocities are zeroed).
//!
//! # Output
//!
//! `t`, every column of the scene in order, and `valid` (always 1: the model has no validity
//! window of its own). Displacement = direction·(J q), velocity = direction·(J q̇),
//! rotation = axis·(R q), zero = 0. Contact (pairs or contact-force columns), a free DOF without
//! mass in a dynamic step and a singular mass matrix are not supported.

use super::{columns_history, exponential_states, unsupported};
use crate::engines::{EngineError, History};
use crate::scene::{
    Attachment, BodyId, Connection, Dimension, Dof, Element, NodeId, Probe, Scene, Step, StepKind,
};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, RowDVector, Vector3};

/// The coordinate layout of a scene and the kinematic maps q ↦ u, q ↦ θ.
struct Layout<'a> {
    scene: &'a Scene,
    /// Translational components per node (2 or 3).
    translations: usize,
    /// Frame axes a body rotates about (2D: z only).
    rotation_axes: &'static [usize],
    /// First coordinate of each node that carries coordinates.
    start: Vec<Option<usize>>,
    /// Each coordinate's node and DOF.
    dofs: Vec<(NodeId, Dof)>,
}

impl<'a> Layout<'a> {
    fn new(scene: &'a Scene) -> Layout<'a> {
        let translations = scene.dimension.count();
        let rotation_axes: &'static [usize] = match scene.dimension {
            Dimension::Two => &[2],
            Dimension::Three => &[0, 1, 2],
        };
        let mut start = vec![None; scene.nodes.len()];
        let mut dofs = Vec::new();
        for (id, node) in scene.nodes.iter().enumerate() {
            let rotations = match node.attachment {
                Attachment::OnBody(_) => continue,
                Attachment::Free if is_ground(scene, id) => continue,
                Attachment::Free => false,
                Attachment::Reference(_) => true,
            };
            start[id] = Some(dofs.len());
            dofs.extend((0..translations).map(|i| (id, Dof::Translation(i))));
            if rotations {
                dofs.extend(rotation_axes.iter().map(|&a| (id, Dof::Rotation(a))));
            }
        }
        Layout {
            scene,
            translations,
            rotation_axes,
            start,
            dofs,
        }
    }

    fn len(&self) -> usize {
        self.dofs.len()
    }

    /// The coordinate of a nodal DOF (`None` for a ground node).
    fn index(&self, node: NodeId, dof: Dof) -> Option<usize> {
        let s = self.start[node]?;
        Some(match dof {
            Dof::Translation(i) if i < self.translations => s + i,
            Dof::Translation(_) => return None,
            Dof::Rotation(a) => {
                // Only a body's reference node has rotations.
                if !matches!(self.scene.nodes[node].attachment, Attachment::Reference(_)) {
                    return None;
                }
                s + self.translations + self.rotation_axes.iter().position(|&x| x == a)?
            }
        })
    }

    /// J: the displacement of a node per unit q (3 × n).
    fn point(&self, node: NodeId) -> DMatrix<f64> {
        let mut j = DMatrix::zeros(3, self.len());
        let n = &self.scene.nodes[node];
        match n.attachment {
            Attachment::Free => {
                if let Some(s) = self.start[node] {
                    for i in 0..self.translations {
                        j.column_mut(s + i).copy_from(&n.frame.column(i));
                    }
                }
            }
            Attachment::Reference(b) | Attachment::OnBody(b) => {
                let o = self.scene.bodies[b].reference;
                let origin = &self.scene.nodes[o];
                let rho = n.position - origin.position;
                let s = self.start[o].expect("a reference node carries coordinates");
                for i in 0..self.translations {
                    j.column_mut(s + i).copy_from(&origin.frame.column(i));
                }
                for (k, &a) in self.rotation_axes.iter().enumerate() {
                    let axis: Vector3<f64> = origin.frame.column(a).into_owned();
                    j.column_mut(s + self.translations + k)
                        .copy_from(&axis.cross(&rho));
                }
            }
        }
        j
    }

    /// R: the rotation vector of a body per unit q (3 × n).
    fn rotation(&self, body: BodyId) -> DMatrix<f64> {
        let mut r = DMatrix::zeros(3, self.len());
        let o = self.scene.bodies[body].reference;
        let s = self.start[o].expect("a reference node carries coordinates");
        for (k, &a) in self.rotation_axes.iter().enumerate() {
            r.column_mut(s + self.translations + k)
                .copy_from(&self.scene.nodes[o].frame.column(a));
        }
        r
    }

    /// g: an element's elongation per unit q (1 × n).
    fn elongation(&self, e: &Element) -> RowDVector<f64> {
        let nodes = &self.scene.nodes;
        let (j, d) = match &e.connection {
            Connection::Grounded {
                node,
                dof: Dof::Translation(i),
            } => (
                self.point(*node),
                nodes[*node].frame.column(*i).into_owned(),
            ),
            Connection::Grounded {
                node,
                dof: Dof::Rotation(a),
            } => {
                let Attachment::Reference(b) = nodes[*node].attachment else {
                    unreachable!("the scene allows rotational DOFs at reference nodes only")
                };
                (self.rotation(b), nodes[*node].frame.column(*a).into_owned())
            }
            Connection::FixedDirection {
                nodes: [a, b],
                direction,
            } => (self.point(*b) - self.point(*a), *direction),
            Connection::Axial { nodes: [a, b] } => (
                self.point(*b) - self.point(*a),
                (nodes[*b].position - nodes[*a].position).normalize(),
            ),
        };
        d.transpose() * j
    }

    /// "ux of node `N`", for messages.
    fn describe(&self, k: usize) -> String {
        let (node, dof) = self.dofs[k];
        format!("{dof} of node `{}`", self.scene.nodes[node].name)
    }
}

/// A probe as a linear map: (J or R, the direction it is read along, whether it reads q̇).
type ProbeMap = (DMatrix<f64>, Vector3<f64>, bool);

/// Free, massless and held (or prescribed to 0) in every translation in every step.
fn is_ground(scene: &Scene, node: NodeId) -> bool {
    scene.nodes[node].attachment == Attachment::Free
        && scene.nodes[node].mass == 0.0
        && scene.steps.iter().all(|step| {
            Dof::all(scene.dimension, false).into_iter().all(|dof| {
                step.conditions
                    .iter()
                    .any(|c| c.node == node && c.dof == dof && c.value.unwrap_or(0.0) == 0.0)
            })
        })
}

/// The rows and columns `rows` × `cols` of a matrix.
fn pick(m: &DMatrix<f64>, rows: &[usize], cols: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), cols.len(), |i, j| m[(rows[i], cols[j])])
}

/// The entries `rows` of a vector.
fn pick_vec(v: &DVector<f64>, rows: &[usize]) -> DVector<f64> {
    DVector::from_fn(rows.len(), |i, _| v[rows[i]])
}

/// The cross-product matrix [c]×.
fn skew(c: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -c.z, c.y, c.z, 0.0, -c.x, -c.y, c.x, 0.0)
}

/// Whether a symmetric positive semi-definite matrix is singular (smallest eigenvalue at
/// round-off of the largest).
fn singular(m: &DMatrix<f64>) -> bool {
    let e = m.clone().symmetric_eigenvalues();
    let max = e.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let min = e.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    !(max > 0.0 && min > 1e-12 * max)
}

/// The held (`true`) coordinates of a step and the prescribed values.
fn conditions(layout: &Layout, step: &Step) -> (Vec<bool>, Vec<(usize, f64)>) {
    let mut held = vec![false; layout.len()];
    let mut prescribed = Vec::new();
    for c in &step.conditions {
        if let Some(k) = layout.index(c.node, c.dof) {
            held[k] = true;
            if let Some(v) = c.value {
                prescribed.push((k, v));
            }
        }
    }
    (held, prescribed)
}

/// Solve a linear scene without contact exactly: the equations assembled once, the steps taken
/// in order (a static one solved for its equilibrium, a dynamic one by the exponential of its
/// state matrix at each output time it reports), then the probes read at every output time.
pub fn solve(scene: &Scene) -> Result<History, EngineError> {
    if !scene.contacts.is_empty() {
        return unsupported("the linear solver does not do contact");
    }
    if let Some(c) = scene
        .columns
        .iter()
        .find(|c| matches!(c.probe, Probe::ContactForce { .. } | Probe::Gap { .. }))
    {
        return unsupported(format!(
            "column `{}`: the linear solver does not do contact",
            c.name
        ));
    }
    let layout = Layout::new(scene);
    let equations = Equations::assemble(scene, &layout);
    let mut motion = Motion::new(scene, &layout, &equations);
    for step in &scene.steps {
        let (held, prescribed) = conditions(&layout, step);
        match step.kind {
            StepKind::Static => motion.equilibrium(&held, &prescribed)?,
            StepKind::Dynamic { duration } => motion.dynamic(&held, duration)?,
        }
    }
    Ok(motion.history())
}

/// M q̈ + C q̇ + K q = Q over every coordinate, and the initial velocities projected on them.
struct Equations {
    mass: DMatrix<f64>,
    stiffness: DMatrix<f64>,
    damping: DMatrix<f64>,
    load: DVector<f64>,
    v_initial: DVector<f64>,
}

impl Equations {
    fn assemble(scene: &Scene, layout: &Layout) -> Self {
        let n = layout.len();
        let mut stiffness = DMatrix::zeros(n, n);
        let mut damping = DMatrix::zeros(n, n);
        for (list, target) in [
            (&scene.springs, &mut stiffness),
            (&scene.dashpots, &mut damping),
        ] {
            for e in list {
                let g = layout.elongation(e);
                *target += g.transpose() * g * e.coefficient;
            }
        }
        let mut load = DVector::zeros(n);
        for l in &scene.loads {
            load += layout.point(l.node).transpose() * l.force;
        }
        Equations {
            mass: mass_matrix(scene, layout),
            stiffness,
            damping,
            load,
            v_initial: initial_velocity(scene, layout),
        }
    }

    /// Q_f − K_fh q_h: the loads on the free coordinates less the held ones' spring forces.
    fn free_force(&self, q: &DVector<f64>, free: &[usize], fixed: &[usize]) -> DVector<f64> {
        pick_vec(&self.load, free) - pick(&self.stiffness, free, fixed) * pick_vec(q, fixed)
    }
}

/// M = Σ_particles m JᵀJ + Σ_bodies [T; R]ᵀ M_b [T; R].
fn mass_matrix(scene: &Scene, layout: &Layout) -> DMatrix<f64> {
    let n = layout.len();
    let mut mass = DMatrix::zeros(n, n);
    for (id, node) in scene.nodes.iter().enumerate() {
        if node.attachment == Attachment::Free && node.mass > 0.0 {
            let j = layout.point(id);
            mass += j.transpose() * j * node.mass;
        }
    }
    for (b, body) in scene.bodies.iter().enumerate() {
        let mut tr = DMatrix::zeros(6, n);
        tr.rows_mut(0, 3).copy_from(&layout.point(body.reference));
        tr.rows_mut(3, 3).copy_from(&layout.rotation(b));
        let mc = skew(&body.centre_offset) * body.mass;
        let mut mb = Matrix6::zeros();
        mb.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * body.mass));
        mb.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-mc));
        mb.fixed_view_mut::<3, 3>(3, 0).copy_from(&mc);
        mb.fixed_view_mut::<3, 3>(3, 3).copy_from(&body.inertia);
        let mb = DMatrix::from_iterator(6, 6, mb.iter().copied());
        mass += tr.transpose() * mb * tr;
    }
    mass
}

/// The scene's initial velocities (translational and, at a reference node, angular) projected
/// on the coordinates.
fn initial_velocity(scene: &Scene, layout: &Layout) -> DVector<f64> {
    let mut v_initial = DVector::zeros(layout.len());
    for iv in &scene.initial_velocities {
        let frame = scene.nodes[iv.node].frame;
        for i in 0..layout.translations {
            if let Some(k) = layout.index(iv.node, Dof::Translation(i)) {
                v_initial[k] = frame.column(i).dot(&iv.velocity);
            }
        }
        for &a in layout.rotation_axes {
            if let Some(k) = layout.index(iv.node, Dof::Rotation(a)) {
                v_initial[k] = frame.column(a).dot(&iv.angular);
            }
        }
    }
    v_initial
}

/// The coordinates and their rates through the steps, and the state at every output time.
struct Motion<'a> {
    scene: &'a Scene,
    layout: &'a Layout<'a>,
    eq: &'a Equations,
    times: Vec<f64>,
    /// Each dynamic step's start time.
    starts: Vec<f64>,
    /// The dynamic step that reports each output time: the last starting at or before it.
    owner: Vec<usize>,
    q: DVector<f64>,
    qd: DVector<f64>,
    states: Vec<Option<(DVector<f64>, DVector<f64>)>>,
    dynamic_index: usize,
}

impl<'a> Motion<'a> {
    fn new(scene: &'a Scene, layout: &'a Layout<'a>, eq: &'a Equations) -> Self {
        let times = scene.output_times();
        let tol = 1e-12 * scene.duration().max(f64::MIN_POSITIVE);
        let mut starts = Vec::new();
        let mut t0 = 0.0;
        for step in &scene.steps {
            if let StepKind::Dynamic { duration } = step.kind {
                starts.push(t0);
                t0 += duration;
            }
        }
        let owner: Vec<usize> = times
            .iter()
            .map(|&t| starts.iter().rposition(|&s| s <= t + tol).unwrap_or(0))
            .collect();
        let n = layout.len();
        Motion {
            scene,
            layout,
            eq,
            states: vec![None; times.len()],
            times,
            starts,
            owner,
            q: DVector::zeros(n),
            qd: DVector::zeros(n),
            dynamic_index: 0,
        }
    }

    /// A static step: the prescribed DOFs set, the free ones solved from K_ff q_f = Q_f − K_fp
    /// q_p (velocities untouched).
    fn equilibrium(
        &mut self,
        held: &[bool],
        prescribed: &[(usize, f64)],
    ) -> Result<(), EngineError> {
        let n = self.layout.len();
        let free: Vec<usize> = (0..n).filter(|&k| !held[k]).collect();
        let fixed: Vec<usize> = (0..n).filter(|&k| held[k]).collect();
        for &(k, v) in prescribed {
            self.q[k] = v;
        }
        if free.is_empty() {
            return Ok(());
        }
        let kff = pick(&self.eq.stiffness, &free, &free);
        if singular(&kff) {
            return unsupported(
                "static step: the free DOFs are not restrained (singular stiffness)",
            );
        }
        let rhs = self.eq.free_force(&self.q, &free, &fixed);
        let qf = kff.lu().solve(&rhs).ok_or_else(|| {
            EngineError::Unsupported("analytic: static step: singular stiffness".into())
        })?;
        for (i, &k) in free.iter().enumerate() {
            self.q[k] = qf[i];
        }
        Ok(())
    }

    /// A dynamic step of `duration`: the held DOFs frozen, the free ones by the exponential of
    /// the augmented state matrix, at each output time the step reports and at its end.
    fn dynamic(&mut self, held: &[bool], duration: f64) -> Result<(), EngineError> {
        let n = self.layout.len();
        let free: Vec<usize> = (0..n).filter(|&k| !held[k]).collect();
        let fixed: Vec<usize> = (0..n).filter(|&k| held[k]).collect();
        if self.dynamic_index == 0 {
            self.qd.copy_from(&self.eq.v_initial);
        }
        for &k in &fixed {
            self.qd[k] = 0.0;
        }
        let here: Vec<usize> = (0..self.times.len())
            .filter(|&i| self.owner[i] == self.dynamic_index)
            .collect();
        let start = self.starts[self.dynamic_index];
        self.dynamic_index += 1;
        let nf = free.len();
        if nf == 0 {
            for &i in &here {
                self.states[i] = Some((self.q.clone(), self.qd.clone()));
            }
            return Ok(());
        }
        let a = self.state_matrix(&free, &fixed)?;
        let mut s0 = DVector::zeros(2 * nf + 1);
        for (i, &k) in free.iter().enumerate() {
            s0[i] = self.q[k];
            s0[nf + i] = self.qd[k];
        }
        s0[2 * nf] = 1.0;
        // Each output time from the step's start, then the step's end (the next step's start).
        let offsets: Vec<f64> = here
            .iter()
            .map(|&i| self.times[i] - start)
            .chain(std::iter::once(duration))
            .collect();
        let solved = exponential_states(&a, &s0, &offsets)?;
        let expand = |s: &DVector<f64>| {
            let (mut qq, mut vv) = (self.q.clone(), self.qd.clone());
            for (i, &k) in free.iter().enumerate() {
                qq[k] = s[i];
                vv[k] = s[nf + i];
            }
            (qq, vv)
        };
        let at_times: Vec<_> = here
            .iter()
            .zip(&solved)
            .map(|(&i, s)| (i, expand(s)))
            .collect();
        let end = expand(solved.last().expect("the end state"));
        for (i, state) in at_times {
            self.states[i] = Some(state);
        }
        (self.q, self.qd) = end;
        Ok(())
    }

    /// A = [[0, 1, 0], [−M_ff⁻¹K_ff, −M_ff⁻¹C_ff, M_ff⁻¹(Q_f − K_fh q_h)], [0, 0, 0]]; a free
    /// DOF without mass, or a singular mass matrix, is refused.
    fn state_matrix(&self, free: &[usize], fixed: &[usize]) -> Result<DMatrix<f64>, EngineError> {
        let (eq, nf) = (self.eq, free.len());
        let mff = pick(&eq.mass, free, free);
        if let Some(k) = free.iter().find(|&&k| eq.mass[(k, k)] <= 0.0) {
            return unsupported(format!(
                "{} is free in a dynamic step but has no mass",
                self.layout.describe(*k)
            ));
        }
        if singular(&mff) {
            return unsupported("singular mass matrix");
        }
        let chol = mff.cholesky().ok_or_else(|| {
            EngineError::Unsupported("analytic: the mass matrix is not positive definite".into())
        })?;
        let force = eq.free_force(&self.q, free, fixed);
        let mut a = DMatrix::zeros(2 * nf + 1, 2 * nf + 1);
        a.view_mut((0, nf), (nf, nf)).fill_with_identity();
        a.view_mut((nf, 0), (nf, nf))
            .copy_from(&-chol.solve(&pick(&eq.stiffness, free, free)));
        a.view_mut((nf, nf), (nf, nf))
            .copy_from(&-chol.solve(&pick(&eq.damping, free, free)));
        a.view_mut((nf, 2 * nf), (nf, 1))
            .copy_from(&chol.solve(&force));
        Ok(a)
    }

    /// The history: each probe read from the state at every output time.
    fn history(self) -> History {
        let (scene, layout) = (self.scene, self.layout);
        let maps: Vec<Option<ProbeMap>> = scene
            .columns
            .iter()
            .map(|c| match &c.probe {
                Probe::Displacement { node, direction } => {
                    Some((layout.point(*node), *direction, false))
                }
                Probe::Velocity { node, direction } => {
                    Some((layout.point(*node), *direction, true))
                }
                Probe::Rotation { body, axis } => Some((layout.rotation(*body), *axis, false)),
                Probe::Zero { .. } | Probe::ContactForce { .. } | Probe::Gap { .. } => None,
            })
            .collect();
        columns_history(scene, &self.times, |i, _| {
            let (q, qd) =
                (self.states[i].as_ref()).expect("every output time lies in a dynamic step");
            (maps.iter())
                .map(|m| match m {
                    Some((j, d, velocity)) => {
                        let u = j * if *velocity { qd } else { q };
                        d.dot(&Vector3::new(u[0], u[1], u[2]))
                    }
                    None => 0.0,
                })
                .collect()
        })
    }
}
