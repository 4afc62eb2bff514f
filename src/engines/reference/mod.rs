//! `reference`: the converged solution of each case's own finite-rotation model, the one the
//! finite-rotation engines approximate as the increment goes to 0 and the penalty stiffness to
//! infinity: finite rotation, rigid contact (a closed pair's node slaved to the turning
//! surface), every other element as the scene says.
//!
//! The equations ([`mechanism`]) are written from Newton–Euler's laws with each closed contact
//! as a constraint solved with its multiplier at every evaluation, independently of the
//! explicit engine's force assembly, and integrated by Dormand–Prince 8(5,3) with error control
//! (`ode_solvers::Dop853`) at a relative tolerance of [`TOLERANCE`], restarted at every output
//! time so no row is interpolated, and at the end of every dynamic step another follows. The
//! whole solution is computed twice, the second time at half the tolerance and with steps of at most half an output interval (so it takes another
//! path even where one step per row meets both tolerances); the largest change of any column
//! over its peak is reported as the measure `tolerance_halving_change` (summary.json), with
//! `constraint_drift` (the largest departure of a closed contact's gap from zero, in length
//! units).
//!
//! Contact is event-driven and exact through every switch: an open pair whose gap reaches zero
//! while closing strikes (Newton's restitution law, the impulse through the mass matrix), a
//! closed pair whose force reaches zero opens. Events are watched after every accepted
//! integration step and located by bisection; they are reported as measures (`impact_<i>_time`,
//! `impact_<i>_speed`, `impact_<i>_rebound`, `opening_<i>_time`, `impacts`, `openings`), with
//! the contact force's smallest margin over its largest (`contact_margin`) and an `impacts`
//! column. Every row is valid.
//!
//! Static steps set the prescribed DOFs and solve the equilibrium of the free ones by Newton's
//! method (a finite-difference Jacobian; the converged point does not depend on it). Not
//! solved (refused with a reason): a contact node that is a body point, a held DOF on a body
//! point other than the reference node, a static step with both free DOFs and contact, a free
//! DOF without mass. A matrix that turns singular during the run (two contacts that fix the
//! same motion, say) fails the run with its time.

pub mod mechanism;

use super::{Engine, EngineError, History, RunInfo, RunOutput, RunSettings};
use crate::contract::{IMPACTS_COLUMN, IMPACTS_REPORTED, VALID_COLUMN};
use crate::scene::{Probe, Scene, StepKind};
use mechanism::{Mechanism, Placement, twist};
use nalgebra::{DMatrix, DVector, Vector3};
use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::time::Instant;

/// Relative tolerance of the integration (the absolute one is this × 10^-3).
pub const TOLERANCE: f64 = 1e-12;

/// Most integration steps between two output rows (each run is bounded in time).
const MAX_STEPS_PER_ROW: u32 = 1_000_000;

/// The converged finite-rotation reference.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReferenceEngine;

/// One solution at one tolerance.
struct Solution {
    history: History,
    contact: Vec<f64>,
    drift: f64,
    steps: u64,
    evaluations: u64,
    events: Vec<ContactEvent>,
}

impl Engine for ReferenceEngine {
    fn name(&self) -> &str {
        "reference"
    }

