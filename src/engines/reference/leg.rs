//! One integration leg: Dormand–Prince from `(t, y)` towards a time with a fixed free basis and
//! a fixed set of closed contacts in fixed grips, stopped at the end of the first accepted step
//! by which a contact event has happened.
//!
//! The state is the positions, the free velocities w, in a scene with friction the energy
//! friction has dissipated (its rate the sliding pairs' power), and in a scene whose loads vary
//! in time the time itself (its rate 1), which the loads' amplitudes are evaluated at: the
//! equations the integrator sees are autonomous. ode_solvers 0.6.2's Dop853 evaluates its 12th
//! stage at the step's start instead of its end (its node c₁₂ is 0, not 1; ode-solvers pull
//! request 42), which is exact only for equations that do not read the time argument.

use super::mechanism::{Grip, Mechanism, Placement};
use crate::engines::EngineError;
use nalgebra::{DMatrix, DVector};
use std::cell::{Cell, RefCell};

/// Most integration steps between two output rows (each run is bounded in time).
const MAX_STEPS_PER_ROW: u32 = 1_000_000;

/// The shortest leg the bisection integrates, relative to its end time: Dop853 refuses a step
/// below 10 ε |t| (step size underflow), so an event closer than this to a leg's start (a
/// break-away that falls on a leg's boundary) is located to this, 1e-14 |t|.
const SHORTEST_LEG: f64 = 100.0 * f64::EPSILON;

/// The sliding pairs' directions as the integration goes (each [`Grip::Slip`]'s reference is
/// the slip's direction at the last accepted step), and which pairs' slip has stopped.
#[derive(Debug, Clone)]
pub(super) struct Tracking {
    /// The grips, the sliding ones' references updated after every accepted step.
    pub(super) grips: Vec<Grip>,
    /// A sliding pair has stopped once v_t·s is below this: 0, or at the leg's start the
    /// (round-off) value of a pair that has just started to slip from rest.
    floors: Vec<f64>,
    /// The sliding pairs whose slip has stopped by the last accepted step.
    pub(super) stopped: Vec<bool>,
}

/// The free velocities in state `y`.
pub(super) fn free_velocity(
    m: &Mechanism,
    basis: &DMatrix<f64>,
    y: &ode_solvers::DVector<f64>,
) -> DVector<f64> {
    let np = m.position_len();
    DVector::from_column_slice(&y.as_slice()[np..np + basis.ncols()])
}

/// The equations for the ODE solver over one dynamic step (fixed free basis) with a fixed
/// set of closed contacts; after every accepted step it looks for a contact event and stops
/// the integration there if one has happened.
struct Motion<'a> {
    mechanism: &'a Mechanism,
    basis: &'a DMatrix<f64>,
    active: &'a [bool],
    inside: &'a [bool],
    tracking: &'a RefCell<Tracking>,
    error: &'a RefCell<Option<EngineError>>,
    fired: &'a Cell<bool>,
}

