//! From the stepped states to the output contract: `t`, the scene's columns, then the energy
//! columns `e_kinetic, e_elastic, e_viscous, [e_frictional,] w_external, e_balance`
//! (`e_frictional` on a scene with friction), at exactly the scene's output times.
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
//! work F·(displacement of the load point since the start of the first dynamic step); frictional
//! Σ over steps and contact points of −P·s/h, P the step's friction impulse on the ball's body,
//! s the point's slip over the step, h its length (rapier's own path times its friction force,
//! interpolated between steps); balance = kinetic + elastic + viscous [+ frictional] − work −
//! (kinetic + elastic at the start). Since rapier's springs
//! are implicit, the balance drifts negative: that drift is rapier's numerical energy loss.
//!
//! A contact force is what rapier's impulses deliver over a window centred on the row: each
//! step's normal impulse is spread evenly over the step, and a row at t carries the impulse
//! over [t − w, t + w] divided by 2w, with w half the shorter of the output intervals on either
//! side (so that a force that changes linearly is read without bias). The first and last rows
//! have no room on one side: they carry the mean force of the step that holds them, or of the
//! full step before it where that step is the run's last, cut short to end on the duration
//! (rapier's position correction does not scale with a step's length, so the impulse of a short
//! step over its length is no force). Rapier
//! resolves contact by impulses, which come step by step and, where a contact carries little
//! load, not in every step; a row that sampled one step's impulse would alias them.
//!
//! The [`Recorder`] receives the stepped states one at a time and keeps no per-step data: the
//! previous state, running totals (the impulse delivered so far among them), the output rows,
//! and the impulse at the window edges that rows still need. Its memory is that of the output,
//! whatever the number of steps.

use super::backend::{FrictionImpulse, Record};
use super::plan::{BodyState, Plan, twist};
use crate::contract::energy_columns;
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
    /// Impact times, every pair's in the order they came: the middle of each step where a
    /// pair that had no contact impulse in the step before gets one (rapier's impulse acts
    /// somewhere within that step; the contact-force column spreads it over the step).
    pub impacts: Vec<f64>,
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

    /// The work of the constant loads since `start` (a load that varies in time is summed
    /// step by step: [`Recorder::push`]).
    fn work(&self, s: &[BodyState], start: &[BodyState]) -> f64 {
        self.scene
            .loads
            .iter()
            .filter(|l| l.amplitude.is_none())
            .map(|l| {
                l.force
                    .dot(&(self.position(s, l.node) - self.position(start, l.node)))
            })
            .sum()
    }

    /// The energy friction dissipated in a step of length `h` from `before` to `after`: per
    /// contact point, minus its impulse on the ball's body over h (the step's mean force) dotted
    /// with the point's slip over the step, the travel of the ball's body point there less the
    /// face's (both body points taken where the point is at the step's start).
    fn friction_work(
        &self,
        (before, after): (&[BodyState], &[BodyState]),
        impulses: &[Vec<FrictionImpulse>],
        h: f64,
    ) -> f64 {
        let travel = |b: usize, at: &Vector3<f64>| {
            let local = before[b].rotation.inverse() * (at - before[b].position);
            after[b].point(&local) - at
        };
        (self.plan.contacts.iter())
            .zip(impulses)
            .flat_map(|(c, points)| {
                let ball = self.plan.colliders[c.ball].body;
                let face = self.plan.colliders[c.slab].body;
                points
                    .iter()
                    .map(move |p| -p.impulse.dot(&(travel(ball, &p.at) - travel(face, &p.at))) / h)
            })
            .sum()
    }

    /// Gap of a contact pair (negative: penetration).
    fn gap(&self, s: &[BodyState], k: usize) -> f64 {
        let c = &self.plan.contacts[k];
        let face = &s[c.body];
        let local = face.rotation.inverse() * (self.position(s, c.node) - face.position);
        crate::scene::surface_distance(&c.surface, &local).0 - c.node_radius
    }
}