    fn run(&self, scene: &Scene, _settings: &RunSettings) -> Result<RunOutput, EngineError> {
        let start = Instant::now();
        let mechanism = Mechanism::new(scene)?;
        let fine = solve(scene, &mechanism, TOLERANCE, 1.0)?;
        let finer = solve(scene, &mechanism, TOLERANCE / 2.0, 0.5)?;
        let mut measures = BTreeMap::new();
        measures.insert(
            "tolerance_halving_change".into(),
            largest_change(&fine.history, &finer.history),
        );
        if mechanism.contact_count() > 0 {
            measures.insert("constraint_drift".into(), fine.drift);
            let valid = valid_rows(&fine.history);
            let forces: Vec<f64> = fine.contact.iter().take(valid).copied().collect();
            let largest = forces.iter().fold(0.0_f64, |a, f| a.max(*f));
            let smallest = forces.iter().fold(f64::INFINITY, |a, f| a.min(*f));
            measures.insert("initial_contact_force".into(), fine.contact[0]);
            if largest > 0.0 {
                measures.insert("contact_margin".into(), smallest / largest);
            }
            if valid < fine.history.rows.len() {
                measures.insert("valid_until".into(), fine.history.rows[valid][0]);
            }
            let mut impacts = 0;
            let mut openings = 0;
            for event in &fine.events {
                match *event {
                    ContactEvent::Impact {
                        time,
                        speed,
                        rebound,
                        ..
                    } => {
                        impacts += 1;
                        if impacts <= IMPACTS_REPORTED {
                            measures.insert(format!("impact_{impacts}_time"), time);
                            measures.insert(format!("impact_{impacts}_speed"), speed);
                            measures.insert(format!("impact_{impacts}_rebound"), rebound);
                        }
                    }
                    ContactEvent::Opening { time, .. } => {
                        openings += 1;
                        if openings <= IMPACTS_REPORTED {
                            measures.insert(format!("opening_{openings}_time"), time);
                        }
                    }
                }
            }
            measures.insert("impacts".into(), impacts as f64);
            measures.insert("openings".into(), openings as f64);
        }
        let mut counters = BTreeMap::new();
        counters.insert("integration_steps".into(), fine.steps);
        counters.insert("evaluations".into(), fine.evaluations);
        Ok(RunOutput {
            engine: self.name().into(),
            history: fine.history,
            info: RunInfo {
                increment: 0.0,
                steps: fine.steps,
                stable_increment: None,
                penalty_stiffness: None,
                wall_seconds: start.elapsed().as_secs_f64(),
                counters,
                measures,
            },
        })
    }
}

/// Rows before the first invalid one.
fn valid_rows(history: &History) -> usize {
    let column = history.columns.len() - 1;
    history
        .rows
        .iter()
        .position(|r| r[column] == 0.0)
        .unwrap_or(history.rows.len())
}

/// The largest change of any column between two histories, over that column's peak.
fn largest_change(a: &History, b: &History) -> f64 {
    let mut largest = 0.0_f64;
    for c in 1..a.columns.len() - 1 {
        if a.columns[c] == IMPACTS_COLUMN {
            continue;
        }
        let peak = a.rows.iter().fold(0.0_f64, |m, r| m.max(r[c].abs()));
        if peak == 0.0 {
            continue;
        }
        let change = a
            .rows
            .iter()
            .zip(&b.rows)
            .fold(0.0_f64, |m, (x, y)| m.max((x[c] - y[c]).abs()));
        largest = largest.max(change / peak);
    }
    largest
}

/// The equations for the ODE solver over one dynamic step (fixed free basis) with a fixed
/// set of closed contacts; after every accepted step it looks for a contact event and stops
/// the integration there if one has happened.
struct Motion<'a> {
    mechanism: &'a Mechanism,
    basis: &'a DMatrix<f64>,
    active: &'a [bool],
    inside: &'a [bool],
    error: &'a RefCell<Option<EngineError>>,
    fired: &'a Cell<bool>,
}

impl ode_solvers::System<f64, ode_solvers::DVector<f64>> for Motion<'_> {
    fn system(&self, _t: f64, y: &ode_solvers::DVector<f64>, dy: &mut ode_solvers::DVector<f64>) {
        let m = self.mechanism;
        let np = m.position_len();
        let at = m.unpack(y.as_slice());
        let w = DVector::from_column_slice(&y.as_slice()[np..]);
        match m.evaluate(&at, self.basis, &w, self.active) {
            Ok(e) => {
                let u = self.basis * &w;
                m.position_rate(&at, &u, &mut dy.as_mut_slice()[..np]);
                dy.as_mut_slice()[np..].copy_from_slice(e.acceleration.as_slice());
            }
            Err(e) => {
                dy.fill(0.0);
                self.error.borrow_mut().get_or_insert(e);
            }
        }
    }

    fn solout(
        &mut self,
        _t: f64,
        y: &ode_solvers::DVector<f64>,
        _dy: &ode_solvers::DVector<f64>,
    ) -> bool {
        if self.error.borrow().is_some() {
            return true;
        }
        match fired(self.mechanism, self.basis, self.active, self.inside, y) {
            Ok(true) => {
                self.fired.set(true);
                true
            }
            Ok(false) => false,
            Err(e) => {
                self.error.borrow_mut().get_or_insert(e);
                true
            }
        }
    }
}

