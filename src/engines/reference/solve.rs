//! One whole solution at one relative tolerance ([`solve`]): the steps in order, each static
//! one solved for its equilibrium, each dynamic one integrated leg by leg ([`Leg`]) from row to
//! row, its contact events located ([`Leg::first_event`]) and resolved (impacts, openings,
//! and the friction's stops, sticks and slips, [`settle`]) where they happen.

mod settle;

use super::leg::{Leg, free_velocity, gaps_at};
use super::mechanism::{Grip, Mechanism, Placement, twist};
use super::{ContactEvent, Solution};
use crate::contract::{IMPACTS_COLUMN, VALID_COLUMN};
use crate::engines::{EngineError, History};
use crate::scene::{Column, Probe, Scene, Step, StepKind};
use nalgebra::{DMatrix, DVector, Vector3};

/// Legs per output interval. Events are looked for after every accepted integration step, and
/// no step is longer than its leg, so an excursion through a surface shorter than a quarter of
/// an interval can still be missed only if it begins and ends inside one step.
const EVENT_CHECKS_PER_ROW: usize = 4;

/// Most passes of impulses over the pairs that strike at one instant.
const MAX_IMPACT_PASSES: usize = 1000;

/// Below this fraction of the largest approach speed met so far, an impact is taken as
/// plastic: a bouncing node's impacts accumulate (their times form a geometric series), and
/// this ends the series where what is left of it is below the integration's tolerance.
pub(super) const RESTING_SPEED: f64 = 1e-6;

/// Open every closed pair that pulls (negative force) at `y`, and let it go without an
/// impulse (and without a grip).
fn release(
    mechanism: &Mechanism,
    basis: &DMatrix<f64>,
    (active, grips): (&mut [bool], &mut [Grip]),
    y: &ode_solvers::DVector<f64>,
    time: f64,
    events: &mut Vec<ContactEvent>,
) -> Result<(), EngineError> {
    let at = mechanism.unpack(y.as_slice());
    let w = free_velocity(mechanism, basis, y);
    let e = mechanism.evaluate(&at, basis, &w, active, grips, time)?;
    for (k, (closed, force)) in active.iter_mut().zip(&e.contact).enumerate() {
        if *closed && *force < 0.0 {
            *closed = false;
            grips[k] = Grip::Free;
            events.push(ContactEvent::Opening { contact: k, time });
        }
    }
    Ok(())
}

/// An error met after the integration started is the run's failure at time `t`, not a scene
/// the reference does not solve: the matrix that turns singular mid-run (two contacts that fix
/// the same motion, say) was regular at the start.
fn during(t: f64) -> impl Fn(EngineError) -> EngineError {
    move |e| match e {
        EngineError::Unsupported(what) => EngineError::Failed(format!("{what} (at t = {t:e})")),
        other => other,
    }
}

/// Newton's method on the equilibrium of the free DOFs of a static step, under the loads at
/// time `t`.
fn equilibrium(
    mechanism: &Mechanism,
    basis: &DMatrix<f64>,
    at: &mut Placement,
    (length, t): (f64, f64),
) -> Result<(), EngineError> {
    let nf = basis.ncols();
    if nf == 0 {
        return Ok(());
    }
    if mechanism.contact_count() > 0 {
        return Err(EngineError::Unsupported(
            "reference: a static step with free DOFs and contact".into(),
        ));
    }
    let still = DVector::zeros(mechanism.velocity_len());
    let residual = |p: &Placement| -> Result<DVector<f64>, EngineError> {
        Ok(basis.transpose() * mechanism.applied(p, &still, t)?)
    };
    let displaced = |p: &Placement, d: &DVector<f64>| {
        let du = basis * d;
        let mut q = p.clone();
        let n = q.particles.len();
        for (i, x) in q.particles.iter_mut().enumerate() {
            *x += du.fixed_rows::<3>(3 * i);
        }
        for (b, (x, r)) in q.origins.iter_mut().zip(&mut q.orientations).enumerate() {
            let k = 3 * n + 6 * b;
            *x += du.fixed_rows::<3>(k);
            let turn: Vector3<f64> = du.fixed_rows::<3>(k + 3).into_owned();
            *r = nalgebra::UnitQuaternion::from_scaled_axis(turn) * *r;
        }
        q
    };
    let h = 1e-6 * length;
    for _ in 0..100 {
        let r = residual(at)?;
        let mut jacobian = DMatrix::zeros(nf, nf);
        for j in 0..nf {
            let mut d = DVector::zeros(nf);
            d[j] = h;
            let plus = residual(&displaced(at, &d))?;
            let minus = residual(&displaced(at, &(-&d)))?;
            jacobian.set_column(j, &((plus - minus) / (2.0 * h)));
        }
        let step = jacobian.lu().solve(&(-r)).ok_or_else(|| {
            EngineError::Unsupported(
                "reference: static step: the free DOFs are not restrained (singular stiffness)"
                    .into(),
            )
        })?;
        *at = displaced(at, &step);
        if step.amax() <= 1e-15 * length {
            return Ok(());
        }
    }
    Err(EngineError::Failed(
        "reference: static step: Newton's method did not converge in 100 iterations".into(),
    ))
}

