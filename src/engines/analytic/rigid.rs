//! The rigid body with an attached spring, a contact spring and a point load: the benchmark's
//! small-rotation model with rigid, persistent contact.
//!
//! Planar motion of the reference node O: q = (u_x, u_y, θ), the held ones removed. A body point
//! at r from O moves by J(r) q with J(r) = [[1, 0, −r_y], [0, 1, r_x]]. The contact node N is
//! slaved to the face point it touches: its normal displacement equals that of the face point,
//! n·u_N = n·J(r_N) q, and it moves along its one free direction e, so
//! u_N = e (nᵀ J(r_N) q)/(n·e) = J_N q. Lagrange's equations give
//!
//!   M q̈ + C q̇ + K q = Q,
//!   M = M_body + m_N J_Nᵀ J_N,   M_body = [[m, 0, −m c_y], [0, m, m c_x], [−m c_y, m c_x, I_O]],
//!   K = Σ k gᵀg, C = Σ c gᵀg with g = dᵀ(J_B − J_A) for an element along d between A and B,
//!   Q = Σ J_Pᵀ F for the loads,
//!
//! solved exactly as s(t) = exp(A t) s0 with the augmented state s = (q, q̇, 1). The contact
//! force follows from the node's own equation along e:
//! λ (n·e) = m_N e·ü_N − e·F_N (F_N: the element forces on N), compressive positive. The model is
//! valid while λ ≥ 0; rows after the first tensile λ are marked invalid.

use super::{exponential_states, history, unsupported};
use crate::engines::{EngineError, History};
use crate::scene::{
    Attachment, Connection, ContactState, Dimension, Dof, Element, NodeId, Probe, RigidBody, Scene,
    StepKind,
};
use nalgebra::{DMatrix, DVector, Matrix2x3, RowVector3, Vector2, Vector3};

/// The closed form's answer and what it says about its own validity.
#[derive(Debug, Clone)]
pub struct RigidSolution {
    /// Contract columns and `valid`.
    pub history: History,
    /// Contact force at t = 0 (compressive positive).
    pub initial_contact_force: f64,
    /// Smallest contact force over the valid rows divided by the largest.
    pub contact_margin: f64,
    /// First time the contact force turns tensile, if it does.
    pub valid_until: Option<f64>,
}

/// An element's elongation gradient g = ∂e/∂q and, if it touches the contact node, the sign
/// and direction of its force there per unit coefficient × elongation.
struct ElementRow {
    g: RowVector3<f64>,
    at_node: Option<(f64, Vector2<f64>)>,
}

fn planar(v: &Vector3<f64>) -> Vector2<f64> {
    Vector2::new(v.x, v.y)
}

fn jacobian(r: &Vector2<f64>) -> Matrix2x3<f64> {
    Matrix2x3::new(1.0, 0.0, -r.y, 0.0, 1.0, r.x)
}

/// Solve a rigid-body-family scene: the form's assumptions checked and its kinematics set up,
/// the equations of motion assembled and reduced to the free coordinates, solved exactly, and
/// the contact force's sign judged row by row.
pub fn solve(scene: &Scene) -> Result<RigidSolution, EngineError> {
    let kinematics = Kinematics::of(scene)?;
    let equations = Equations::assemble(&kinematics, &scene.bodies[0])?;
    let reduced = Reduced::of(&equations, &kinematics.free)?;
    let times = scene.output_times();
    let states = exponential_states(
        &reduced.state_matrix(),
        &reduced.initial_state(&equations.v0),
        &times,
    )?;
    let mut rows = Vec::with_capacity(times.len());
    let mut forces = Vec::with_capacity(times.len());
    for s in &states {
        let (row, lambda) = kinematics.row(&equations, &reduced, s)?;
        rows.push(row);
        forces.push(lambda);
    }
    Ok(judged(scene, &times, rows, &forces))
}

/// The form's kinematics: the reference node O, the free coordinates among (u_x, u_y, θ), and
/// the contact node N slaved to the face along its one free direction e.
struct Kinematics<'a> {
    scene: &'a Scene,
    /// O's position.
    origin: Vector3<f64>,
    /// The free coordinates' indices among (u_x, u_y, θ).
    free: Vec<usize>,
    /// The contact node N.
    node: NodeId,
    /// N's one free direction e.
    e: Vector2<f64>,
    /// The face's normal n.
    n: Vector2<f64>,
    /// N's Jacobian J_N: u_N = J_N q.
    j_node: Matrix2x3<f64>,
}

