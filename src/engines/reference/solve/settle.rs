//! The friction's events: the closed pairs with friction put in a consistent grip at a step's
//! start and after each event.
//!
//! A pair sliding at the first step's start slides on along its relative tangential velocity;
//! one at rest there, or one whose slip has stopped, is tried stuck: its tangential velocity is
//! set to zero (the projection of [`Mechanism::admissible`], by round-off only after a stop) and
//! it sticks if the tangential force that takes, |λ_t|, is within μ_s λ_n; otherwise it slides
//! on at once along the force that drives it, −λ_t. A stuck pair whose |λ_t| has reached μ_s λ_n
//! slides off the same way. Where several pairs change at one instant, the one furthest beyond
//! its limit slides first and the forces are solved again.

use super::{ContactEvent, Solver, free_velocity, gaps_at};
use crate::engines::EngineError;
use crate::engines::reference::mechanism::{Evaluation, Grip, Mechanism};
use nalgebra::DMatrix;

/// Below this fraction of the largest velocity coordinate, a pair's relative tangential
/// velocity at the first step's start is rest.
const AT_REST: f64 = 1e-12;

/// Most changes of grip at one instant.
const MAX_CHANGES: usize = 1000;

/// Why a pair is tried stuck.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Trial {
    /// It is at rest where it starts.
    AtRest,
    /// Its slip has stopped.
    Stopped,
}

