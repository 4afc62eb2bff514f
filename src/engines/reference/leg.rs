//! One integration leg: Dormand–Prince from `(t, y)` towards a time with a fixed free basis and
//! a fixed set of closed contacts, stopped at the end of the first accepted step by which a
//! contact event has happened.

use super::mechanism::{Mechanism, Placement};
use crate::engines::EngineError;
use nalgebra::{DMatrix, DVector};
use std::cell::{Cell, RefCell};

/// Most integration steps between two output rows (each run is bounded in time).
const MAX_STEPS_PER_ROW: u32 = 1_000_000;

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
pub(super) fn gaps_at(
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

/// One integration from `(t, y)` to `to` with the closed set `active`.
pub(super) struct Leg<'a> {
    pub(super) mechanism: &'a Mechanism,
    pub(super) basis: &'a DMatrix<f64>,
    pub(super) rtol: f64,
    pub(super) max_step: f64,
    pub(super) steps: u64,
    pub(super) evaluations: u64,
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
    pub(super) fn run(
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

    /// The first event after `t`: a leg from `(t, y)` stopped by one at `stopped` (state
    /// `reached`) is bisected on its end time, none by `lo`, one by `hi`, to a few ulps.
    pub(super) fn first_event(
        &mut self,
        active: &[bool],
        t: f64,
        y: &ode_solvers::DVector<f64>,
        stopped: f64,
        reached: ode_solvers::DVector<f64>,
    ) -> Result<(f64, ode_solvers::DVector<f64>), EngineError> {
        let (mut lo, mut hi, mut at_hi) = (t, stopped, reached);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            let (stopped, state, event) = self.run(active, t, y, mid)?;
            if event {
                if stopped < lo {
                    // The shorter integration took other steps and met the event before
                    // `lo`: the bracket restarts from the leg's start.
                    lo = t;
                }
                (hi, at_hi) = (stopped, state);
            } else {
                lo = mid;
            }
        }
        Ok((hi, at_hi))
    }
}
