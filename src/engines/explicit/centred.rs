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
//!
//! A line that turns (an axial dashpot under finite rotation) is not normalised: it is taken as
//! l, its span from end a to end b over its length at t = 0 (never zero: the case reader
//! refuses coincident ends), and `e_j` is built from l_j. Multiplying row i of the system
//! above by |l_i| gives the rows in the unknown `σ_j = r_j/|l_j|`:
//! `(S + (h/2)·K) σ = E w`, with `S = diag(|l_j|²)` (1 for a fixed unit line) and K now
//! formed from the unnormalised `e_j`; `S + (h/2)·K` is non-singular while every |l_j| > 0.
//! The force on the ends is `−c_j σ_j e_j` and the power `Σ c_j |l_j|² σ_j²`. No square root
//! or normalising division is on the increment's chain. A line does not turn where every
//! moving end is confined to it (held on every direction across it): for a step it is then the
//! fixed unit line along its span at the step's start, the rate along it being the rate of
//! its length (the span's direction only flips, which the force, quadratic in the line, does
//! not see). Where no line turns, `I + (h/2)·K` is the same at every increment of a step, and
//! its inverse is formed once per step.

use super::model::{
    Config, Constraints, Counters, DashpotLine, Model, ParticleDashpot, Rates, fill_zero,
};
use super::space::{Lin, Space};
use super::velocity::AtIncrement;

/// Above this many dashpots the iteration is used (the elimination is O(k³) per increment).
pub const MAX_DASHPOTS: usize = 8;

/// A dashpot's moving end: (dashpot, particle, signed line, P M⁻¹ of that line).
pub type End<S> = (usize, usize, <S as Space>::V, <S as Space>::V);

/// The dashpots of a scene that the direct solve applies to, with the solve's scratch space.
#[derive(Debug, Clone)]
pub struct ParticleDashpots<S: Space> {
    list: Vec<ParticleDashpot<S>>,
    /// Each dashpot's line in the current step: its own, or fixed where it does not turn
    /// ([`ParticleDashpots::prepare`]).
    lines: Vec<DashpotLine<S>>,
    /// Each dashpot's moving ends at this increment (for the whole step where no line turns).
    ends: Vec<End<S>>,
    /// Each dashpot's |l|² at this increment (1 for a fixed unit line).
    span_squares: [f64; MAX_DASHPOTS],
    /// The augmented system `[S + (h/2)·K | E w]`, row-major, k × (k + 1).
    system: Vec<f64>,
    /// Where no dashpot's line turns, `(I + (h/2)·K)⁻¹` (row-major, k × k) of the current
    /// step: it and `ends` depend only on the step's constraints, its increment and the lines
    /// at its start, so [`ParticleDashpots::prepare`] forms them once per step and an
    /// increment only multiplies.
    steady: Option<Vec<f64>>,
}

impl<S: Space> ParticleDashpots<S> {
    /// The model's dashpots, when every one acts between particles or a particle and the
    /// ground along a line and there are at most [`MAX_DASHPOTS`] of them.
    pub fn of<const FINITE: bool>(model: &Model<S, FINITE>) -> Option<Self> {
        let list = model.particle_dashpots()?;
        let k = list.len();
        (k <= MAX_DASHPOTS).then(|| Self {
            lines: list.iter().map(|d| d.line).collect(),
            list,
            ends: Vec::with_capacity(2 * k),
            span_squares: [1.0; MAX_DASHPOTS],
            system: vec![0.0; k * (k + 1)],
            steady: None,
        })
    }