/// Whether a contact event has happened by state `y`: an open pair's gap below zero, or a
/// closed pair's force below zero. A pair that was `inside` at the leg's start (it has just
/// rebounded, or just opened, and sits a few ulps inside while it leaves) strikes only while it
/// closes (ġ < 0); any other pair strikes once its gap is below zero, so that a grazing impact
/// caught only after the gap turned again is still found.
fn fired(
    mechanism: &Mechanism,
    basis: &DMatrix<f64>,
    active: &[bool],
    inside: &[bool],
    y: &ode_solvers::DVector<f64>,
) -> Result<bool, EngineError> {
    let m = mechanism;
    if m.contact_count() == 0 {
        return Ok(false);
    }
    let (at, w, u, gaps) = gaps_at(m, basis, active, y);
    let striking = (0..active.len())
        .any(|k| !active[k] && gaps[k] < 0.0 && (!inside[k] || m.gap_rate(&at, &u, k) < 0.0));
    if striking {
        return Ok(true);
    }
    if active.iter().any(|a| *a) {
        let e = m.evaluate(&at, basis, &w, active)?;
        return Ok(e.contact.iter().zip(active).any(|(f, a)| *a && *f < 0.0));
    }
    Ok(false)
}

/// The placement, free velocities, full velocity and every pair's gap at state `y`.
fn gaps_at(
    m: &Mechanism,
    basis: &DMatrix<f64>,
    active: &[bool],
    y: &ode_solvers::DVector<f64>,
) -> (Placement, DVector<f64>, DVector<f64>, Vec<f64>) {
    let at = m.unpack(y.as_slice());
    let w = DVector::from_column_slice(&y.as_slice()[m.position_len()..]);
    let u = basis * &w;
    let (gaps, _, _) = m.constraints(&at, &u, active);
    (at, w, u, gaps)
}

/// Legs per output interval. Events are looked for after every accepted integration step, and
/// no step is longer than its leg, so an excursion through a surface shorter than a quarter of
/// an interval can still be missed only if it begins and ends inside one step.
const EVENT_CHECKS_PER_ROW: usize = 4;

/// Most passes of impulses over the pairs that strike at one instant.
const MAX_IMPACT_PASSES: usize = 1000;

/// Below this fraction of the largest approach speed met so far, an impact is taken as
/// plastic: a bouncing node's impacts accumulate (their times form a geometric series), and
/// this ends the series where what is left of it is below the integration's tolerance.
const RESTING_SPEED: f64 = 1e-6;

/// What happened to a contact pair, and when.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactEvent {
    /// The gap reached zero: an impact with this approach speed, after which the contact
    /// closed (plastic, or an approach below [`RESTING_SPEED`]) or rebounded.
    Impact {
        /// Pair index.
        contact: usize,
        /// Time.
        time: f64,
        /// Approach speed −ġ before the impact.
        speed: f64,
        /// Separation speed ġ after it.
        rebound: f64,
    },
    /// The contact force reached zero: the pair opened.
    Opening {
        /// Pair index.
        contact: usize,
        /// Time.
        time: f64,
    },
}

/// One integration from `(t, y)` to `to` with the closed set `active`.
struct Leg<'a> {
    mechanism: &'a Mechanism,
    basis: &'a DMatrix<f64>,
    rtol: f64,
    max_step: f64,
    steps: u64,
    evaluations: u64,
}