/// The whole solution at one relative tolerance.
///
/// `max_step` is the largest integration step as a fraction of the output interval: 1 for the
/// solution, ½ for the check (otherwise, where one step per row already meets both tolerances,
/// halving the tolerance would retrace the same steps and prove nothing).
///
/// Contact is event-driven: between events the set of closed pairs is fixed; an open pair
/// whose gap reaches zero strikes (Newton's restitution law on the approach rate; plastic
/// impacts and resting approaches close it), a closed pair whose force reaches zero opens.
/// Each event's time is found by bisection on the integrated state to a few ulps.
pub(super) fn solve(
    scene: &Scene,
    mechanism: &Mechanism,
    rtol: f64,
    max_step: f64,
) -> Result<Solution, EngineError> {
    let mut solver = Solver::new(scene, mechanism);
    for step in &scene.steps {
        solver.step(step, rtol, max_step)?;
    }
    Ok(solver.finish())
}

/// The times of every load's amplitude table, in order, each once (none without amplitudes).
fn kinks(scene: &Scene) -> Vec<f64> {
    let mut kinks: Vec<f64> = scene
        .loads
        .iter()
        .filter_map(|l| l.amplitude.as_ref())
        .flat_map(|a| a.points.iter().map(|(t, _)| *t))
        .collect();
    kinks.sort_by(f64::total_cmp);
    kinks.dedup();
    kinks
}

