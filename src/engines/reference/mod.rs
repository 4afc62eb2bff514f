//! `reference`: the converged solution of each case's own finite-rotation model, the one the
//! finite-rotation engines approximate as the increment goes to 0 and the penalty stiffness to
//! infinity: finite rotation, rigid contact (a closed pair's node slaved to the turning
//! surface), every other element as the scene says.
//!
//! The equations ([`mechanism`]) are written from Newton–Euler's laws with each closed contact
//! as a constraint solved with its multiplier at every evaluation, independently of the
//! explicit engine's force assembly, and integrated by Dormand–Prince 8(5,3) with error control
//! (`ode_solvers::Dop853`) at a relative tolerance of [`TOLERANCE`], restarted at every output
//! time so no row is interpolated, at the end of every dynamic step another follows, and at
//! every time of a load's amplitude table (the force's rate jumps there; no step straddles such
//! a kink, so the error control sees a smooth right-hand side on every step; no row is written
//! there). A load with an amplitude is its force times the amplitude at the time of each
//! evaluation. The whole solution is computed twice, the second time at half the tolerance and
//! with steps of at most half an output interval (so it takes another path even where one step
//! per row meets both tolerances); the largest change of any column over its peak is reported
//! as the measure `tolerance_halving_change` (summary.json), with `constraint_drift` (the
//! largest departure of a closed contact's gap from zero, in length units).
//!
//! A pair's node is a free node, which touches with itself, or a node of a body carrying a ball
//! (a disc in 2D) of the pair's `node_radius`, rigid with the body, which touches a plane face
//! at the point a radius below the node along the face's normal: the gap is the node's
//! distance to the plane less the radius, and the velocities that close it and that slip are
//! those of the slave body's material point at the contact point relative to the master's.
//!
//! Contact is event-driven and exact through every switch: an open pair whose gap reaches zero
//! while closing strikes (Newton's restitution law, the impulse through the mass matrix), a
//! closed pair whose force reaches zero opens. Events are watched after every accepted
//! integration step and located by bisection; they are reported as measures (`impact_<i>_time`,
//! `impact_<i>_speed`, `impact_<i>_rebound`, `opening_<i>_time`, `impacts`, `openings`), with
//! the contact force's smallest margin over its largest (`contact_margin`) and an `impacts`
//! column. Every row is valid.
//!
//! Coulomb friction (a pair's `friction`) is event-driven too ([`mechanism::Grip`]). A stuck
//! pair's tangential velocity at its contact point relative to the body it touches is a
//! constraint (for a ball, rolling), its
//! multipliers λ_t the friction force; a sliding node is pushed by μ_k λ_n against that
//! velocity, λ_n solved with the friction in the normal's column. A slip stops when its
//! relative tangential velocity reaches zero; the node then sticks if the force that takes is
//! within μ_s λ_n, and otherwise slides on at once along the force that drives it (a
//! reversal); a stuck node slips when |λ_t| reaches μ_s λ_n. In 3D the slip follows the
//! relative velocity as it turns. The transitions are located by bisection like the contact
//! events and reported as `stick_<i>_time`, `slip_<i>_time` and `reversal_<i>_time` (the first
//! [`IMPACTS_REPORTED`] of each) with their counts `sticks`, `slips`, `reversals`; the energy
//! friction dissipated, μ_k λ_n |v_t| integrated with the state, is the measure
//! `frictional_dissipation`. Not solved: a pair with friction that starts open, and an impact
//! while a pair with friction is closed (Coulomb's law for the impulse is not modelled); the
//! run fails at such an impact with its time.
//!
//! Static steps set the prescribed DOFs and solve the equilibrium of the free ones by Newton's
//! method (a finite-difference Jacobian; the converged point does not depend on it). Not
//! solved (refused with a reason): a contact node of a body without a ball, or whose ball
//! touches a solid (not a plane) or its own body, a held DOF on a body
//! point other than the reference node, a static step with both free DOFs and contact, a free
//! DOF without mass. A matrix that turns singular during the run (two contacts that fix the
//! same motion, say) fails the run with its time.

mod leg;
pub mod mechanism;
mod solve;

use super::{Engine, EngineError, History, RunInfo, RunOutput, RunSettings};
use crate::contract::{IMPACTS_COLUMN, IMPACTS_REPORTED};
use crate::scene::Scene;
use mechanism::Mechanism;
use solve::solve;
use std::collections::BTreeMap;
use std::time::Instant;

