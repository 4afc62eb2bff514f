//! From the stepped states to the output contract: `t`, the scene's columns, then the energy
//! columns `e_kinetic, e_elastic, e_viscous, w_external, e_balance`, at exactly the scene's
//! output times.
//!
//! An output time that falls on a step (within 1e-9 of the duration) is read from that step;
//! otherwise positions and velocities are interpolated linearly between the two steps around it
//! (orientations by slerp) and everything is computed from the interpolated state. At a step
//! boundary the later step's start is reported (its held velocities zeroed).
//!
//! The energies follow the scene's definitions, computed from rapier's state: kinetic
//! ½ m v_G² + ½ ω·I_G ω (particles ½ m v²); elastic ½ k e² of every spring with e from the
//! current node positions per element kind (grounded: the DOF's displacement or twist;
//! fixed-direction: d·(u_B − u_A); axial: current length − undeformed length), nothing for
//! contact; viscous ∫ Σ c·rate² dt (trapezoid on steps, interpolated between them); external
//! work F·(displacement of the load point since the start of the first dynamic step); balance =
//! kinetic + elastic + viscous − work − (kinetic + elastic at the start). Since rapier's springs
//! are implicit, the balance drifts negative: that drift is rapier's numerical energy loss.

use super::backend::Trace;
use super::plan::{BodyState, Plan, twist};
use crate::contract::ENERGY_COLUMNS;
use crate::engines::{EngineError, History};
use crate::scene::{Connection, Dof, Element, Probe, Scene};
use nalgebra::Vector3;

/// What the contact did, per contact pair, over the steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostics {
    /// Mean penetration of the node into the face (gap < 0 counted, separation as 0).
    pub mean_penetration: Vec<f64>,
    /// Largest penetration.
    pub max_penetration: Vec<f64>,
    /// Largest separation (gap > 0).
    pub max_separation: Vec<f64>,
}

struct Kinematics<'a> {
    scene: &'a Scene,
    plan: &'a Plan,
}

impl Kinematics<'_> {
    fn position(&self, s: &[BodyState], node: usize) -> Vector3<f64> {
        let r = self.plan.nodes[node];
        s[r.body].point(&r.local)
    }

    fn velocity(&self, s: &[BodyState], node: usize) -> Vector3<f64> {
        let r = self.plan.nodes[node];
        s[r.body].velocity(&self.plan.bodies[r.body].com, &r.local)
    }

    fn displacement(&self, s: &[BodyState], node: usize) -> Vector3<f64> {
        self.position(s, node) - self.scene.nodes[node].position
    }

    /// Elongation and its rate of an element.
    fn stretch(&self, s: &[BodyState], e: &Element) -> (f64, f64) {
        let nodes = &self.scene.nodes;
        match &e.connection {
            Connection::Grounded {
                node,
                dof: Dof::Translation(i),
            } => {
                let d: Vector3<f64> = nodes[*node].frame.column(*i).into_owned();
                (
                    d.dot(&self.displacement(s, *node)),
                    d.dot(&self.velocity(s, *node)),
                )
            }
            Connection::Grounded {
                node,
                dof: Dof::Rotation(i),
            } => {
                let a: Vector3<f64> = nodes[*node].frame.column(*i).into_owned();
                let b = &s[self.plan.nodes[*node].body];
                (twist(&b.rotation, &a), a.dot(&b.angvel))
            }
            Connection::FixedDirection {
                nodes: [a, b],
                direction,
            } => (
                direction.dot(&(self.displacement(s, *b) - self.displacement(s, *a))),
                direction.dot(&(self.velocity(s, *b) - self.velocity(s, *a))),
            ),
            Connection::Axial { nodes: [a, b] } => {
                let d = self.position(s, *b) - self.position(s, *a);
                let length = d.norm();
                let rest = (nodes[*b].position - nodes[*a].position).norm();
                let n = d / length.max(f64::MIN_POSITIVE);
                (
                    length - rest,
                    n.dot(&(self.velocity(s, *b) - self.velocity(s, *a))),
                )
            }
        }
    }

    fn kinetic(&self, s: &[BodyState]) -> f64 {
        self.plan
            .bodies
            .iter()
            .zip(s)
            .map(|(b, st)| {
                let r = st.rotation.to_rotation_matrix();
                let inertia = r.matrix() * b.inertia * r.matrix().transpose();
                0.5 * b.mass * st.linvel.norm_squared()
                    + 0.5 * st.angvel.dot(&(inertia * st.angvel))
            })
            .sum()
    }

    fn elastic(&self, s: &[BodyState]) -> f64 {
        self.scene
            .springs
            .iter()
            .map(|e| {
                let (x, _) = self.stretch(s, e);
                0.5 * e.coefficient * x * x
            })
            .sum()
    }

    fn dissipation_rate(&self, s: &[BodyState]) -> f64 {
        self.scene
            .dashpots
            .iter()
            .map(|e| {
                let (_, rate) = self.stretch(s, e);
                e.coefficient * rate * rate
            })
            .sum()
    }

    fn work(&self, s: &[BodyState], start: &[BodyState]) -> f64 {
        self.scene
            .loads
            .iter()
            .map(|l| {
                l.force
                    .dot(&(self.position(s, l.node) - self.position(start, l.node)))
            })
            .sum()
    }

    /// Gap of a contact pair (negative: penetration).
    fn gap(&self, s: &[BodyState], k: usize) -> f64 {
        let c = &self.plan.contacts[k];
        let face = &s[c.body];
        let n = face.rotation * c.face_normal;
        n.dot(&(self.position(s, c.node) - face.point(&c.face_point)))
    }
}

