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

/// The dashpots of a scene that the direct solve applies to.
#[derive(Debug, Clone)]
pub struct ParticleDashpots<S: Space> {
    list: Vec<ParticleDashpot<S>>,
}

impl<S: Space> ParticleDashpots<S> {
    /// The model's dashpots, when every one acts between particles or a particle and the
    /// ground along a line and there are at most [`MAX_DASHPOTS`] of them.
    pub fn of<const FINITE: bool>(model: &Model<S, FINITE>) -> Option<Self> {
        let list = model.particle_dashpots()?;
        (list.len() <= MAX_DASHPOTS).then_some(Self { list })
    }

    /// The centred velocity `v_n` and the accelerations `acc` at it, from the position forces
    /// and the half-step velocity `v_half`, with `directions` the two-point dashpots' lines at
    /// this configuration; returns the dashpots' dissipation power. Only for a step without
    /// centripetal or gyroscopic terms (the bodies' accelerations do not read the velocity).
    #[allow(clippy::too_many_arguments)]
    pub fn solve<const FINITE: bool>(
        &self,
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        forces: &Forces<S>,
        directions: &[S::V],
        v_half: &Rates<S>,
        h: f64,
        held: &Constraints<S>,
        acc: &mut Rates<S>,
        v_n: &mut Rates<S>,
        counters: &mut Counters,
    ) -> f64 {
        counters.damping_evaluations += 1;
        model.accelerations(cfg, forces, v_half, held, acc, counters);
        v_n.set_plus(v_half, 0.5 * h, acc);
        let k = self.list.len();
        // Each dashpot's moving ends: (particle, signed direction, P M⁻¹ of that direction).
        let mut ends = [[(0usize, S::V::zero(), S::V::zero()); 2]; MAX_DASHPOTS];
        let mut count = [0usize; MAX_DASHPOTS];
        for (j, dashpot) in self.list.iter().enumerate() {
            let d = match dashpot.line {
                DashpotLine::Fixed(d) => d,
                DashpotLine::TwoPoint(i) => directions[i],
            };
            for (end, e) in [(dashpot.a, -d), (dashpot.b, d)] {
                if let Some(p) = end {
                    ends[j][count[j]] = (p, e, model.particle_response(held, p, e));
                    count[j] += 1;
                }
            }
        }
        // The augmented system [I + (h/2)·K | E w].
        let mut system = [[0.0; MAX_DASHPOTS + 1]; MAX_DASHPOTS];
        for i in 0..k {
            system[i][i] = 1.0;
            for &(p, e, _) in &ends[i][..count[i]] {
                system[i][MAX_DASHPOTS] += e.dot(&v_n.p[p]);
            }
            for j in 0..k {
                let scale = 0.5 * h * self.list[j].c;
                for &(p, e, _) in &ends[i][..count[i]] {
                    for &(q, _, g) in &ends[j][..count[j]] {
                        if p == q {
                            system[i][j] += scale * e.dot(&g);
                        }
                    }
                }
            }
        }
        let rates = eliminate(&mut system, k);
        let mut power = 0.0;
        for j in 0..k {
            let force = self.list[j].c * rates[j];
            power += force * rates[j];
            for &(p, _, g) in &ends[j][..count[j]] {
                acc.p[p] -= g * force;
            }
        }
        v_n.set_plus(v_half, 0.5 * h, acc);
        power
    }
}

/// Gaussian elimination with partial pivoting of the first `k` rows of an augmented system
/// whose right-hand side sits in the last column; returns the solution.
#[allow(clippy::needless_range_loop)] // index notation of the elimination
fn eliminate(a: &mut [[f64; MAX_DASHPOTS + 1]; MAX_DASHPOTS], k: usize) -> [f64; MAX_DASHPOTS] {
    const R: usize = MAX_DASHPOTS;
    for col in 0..k {
        let pivot = (col..k)
            .max_by(|x, y| a[*x][col].abs().total_cmp(&a[*y][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        for row in col + 1..k {
            let factor = a[row][col] / a[col][col];
            if factor != 0.0 {
                for c in col..k {
                    a[row][c] -= factor * a[col][c];
                }
                a[row][R] -= factor * a[col][R];
            }
        }
    }
    let mut x = [0.0; MAX_DASHPOTS];
    for row in (0..k).rev() {
        let mut s = a[row][R];
        for c in row + 1..k {
            s -= a[row][c] * x[c];
        }
        x[row] = s / a[row][row];
    }
    x
}