impl<'a> Kinematics<'a> {
    /// The form's assumptions checked (one body, one closed planar contact, one dynamic step,
    /// planar motion, global DOFs at O, a contact node moving along one direction not tangent
    /// to the face) and its kinematics set up.
    fn of(scene: &'a Scene) -> Result<Self, EngineError> {
        let [body] = scene.bodies.as_slice() else {
            return unsupported("the rigid-contact form has exactly one body");
        };
        let [contact] = scene.contacts.as_slice() else {
            return unsupported("the rigid-contact form has exactly one contact pair");
        };
        let [step] = scene.steps.as_slice() else {
            return unsupported("the rigid-contact form has one dynamic step");
        };
        if step.kind == StepKind::Static {
            return unsupported("the rigid-contact form has one dynamic step");
        }
        let held = |node: NodeId, dof: Dof| {
            step.conditions
                .iter()
                .any(|c| c.node == node && c.dof == dof)
        };
        let o = body.reference;
        let origin = scene.nodes[o].position;
        if scene.dimension == Dimension::Three {
            let out_of_plane = [Dof::Translation(2), Dof::Rotation(0), Dof::Rotation(1)];
            if !out_of_plane.iter().all(|d| held(o, *d)) || !held(contact.node, Dof::Translation(2))
            {
                return unsupported(
                    "3D motion must be planar (uz, rx, ry of the body and uz of the node held)",
                );
            }
        }
        if scene.nodes[o].frame != nalgebra::Matrix3::identity() {
            return unsupported("the reference node's DOFs must be global");
        }
        // Free generalised coordinates among (u_x, u_y, θ).
        let all = [Dof::Translation(0), Dof::Translation(1), Dof::Rotation(2)];
        let free: Vec<usize> = (0..3).filter(|&i| !held(o, all[i])).collect();

        // The contact node and its one free direction.
        let node = contact.node;
        let node_free: Vec<Vector2<f64>> = [0, 1]
            .into_iter()
            .filter(|&k| !held(node, Dof::Translation(k)))
            .map(|k| planar(&scene.nodes[node].frame.column(k).into_owned()))
            .collect();
        let [e] = node_free.as_slice() else {
            return unsupported("the contact node must move along exactly one direction");
        };
        let Some((_, face_normal)) = contact.plane() else {
            return unsupported("the rigid-contact form has a planar face");
        };
        if contact.initially == ContactState::Open {
            return unsupported("the rigid-contact form keeps the contact closed from t = 0");
        }
        let n = planar(&face_normal);
        if n.dot(e).abs() < 1e-9 {
            return unsupported("the contact node's direction is tangent to the face");
        }
        let r_contact = planar(&(scene.nodes[node].position - origin));
        let j_node: Matrix2x3<f64> = e * (n.transpose() * jacobian(&r_contact)) / n.dot(e);
        Ok(Kinematics {
            scene,
            origin,
            free,
            node,
            e: *e,
            n,
            j_node,
        })
    }

    /// The Jacobian of a point's displacement in q.
    fn point(&self, node: NodeId) -> Result<Matrix2x3<f64>, EngineError> {
        let scene = self.scene;
        match scene.nodes[node].attachment {
            Attachment::Reference(_) | Attachment::OnBody(_) => Ok(jacobian(&planar(
                &(scene.nodes[node].position - self.origin),
            ))),
            Attachment::Free if node == self.node => Ok(self.j_node),
            Attachment::Free if scene.nodes[node].mass == 0.0 => Ok(Matrix2x3::zeros()),
            Attachment::Free => unsupported(format!(
                "free node `{}` other than the contact node",
                scene.nodes[node].name
            )),
        }
    }

