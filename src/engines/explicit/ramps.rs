//! Loads that vary in time (a tabular amplitude): added to the force pass at the increment's
//! time, their work summed increment by increment.

use super::model::{Forces, Model};
use super::space::{Lin, Space};
use super::state::Config;

/// The work of the ramped loads since the dynamic start, by the trapezoidal rule over each
/// increment: ½(F(n−1) + F(n))·(u(n) − u(n−1)) at each load's point (second order, as the
/// scheme).
#[derive(Debug, Clone)]
pub struct RampedWork<S: Space> {
    /// Each load's force and its point's displacement at the last increment.
    last: Vec<(S::V, S::V)>,
    /// The work so far.
    pub work: f64,
}

impl<S: Space> RampedWork<S> {
    /// The account at the dynamic start (`None` without ramped loads).
    pub fn new<const FINITE: bool>(model: &Model<S, FINITE>) -> Option<Self> {
        (!model.ramped_loads.is_empty()).then(|| RampedWork {
            last: Vec::new(),
            work: 0.0,
        })
    }

    /// Add increment n's work: the loads at time `t` and configuration `cfg`.
    pub fn add<const FINITE: bool>(&mut self, model: &Model<S, FINITE>, cfg: &Config<S>, t: f64) {
        let now = model
            .ramped_loads
            .iter()
            .map(|(l, a)| (l.force * a.at(t), model.displacement(cfg, &l.point)));
        if self.last.is_empty() {
            self.last = now.collect();
            return;
        }
        for ((f0, u0), (f1, u1)) in self.last.iter_mut().zip(now) {
            self.work += 0.5 * (*f0 + f1).dot(&(u1 - *u0));
            (*f0, *u0) = (f1, u1);
        }
    }
}

impl<S: Space, const FINITE: bool> Model<S, FINITE> {
    /// Add the ramped loads at time `t` to `out`.
    pub fn ramped_forces(&self, cfg: &Config<S>, t: f64, out: &mut Forces<S>) {
        for (l, a) in &self.ramped_loads {
            self.apply(cfg, &l.point, l.force * a.at(t), out);
        }
    }
}
