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
}

impl Engine for ReferenceEngine {
    fn name(&self) -> &str {
        "reference"
    }

    fn run(&self, scene: &Scene, _settings: &RunSettings) -> Result<RunOutput, EngineError> {
        let start = Instant::now();
        if scene.has_friction() {
            return Err(EngineError::Unsupported(
                "reference: contact with friction".into(),
            ));
        }
        if scene.has_amplitudes() {
            return Err(EngineError::Unsupported(
                "reference: a load that varies in time (an amplitude)".into(),
            ));
        }
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
}