impl ode_solvers::System<f64, ode_solvers::DVector<f64>> for Motion<'_> {
    /// The rates at state `y`. The time argument is not read (see the module's doc): where the
    /// loads vary in time, the state carries the time.
    fn system(&self, _t: f64, y: &ode_solvers::DVector<f64>, dy: &mut ode_solvers::DVector<f64>) {
        let m = self.mechanism;
        let np = m.position_len();
        let nf = self.basis.ncols();
        let at = m.unpack(y.as_slice());
        let w = free_velocity(m, self.basis, y);
        let tracking = self.tracking.borrow();
        let time = state_time(m, y);
        match m.evaluate(&at, self.basis, &w, self.active, &tracking.grips, time) {
            Ok(e) => {
                let u = self.basis * &w;
                m.position_rate(&at, &u, &mut dy.as_mut_slice()[..np]);
                dy.as_mut_slice()[np..np + nf].copy_from_slice(e.acceleration.as_slice());
                if m.has_friction() {
                    dy[np + nf] = e.dissipation;
                }
                if m.varies_in_time() {
                    dy[y.len() - 1] = 1.0;
                }
            }
            Err(e) => {
                dy.fill(0.0);
                self.error.borrow_mut().get_or_insert(e);
            }
        }
    }

    fn solout(
        &mut self,
        t: f64,
        y: &ode_solvers::DVector<f64>,
        _dy: &ode_solvers::DVector<f64>,
    ) -> bool {
        if self.error.borrow().is_some() {
            return true;
        }
        let tracking = &mut self.tracking.borrow_mut();
        match fired(
            self.mechanism,
            self.basis,
            (self.active, self.inside),
            tracking,
            (t, y),
        ) {
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

/// Whether a contact event has happened by state `y` at time `t`: an open pair's gap below zero,
/// or a closed pair's force below zero, a sliding pair's slip stopped (its relative tangential
/// velocity turned against its last direction, `tracking.stopped`), a stuck pair's friction
/// beyond μ_s λ_n (the forces at `t`: a load's amplitude moves them). A pair that was `inside`
/// at the leg's start (it has just rebounded, or just opened, and sits a few ulps inside while
/// it leaves) strikes only while it closes (ġ < 0); any other pair strikes once its gap is
/// below zero, so that a grazing impact caught only after the gap turned again is still found.
/// Without an event, the sliding pairs' directions are updated.
fn fired(
    mechanism: &Mechanism,
    basis: &DMatrix<f64>,
    (active, inside): (&[bool], &[bool]),
    tracking: &mut Tracking,
    (t, y): (f64, &ode_solvers::DVector<f64>),
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
        let e = m.evaluate(&at, basis, &w, active, &tracking.grips, t)?;
        let pulling = e.contact.iter().zip(active).any(|(f, a)| *a && *f < 0.0);
        if !m.has_friction() {
            return Ok(pulling);
        }
        let slipping = stick_fails(m, active, &tracking.grips, &e);
        let stopped = slips_stopped(m, &at, &u, active, tracking);
        return Ok(pulling || slipping || stopped);
    }
    Ok(false)
}

/// Whether a stuck pair's friction exceeds μ_s λ_n.
fn stick_fails(
    m: &Mechanism,
    active: &[bool],
    grips: &[Grip],
    e: &super::mechanism::Evaluation,
) -> bool {
    (0..active.len()).any(|k| {
        active[k]
            && grips[k] == Grip::Stick
            && m.friction(k)
                .is_some_and(|f| e.friction[k].norm() > f.static_coefficient * e.contact[k])
    })
}

/// Whether a sliding pair's relative tangential velocity has turned against its direction at
/// the last accepted step (then `tracking.stopped` says which); where none has, each sliding
/// pair's direction is updated to its velocity's.
fn slips_stopped(
    m: &Mechanism,
    at: &Placement,
    u: &DVector<f64>,
    active: &[bool],
    tracking: &mut Tracking,
) -> bool {
    let mut velocities = vec![None; active.len()];
    for k in 0..active.len() {
        if let (true, Grip::Slip { reference }) = (active[k], tracking.grips[k]) {
            let v_t = m.slip_velocity(at, u, k);
            let along = v_t.dot(&m.to_world(at, k, &reference));
            tracking.stopped[k] = along < tracking.floors[k];
            if along > 0.0 {
                velocities[k] = Some(v_t);
            }
        }
    }
    if tracking.stopped.iter().any(|s| *s) {
        return true;
    }
    for (k, v_t) in velocities.iter().enumerate() {
        if let Some(v_t) = v_t {
            tracking.grips[k] = Grip::Slip {
                reference: m.to_body(at, k, &v_t.normalize()),
            };
            tracking.floors[k] = 0.0;
        }
    }
    false
}

/// The time state `y` carries, where the loads vary in time (its last entry); 0 otherwise,
/// where nothing reads it.
pub(super) fn state_time(m: &Mechanism, y: &ode_solvers::DVector<f64>) -> f64 {
    if m.varies_in_time() {
        y[y.len() - 1]
    } else {
        0.0
    }
}

/// State `y` at time `t`: with the time it carries set to `t`, where the loads vary in time.
fn start(m: &Mechanism, t: f64, y: &ode_solvers::DVector<f64>) -> ode_solvers::DVector<f64> {
    let mut y = y.clone();
    if m.varies_in_time() {
        let last = y.len() - 1;
        y[last] = t;
    }
    y
}

/// The placement, free velocities, full velocity and every pair's gap at state `y`.
pub(super) fn gaps_at(
    m: &Mechanism,
    basis: &DMatrix<f64>,
    active: &[bool],
    y: &ode_solvers::DVector<f64>,
) -> (Placement, DVector<f64>, DVector<f64>, Vec<f64>) {
    let at = m.unpack(y.as_slice());
    let w = free_velocity(m, basis, y);
    let u = basis * &w;
    let (gaps, _, _) = m.constraints(&at, &u, active, &[]);
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

    /// The tracking of the sliding pairs for a leg from state `y` with `grips`.
    fn tracking(&self, active: &[bool], grips: &[Grip], y: &ode_solvers::DVector<f64>) -> Tracking {
        let m = self.mechanism;
        let mut floors = vec![0.0; grips.len()];
        if m.has_friction() {
            let (at, _, u, _) = gaps_at(m, self.basis, active, y);
            for (k, grip) in grips.iter().enumerate() {
                if let (true, Grip::Slip { reference }) = (active[k], grip) {
                    let along = m
                        .slip_velocity(&at, &u, k)
                        .dot(&m.to_world(&at, k, reference));
                    floors[k] = along.min(0.0);
                }
            }
        }
        Tracking {
            grips: grips.to_vec(),
            floors,
            stopped: vec![false; grips.len()],
        }
    }

    /// Integrates from `(t, y)` towards `to` with the closed pairs `active` in `grips` and
    /// returns where it stopped: at `to`, or at the end of the first accepted step by which a
    /// contact event has happened. The time a state carries starts at `t` (it accumulates no
    /// round-off from leg to leg).
    pub(super) fn run(
        &mut self,
        (active, grips): (&[bool], &[Grip]),
        t: f64,
        y: &ode_solvers::DVector<f64>,
        to: f64,
    ) -> Result<Reach, EngineError> {
        let failure = RefCell::new(None);
        let fired = Cell::new(false);
        let inside = self.inside(active, y);
        let tracking = RefCell::new(self.tracking(active, grips, y));
        let motion = Motion {
            mechanism: self.mechanism,
            basis: self.basis,
            active,
            inside: &inside,
            tracking: &tracking,
            error: &failure,
            fired: &fired,
        };
        let mut stepper = ode_solvers::Dop853::from_param(
            motion,
            t,
            to,
            to - t,
            start(self.mechanism, t, y),
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
        Ok(Reach {
            time: *stepper.x_out().last().expect("the end time"),
            state: stepper.y_out().last().expect("the end state").clone(),
            event: fired.get(),
            tracking: tracking.into_inner(),
        })
    }

    /// The first event after `t`: a leg from `(t, y)` stopped by one (`reached`) is bisected
    /// on its end time, none by `lo`, one by `hi`, to a few ulps (an event within
    /// [`SHORTEST_LEG`] of `t`, to that); where it is, at `hi`.
    pub(super) fn first_event(
        &mut self,
        closed: (&[bool], &[Grip]),
        t: f64,
        y: &ode_solvers::DVector<f64>,
        reached: Reach,
    ) -> Result<Reach, EngineError> {
        let (mut lo, mut hi) = (t, reached);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi.time);
            if mid <= lo || mid >= hi.time || mid - t <= SHORTEST_LEG * mid.abs() {
                break;
            }
            let reach = self.run(closed, t, y, mid)?;
            if reach.event {
                if reach.time < lo {
                    // The shorter integration took other steps and met the event before
                    // `lo`: the bracket restarts from the leg's start.
                    lo = t;
                }
                hi = reach;
            } else {
                lo = mid;
            }
        }
        Ok(hi)
    }
}

/// Where a leg stopped: its time and state, whether an event stopped it, and the sliding
/// pairs' tracking there.
pub(super) struct Reach {
    pub(super) time: f64,
    pub(super) state: ode_solvers::DVector<f64>,
    pub(super) event: bool,
    pub(super) tracking: Tracking,
}