/// The state of a solution between steps and rows.
struct Solver<'a> {
    scene: &'a Scene,
    mechanism: &'a Mechanism,
    /// The output times.
    times: Vec<f64>,
    /// The times where a load's amplitude changes slope (its table's times), in order: the
    /// integration stops there too, so that no step straddles a kink of the force.
    kinks: Vec<f64>,
    /// Two times closer than this are the same (a row on a step's boundary).
    tol: f64,
    /// A leg's length: a fraction of the output interval ([`EVENT_CHECKS_PER_ROW`]); the last
    /// leg to a target within 1.5 of it goes there in one.
    check: f64,
    /// The scene's largest coordinate (the static steps' length scale).
    length: f64,
    /// The placement at the start of the next step.
    at: Placement,
    /// The full velocity there.
    u: DVector<f64>,
    /// Which contact pairs are closed.
    active: Vec<bool>,
    /// The closed pairs' friction states (every one [`Grip::Free`] without friction).
    grips: Vec<Grip>,
    /// The energy friction has dissipated by the start of the next step.
    dissipation: f64,
    /// The contact events so far, in time order.
    events: Vec<ContactEvent>,
    /// The fastest approach met so far (resting impacts are judged against it).
    fastest: f64,
    /// The start of the next step.
    t0: f64,
    /// The next output row.
    next: usize,
    /// Dynamic steps begun (the initial velocity is taken at the first).
    dynamic_index: usize,
    /// Dynamic steps in the scene (the last reports every output time left).
    dynamic_count: usize,
    /// The rows written.
    rows: Vec<Vec<f64>>,
    /// The first pair's contact force at each row.
    contact_history: Vec<f64>,
    /// Each rotation column's last value (rotations are unwrapped row to row).
    previous_rotation: Vec<f64>,
    /// The largest departure of a closed pair's gap from zero at a row.
    drift: f64,
    /// Accepted integration steps.
    steps: u64,
    /// Evaluations of the equations of motion.
    evaluations: u64,
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene, mechanism: &'a Mechanism) -> Self {
        let times = scene.output_times();
        let duration = scene.duration();
        let interval = duration / (times.len() - 1).max(1) as f64;
        let length = scene
            .nodes
            .iter()
            .fold(1.0_f64, |m, n| m.max(n.position.amax()));
        Solver {
            scene,
            mechanism,
            tol: 1e-12 * duration.max(f64::MIN_POSITIVE),
            check: interval / EVENT_CHECKS_PER_ROW as f64,
            length,
            at: mechanism.initial_placement(),
            u: DVector::zeros(mechanism.velocity_len()),
            active: mechanism.initially_closed(),
            grips: vec![Grip::Free; mechanism.contact_count()],
            dissipation: 0.0,
            events: Vec::new(),
            fastest: 0.0,
            t0: 0.0,
            next: 0,
            dynamic_index: 0,
            dynamic_count: scene
                .steps
                .iter()
                .filter(|s| matches!(s.kind, StepKind::Dynamic { .. }))
                .count(),
            rows: Vec::with_capacity(times.len()),
            contact_history: Vec::with_capacity(times.len()),
            previous_rotation: vec![0.0; scene.columns.len()],
            drift: 0.0,
            steps: 0,
            evaluations: 0,
            times,
            kinks: kinks(scene),
        }
    }

    /// One step: a static one's equilibrium, or a dynamic one integrated to its end with
    /// its rows written.
    fn step(&mut self, step: &Step, rtol: f64, max_step: f64) -> Result<(), EngineError> {
        let (m, t0) = (self.mechanism, self.t0);
        // What fails at the first step is a scene the reference does not solve; what fails at
        // a later one is this run's failure at that step's start.
        let started = |e| if t0 > 0.0 { during(t0)(e) } else { e };
        let basis = m.free_basis(step).map_err(started)?;
        m.prescribe(step, &mut self.at);
        let duration = match step.kind {
            StepKind::Static => {
                let scales = (self.length, t0);
                return equilibrium(m, &basis, &mut self.at, scales).map_err(started);
            }
            StepKind::Dynamic { duration } => duration,
        };
        if self.dynamic_index == 0 {
            self.first_motion(&basis);
        }
        let w = m
            .admissible(&self.at, &basis, &self.u, (&self.active, &self.grips))
            .map_err(started)?;
        let np = m.position_len();
        let nf = w.len();
        let (friction, ramps) = (m.has_friction(), m.varies_in_time());
        let len = np + nf + usize::from(friction) + usize::from(ramps);
        let mut y = ode_solvers::DVector::zeros(len);
        m.pack(&self.at, &mut y.as_mut_slice()[..np]);
        y.as_mut_slice()[np..np + nf].copy_from_slice(w.as_slice());
        if friction {
            y[np + nf] = self.dissipation;
        }
        if ramps {
            y[len - 1] = t0;
        }
        let closed = (self.active.as_mut_slice(), self.grips.as_mut_slice());
        release(m, &basis, closed, &y, t0, &mut self.events).map_err(started)?;
        self.settle(&basis, &mut y, t0, None).map_err(started)?;
        let mut leg = Leg {
            mechanism: m,
            basis: &basis,
            rtol,
            max_step,
            steps: 0,
            evaluations: 0,
        };
        self.dynamic_index += 1;
        let end = t0 + duration;
        let mut t = t0;
        while let Some((target, output)) = self.next_target(t, end) {
            (t, y) = self.advance(&mut leg, t, y, target)?;
            if output {
                self.write_row(&basis, &y, target)?;
            }
        }
        self.steps += leg.steps;
        self.evaluations += leg.evaluations;
        self.at = m.unpack(y.as_slice());
        self.u = &basis * free_velocity(m, &basis, &y);
        if friction {
            self.dissipation = y[np + nf];
        }
        self.t0 = end;
        Ok(())
    }

    /// The initial velocity, taken at the first dynamic step; a pair closed at t = 0 whose
    /// node already moves away from the surface opens.
    fn first_motion(&mut self, basis: &DMatrix<f64>) {
        let m = self.mechanism;
        self.u = m.initial_velocity(self.scene);
        let w = basis.transpose() * &self.u;
        let full = basis * &w;
        for (k, a) in self.active.iter_mut().enumerate() {
            let scale = full.amax().max(f64::MIN_POSITIVE);
            if *a && m.gap_rate(&self.at, &full, k) > 1e-12 * scale {
                *a = false;
                self.events.push(ContactEvent::Opening {
                    contact: k,
                    time: self.t0,
                });
            }
        }
    }

    /// Where the step integrating from `t` to `end` goes next, and whether it writes a row
    /// there: the step reports the output times up to its end (the last step: all the rest);
    /// a time on a boundary belongs to the later step. A step that another dynamic step
    /// follows is integrated past its last row to its end, where the next one starts. An
    /// amplitude's kink before that is a target of its own, without a row.
    fn next_target(&self, t: f64, end: f64) -> Option<(f64, bool)> {
        let last = self.dynamic_index == self.dynamic_count;
        let times = &self.times;
        let target = if self.next < times.len() && (last || times[self.next] < end - self.tol) {
            (times[self.next], true)
        } else if !last && t < end - self.tol {
            (end, false)
        } else {
            return None;
        };
        let i = self.kinks.partition_point(|k| *k <= t + self.tol);
        match self.kinks.get(i) {
            Some(&kink) if kink < target.0 - self.tol => Some((kink, false)),
            _ => Some(target),
        }
    }

    /// Integrate from `(t, y)` to `target` in legs of [`Self::check`] (the last within 1.5 of
    /// it in one), each event on the way located and resolved.
    fn advance(
        &mut self,
        leg: &mut Leg,
        mut t: f64,
        mut y: ode_solvers::DVector<f64>,
        target: f64,
    ) -> Result<(f64, ode_solvers::DVector<f64>), EngineError> {
        let (m, basis) = (self.mechanism, leg.basis);
        while target > t + self.tol {
            let to = if target - t > 1.5 * self.check {
                t + self.check
            } else {
                target
            };
            let closed = (self.active.as_slice(), self.grips.as_slice());
            let mut reach = leg.run(closed, t, &y, to).map_err(during(t))?;
            if !reach.event {
                (t, y, self.grips) = (to, reach.state, reach.tracking.grips);
                continue;
            }
            reach = leg.first_event(closed, t, &y, reach).map_err(during(t))?;
            (t, y, self.grips) = (reach.time, reach.state, reach.tracking.grips);
            let w = self.strike(basis, t, &y)?;
            let np = m.position_len();
            y.as_mut_slice()[np..np + w.len()].copy_from_slice(w.as_slice());
            let closed = (self.active.as_mut_slice(), self.grips.as_mut_slice());
            release(m, basis, closed, &y, t, &mut self.events).map_err(during(t))?;
            let stopped = Some(reach.tracking.stopped.as_slice());
            self.settle(basis, &mut y, t, stopped).map_err(during(t))?;
            if t >= target - self.tol {
                t = target;
            }
        }
        Ok((t, y))
    }

    /// The impacts at time `t` (state `y`): the free velocities after them. Simultaneous
    /// impacts: one pair's impulse can make another close again, so the impulses are repeated
    /// until no open pair inside closes (sequential impulses, each at most elastic; a pair
    /// closing slower than [`RESTING_SPEED`] of the fastest rests).
    fn strike(
        &mut self,
        basis: &DMatrix<f64>,
        t: f64,
        y: &ode_solvers::DVector<f64>,
    ) -> Result<DVector<f64>, EngineError> {
        let m = self.mechanism;
        let (placed, mut w, _, gaps) = gaps_at(m, basis, &self.active, y);
        let mut struck: Vec<Option<usize>> = vec![None; self.active.len()];
        for _ in 0..MAX_IMPACT_PASSES {
            let mut any = false;
            for k in 0..self.active.len() {
                if self.active[k] || gaps[k] >= 0.0 {
                    continue;
                }
                let speed = -m.gap_rate(&placed, &(basis * &w), k);
                if speed <= 0.0 {
                    // Inside by round-off while leaving: the rebound of an earlier impact, or
                    // a graze that has already turned.
                    continue;
                }
                any = true;
                self.refuse_impact_with_friction(k, t)?;
                w = self.impact(k, speed, (&placed, basis, &w), &mut struck[k], t)?;
            }
            if !any {
                return Ok(w);
            }
        }
        Err(EngineError::Failed(format!(
            "reference: simultaneous impacts at t = {t:e} did not settle in \
             {MAX_IMPACT_PASSES} passes"
        )))
    }

    /// Pair `k` strikes at `speed`: the free velocities after its impulse. Struck again in a
    /// later pass, it is one impact, its rebound the last.
    fn impact(
        &mut self,
        k: usize,
        speed: f64,
        (placed, basis, w): (&Placement, &DMatrix<f64>, &DVector<f64>),
        struck: &mut Option<usize>,
        t: f64,
    ) -> Result<DVector<f64>, EngineError> {
        let m = self.mechanism;
        self.fastest = self.fastest.max(speed);
        let e = m.restitution(k);
        let rests = e == 0.0 || speed <= RESTING_SPEED * self.fastest;
        let restitution = if rests { 0.0 } else { e };
        let w = m
            .impact(
                placed,
                basis,
                w,
                (&self.active, &self.grips),
                Some((k, restitution)),
            )
            .map_err(during(t))?;
        let rebound = m.gap_rate(placed, &(basis * &w), k);
        match *struck {
            Some(i) => {
                if let ContactEvent::Impact { rebound: r, .. } = &mut self.events[i] {
                    *r = rebound;
                }
            }
            None => {
                *struck = Some(self.events.len());
                self.events.push(ContactEvent::Impact {
                    contact: k,
                    time: t,
                    speed,
                    rebound,
                });
            }
        }
        if rests {
            self.active[k] = true;
        }
        Ok(w)
    }

    /// The row at output time `target` (state `y`), with the closed pairs' drift and the
    /// first pair's contact force.
    fn write_row(
        &mut self,
        basis: &DMatrix<f64>,
        y: &ode_solvers::DVector<f64>,
        target: f64,
    ) -> Result<(), EngineError> {
        let m = self.mechanism;
        let at = m.unpack(y.as_slice());
        let w = free_velocity(m, basis, y);
        let full = basis * &w;
        let evaluation = m
            .evaluate(&at, basis, &w, &self.active, &self.grips, target)
            .map_err(during(target))?;
        let (gaps, _, _) = m.constraints(&at, &full, &self.active, &[]);
        self.drift = gaps
            .iter()
            .zip(&self.active)
            .filter(|(_, a)| **a)
            .fold(self.drift, |d, (g, _)| d.max(g.abs()));
        let contact = &evaluation.contact;
        self.contact_history
            .push(contact.first().copied().unwrap_or(0.0));
        let mut row = Vec::with_capacity(self.scene.columns.len() + 2);
        row.push(target);
        for (ci, column) in self.scene.columns.iter().enumerate() {
            row.push(self.probe(ci, column, &at, &full, contact));
        }
        if m.contact_count() > 0 {
            let impacts = self.events.iter();
            let impacts = impacts.filter(|e| matches!(e, ContactEvent::Impact { .. }));
            row.push(impacts.count() as f64);
        }
        // Exact through every contact event: every row is valid.
        row.push(1.0);
        if row.iter().any(|x| !x.is_finite()) {
            return Err(EngineError::Failed(format!(
                "reference: a non-finite value at t = {target:e}"
            )));
        }
        self.rows.push(row);
        self.next += 1;
        Ok(())
    }

    /// Column `ci`'s value at placement `at`, full velocity `full` and contact forces
    /// `contact` (a rotation unwrapped against the column's last value).
    fn probe(
        &mut self,
        ci: usize,
        column: &Column,
        at: &Placement,
        full: &DVector<f64>,
        contact: &[f64],
    ) -> f64 {
        let (m, scene) = (self.mechanism, self.scene);
        match &column.probe {
            Probe::Displacement { node, direction } => {
                direction.dot(&(m.position(at, *node) - scene.nodes[*node].position))
            }
            Probe::Velocity { node, direction } => direction.dot(&m.velocity(at, full, *node)),
            Probe::Rotation { body, axis } => {
                let raw = twist(&at.orientations[*body], axis);
                let turns = ((self.previous_rotation[ci] - raw) / std::f64::consts::TAU).round();
                let unwrapped = raw + turns * std::f64::consts::TAU;
                self.previous_rotation[ci] = unwrapped;
                unwrapped
            }
            Probe::ContactForce { contact: k } => contact[*k],
            Probe::Gap { contact } => m.distance(at, *contact),
            Probe::Zero { .. } => 0.0,
        }
    }

    /// The solution: its history with the columns named, and what the run measured.
    fn finish(self) -> Solution {
        let contact = self.mechanism.contact_count() > 0;
        let columns = std::iter::once("t".to_string())
            .chain(self.scene.columns.iter().map(|c| c.name.clone()))
            .chain(contact.then(|| IMPACTS_COLUMN.to_string()))
            .chain(std::iter::once(VALID_COLUMN.to_string()))
            .collect();
        Solution {
            history: History {
                columns,
                rows: self.rows,
            },
            contact: self.contact_history,
            drift: self.drift,
            steps: self.steps,
            evaluations: self.evaluations,
            events: self.events,
            dissipation: self.mechanism.has_friction().then_some(self.dissipation),
        }
    }
}