/// The output history of a rapier run, built while the run steps.
pub struct Recorder<'a> {
    k: Kinematics<'a>,
    columns: Vec<String>,
    times: Vec<f64>,
    /// Index of the next output time to emit.
    next: usize,
    tol: f64,
    rows: Vec<Vec<f64>>,
    /// The first record's states and energy (the work and balance are relative to them).
    start: Option<(Vec<BodyState>, f64)>,
    /// The previous record, its dissipated energy and dissipation rate.
    previous: Option<(Record, f64, f64)>,
    /// The work of the loads that vary in time up to the previous record, and up to the
    /// last: each step's applied force (at its middle) times its point's travel in it.
    ramped_work: (f64, f64),
    /// Whether any load varies in time.
    ramped: bool,
    /// On a scene with friction, the energy friction dissipated up to the previous record and
    /// up to the last (`None` without friction).
    frictional: Option<(f64, f64)>,
    /// Per contact, the impulse delivered from the start to the previous record.
    impulse: Vec<f64>,
    /// Per contact, the mean force of the last step.
    last_force: Vec<f64>,
    /// The longest step so far, and the force of the last step that long.
    longest_step: f64,
    full_force: Vec<f64>,
    /// The edges of the rows' windows: row j's is [edges[2j], edges[2j + 1]] (of no length at
    /// the first and last rows).
    edges: Vec<f64>,
    /// Index of the next edge whose impulse is still unknown.
    next_edge: usize,
    /// At the edges passed whose rows are not filled yet, per contact: the impulse delivered up
    /// to the edge, and the mean force of the step that holds it.
    at_edges: std::collections::VecDeque<(Vec<f64>, Vec<f64>)>,
    /// Rows (indices) whose contact-force columns await the impulse at their window's end.
    pending: std::collections::VecDeque<usize>,
    /// The most rows ever pending at once.
    most_pending: usize,
    /// (column index in a row, contact pair) of every contact-force column.
    contact_columns: Vec<(usize, usize)>,
    previous_rotation: Vec<f64>,
    penetration_sum: Vec<f64>,
    max_penetration: Vec<f64>,
    max_separation: Vec<f64>,
    /// Per pair, whether the last step had a contact impulse (`None` before the first step).
    pressed: Vec<Option<bool>>,
    impacts: Vec<f64>,
    counted: usize,
}

impl<'a> Recorder<'a> {
    /// An empty recorder for `scene` built as `plan`.
    pub fn new(scene: &'a Scene, plan: &'a Plan) -> Self {
        let columns: Vec<String> = std::iter::once("t".to_string())
            .chain(scene.columns.iter().map(|c| c.name.clone()))
            .chain(
                energy_columns(scene.has_friction())
                    .iter()
                    .map(|s| s.to_string()),
            )
            .collect();
        let contact_columns = scene
            .columns
            .iter()
            .enumerate()
            .filter_map(|(ci, c)| match c.probe {
                Probe::ContactForce { contact } => Some((ci + 1, contact)),
                _ => None,
            })
            .collect();
        let nc = plan.contacts.len();
        let times = scene.output_times();
        let edges: Vec<f64> = (0..times.len())
            .flat_map(|j| {
                let left = if j > 0 { times[j] - times[j - 1] } else { 0.0 };
                let right = times.get(j + 1).map_or(0.0, |t| t - times[j]);
                let w = 0.5 * left.min(right);
                [times[j] - w, times[j] + w]
            })
            .collect();
        Recorder {
            k: Kinematics { scene, plan },
            columns,
            times,
            next: 0,
            tol: 1e-9 * scene.duration().max(f64::MIN_POSITIVE),
            rows: Vec::with_capacity(scene.output_rows),
            start: None,
            previous: None,
            ramped_work: (0.0, 0.0),
            ramped: scene.has_amplitudes(),
            frictional: scene.has_friction().then_some((0.0, 0.0)),
            impulse: vec![0.0; nc],
            last_force: vec![0.0; nc],
            longest_step: 0.0,
            full_force: vec![0.0; nc],
            edges,
            next_edge: 0,
            at_edges: std::collections::VecDeque::new(),
            pending: std::collections::VecDeque::new(),
            most_pending: 0,
            contact_columns,
            previous_rotation: vec![0.0; scene.columns.len()],
            penetration_sum: vec![0.0; nc],
            max_penetration: vec![0.0; nc],
            max_separation: vec![0.0; nc],
            pressed: vec![None; nc],
            impacts: Vec::new(),
            counted: 0,
        }
    }