/// Linear interpolation of a series (`x` ascending) at `t`, held constant outside.
fn interpolate(x: &[f64], y: &[f64], t: f64) -> f64 {
    match x.len() {
        0 => 0.0,
        1 => y[0],
        _ => {
            if t <= x[0] {
                return y[0];
            }
            if t >= x[x.len() - 1] {
                return y[y.len() - 1];
            }
            let i = x.partition_point(|&v| v <= t).max(1) - 1;
            let s = (t - x[i]) / (x[i + 1] - x[i]);
            y[i] + s * (y[i + 1] - y[i])
        }
    }
}

/// The history of a run, and its contact diagnostics.
pub fn history(
    scene: &Scene,
    plan: &Plan,
    trace: &Trace,
) -> Result<(History, Diagnostics), EngineError> {
    let k = Kinematics { scene, plan };
    let records = &trace.records;
    let Some(first) = records.first() else {
        return Err(EngineError::Failed("rapier: nothing was recorded".into()));
    };

    // Dissipated energy at each record (trapezoid over steps).
    let mut dissipated = Vec::with_capacity(records.len());
    let mut previous: Option<(f64, f64)> = None;
    let mut total = 0.0;
    for r in records {
        let power = k.dissipation_rate(&r.bodies);
        if let Some((t, p)) = previous {
            total += 0.5 * (r.time - t) * (p + power);
        }
        dissipated.push(total);
        previous = Some((r.time, power));
    }

    // Contact forces at the middle of their steps; contact diagnostics.
    let nc = plan.contacts.len();
    let mut middles = Vec::new();
    let mut forces: Vec<Vec<f64>> = vec![Vec::new(); nc];
    let mut penetration_sum = vec![0.0; nc];
    let mut max_penetration = vec![0.0f64; nc];
    let mut max_separation = vec![0.0f64; nc];
    let mut counted = 0usize;
    for (i, r) in records.iter().enumerate() {
        let Some(f) = &r.contact_force else { continue };
        middles.push(0.5 * (records[i - 1].time + r.time));
        counted += 1;
        for c in 0..nc {
            forces[c].push(f[c]);
            let gap = k.gap(&r.bodies, c);
            penetration_sum[c] += (-gap).max(0.0);
            max_penetration[c] = max_penetration[c].max(-gap);
            max_separation[c] = max_separation[c].max(gap);
        }
    }
    let diagnostics = Diagnostics {
        mean_penetration: penetration_sum
            .iter()
            .map(|s| s / counted.max(1) as f64)
            .collect(),
        max_penetration,
        max_separation,
    };

    let start = &first.bodies;
    let energy0 = k.kinetic(start) + k.elastic(start);
    let duration = scene.duration();
    let tol = 1e-9 * duration.max(f64::MIN_POSITIVE);
    let columns: Vec<String> = std::iter::once("t".to_string())
        .chain(scene.columns.iter().map(|c| c.name.clone()))
        .chain(ENERGY_COLUMNS.iter().map(|s| s.to_string()))
        .collect();
    let mut previous_rotation = vec![0.0; scene.columns.len()];
    let mut rows = Vec::with_capacity(scene.output_rows);
    for t in scene.output_times() {
        let i = records.partition_point(|r| r.time <= t + tol).max(1) - 1;
        let (state, dissipation): (Vec<BodyState>, f64) =
            if (records[i].time - t).abs() <= tol || i + 1 >= records.len() {
                (records[i].bodies.clone(), dissipated[i])
            } else {
                let (a, b) = (&records[i], &records[i + 1]);
                let s = ((t - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
                (
                    a.bodies
                        .iter()
                        .zip(&b.bodies)
                        .map(|(x, y)| x.lerp(y, s))
                        .collect(),
                    dissipated[i] + s * (dissipated[i + 1] - dissipated[i]),
                )
            };
        let mut row = Vec::with_capacity(columns.len());
        row.push(t);
        for (ci, c) in scene.columns.iter().enumerate() {
            row.push(match &c.probe {
                Probe::Displacement { node, direction } => {
                    direction.dot(&k.displacement(&state, *node))
                }
                Probe::Velocity { node, direction } => direction.dot(&k.velocity(&state, *node)),
                Probe::Rotation { body, axis } => {
                    let b = plan.nodes[scene.bodies[*body].reference].body;
                    let raw = twist(&state[b].rotation, axis);
                    let turns = ((previous_rotation[ci] - raw) / std::f64::consts::TAU).round();
                    let unwrapped = raw + turns * std::f64::consts::TAU;
                    previous_rotation[ci] = unwrapped;
                    unwrapped
                }
                Probe::ContactForce { contact } => interpolate(&middles, &forces[*contact], t),
                Probe::Zero { .. } => 0.0,
            });
        }
        let kinetic = k.kinetic(&state);
        let elastic = k.elastic(&state);
        let work = k.work(&state, start);
        row.extend([
            kinetic,
            elastic,
            dissipation,
            work,
            kinetic + elastic + dissipation - work - energy0,
        ]);
        if row.iter().any(|x| !x.is_finite()) {
            return Err(EngineError::Failed(format!(
                "rapier: non-finite output at t = {t:e}"
            )));
        }
        rows.push(row);
    }
    Ok((History { columns, rows }, diagnostics))
}
