//! A user's engine: semi-implicit (symplectic) Euler on particles joined by springs and
//! dashpots, written against crosscheck's public [`Engine`] trait and nothing else of it.
//!
//! What an engine provides: a name; a history per the output contract for a scene (the case's
//! output columns at its output times, then, optionally, the energy columns, which the
//! stability map reads); what it cost ([`RunInfo`]); how the studies may step it
//! ([`Engine::stepping`]); and a refusal ([`EngineError::Unsupported`]) for what it does not
//! model. Here: rigid bodies and contact. Everything else is the harness's: the jobs, the
//! exact solutions it is judged against, the sweep, the stability map and the report.

use crosscheck::contract::{ENERGY_COLUMNS, History};
use crosscheck::engines::{
    Coarsest, Engine, EngineError, Needs, RunInfo, RunOutput, RunSettings, Stepping,
};
use crosscheck::scene::{Connection, Dof, Element, IncrementRule, Probe, Scene, StepKind};
use nalgebra::{DMatrix, DVector, Vector3};
use std::collections::BTreeMap;

/// Semi-implicit Euler: v ← v + h·a(x, v), then x ← x + h·v. First order (its velocity lags
/// half an increment), stable for h < 2/ω without damping.
pub struct SemiImplicitEuler;

impl Engine for SemiImplicitEuler {
    fn name(&self) -> &str {
        "semi_implicit_euler"
    }
    /// It has no stable-increment estimate of its own: the harness hands it the explicit
    /// engine's increment (and, in the stability map, ratios of it).
    fn needs(&self) -> Needs {
        Needs::MatchedIncrement
    }
    fn stepping(&self) -> Option<Stepping> {
        Some(Stepping {
            coarsest: Coarsest::OutputInterval,
            penalty: false,
            substeps: None,
            budget_share: 1.0,
            precision: "f64",
            on_request: false,
        })
    }
    fn increments(&self, scene: &Scene, settings: &RunSettings) -> Option<f64> {
        Some(scene.duration() / increment(scene, settings).ok()?)
    }
    fn run(&self, scene: &Scene, settings: &RunSettings) -> Result<RunOutput, EngineError> {
        let start = std::time::Instant::now();
        let h = increment(scene, settings)?;
        let mut state = State::new(scene)?;
        let (history, steps) = state.integrate(scene, h)?;
        let info = RunInfo {
            increment: h,
            steps,
            stable_increment: None,
            penalty_stiffness: None,
            wall_seconds: start.elapsed().as_secs_f64(),
            counters: BTreeMap::from([("force_evaluations".to_string(), steps)]),
            measures: BTreeMap::new(),
        };
        let engine = self.name().to_string();
        Ok(RunOutput {
            engine,
            history,
            info,
        })
    }
}

/// The increment: a given or forced one shortened to divide the output interval; an exact one
/// as it is (rows are then interpolated). It chooses none of its own.
fn increment(scene: &Scene, settings: &RunSettings) -> Result<f64, EngineError> {
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    match settings.increment.unwrap_or(scene.settings.increment) {
        IncrementRule::Given(h) | IncrementRule::Forced(h) if h > 0.0 => {
            Ok(interval / (interval / h - 1e-9).ceil())
        }
        IncrementRule::Exact(h) if h > 0.0 => Ok(h),
        rule => Err(EngineError::Unsupported(format!(
            "semi_implicit_euler chooses no increment of its own ({rule:?}): give one"
        ))),
    }
}

/// Positions and velocities of every node, and the energy bookkeeping.
struct State {
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    /// Directions held in the current step, per node, with their target displacement.
    held: Vec<Vec<(Vector3<f64>, Option<f64>)>>,
    viscous: f64,
    work: f64,
    initial_energy: f64,
}

impl State {
    fn new(scene: &Scene) -> Result<State, EngineError> {
        if !scene.bodies.is_empty() || !scene.contacts.is_empty() {
            return Err(EngineError::Unsupported(
                "semi_implicit_euler models particles, springs and dashpots only".into(),
            ));
        }
        let x: Vec<Vector3<f64>> = scene.nodes.iter().map(|n| n.position).collect();
        let v = vec![Vector3::zeros(); x.len()];
        let held = vec![Vec::new(); x.len()];
        let (viscous, work, initial_energy) = (0.0, 0.0, 0.0);
        Ok(State {
            x,
            v,
            held,
            viscous,
            work,
            initial_energy,
        })
    }