/// Relative tolerance of the integration (the absolute one is this × 10^-3).
pub const TOLERANCE: f64 = 1e-12;

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
    /// The energy friction dissipated, in a scene with friction.
    dissipation: Option<f64>,
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
            report_events(&fine.events, &mut measures);
        }
        if let Some(dissipation) = fine.dissipation {
            measures.insert("frictional_dissipation".into(), dissipation);
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

/// The contact events as measures: the first [`IMPACTS_REPORTED`] of each kind with their
/// times (`impact_<i>_time`, with `_speed` and `_rebound`; `opening_<i>_time`; in a scene with
/// friction `stick_<i>_time`, `slip_<i>_time`, `reversal_<i>_time`), and how many of each
/// (`impacts`, `openings`; `sticks`, `slips`, `reversals` where there are any).
fn report_events(events: &[ContactEvent], measures: &mut BTreeMap<String, f64>) {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for kind in ["impact", "opening"] {
        counts.insert(kind, 0);
    }
    for event in events {
        let kind = event.kind();
        let count = counts.entry(kind).or_insert(0);
        *count += 1;
        if *count > IMPACTS_REPORTED {
            continue;
        }
        let i = *count;
        measures.insert(format!("{kind}_{i}_time"), event.time());
        if let ContactEvent::Impact { speed, rebound, .. } = *event {
            measures.insert(format!("impact_{i}_speed"), speed);
            measures.insert(format!("impact_{i}_rebound"), rebound);
        }
    }
    for (kind, count) in counts {
        measures.insert(format!("{kind}s"), count as f64);
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

/// Below this fraction of the largest column's peak, a column's peak is round-off of an exact
/// zero (a sliding node's sideways displacement of 1e-15 m beside forces of 10 N): its change
/// over its peak says nothing, and [`largest_change`] leaves it out.
const ROUND_OFF_PEAK: f64 = 1e-12;

/// The largest change of any column between two histories, over that column's peak (columns
/// whose peak is round-off, [`ROUND_OFF_PEAK`], left out).
fn largest_change(a: &History, b: &History) -> f64 {
    let measured = 1..a.columns.len() - 1;
    let peaks: Vec<f64> = measured
        .clone()
        .map(|c| a.rows.iter().fold(0.0_f64, |m, r| m.max(r[c].abs())))
        .collect();
    let floor = ROUND_OFF_PEAK * peaks.iter().fold(0.0_f64, |m, p| m.max(*p));
    let mut largest = 0.0_f64;
    for (c, peak) in measured.zip(peaks) {
        if a.columns[c] == IMPACTS_COLUMN || peak == 0.0 || peak < floor {
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

/// What happened to a contact pair, and when.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactEvent {
    /// The gap reached zero: an impact with this approach speed, after which the contact
    /// closed (plastic, or an approach below a millionth of the fastest met so far) or
    /// rebounded.
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
    /// The pair stuck: its slip stopped (or it was at rest at the start) and the tangential
    /// force that holds it is within μ_s λ_n.
    Stick {
        /// Pair index.
        contact: usize,
        /// Time.
        time: f64,
    },
    /// The pair began to slide from rest: it was stuck and its tangential force reached
    /// μ_s λ_n (or it was at rest at the start and could not stick).
    Slip {
        /// Pair index.
        contact: usize,
        /// Time.
        time: f64,
    },
    /// The pair's slip stopped and, unable to stick, it slid on at once along the force that
    /// drives it (a turning point).
    Reversal {
        /// Pair index.
        contact: usize,
        /// Time.
        time: f64,
    },
}

impl ContactEvent {
    /// The event's name in its measures.
    fn kind(&self) -> &'static str {
        match self {
            ContactEvent::Impact { .. } => "impact",
            ContactEvent::Opening { .. } => "opening",
            ContactEvent::Stick { .. } => "stick",
            ContactEvent::Slip { .. } => "slip",
            ContactEvent::Reversal { .. } => "reversal",
        }
    }

    /// When it happened.
    fn time(&self) -> f64 {
        match *self {
            ContactEvent::Impact { time, .. }
            | ContactEvent::Opening { time, .. }
            | ContactEvent::Stick { time, .. }
            | ContactEvent::Slip { time, .. }
            | ContactEvent::Reversal { time, .. } => time,
        }
    }
}