    /// Take the next record (in time order; a step boundary comes twice, end then start).
    pub fn push(&mut self, record: Record) -> Result<(), EngineError> {
        let power = self.k.dissipation_rate(&record.bodies);
        let dissipated = match &self.previous {
            Some((p, d, pp)) => d + 0.5 * (record.time - p.time) * (pp + power),
            None => 0.0,
        };
        if self.start.is_none() {
            let energy0 = self.k.kinetic(&record.bodies) + self.k.elastic(&record.bodies);
            self.start = Some((record.bodies.clone(), energy0));
        }
        if let (true, Some((p, ..))) = (self.ramped, &self.previous) {
            let middle = 0.5 * (p.time + record.time);
            let step: f64 = (self.k.scene.loads.iter())
                .filter(|l| l.amplitude.is_some())
                .map(|l| {
                    let travel = self.k.position(&record.bodies, l.node)
                        - self.k.position(&p.bodies, l.node);
                    l.force_at(middle).dot(&travel)
                })
                .sum();
            self.ramped_work = (self.ramped_work.1, self.ramped_work.1 + step);
        }
        if let (Some((_, f1)), Some((p, ..))) = (self.frictional, &self.previous) {
            let step = match &record.friction {
                Some(impulses) => {
                    let states = (&p.bodies[..], &record.bodies[..]);
                    self.k.friction_work(states, impulses, record.time - p.time)
                }
                None => 0.0,
            };
            self.frictional = Some((f1, f1 + step));
        }
        if let (Some(f), Some((p, ..))) = (&record.contact_force, &self.previous) {
            self.counted += 1;
            for c in 0..f.len() {
                let gap = self.k.gap(&record.bodies, c);
                self.penetration_sum[c] += (-gap).max(0.0);
                self.max_penetration[c] = self.max_penetration[c].max(-gap);
                self.max_separation[c] = self.max_separation[c].max(gap);
            }
            let middle = 0.5 * (p.time + record.time);
            for (was, force) in self.pressed.iter_mut().zip(f) {
                let now = *force > 0.0;
                if now && *was == Some(false) {
                    self.impacts.push(middle);
                }
                *was = Some(now);
            }
            // A step shorter than the run's others (the last, cut to end on the duration) is
            // no force to read alone: rapier's position correction does not scale with its
            // length. A row that reads one step's force reads the last full step's instead.
            let length = record.time - p.time;
            if length >= self.longest_step * (1.0 - 1e-6) {
                self.longest_step = self.longest_step.max(length);
                self.full_force.clone_from(f);
            }
            let read = if length >= self.longest_step * (1.0 - 1e-6) {
                f.clone()
            } else {
                self.full_force.clone()
            };
            // The impulse at each window edge this step passes, the step's spread evenly.
            while !self.contact_columns.is_empty()
                && self.next_edge < self.edges.len()
                && self.edges[self.next_edge] <= record.time + self.tol
            {
                let into = (self.edges[self.next_edge] - p.time).clamp(0.0, record.time - p.time);
                let at: Vec<f64> = self
                    .impulse
                    .iter()
                    .zip(f)
                    .map(|(i, f)| i + f * into)
                    .collect();
                self.at_edges.push_back((at, read.clone()));
                self.next_edge += 1;
            }
            for (i, f) in self.impulse.iter_mut().zip(f) {
                *i += f * (record.time - p.time);
            }
            self.last_force = read;
        }
        // Rows the new record has passed: the previous record is the last at or before them.
        while self.next < self.times.len() && record.time > self.times[self.next] + self.tol {
            let t = self.times[self.next];
            let Some((p, pd, _)) = &self.previous else {
                break;
            };
            let (w0, w1) = self.ramped_work;
            let frictional = self.frictional.map(|(f0, f1)| (f0, f1 - f0));
            let (state, dissipation, ramped) = if (p.time - t).abs() <= self.tol {
                let frictional = frictional.map(|(f0, _)| f0);
                (p.bodies.clone(), (*pd, frictional), w0)
            } else {
                let s = ((t - p.time) / (record.time - p.time)).clamp(0.0, 1.0);
                (
                    p.bodies
                        .iter()
                        .zip(&record.bodies)
                        .map(|(x, y)| x.lerp(y, s))
                        .collect(),
                    (
                        pd + s * (dissipated - pd),
                        frictional.map(|(f0, df)| f0 + s * df),
                    ),
                    w0 + s * (w1 - w0),
                )
            };
            self.emit(t, &state, dissipation, ramped);
        }
        self.previous = Some((record, dissipated, power));
        self.resolve(false);
        Ok(())
    }