    /// g = ∂(elongation)/∂q for an element, and the direction it acts along at the node (if
    /// any).
    fn element(&self, e: &Element) -> Result<ElementRow, EngineError> {
        let scene = self.scene;
        let (a, b, d) = match &e.connection {
            Connection::Grounded {
                node,
                dof: Dof::Translation(k),
            } => (
                None,
                *node,
                planar(&scene.nodes[*node].frame.column(*k).into_owned()),
            ),
            Connection::Grounded { .. } => return unsupported("rotational springs"),
            Connection::FixedDirection { nodes, direction } => {
                (Some(nodes[0]), nodes[1], planar(direction))
            }
            Connection::Axial { nodes } => {
                let d = planar(&(scene.nodes[nodes[1]].position - scene.nodes[nodes[0]].position));
                (Some(nodes[0]), nodes[1], d.normalize())
            }
        };
        let jb = self.point(b)?;
        let ja = match a {
            Some(a) => self.point(a)?,
            None => Matrix2x3::zeros(),
        };
        let g = d.transpose() * (jb - ja);
        // Force on the node per unit (coefficient × elongation): −d at end B, +d at end A.
        let at_node = if b == self.node {
            Some((-1.0, d))
        } else if a == Some(self.node) {
            Some((1.0, d))
        } else {
            None
        };
        Ok(ElementRow { g, at_node })
    }

    /// The row of state `s` (the contract's columns), and the contact force from the node's
    /// own equation along e: λ (n·e) = m_N e·ü_N − e·F_N.
    fn row(
        &self,
        eq: &Equations,
        reduced: &Reduced,
        s: &DVector<f64>,
    ) -> Result<(Vec<f64>, f64), EngineError> {
        let nf = self.free.len();
        let full = |x: &[f64]| -> Vector3<f64> {
            let mut v = Vector3::zeros();
            for (i, &k) in self.free.iter().enumerate() {
                v[k] = x[i];
            }
            v
        };
        let q = full(&s.as_slice()[..nf]);
        let qd = full(&s.as_slice()[nf..2 * nf]);
        let Reduced {
            minv, kf, cf, qf, ..
        } = reduced;
        let qdd_f = minv * (qf - kf * s.rows(0, nf) - cf * s.rows(nf, nf));
        let qdd = full(qdd_f.as_slice());
        let mut f_node = Vector2::zeros();
        for (coef, g, d, viscous) in &eq.node_terms {
            let rate = if *viscous { (g * qd)[0] } else { (g * q)[0] };
            f_node += d * (coef * rate);
        }
        for l in self.scene.loads.iter().filter(|l| l.node == self.node) {
            f_node += planar(&l.force);
        }
        let (e, n) = (&self.e, &self.n);
        let m_node = self.scene.nodes[self.node].mass;
        let lambda = (m_node * e.dot(&(self.j_node * qdd)) - e.dot(&f_node)) / n.dot(e);
        let mut row = Vec::with_capacity(5);
        for col in self.scene.columns.iter().take(4) {
            row.push(match &col.probe {
                Probe::Displacement { node, direction } => {
                    planar(direction).dot(&(self.point(*node)? * q))
                }
                Probe::Velocity { node, direction } => {
                    planar(direction).dot(&(self.point(*node)? * qd))
                }
                Probe::Rotation { axis, .. } => q.z * axis.z,
                Probe::ContactForce { .. } => lambda,
                // The closed form keeps the contact closed: the node on its face.
                Probe::Gap { .. } => 0.0,
                Probe::Zero { .. } => 0.0,
            });
        }
        Ok((row, lambda))
    }
}

/// One element's term in the contact node's equation: coefficient × sign, g, the direction it
/// acts along, and whether it reads the rate (a dashpot) or the elongation (a spring).
type NodeTerm = (f64, RowVector3<f64>, Vector2<f64>, bool);

/// M q̈ + C q̇ + K q = Q over the three coordinates (u_x, u_y, θ), the initial velocity, and the
/// element terms of the contact node's own equation.
struct Equations {
    mass: DMatrix<f64>,
    stiffness: DMatrix<f64>,
    damping: DMatrix<f64>,
    load: DVector<f64>,
    v0: DVector<f64>,
    node_terms: Vec<NodeTerm>,
}