    /// Start a step with constraints `held` at increment `h` from `cfg`: each dashpot's line
    /// for the step (fixed where its moving ends are confined to it), and where no line turns, the step's ends and the inverse
    /// of `I + (h/2)·K` formed once (the same arithmetic [`ParticleDashpots::solve`] does
    /// otherwise at every increment).
    pub fn prepare<const FINITE: bool>(
        &mut self,
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        held: &Constraints<S>,
        h: f64,
    ) {
        self.steady = None;
        self.span_squares = [1.0; MAX_DASHPOTS];
        for (line, dashpot) in self.lines.iter_mut().zip(&self.list) {
            *line = step_line(model, cfg, held, dashpot);
        }
        if self
            .lines
            .iter()
            .any(|line| matches!(line, DashpotLine::TwoPoint { .. }))
        {
            return;
        }
        self.fill_ends(model, cfg, held);
        self.fill_matrix(h);
        let k = self.list.len();
        let width = k + 1;
        // Column j of the inverse solves the system for the j-th unit vector.
        let mut inverse = vec![0.0; k * k];
        let mut column = [0.0; MAX_DASHPOTS];
        let mut augmented = vec![0.0; k * width];
        for j in 0..k {
            for (i, row) in augmented.chunks_mut(width).enumerate() {
                row[..k].copy_from_slice(&self.system[i * width..i * width + k]);
                row[k] = if i == j { 1.0 } else { 0.0 };
            }
            eliminate(&mut augmented, k, &mut column);
            for i in 0..k {
                inverse[i * k + j] = column[i];
            }
        }
        self.steady = Some(inverse);
    }

    /// Each dashpot's moving ends into `self.ends` and its |l|² into `self.span_squares`, at `cfg`.
    #[inline(always)]
    fn fill_ends<const FINITE: bool>(
        &mut self,
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        held: &Constraints<S>,
    ) {
        self.ends.clear();
        for (j, (dashpot, line)) in self.list.iter().zip(&self.lines).enumerate() {
            let d = match *line {
                DashpotLine::Fixed(d) => d,
                DashpotLine::TwoPoint { dashpot, scale } => {
                    let l = model.dashpot_span(cfg, dashpot) * scale;
                    self.span_squares[j] = l.dot(&l);
                    l
                }
            };
            for (end, e) in [(dashpot.a, -d), (dashpot.b, d)] {
                if let Some(p) = end {
                    self.ends
                        .push((j, p, e, model.particle_response(held, p, e)));
                }
            }
        }
    }

    /// `S + (h/2)·K` from `self.ends` and `self.span_squares` into the first k columns of
    /// `self.system` (the right-hand side column zeroed): K_ij = c_j Σ over the particles both
    /// move of e_i·g_j.
    #[inline(always)]
    fn fill_matrix(&mut self, h: f64) {
        let k = self.list.len();
        let width = k + 1;
        let system = &mut self.system;
        fill_zero(system, 0.0);
        for i in 0..k {
            system[i * width + i] = self.span_squares[i];
        }
        for &(i, p, e, _) in &self.ends {
            for &(j, q, _, g) in &self.ends {
                if p == q {
                    system[i * width + j] += 0.5 * h * self.list[j].c * e.dot(&g);
                }
            }
        }
    }

    /// The accelerations `acc` at the centred velocity, and that velocity into `v_n`, from the
    /// position forces and the half-step velocity of `at`; returns the dashpots' dissipation
    /// power. Only for a step without centripetal or gyroscopic terms (the bodies'
    /// accelerations do not read the velocity), and at the increment and constraints of the
    /// last [`ParticleDashpots::prepare`].
    pub(super) fn solve<const FINITE: bool>(
        &mut self,
        at: &AtIncrement<S, FINITE>,
        acc: &mut Rates<S>,
        v_n: &mut Rates<S>,
        counters: &mut Counters,
    ) -> f64 {
        let power = self.accelerations(at, acc, counters);
        v_n.set_plus(at.v_half, 0.5 * at.h, acc);
        power
    }