impl Leg<'_> {
    /// The open pairs whose gap is below zero at `y`.
    fn inside(&self, active: &[bool], y: &ode_solvers::DVector<f64>) -> Vec<bool> {
        if self.mechanism.contact_count() == 0 {
            return Vec::new();
        }
        let (_, _, _, gaps) = gaps_at(self.mechanism, self.basis, active, y);
        (0..active.len())
            .map(|k| !active[k] && gaps[k] < 0.0)
            .collect()
    }

    /// Integrates from `(t, y)` towards `to` and returns where it stopped: at `to`, or at the
    /// end of the first accepted step by which a contact event has happened (then `true`).
    fn run(
        &mut self,
        active: &[bool],
        t: f64,
        y: &ode_solvers::DVector<f64>,
        to: f64,
    ) -> Result<(f64, ode_solvers::DVector<f64>, bool), EngineError> {
        let failure = RefCell::new(None);
        let fired = Cell::new(false);
        let inside = self.inside(active, y);
        let motion = Motion {
            mechanism: self.mechanism,
            basis: self.basis,
            active,
            inside: &inside,
            error: &failure,
            fired: &fired,
        };
        let mut stepper = ode_solvers::Dop853::from_param(
            motion,
            t,
            to,
            to - t,
            y.clone(),
            self.rtol,
            self.rtol * 1e-3,
            0.9,
            0.0,
            0.333,
            6.0,
            (to - t) * self.max_step,
            0.0,
            MAX_STEPS_PER_ROW,
            1000,
            ode_solvers::dop_shared::OutputType::Sparse,
        );
        let stats = stepper
            .integrate()
            .map_err(|e| EngineError::Failed(format!("reference: integration to t = {to:e}: {e}")));
        if let Some(e) = failure.take() {
            return Err(e);
        }
        let stats = stats?;
        self.steps += u64::from(stats.accepted_steps);
        self.evaluations += u64::from(stats.num_eval);
        let reached = *stepper.x_out().last().expect("the end time");
        let state = stepper.y_out().last().expect("the end state").clone();
        Ok((reached, state, fired.get()))
    }
}