    /// One output row at `t` from `state`, with the energy dashpots and (on a scene with
    /// friction) friction dissipated by then; its contact-force columns are filled later.
    fn emit(
        &mut self,
        t: f64,
        state: &[BodyState],
        (dissipation, frictional): (f64, Option<f64>),
        ramped_work: f64,
    ) {
        let (start, energy0) = self.start.as_ref().expect("a record came first");
        let k = &self.k;
        let mut row = Vec::with_capacity(self.columns.len());
        row.push(t);
        for (ci, c) in k.scene.columns.iter().enumerate() {
            row.push(match &c.probe {
                Probe::Displacement { node, direction } => {
                    direction.dot(&k.displacement(state, *node))
                }
                Probe::Velocity { node, direction } => direction.dot(&k.velocity(state, *node)),
                Probe::Rotation { body, axis } => {
                    let b = k.plan.nodes[k.scene.bodies[*body].reference].body;
                    let raw = twist(&state[b].rotation, axis);
                    let turns =
                        ((self.previous_rotation[ci] - raw) / std::f64::consts::TAU).round();
                    let unwrapped = raw + turns * std::f64::consts::TAU;
                    self.previous_rotation[ci] = unwrapped;
                    unwrapped
                }
                Probe::ContactForce { .. } => f64::NAN, // filled by `resolve`
                Probe::Gap { contact } => k.gap(state, *contact),
                Probe::Zero { .. } => 0.0,
            });
        }
        let kinetic = k.kinetic(state);
        let elastic = k.elastic(state);
        let mut work = k.work(state, start);
        if self.ramped {
            work += ramped_work;
        }
        match frictional {
            None => row.extend([
                kinetic,
                elastic,
                dissipation,
                work,
                kinetic + elastic + dissipation - work - energy0,
            ]),
            Some(f) => row.extend([
                kinetic,
                elastic,
                dissipation,
                f,
                work,
                kinetic + elastic + dissipation + f - work - energy0,
            ]),
        }
        self.rows.push(row);
        self.next += 1;
        if !self.contact_columns.is_empty() {
            self.pending.push_back(self.rows.len() - 1);
            self.most_pending = self.most_pending.max(self.pending.len());
        }
    }

    /// Fill the contact-force columns of pending rows whose window's end the steps have passed
    /// (all of them at the end of the run, where the edges left take the impulse delivered and
    /// the last step's force): the impulse over the window divided by its length, or where the
    /// window has none, the force of the step that holds the row.
    fn resolve(&mut self, at_end: bool) {
        if at_end && !self.contact_columns.is_empty() {
            let last = self.last_force.clone();
            while self.next_edge < self.edges.len() {
                self.at_edges
                    .push_back((self.impulse.clone(), last.clone()));
                self.next_edge += 1;
            }
        }
        while let Some(&row) = self.pending.front() {
            // The row's two edges are at the front.
            let (Some((low, _)), Some((high, force))) =
                (self.at_edges.front(), self.at_edges.get(1))
            else {
                break;
            };
            let length = self.edges[2 * row + 1] - self.edges[2 * row];
            for &(col, contact) in &self.contact_columns {
                self.rows[row][col] = if length > self.tol {
                    (high[contact] - low[contact]) / length
                } else {
                    force[contact]
                };
            }
            self.pending.pop_front();
            self.at_edges.drain(..2);
        }
    }

    /// The rows still pending their contact force, at most, over the run so far.
    pub fn most_pending(&self) -> usize {
        self.most_pending
    }

    /// Capacity of the row buffer (the output rows, reserved once).
    pub fn row_capacity(&self) -> usize {
        self.rows.capacity()
    }

    /// Impulse samples (at window edges) held now.
    pub fn edges_held(&self) -> usize {
        self.at_edges.len()
    }

    /// The history and the contact diagnostics.
    pub fn finish(mut self) -> Result<(History, Diagnostics), EngineError> {
        let Some((last, ld, _)) = self.previous.take() else {
            return Err(EngineError::Failed("rapier: nothing was recorded".into()));
        };
        while self.next < self.times.len() {
            let t = self.times[self.next];
            let frictional = self.frictional.map(|(_, f1)| f1);
            self.emit(t, &last.bodies, (ld, frictional), self.ramped_work.1);
        }
        self.resolve(true);
        if let Some(row) = self.rows.iter().find(|r| r.iter().any(|x| !x.is_finite())) {
            return Err(EngineError::Unstable(format!(
                "rapier: non-finite output at t = {:e}",
                row[0]
            )));
        }
        let diagnostics = Diagnostics {
            mean_penetration: self
                .penetration_sum
                .iter()
                .map(|s| s / self.counted.max(1) as f64)
                .collect(),
            max_penetration: self.max_penetration,
            max_separation: self.max_separation,
            impacts: self.impacts,
        };
        Ok((
            History {
                columns: self.columns,
                rows: self.rows,
            },
            diagnostics,
        ))
    }
}