    /// [`ParticleDashpots::solve`] without the centred velocity itself: the accelerations
    /// `acc` at it and the dashpots' power, for an increment that writes no row.
    pub(super) fn accelerations<const FINITE: bool>(
        &mut self,
        at: &AtIncrement<S, FINITE>,
        acc: &mut Rates<S>,
        counters: &mut Counters,
    ) -> f64 {
        let (model, cfg, forces) = (at.model, at.cfg, at.forces);
        let (v_half, h, held) = (at.v_half, at.h, at.held);
        counters.damping_evaluations += 1;
        model.accelerations(cfg, forces, v_half, held, acc, counters);
        let k = self.list.len();
        // The centred velocity before the dashpots act, as `Rates::set_plus` forms it.
        let centred = |p: usize| v_half.p.get(p) + acc.p.get(p) * (0.5 * h);
        // σ_j: the rates over |l_j| (the rates themselves on fixed unit lines).
        let mut sigma = [0.0; MAX_DASHPOTS];
        if let Some(inverse) = &self.steady {
            // E w, then σ from the step's inverse.
            let mut rhs = [0.0; MAX_DASHPOTS];
            for &(i, p, e, _) in &self.ends {
                rhs[i] += e.dot(&centred(p));
            }
            for (j, s) in sigma[..k].iter_mut().enumerate() {
                *s = inverse[j * k..(j + 1) * k]
                    .iter()
                    .zip(&rhs)
                    .map(|(a, b)| a * b)
                    .sum();
            }
        } else {
            self.fill_ends(model, cfg, held);
            self.fill_matrix(h);
            let width = k + 1;
            for &(i, p, e, _) in &self.ends {
                self.system[i * width + k] += e.dot(&centred(p));
            }
            eliminate(&mut self.system, k, &mut sigma);
        }
        let mut power = 0.0;
        for (j, dashpot) in self.list.iter().enumerate() {
            power += dashpot.c * self.span_squares[j] * sigma[j] * sigma[j];
        }
        for &(j, p, _, g) in &self.ends {
            acc.p.sub(p, g * (self.list[j].c * sigma[j]));
        }
        power
    }
}

/// `dashpot`'s line in a step that starts at `cfg` under `held`: a two-point line whose moving
/// ends are each confined to it ([`Motion::confines_to`](super::model::Motion::confines_to))
/// is fixed along its span at the start; any other line is its own.
fn step_line<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &Config<S>,
    held: &Constraints<S>,
    dashpot: &ParticleDashpot<S>,
) -> DashpotLine<S> {
    let DashpotLine::TwoPoint { dashpot: index, .. } = dashpot.line else {
        return dashpot.line;
    };
    let u = model.dashpot_line(cfg, index);
    // Coincident ends (u not finite) have no line to be confined to.
    let confined = |p: usize| held.particle_projection(p).confines_to(u);
    let unit = (u.dot(&u) - 1.0).abs() <= 1e-12;
    if unit && [dashpot.a, dashpot.b].into_iter().flatten().all(confined) {
        DashpotLine::Fixed(u)
    } else {
        dashpot.line
    }
}

/// Gaussian elimination with partial pivoting of a k × (k + 1) augmented system (row-major,
/// right-hand side last); the solution goes to `x[..k]`.
fn eliminate(a: &mut [f64], k: usize, x: &mut [f64; MAX_DASHPOTS]) {
    if k == 1 {
        // One row: no pivot to choose and nothing to eliminate; the back-substitution below
        // reduces to this division.
        x[0] = a[1] / a[0];
        return;
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case;
    use crate::engines::explicit::space::Planar;

    /// springs_n2n_c's dynamic step holds both masses across the dashpot's 45° line: the line
    /// is fixed for the step and the system's inverse formed once. Release either mass across
    /// the line and the line turns again, formed at every increment.
    #[test]
    fn a_dashpot_whose_moving_ends_are_held_across_its_line_does_not_turn() {
        let scene = case::load(&case::cases_dir().join("springs_n2n_c.toml")).unwrap();
        let model = Model::<Planar, true>::compile(&scene, 1.0);
        let cfg = model.initial_config();
        let prepared = |step: &crate::scene::Step| {
            let mut dashpots = ParticleDashpots::of(&model).expect("one particle dashpot");
            assert!(matches!(
                dashpots.list[0].line,
                DashpotLine::TwoPoint { .. }
            ));
            dashpots.prepare(&model, &cfg, &model.constraints(step), 1e-4);
            dashpots
        };
        let held = prepared(&scene.steps[1]);
        let DashpotLine::Fixed(line) = held.lines[0] else {
            panic!("the line of a dashpot held on it is fixed");
        };
        let diagonal = std::f64::consts::FRAC_1_SQRT_2;
        assert!((line.x - diagonal).abs() <= 1e-16 && (line.y - diagonal).abs() <= 1e-16);
        assert!(held.steady.is_some());
        for name in ["102", "103"] {
            let node = scene.node_named(name).unwrap();
            let mut released = scene.steps[1].clone();
            released.conditions.retain(|c| c.node != node);
            let turning = prepared(&released);
            assert!(
                matches!(turning.lines[0], DashpotLine::TwoPoint { .. }),
                "{name}"
            );
            assert!(turning.steady.is_none(), "{name}");
        }
    }
}