/// Open every closed pair that pulls (negative force) at `y`, and let it go without an
/// impulse.
fn release(
    mechanism: &Mechanism,
    basis: &DMatrix<f64>,
    active: &mut [bool],
    y: &ode_solvers::DVector<f64>,
    time: f64,
    events: &mut Vec<ContactEvent>,
) -> Result<(), EngineError> {
    let np = mechanism.position_len();
    let at = mechanism.unpack(y.as_slice());
    let w = DVector::from_column_slice(&y.as_slice()[np..]);
    let e = mechanism.evaluate(&at, basis, &w, active)?;
    for (k, (closed, force)) in active.iter_mut().zip(&e.contact).enumerate() {
        if *closed && *force < 0.0 {
            *closed = false;
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

/// Newton's method on the equilibrium of the free DOFs of a static step.
fn equilibrium(
    mechanism: &Mechanism,
    basis: &DMatrix<f64>,
    at: &mut Placement,
    length: f64,
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
        Ok(basis.transpose() * mechanism.applied(p, &still)?)
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
fn solve(
    scene: &Scene,
    mechanism: &Mechanism,
    rtol: f64,
    max_step: f64,
) -> Result<Solution, EngineError> {
    let times = scene.output_times();
    let duration = scene.duration();
    let tol = 1e-12 * duration.max(f64::MIN_POSITIVE);
    let interval = duration / (times.len() - 1).max(1) as f64;
    let length = scene
        .nodes
        .iter()
        .fold(1.0_f64, |m, n| m.max(n.position.amax()));
    let mut at = mechanism.initial_placement();
    let mut u = DVector::zeros(mechanism.velocity_len());
    let mut active = mechanism.initially_closed();
    let mut events: Vec<ContactEvent> = Vec::new();
    let mut fastest = 0.0_f64;
    let mut first_dynamic = true;
    let mut t0 = 0.0;
    let mut next = 0;
    let mut rows: Vec<Vec<f64>> = Vec::with_capacity(times.len());
    let mut contact_history = Vec::with_capacity(times.len());
    let mut previous_rotation = vec![0.0; scene.columns.len()];
    let mut drift = 0.0_f64;
    let (mut steps, mut evaluations) = (0_u64, 0_u64);
    let dynamic_count = scene
        .steps
        .iter()
        .filter(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .count();
    let mut dynamic_index = 0;
    let np = mechanism.position_len();
    for step in &scene.steps {
        // What fails at the first step is a scene the reference does not solve; what fails at
        // a later one is this run's failure at that step's start.
        let started = |e| if t0 > 0.0 { during(t0)(e) } else { e };
        let basis = mechanism.free_basis(step).map_err(started)?;
        mechanism.prescribe(step, &mut at);
        let duration = match step.kind {
            StepKind::Static => {
                equilibrium(mechanism, &basis, &mut at, length).map_err(started)?;
                continue;
            }
            StepKind::Dynamic { duration } => duration,
        };
        if first_dynamic {
            u = mechanism.initial_velocity(scene);
            first_dynamic = false;
            // A pair closed at t = 0 whose node already moves away from the surface opens.
            let w = basis.transpose() * &u;
            let full = &basis * &w;
            for (k, a) in active.iter_mut().enumerate() {
                let scale = full.amax().max(f64::MIN_POSITIVE);
                if *a && mechanism.gap_rate(&at, &full, k) > 1e-12 * scale {
                    *a = false;
                    events.push(ContactEvent::Opening {
                        contact: k,
                        time: t0,
                    });
                }
            }
        }
        let mut w = mechanism
            .admissible(&at, &basis, &u, &active)
            .map_err(started)?;
        let mut y = ode_solvers::DVector::zeros(np + w.len());
        mechanism.pack(&at, &mut y.as_mut_slice()[..np]);
        y.as_mut_slice()[np..].copy_from_slice(w.as_slice());
        release(mechanism, &basis, &mut active, &y, t0, &mut events).map_err(started)?;
        let mut leg = Leg {
            mechanism,
            basis: &basis,
            rtol,
            max_step,
            steps: 0,
            evaluations: 0,
        };
        dynamic_index += 1;
        let end = t0 + duration;
        let mut t = t0;
        let check = interval / EVENT_CHECKS_PER_ROW as f64;
        // This step reports the output times up to its end (the last step: all the rest);
        // a time on a boundary belongs to the later step. A step that another dynamic step
        // follows is integrated past its last row to its end, where the next one starts.
        loop {
            let output =
                next < times.len() && (dynamic_index == dynamic_count || times[next] < end - tol);
            let target = if output {
                times[next]
            } else if dynamic_index < dynamic_count && t < end - tol {
                end
            } else {
                break;
            };
            while target > t + tol {
                let to = if target - t > 1.5 * check {
                    t + check
                } else {
                    target
                };
                let (stopped, reached, event) = leg.run(&active, t, &y, to).map_err(during(t))?;
                if !event {
                    (t, y) = (to, reached);
                    continue;
                }
                // Bisect for the first event: none by `lo`, one by `hi`.
                let (mut lo, mut hi, mut at_hi) = (t, stopped, reached);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    let (stopped, state, event) =
                        leg.run(&active, t, &y, mid).map_err(during(t))?;
                    if event {
                        if stopped < lo {
                            // The shorter integration took other steps and met the event
                            // before `lo`: the bracket restarts from the leg's start.
                            lo = t;
                        }
                        (hi, at_hi) = (stopped, state);
                    } else {
                        lo = mid;
                    }
                }
                t = hi;
                y = at_hi;
                let (placed, mut wv, _, gaps) = gaps_at(mechanism, &basis, &active, &y);
                // Simultaneous impacts: one pair's impulse can make another close again, so
                // the impulses are repeated until no open pair inside closes (sequential
                // impulses, each at most elastic; a pair closing slower than RESTING_SPEED of
                // the fastest rests).
                let mut struck: Vec<Option<usize>> = vec![None; active.len()];
                let mut settled = false;
                for _ in 0..MAX_IMPACT_PASSES {
                    let mut any = false;
                    for k in 0..active.len() {
                        if active[k] || gaps[k] >= 0.0 {
                            continue;
                        }
                        let speed = -mechanism.gap_rate(&placed, &(&basis * &wv), k);
                        if speed <= 0.0 {
                            // Inside by round-off while leaving: the rebound of an earlier
                            // impact, or a graze that has already turned.
                            continue;
                        }
                        any = true;
                        fastest = fastest.max(speed);
                        let e = mechanism.restitution(k);
                        let rests = e == 0.0 || speed <= RESTING_SPEED * fastest;
                        wv = mechanism
                            .impact(
                                &placed,
                                &basis,
                                &wv,
                                &active,
                                Some((k, if rests { 0.0 } else { e })),
                            )
                            .map_err(during(t))?;
                        let rebound = mechanism.gap_rate(&placed, &(&basis * &wv), k);
                        match struck[k] {
                            // A later pass strikes the pair again: one impact, its rebound
                            // the last.
                            Some(i) => {
                                if let ContactEvent::Impact { rebound: r, .. } = &mut events[i] {
                                    *r = rebound;
                                }
                            }
                            None => {
                                struck[k] = Some(events.len());
                                events.push(ContactEvent::Impact {
                                    contact: k,
                                    time: t,
                                    speed,
                                    rebound,
                                });
                            }
                        }
                        if rests {
                            active[k] = true;
                        }
                    }
                    if !any {
                        settled = true;
                        break;
                    }
                }
                if !settled {
                    return Err(EngineError::Failed(format!(
                        "reference: simultaneous impacts at t = {t:e} did not settle in \
                         {MAX_IMPACT_PASSES} passes"
                    )));
                }
                y.as_mut_slice()[np..].copy_from_slice(wv.as_slice());
                release(mechanism, &basis, &mut active, &y, t, &mut events).map_err(during(t))?;
                if t >= target - tol {
                    t = target;
                }
            }
            if !output {
                continue;
            }
            at = mechanism.unpack(y.as_slice());
            w = DVector::from_column_slice(&y.as_slice()[np..]);
            let full = &basis * &w;
            let evaluation = mechanism
                .evaluate(&at, &basis, &w, &active)
                .map_err(during(target))?;
            let (gaps, _, _) = mechanism.constraints(&at, &full, &active);
            drift = gaps
                .iter()
                .zip(&active)
                .filter(|(_, a)| **a)
                .fold(drift, |m, (g, _)| m.max(g.abs()));
            contact_history.push(evaluation.contact.first().copied().unwrap_or(0.0));
            let mut row = Vec::with_capacity(scene.columns.len() + 2);
            row.push(target);
            for (ci, column) in scene.columns.iter().enumerate() {
                row.push(match &column.probe {
                    Probe::Displacement { node, direction } => direction
                        .dot(&(mechanism.position(&at, *node) - scene.nodes[*node].position)),
                    Probe::Velocity { node, direction } => {
                        direction.dot(&mechanism.velocity(&at, &full, *node))
                    }
                    Probe::Rotation { body, axis } => {
                        let raw = twist(&at.orientations[*body], axis);
                        let turns = ((previous_rotation[ci] - raw) / std::f64::consts::TAU).round();
                        let unwrapped = raw + turns * std::f64::consts::TAU;
                        previous_rotation[ci] = unwrapped;
                        unwrapped
                    }
                    Probe::ContactForce { contact } => evaluation.contact[*contact],
                    Probe::Gap { contact } => mechanism.distance(&at, *contact),
                    Probe::Zero { .. } => 0.0,
                });
            }
            if mechanism.contact_count() > 0 {
                row.push(
                    events
                        .iter()
                        .filter(|e| matches!(e, ContactEvent::Impact { .. }))
                        .count() as f64,
                );
            }
            // Exact through every contact event: every row is valid.
            row.push(1.0);
            if row.iter().any(|x| !x.is_finite()) {
                return Err(EngineError::Failed(format!(
                    "reference: a non-finite value at t = {target:e}"
                )));
            }
            rows.push(row);
            next += 1;
        }
        steps += leg.steps;
        evaluations += leg.evaluations;
        at = mechanism.unpack(y.as_slice());
        w = DVector::from_column_slice(&y.as_slice()[np..]);
        u = &basis * &w;
        t0 = end;
    }
    let columns = std::iter::once("t".to_string())
        .chain(scene.columns.iter().map(|c| c.name.clone()))
        .chain((mechanism.contact_count() > 0).then(|| IMPACTS_COLUMN.to_string()))
        .chain(std::iter::once(VALID_COLUMN.to_string()))
        .collect();
    Ok(Solution {
        history: History { columns, rows },
        contact: contact_history,
        drift,
        steps,
        evaluations,
        events,
    })
}