    /// The static steps, then every dynamic step, sampled at the output times.
    fn integrate(&mut self, scene: &Scene, h: f64) -> Result<(History, u64), EngineError> {
        let dynamic = scene.steps.iter().position(|s| s.kind != StepKind::Static);
        for step in &scene.steps[..dynamic.unwrap_or(scene.steps.len())] {
            self.hold(scene, step);
            self.equilibrium(scene)?;
        }
        for iv in &scene.initial_velocities {
            self.v[iv.node] = iv.velocity;
        }
        let mut columns = vec!["t".to_string()];
        columns.extend(scene.columns.iter().map(|c| c.name.clone()));
        columns.extend(ENERGY_COLUMNS.iter().map(|c| c.to_string()));
        let times = scene.output_times();
        let (mut rows, mut t, mut steps) = (Vec::new(), 0.0, 0u64);
        let mut previous = self.row(scene)?;
        self.initial_energy = previous[previous.len() - 5] + previous[previous.len() - 4];
        previous = self.row(scene)?;
        let mut step_start = 0.0;
        for step in &scene.steps[dynamic.unwrap_or(scene.steps.len())..] {
            let StepKind::Dynamic { duration } = step.kind else {
                return Err(EngineError::Unsupported(
                    "a static step after a dynamic one".into(),
                ));
            };
            self.hold(scene, step);
            // Times from the step's start, so that round-off does not add up over increments;
            // the last increment is shortened to end the step.
            let increments = (duration / h - 1e-9).ceil().max(1.0) as u64;
            for k in 1..=increments {
                let next = if k == increments {
                    step_start + duration
                } else {
                    step_start + k as f64 * h
                };
                let dt = next - t;
                self.advance(scene, dt);
                steps += 1;
                let current = self.row(scene)?;
                // Rows at output times in (t, next], interpolated linearly.
                while let Some(&at) = times.get(rows.len())
                    && at <= next + 1e-9 * dt
                {
                    let w = ((at - t) / dt).clamp(0.0, 1.0);
                    let mut row: Vec<f64> = (previous.iter().zip(&current))
                        .map(|(a, b)| a + w * (b - a))
                        .collect();
                    row.insert(0, at);
                    rows.push(row);
                }
                (previous, t) = (current, next);
            }
            step_start += duration;
        }
        Ok((History { columns, rows }, steps))
    }

    /// The conditions of `step`: each held or prescribed DOF as a direction and a target.
    fn hold(&mut self, scene: &Scene, step: &crosscheck::scene::Step) {
        self.held.iter_mut().for_each(Vec::clear);
        for c in &step.conditions {
            if let Dof::Translation(axis) = c.dof {
                let d = scene.nodes[c.node].frame.column(axis).into_owned();
                self.held[c.node].push((d, c.value));
                let at = scene.nodes[c.node].position.dot(&d) + c.value.unwrap_or(0.0);
                let (x, v) = (self.x[c.node], self.v[c.node]);
                if c.value.is_some() {
                    self.x[c.node] += (at - x.dot(&d)) * d;
                }
                self.v[c.node] -= v.dot(&d) * d;
            }
        }
    }

    /// One increment: v ← v + h·a(x, v), then x ← x + h·v.
    fn advance(&mut self, scene: &Scene, h: f64) {
        let (f, dissipation) = forces(scene, &self.x, &self.v);
        for (i, node) in scene.nodes.iter().enumerate() {
            let a = if node.mass > 0.0 {
                f[i] / node.mass
            } else {
                Vector3::zeros()
            };
            let dv = h * self.free(i, a);
            self.v[i] += dv;
        }
        let before = self.x.clone();
        for i in 0..self.x.len() {
            self.x[i] += h * self.v[i];
        }
        self.viscous += h * dissipation;
        for l in &scene.loads {
            self.work += l.force.dot(&(self.x[l.node] - before[l.node]));
        }
    }

    /// `a` without its components along the node's held directions.
    fn free(&self, node: usize, a: Vector3<f64>) -> Vector3<f64> {
        self.held[node].iter().fold(a, |a, (d, _)| a - a.dot(d) * d)
    }