impl Solver<'_> {
    /// The closed pairs' grips at time `t`, state `y` (whose free velocities a pair tried
    /// stuck changes), with the events they make: at a step's start (`stopped` none), or after
    /// an event, `stopped` the sliding pairs whose slip has stopped.
    pub(super) fn settle(
        &mut self,
        basis: &DMatrix<f64>,
        y: &mut ode_solvers::DVector<f64>,
        t: f64,
        stopped: Option<&[bool]>,
    ) -> Result<(), EngineError> {
        let m = self.mechanism;
        if !m.has_friction() {
            return Ok(());
        }
        let trials = self.trials(basis, y, stopped);
        if trials.iter().any(Option::is_some) {
            let (at, _, u, _) = gaps_at(m, basis, &self.active, y);
            let w = m.admissible(&at, basis, &u, (&self.active, &self.grips))?;
            let np = m.position_len();
            y.as_mut_slice()[np..np + w.len()].copy_from_slice(w.as_slice());
        }
        let slid = self.slide_off(basis, y, t)?;
        for (k, trial) in trials.iter().enumerate() {
            if !self.active[k] {
                // Opened (an opening event).
                continue;
            }
            let sticks = self.grips[k] == Grip::Stick;
            let event = match (trial, sticks) {
                (Some(_), true) => Some(ContactEvent::Stick {
                    contact: k,
                    time: t,
                }),
                (Some(Trial::Stopped), false) => Some(ContactEvent::Reversal {
                    contact: k,
                    time: t,
                }),
                (Some(Trial::AtRest), false) => Some(ContactEvent::Slip {
                    contact: k,
                    time: t,
                }),
                (None, _) if slid[k] => Some(ContactEvent::Slip {
                    contact: k,
                    time: t,
                }),
                (None, _) => None,
            };
            self.events.extend(event);
        }
        Ok(())
    }

    /// Each closed pair with friction whose grip is to be tried stuck (its grip set to
    /// [`Grip::Stick`]): one at rest at a step's start or whose slip has `stopped`; at a step's
    /// start, a pair that moves slides along its relative tangential velocity.
    fn trials(
        &mut self,
        basis: &DMatrix<f64>,
        y: &ode_solvers::DVector<f64>,
        stopped: Option<&[bool]>,
    ) -> Vec<Option<Trial>> {
        let m = self.mechanism;
        let (at, _, u, _) = gaps_at(m, basis, &self.active, y);
        let rest = AT_REST * u.amax();
        let mut trials = vec![None; self.grips.len()];
        for (k, trial) in trials.iter_mut().enumerate() {
            if !self.active[k] || m.friction(k).is_none() {
                self.grips[k] = Grip::Free;
                continue;
            }
            let starting = stopped.is_none() && self.grips[k] != Grip::Stick;
            if starting {
                let v_t = m.slip_velocity(&at, &u, k);
                if v_t.norm() > rest {
                    let reference = m.to_body(&at, k, &v_t.normalize());
                    self.grips[k] = Grip::Slip { reference };
                } else {
                    *trial = Some(Trial::AtRest);
                }
            } else if stopped.is_some_and(|s| s[k]) {
                *trial = Some(Trial::Stopped);
            }
            if trial.is_some() {
                self.grips[k] = Grip::Stick;
            }
        }
        trials
    }

    /// Stuck pairs beyond their limit slide off (and pulling pairs open) until every grip is
    /// consistent; which pairs slid off.
    fn slide_off(
        &mut self,
        basis: &DMatrix<f64>,
        y: &ode_solvers::DVector<f64>,
        t: f64,
    ) -> Result<Vec<bool>, EngineError> {
        let m = self.mechanism;
        let at = m.unpack(y.as_slice());
        let w = free_velocity(m, basis, y);
        let mut slid = vec![false; self.grips.len()];
        for _ in 0..MAX_CHANGES {
            let e = m.evaluate(&at, basis, &w, &self.active, &self.grips, t)?;
            let pulling: Vec<usize> = (0..self.active.len())
                .filter(|k| self.active[*k] && e.contact[*k] < 0.0)
                .collect();
            for &k in &pulling {
                self.active[k] = false;
                self.grips[k] = Grip::Free;
                self.events.push(ContactEvent::Opening {
                    contact: k,
                    time: t,
                });
            }
            if !pulling.is_empty() {
                continue;
            }
            let Some(k) = beyond_limit(m, &self.active, &self.grips, &e) else {
                return Ok(slid);
            };
            let drive = -e.friction[k] / e.friction[k].norm();
            self.grips[k] = Grip::Slip {
                reference: m.to_body(&at, k, &drive),
            };
            slid[k] = true;
            let after = m.evaluate(&at, basis, &w, &self.active, &self.grips, t)?;
            let u = basis * &w;
            let rate = basis * &after.acceleration;
            if m.slip_acceleration(&at, &u, &rate, k).dot(&drive) <= 0.0 {
                return Err(inconsistent(m, k, t));
            }
        }
        Err(EngineError::Failed(format!(
            "reference: the grips of the pairs with friction did not settle in {MAX_CHANGES} \
             changes at t = {t:e}"
        )))
    }

    /// A pair strikes at time `t`: refused where it, or a closed pair, has friction.
    pub(super) fn refuse_impact_with_friction(&self, k: usize, t: f64) -> Result<(), EngineError> {
        let m = self.mechanism;
        let closed_with_friction =
            (0..self.active.len()).find(|j| self.active[*j] && m.friction(*j).is_some());
        match (m.friction(k), closed_with_friction) {
            (None, None) => Ok(()),
            (Some(_), _) => Err(EngineError::Failed(format!(
                "reference: contact `{}` strikes at t = {t:e}; it has friction, and the \
                 tangential impulse of an impact is not modelled",
                m.contact_name(k)
            ))),
            (None, Some(j)) => Err(EngineError::Failed(format!(
                "reference: contact `{}` strikes at t = {t:e} while `{}`, which has friction, is \
                 closed; the tangential impulse of an impact is not modelled",
                m.contact_name(k),
                m.contact_name(j)
            ))),
        }
    }
}

/// The stuck pair furthest beyond its limit, |λ_t| / (μ_s λ_n) > 1, if any.
fn beyond_limit(m: &Mechanism, active: &[bool], grips: &[Grip], e: &Evaluation) -> Option<usize> {
    (0..active.len())
        .filter(|k| active[*k] && grips[*k] == Grip::Stick)
        .filter_map(|k| {
            let limit = m.friction(k)?.static_coefficient * e.contact[k];
            let force = e.friction[k].norm();
            (force > limit).then_some((k, force / limit))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// Pair `k` can neither stick nor slide off at time `t`.
fn inconsistent(m: &Mechanism, k: usize, t: f64) -> EngineError {
    EngineError::Failed(format!(
        "reference: contact `{}` at t = {t:e} can neither stick (its friction would exceed \
         mu_s times its normal force) nor slide along the force that drives it (the slip would \
         not move that way): Coulomb's law has no consistent solution here",
        m.contact_name(k)
    ))
}
