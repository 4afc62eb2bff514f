//! The centred velocity of an increment whose dashpots all act between particles (or a
//! particle and the ground), solved directly in the dashpots' rates instead of by the
//! fixed-point iteration.
//!
//! With `v(n) = v(n−½) + (h/2)·a(n)` and dashpot forces linear in `v(n)` along lines frozen for
//! the increment, `v(n) = w − (h/2)·Σ_j c_j r_j P M⁻¹ e_j`, where `w = v(n−½) + (h/2)·P M⁻¹ F`
//! is the undamped predictor, `e_j` dashpot j's direction pattern (−d at end a, +d at end b)
//! and `r_j = e_j·v(n)` its rate. The rates therefore solve the k×k system
//! `(I + (h/2)·K) r = E w`, `K_ij = c_j e_iᵀ P M⁻¹ e_j`. `E P M⁻¹ Eᵀ` is positive
//! semi-definite (P, the step's projection, commutes with each particle's scalar mass) and the
//! `c_j` are positive, so `I + (h/2)·K` is never singular. One pass over the forces and a
//! k×k elimination replace the iteration's two or more passes; the answer is its fixed point,
//! to round-off.

use super::model::{
    Config, Constraints, Counters, DashpotLine, Forces, Model, ParticleDashpot, Rates,
};
use super::space::{Lin, Space};

/// Above this many dashpots the iteration is used (the elimination is O(k³) per increment).
pub const MAX_DASHPOTS: usize = 8;

/// The dashpots of a scene that the direct solve applies to, with the solve's scratch space.
#[derive(Debug, Clone)]
pub struct ParticleDashpots<S: Space> {
    list: Vec<ParticleDashpot<S>>,
    /// Each dashpot's moving ends at this increment: (dashpot, particle, signed direction,
    /// P M⁻¹ of that direction).
    ends: Vec<(usize, usize, S::V, S::V)>,
    /// The augmented system `[I + (h/2)·K | E w]`, row-major, k × (k + 1).
    system: Vec<f64>,
}

impl<S: Space> ParticleDashpots<S> {
    /// The model's dashpots, when every one acts between particles or a particle and the
    /// ground along a line and there are at most [`MAX_DASHPOTS`] of them.
    pub fn of<const FINITE: bool>(model: &Model<S, FINITE>) -> Option<Self> {
        let list = model.particle_dashpots()?;
        let k = list.len();
        (k <= MAX_DASHPOTS).then(|| Self {
            list,
            ends: Vec::with_capacity(2 * k),
            system: vec![0.0; k * (k + 1)],
        })
    }

    /// The accelerations `acc` at the centred velocity, and that velocity into `v_n` where one
    /// is given (an increment that only advances needs neither it nor its pass over memory),
    /// from the position forces and the half-step velocity `v_half`, with `directions` the
    /// two-point dashpots' lines at this configuration; returns the dashpots' dissipation
    /// power. Only for a step without centripetal or gyroscopic terms (the bodies'
    /// accelerations do not read the velocity).
    #[allow(clippy::too_many_arguments)]
    pub fn solve<const FINITE: bool>(
        &mut self,
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        forces: &Forces<S>,
        directions: &[S::V],
        v_half: &Rates<S>,
        h: f64,
        held: &Constraints<S>,
        acc: &mut Rates<S>,
        mut v_n: Option<&mut Rates<S>>,
        counters: &mut Counters,
    ) -> f64 {
        counters.damping_evaluations += 1;
        model.accelerations(cfg, forces, v_half, held, acc, counters);
        if let Some(v_n) = v_n.as_deref_mut() {
            v_n.set_plus(v_half, 0.5 * h, acc);
        }
        let k = self.list.len();
        self.ends.clear();
        for (j, dashpot) in self.list.iter().enumerate() {
            let d = match dashpot.line {
                DashpotLine::Fixed(d) => d,
                DashpotLine::TwoPoint(i) => directions[i],
            };
            for (end, e) in [(dashpot.a, -d), (dashpot.b, d)] {
                if let Some(p) = end {
                    self.ends
                        .push((j, p, e, model.particle_response(held, p, e)));
                }
            }
        }
        // Row i of [I + (h/2)·K | E w]: K_ij = c_j Σ over the particles both move of e_i·g_j.
        let width = k + 1;
        let system = &mut self.system;
        system.iter_mut().for_each(|x| *x = 0.0);
        for i in 0..k {
            system[i * width + i] = 1.0;
        }
        for &(i, p, e, _) in &self.ends {
            // The centred velocity before the dashpots act, as `Rates::set_plus` forms it.
            let centred = v_half.p[p] + acc.p[p] * (0.5 * h);
            system[i * width + k] += e.dot(&centred);
            for &(j, q, _, g) in &self.ends {
                if p == q {
                    system[i * width + j] += 0.5 * h * self.list[j].c * e.dot(&g);
                }
            }
        }
        let mut rates = [0.0; MAX_DASHPOTS];
        if k == 1 {
            rates[0] = system[1] / system[0];
        } else {
            eliminate(system, k, &mut rates);
        }
        let mut power = 0.0;
        for (j, dashpot) in self.list.iter().enumerate() {
            power += dashpot.c * rates[j] * rates[j];
        }
        for &(j, p, _, g) in &self.ends {
            acc.p[p] -= g * (self.list[j].c * rates[j]);
            if let Some(v_n) = v_n.as_deref_mut() {
                v_n.p[p] = v_half.p[p] + acc.p[p] * (0.5 * h);
            }
        }
        power
    }
}

/// Gaussian elimination with partial pivoting of a k × (k + 1) augmented system (row-major,
/// right-hand side last); the solution goes to `x[..k]`.
fn eliminate(a: &mut [f64], k: usize, x: &mut [f64; MAX_DASHPOTS]) {
    let w = k + 1;
    for col in 0..k {
        let pivot = (col..k)
            .max_by(|r, s| a[r * w + col].abs().total_cmp(&a[s * w + col].abs()))
            .unwrap_or(col);
        if pivot != col {
            for c in col..w {
                a.swap(col * w + c, pivot * w + c);
            }
        }
        for row in col + 1..k {
            let factor = a[row * w + col] / a[col * w + col];
            if factor != 0.0 {
                for c in col..w {
                    a[row * w + c] -= factor * a[col * w + c];
                }
            }
        }
    }
    for row in (0..k).rev() {
        let mut s = a[row * w + k];
        for c in row + 1..k {
            s -= a[row * w + c] * x[c];
        }
        x[row] = s / a[row * w + row];
    }
}