    /// Static equilibrium of the free directions: Newton's method on the forces, with a
    /// finite-difference tangent; at most 50 iterations.
    fn equilibrium(&mut self, scene: &Scene) -> Result<(), EngineError> {
        let axes = scene.dimension.count();
        let free: Vec<(usize, Vector3<f64>)> = (0..self.x.len())
            .flat_map(|i| (0..axes).map(move |a| (i, a)))
            .map(|(i, a)| (i, scene.nodes[i].frame.column(a).into_owned()))
            .filter(|(i, d)| !self.held[*i].iter().any(|(e, _)| e.dot(d).abs() > 0.5))
            .collect();
        let residual = |x: &[Vector3<f64>]| {
            let (f, _) = forces(scene, x, &vec![Vector3::zeros(); x.len()]);
            DVector::from_iterator(free.len(), free.iter().map(|(i, d)| f[*i].dot(d)))
        };
        if free.is_empty() {
            return Ok(());
        }
        for _ in 0..50 {
            let r = residual(&self.x);
            let mut tangent = DMatrix::zeros(free.len(), free.len());
            for (j, (node, d)) in free.iter().enumerate() {
                let step = 1e-7 * (1.0 + self.x[*node].norm());
                let mut moved = self.x.clone();
                moved[*node] += step * d;
                tangent.set_column(j, &((residual(&moved) - &r) / step));
            }
            let dq = tangent.lu().solve(&(-&r)).ok_or_else(|| {
                EngineError::Failed("a static step has no equilibrium (singular tangent)".into())
            })?;
            for (k, (node, d)) in free.iter().enumerate() {
                self.x[*node] += dq[k] * d;
            }
            // The finite-difference tangent's round-off bounds how far the step can shrink.
            if dq.amax() <= 1e-10 * (1.0 + self.x.iter().map(|p| p.amax()).fold(0.0, f64::max)) {
                return Ok(());
            }
        }
        Err(EngineError::Failed(
            "a static step did not converge in 50 iterations".into(),
        ))
    }

    /// The output columns and the energies at the current state.
    fn row(&self, scene: &Scene) -> Result<Vec<f64>, EngineError> {
        let mut row = Vec::with_capacity(scene.columns.len() + 5);
        for c in &scene.columns {
            row.push(match &c.probe {
                Probe::Displacement { node, direction } => {
                    (self.x[*node] - scene.nodes[*node].position).dot(direction)
                }
                Probe::Velocity { node, direction } => self.v[*node].dot(direction),
                Probe::Zero { .. } => 0.0,
                other => {
                    return Err(EngineError::Unsupported(format!(
                        "semi_implicit_euler has no output for {other:?}"
                    )));
                }
            });
        }
        let kinetic: f64 = (scene.nodes.iter().zip(&self.v))
            .map(|(n, v)| 0.5 * n.mass * v.norm_squared())
            .sum();
        let elastic: f64 = (scene.springs.iter())
            .map(|s| 0.5 * s.coefficient * stretch(scene, s, &self.x).0.powi(2))
            .sum();
        let balance = kinetic + elastic + self.viscous - self.work - self.initial_energy;
        row.extend([kinetic, elastic, self.viscous, self.work, balance]);
        Ok(row)
    }
}

/// The force on every node from the springs, dashpots and loads, and the power the dashpots
/// dissipate.
fn forces(scene: &Scene, x: &[Vector3<f64>], v: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, f64) {
    let mut f = vec![Vector3::zeros(); x.len()];
    for l in &scene.loads {
        f[l.node] += l.force;
    }
    let mut apply = |e: &Element, magnitude: f64| {
        let (_, direction, (a, b)) = stretch(scene, e, x);
        f[b] -= magnitude * direction;
        if let Some(a) = a {
            f[a] += magnitude * direction;
        }
    };
    for s in &scene.springs {
        apply(s, s.coefficient * stretch(scene, s, x).0);
    }
    let mut dissipation = 0.0;
    for d in &scene.dashpots {
        let (_, direction, (a, b)) = stretch(scene, d, x);
        let rate = (v[b] - a.map_or(Vector3::zeros(), |a| v[a])).dot(&direction);
        apply(d, d.coefficient * rate);
        dissipation += d.coefficient * rate * rate;
    }
    (f, dissipation)
}

/// An element's elongation, the direction it acts along, and its nodes (the first `None` for
/// a grounded one).
fn stretch(scene: &Scene, e: &Element, x: &[Vector3<f64>]) -> (f64, Vector3<f64>, Nodes) {
    let displacement = |n: usize| x[n] - scene.nodes[n].position;
    match &e.connection {
        Connection::Grounded { node, dof } => {
            let d = scene.nodes[*node].frame.column(dof.axis()).into_owned();
            (displacement(*node).dot(&d), d, (None, *node))
        }
        Connection::FixedDirection {
            nodes: [a, b],
            direction,
        } => {
            let elongation = (displacement(*b) - displacement(*a)).dot(direction);
            (elongation, *direction, (Some(*a), *b))
        }
        Connection::Axial { nodes: [a, b] } => {
            let now = x[*b] - x[*a];
            let rest = (scene.nodes[*b].position - scene.nodes[*a].position).norm();
            (now.norm() - rest, now.normalize(), (Some(*a), *b))
        }
    }
}

/// The two nodes of an element: the first `None` for a grounded one.
type Nodes = (Option<usize>, usize);