impl Equations {
    fn assemble(k: &Kinematics, body: &RigidBody) -> Result<Self, EngineError> {
        let scene = k.scene;
        let m_node = scene.nodes[k.node].mass;
        let (m, c) = (body.mass, planar(&body.centre_offset));
        let mut mass = DMatrix::from_row_slice(
            3,
            3,
            &[
                m,
                0.0,
                -m * c.y,
                0.0,
                m,
                m * c.x,
                -m * c.y,
                m * c.x,
                body.inertia[(2, 2)],
            ],
        );
        mass += (k.j_node.transpose() * k.j_node * m_node).resize(3, 3, 0.0);
        let mut stiffness = DMatrix::zeros(3, 3);
        let mut damping = DMatrix::zeros(3, 3);
        let mut node_terms: Vec<NodeTerm> = Vec::new();
        for (list, target, viscous) in [
            (&scene.springs, &mut stiffness, false),
            (&scene.dashpots, &mut damping, true),
        ] {
            for e in list {
                let ElementRow { g, at_node } = k.element(e)?;
                let gg = g.transpose() * g * e.coefficient;
                *target += DMatrix::from_iterator(3, 3, gg.iter().copied());
                if let Some((sign, d)) = at_node {
                    node_terms.push((sign * e.coefficient, g, d, viscous));
                }
            }
        }
        let mut load = DVector::zeros(3);
        for l in &scene.loads {
            let q = k.point(l.node)?.transpose() * planar(&l.force);
            load += DVector::from_iterator(3, q.iter().copied());
        }
        let mut v0 = DVector::zeros(3);
        for iv in scene
            .initial_velocities
            .iter()
            .filter(|iv| iv.node == body.reference)
        {
            v0 = DVector::from_vec(vec![iv.velocity.x, iv.velocity.y, iv.angular.z]);
        }
        Ok(Equations {
            mass,
            stiffness,
            damping,
            load,
            v0,
            node_terms,
        })
    }
}

/// The equations reduced to the free coordinates: M⁻¹, K, C and Q.
struct Reduced {
    minv: DMatrix<f64>,
    kf: DMatrix<f64>,
    cf: DMatrix<f64>,
    qf: DVector<f64>,
    free: Vec<usize>,
}

impl Reduced {
    fn of(eq: &Equations, free: &[usize]) -> Result<Self, EngineError> {
        let nf = free.len();
        let pick = |mat: &DMatrix<f64>| DMatrix::from_fn(nf, nf, |i, j| mat[(free[i], free[j])]);
        let (mf, kf, cf) = (pick(&eq.mass), pick(&eq.stiffness), pick(&eq.damping));
        let qf = DVector::from_fn(nf, |i, _| eq.load[free[i]]);
        let minv = mf
            .clone()
            .try_inverse()
            .ok_or_else(|| EngineError::Unsupported("analytic: singular mass matrix".into()))?;
        Ok(Reduced {
            minv,
            kf,
            cf,
            qf,
            free: free.to_vec(),
        })
    }

    /// The augmented state matrix of s = (q, q̇, 1): ṡ = A s.
    fn state_matrix(&self) -> DMatrix<f64> {
        let nf = self.free.len();
        let minv = &self.minv;
        let mut a = DMatrix::zeros(2 * nf + 1, 2 * nf + 1);
        a.view_mut((0, nf), (nf, nf)).fill_with_identity();
        a.view_mut((nf, 0), (nf, nf)).copy_from(&(-minv * &self.kf));
        a.view_mut((nf, nf), (nf, nf))
            .copy_from(&(-minv * &self.cf));
        a.view_mut((nf, 2 * nf), (nf, 1))
            .copy_from(&(minv * &self.qf));
        a
    }

    /// s0 = (0, the free part of `v0`, 1).
    fn initial_state(&self, v0: &DVector<f64>) -> DVector<f64> {
        let nf = self.free.len();
        let mut s0 = DVector::zeros(2 * nf + 1);
        for (i, &k) in self.free.iter().enumerate() {
            s0[nf + i] = v0[k];
        }
        s0[2 * nf] = 1.0;
        s0
    }
}

/// The solution with its validity: rows after the first tensile contact force marked invalid,
/// and the force's smallest margin over the valid rows.
fn judged(scene: &Scene, times: &[f64], mut rows: Vec<Vec<f64>>, forces: &[f64]) -> RigidSolution {
    let valid_until = forces.iter().position(|f| *f < 0.0).map(|i| times[i]);
    let valid_rows = forces.iter().position(|f| *f < 0.0).unwrap_or(forces.len());
    for (i, row) in rows.iter_mut().enumerate() {
        row.push(if i < valid_rows { 1.0 } else { 0.0 });
    }
    let max_force = forces[..valid_rows].iter().fold(0.0f64, |a, b| a.max(*b));
    let min_force = forces[..valid_rows]
        .iter()
        .fold(f64::INFINITY, |a, b| a.min(*b));
    RigidSolution {
        history: history(scene, times, rows),
        initial_contact_force: forces[0],
        contact_margin: if max_force > 0.0 {
            min_force / max_force
        } else {
            0.0
        },
        valid_until,
    }
}
