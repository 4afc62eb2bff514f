//! A small dynamic step whose forces are affine in the displacements, stepped as a recurrence
//! in its free DOFs with the state in registers.
//!
//! Particles on springs along fixed lines ([`AffineSpring`]), constant loads and dashpots along
//! fixed lines, no body and no contact: the force is `F(u) = F(u₀) − K (u − u₀)`, with K formed
//! once per step from the springs. In the step's free DOFs q (the unit frame axes of each
//! particle that the step does not hold) the general path's increment — the accelerations
//! `a = P M⁻¹ F` (P the step's projection), the dashpots' centred rates
//! `σ = (I + (h/2)·K_c)⁻¹ E (v(n−½) + (h/2)·a)` ([`ParticleDashpots`]), `a −= P M⁻¹ Eᵀ c σ`, `v(n+½) = v(n−½) + h·a` and the compensated
//! `q += h·v(n+½)` — is a few products with matrices of at most [`MAX_DOFS`]² entries, on a
//! state that stays in registers for the increments between two output rows. The general path
//! reads that state from memory and sums the forces element by element at every increment.
//!
//! What differs is the order of the forces' sums (`F(u₀) − K q`, with q the motion since the
//! batch started, against each element's force at u), and the rounding of the
//! displacement's compensated sum, which here runs from zero at each batch: a run is the
//! general path's to round-off (`tests/affine.rs`). An axial spring held on its line is checked
//! at every increment; where its ends would pass each other, or come within a rounding margin of
//! it (where the two paths' roundings could take different sides), the batch stops and the
//! general path decides, taking the spring's turning force once they have passed.

use super::centred::ParticleDashpots;
use super::model::{AffineSpring, Config, Constraints, Counters, Forces, Model, Rates, Target};
use super::space::{Lin, Space, compensated_add};
use crate::scene::DampingTreatment;

/// At most this many free DOFs: their displacements, rounding carries and velocities then
/// stay in registers.
pub const MAX_DOFS: usize = 4;
/// At most this many dashpots.
pub const MAX_DASHPOTS: usize = 2;
/// At most this many axial springs held on their lines (each checked at every increment).
pub const MAX_HELD_LINES: usize = 8;

/// An axial spring held on its line: its stretch along the line per unit motion of each free
/// DOF, and what it needs to know where its ends are.
#[derive(Debug, Clone, Copy)]
struct HeldLine<S: Space> {
    a: Option<usize>,
    b: Option<usize>,
    direction: S::V,
    length0: f64,
    stretch: [f64; MAX_DOFS],
}

/// The recurrence of one dynamic step (see the module's documentation), formed by
/// [`AffineStep::of`] at the step's start.
#[derive(Debug, Clone)]
pub struct AffineStep<S: Space> {
    /// The free DOFs: particle and unit direction, grouped by particle.
    dofs: Vec<(usize, S::V)>,
    /// 1/mass of each DOF's particle.
    inverse_masses: [f64; MAX_DOFS],
    /// −M⁻¹K in the free DOFs: the acceleration of DOF j per unit motion of DOF l.
    response: [[f64; MAX_DOFS]; MAX_DOFS],
    /// Number of dashpots.
    dashpots: usize,
    /// Whether the scene has dashpots, whose solve the general path counts at every increment
    /// (even where none acts between particles).
    counts_dashpots: bool,
    /// Dashpot coefficients.
    coefficients: [f64; MAX_DASHPOTS],
    /// E: each dashpot's rate per unit velocity of each DOF.
    rates: [[f64; MAX_DOFS]; MAX_DASHPOTS],
    /// `P M⁻¹` of each dashpot's line in the free DOFs: the acceleration of each DOF per unit
    /// force `c σ` of the dashpot.
    pushes: [[f64; MAX_DOFS]; MAX_DASHPOTS],
    /// `(I + (h/2)·K_c)⁻¹` of the step ([`ParticleDashpots::steady`]).
    inverse: [[f64; MAX_DASHPOTS]; MAX_DASHPOTS],
    held_lines: Vec<HeldLine<S>>,
}

/// Per held line, the stretch at which a batch stops ([`AffineStep::meets`]).
pub type Meets = [f64; MAX_HELD_LINES];

/// The state a batch starts from (in the free DOFs).
struct Start {
    accelerations: [f64; MAX_DOFS],
    velocities: [f64; MAX_DOFS],
    /// Per held line, the stretch since the batch started at which its ends would meet, plus
    /// a rounding margin: at or below it the general path takes the increment.
    meet: [f64; MAX_HELD_LINES],
}

/// The state a batch ends at.
struct Batch {
    increments: u64,
    motion: [f64; MAX_DOFS],
    carry: [f64; MAX_DOFS],
    velocities: [f64; MAX_DOFS],
    dissipated: f64,
    last_power: f64,
}

impl<S: Space> AffineStep<S> {
    /// The recurrence of a dynamic step under `held` at the increment `dashpots` were prepared
    /// for, when the step's forces are affine ([`Model::affine_springs`]), it has 1 to
    /// [`MAX_DOFS`] free DOFs, all of particles, whose projections keep exactly their free
    /// axes, at most [`MAX_DASHPOTS`] dashpots, all on fixed lines and solved with the
    /// centred treatment (`dashpots`, prepared for the step), and at most [`MAX_HELD_LINES`]
    /// axial springs held on their lines. None otherwise.
    pub fn of<const FINITE: bool>(
        model: &Model<S, FINITE>,
        held: &Constraints<S>,
        dashpots: Option<&ParticleDashpots<S>>,
        damping: DampingTreatment,
    ) -> Option<Self> {
        let springs: Vec<AffineSpring<S>> = model.affine_springs()?;
        let (list, ends, inverse) = if model.has_dashpots() {
            if damping != DampingTreatment::Centred {
                return None;
            }
            dashpots?.steady()?
        } else {
            (&[][..], &[][..], &[][..])
        };
        let k = list.len();
        let dofs = model
            .free_dofs(held)
            .into_iter()
            .map(|t| match t {
                Target::Particle(i, d) => Some((i, d)),
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        let n = dofs.len();
        if n == 0 || n > MAX_DOFS || k > MAX_DASHPOTS {
            return None;
        }
        // Each particle's projection keeps its free axes and removes its held ones (to
        // round-off): the free DOFs then carry all of its motion.
        for (i, p) in model.particles.iter().enumerate() {
            let motion = held.motions[held.particle_motion[i] as usize];
            for axis in &p.axes {
                let free = dofs.iter().any(|(j, d)| *j == i && d == axis);
                let kept = if free { *axis } else { S::V::zero() };
                let off = motion.project(*axis) - kept;
                if off.dot(&off) > 1e-24 {
                    return None;
                }
            }
        }
        let mut inverse_masses = [0.0; MAX_DOFS];
        for (m, (p, _)) in inverse_masses.iter_mut().zip(&dofs) {
            *m = model.particles[*p].inverse_mass;
        }
        // An element's pattern: its line's component along each DOF, − at end a, + at end b.
        let pattern = |a: Option<usize>, b: Option<usize>, line: S::V| {
            let mut e = [0.0; MAX_DOFS];
            for (x, (p, d)) in e.iter_mut().zip(&dofs) {
                if a == Some(*p) {
                    *x -= line.dot(d);
                }
                if b == Some(*p) {
                    *x += line.dot(d);
                }
            }
            e
        };
        let mut stiffness = [[0.0; MAX_DOFS]; MAX_DOFS];
        let mut held_lines = Vec::new();
        for s in &springs {
            let e = pattern(s.a, s.b, s.direction);
            for j in 0..n {
                for l in 0..n {
                    stiffness[j][l] += s.c * e[j] * e[l];
                }
            }
            if let Some(length0) = s.held_length {
                held_lines.push(HeldLine {
                    a: s.a,
                    b: s.b,
                    direction: s.direction,
                    length0,
                    stretch: e,
                });
            }
        }
        if held_lines.len() > MAX_HELD_LINES {
            return None;
        }
        let mut response = [[0.0; MAX_DOFS]; MAX_DOFS];
        for j in 0..n {
            for l in 0..n {
                response[j][l] = -stiffness[j][l] * inverse_masses[j];
            }
        }
        let mut step = AffineStep {
            dofs,
            inverse_masses,
            response,
            dashpots: k,
            counts_dashpots: model.has_dashpots(),
            coefficients: [0.0; MAX_DASHPOTS],
            rates: [[0.0; MAX_DOFS]; MAX_DASHPOTS],
            pushes: [[0.0; MAX_DOFS]; MAX_DASHPOTS],
            inverse: [[0.0; MAX_DASHPOTS]; MAX_DASHPOTS],
            held_lines,
        };
        for (i, dashpot) in list.iter().enumerate() {
            step.coefficients[i] = dashpot.c;
            for m in 0..k {
                step.inverse[i][m] = inverse[i * k + m];
            }
        }
        for &(i, p, e, g) in ends {
            for (l, (q, d)) in step.dofs.iter().enumerate() {
                if p == *q {
                    step.rates[i][l] += e.dot(d);
                    step.pushes[i][l] += g.dot(d);
                }
            }
        }
        Some(step)
    }

    /// Per axial spring held on its line, the stretch from `cfg` at which a batch stops
    /// ([`AffineStep::meet`] plus [`AffineStep::margin`]), where every one takes the line's
    /// force at `cfg` (its length at t = 0 plus its stretch along the line is positive, as
    /// `Model::forces_with` asks) by more than the margin; None where one does not: the
    /// general path then takes the increment.
    pub fn meets(&self, cfg: &Config<S>) -> Option<Meets> {
        let mut meets = [0.0; MAX_HELD_LINES];
        for (meet, line) in meets.iter_mut().zip(&self.held_lines) {
            *meet = self.meet(line, cfg) + self.margin(line, cfg);
            if *meet >= 0.0 {
                return None;
            }
        }
        Some(meets)
    }

    /// The stretch since `cfg` at which `line`'s ends would meet.
    fn meet(&self, line: &HeldLine<S>, cfg: &Config<S>) -> f64 {
        let at = |p: Option<usize>| p.map_or(S::V::zero(), |i| cfg.u[i]);
        -(line.length0 + line.direction.dot(&(at(line.b) - at(line.a))))
    }

    /// How close to [`AffineStep::meet`] a batch may come: the span along the line is formed
    /// here from the batch's start plus the motion since, and by the general path from the
    /// displacements, each rounded to a few ulps of the length and the displacements. Within
    /// 10^-12 of their size (some 4,500 ulps) the two could fall on different sides of zero,
    /// where the force jumps by 2·c·length0; there the general path takes the increment.
    fn margin(&self, line: &HeldLine<S>, cfg: &Config<S>) -> f64 {
        let size = |p: Option<usize>| p.map_or(0.0, |i| cfg.u[i].dot(&cfg.u[i]).sqrt());
        1e-12 * (line.length0 + size(line.a) + size(line.b))
    }

    /// Step `count` (≥ 1) increments at most from `cfg`, `carry` and the half-step velocities
    /// `v_half`, where `forces` are the forces at `cfg` and `meets` are
    /// [`AffineStep::meets`] at `cfg`; `dissipated` and `last_power` go on as the time loop
    /// keeps them (the dashpots' work and the power of the last increment). Returns the
    /// increments taken, at least one: fewer than `count` only where an axial spring held on
    /// its line would come within the margin of its ends meeting.
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        v_half: &mut Rates<S>,
        forces: &Forces<S>,
        meets: &Meets,
        h: f64,
        count: u64,
        dissipated: &mut f64,
        last_power: &mut f64,
        counters: &mut Counters,
    ) -> u64 {
        let mut start = Start {
            accelerations: [0.0; MAX_DOFS],
            velocities: [0.0; MAX_DOFS],
            meet: *meets,
        };
        for (l, (p, d)) in self.dofs.iter().enumerate() {
            start.accelerations[l] = self.inverse_masses[l] * d.dot(&forces.p[*p]);
            start.velocities[l] = d.dot(&v_half.p[*p]);
        }
        let (n, k) = (self.dofs.len(), self.dashpots);
        macro_rules! dispatch {
            ($(($n:literal, $k:literal)),*) => {
                match (n, k) {
                    $(($n, $k) => self.run::<$n, $k>(&start, count, h, *dissipated, *last_power),)*
                    _ => unreachable!("AffineStep::of bounds the DOFs and dashpots"),
                }
            };
        }
        let batch = dispatch!(
            (1, 0),
            (1, 1),
            (1, 2),
            (2, 0),
            (2, 1),
            (2, 2),
            (3, 0),
            (3, 1),
            (3, 2),
            (4, 0),
            (4, 1),
            (4, 2)
        );
        // Back into the configuration: each particle's motion along its free axes, added with
        // its rounding carry; its velocity along them replaced, the rest of it kept.
        let mut l = 0;
        while l < n {
            let p = self.dofs[l].0;
            let (mut motion, mut now, mut before) = (S::V::zero(), S::V::zero(), S::V::zero());
            while l < n && self.dofs[l].0 == p {
                let d = self.dofs[l].1;
                motion += d * (batch.motion[l] - batch.carry[l]);
                now += d * batch.velocities[l];
                before += d * start.velocities[l];
                l += 1;
            }
            compensated_add(&mut cfg.u[p], &mut carry.p[p], motion);
            v_half.p[p] = now + (v_half.p[p] - before);
        }
        *dissipated = batch.dissipated;
        *last_power = batch.last_power;
        counters.affine_increments += batch.increments;
        // The caller's force pass served the first increment.
        counters.force_evaluations += batch.increments - 1;
        if self.counts_dashpots {
            counters.damping_evaluations += batch.increments;
        }
        batch.increments
    }

    /// [`AffineStep::advance`] with `N` DOFs and `K` dashpots known to the compiler, so that
    /// the state and the step's matrices are held in registers.
    #[inline(never)]
    fn run<const N: usize, const K: usize>(
        &self,
        start: &Start,
        count: u64,
        h: f64,
        mut dissipated: f64,
        mut last_power: f64,
    ) -> Batch {
        let a0: [f64; N] = std::array::from_fn(|j| start.accelerations[j]);
        let response: [[f64; N]; N] =
            std::array::from_fn(|j| std::array::from_fn(|l| self.response[j][l]));
        let rates: [[f64; N]; K] =
            std::array::from_fn(|i| std::array::from_fn(|l| self.rates[i][l]));
        let pushes: [[f64; N]; K] =
            std::array::from_fn(|i| std::array::from_fn(|l| self.pushes[i][l]));
        let inverse: [[f64; K]; K] =
            std::array::from_fn(|i| std::array::from_fn(|m| self.inverse[i][m]));
        let c: [f64; K] = std::array::from_fn(|i| self.coefficients[i]);
        let lines = &self.held_lines;
        let mut v: [f64; N] = std::array::from_fn(|j| start.velocities[j]);
        let (mut q, mut carry) = ([0.0; N], [0.0; N]);
        let half = 0.5 * h;
        let mut increments = 0;
        'increments: while increments < count {
            for (line, meet) in lines.iter().zip(&start.meet) {
                let mut stretch = 0.0;
                for (e, x) in line.stretch.iter().zip(&q) {
                    stretch += e * x;
                }
                if stretch <= *meet {
                    break 'increments;
                }
            }
            let mut a = [0.0; N];
            for j in 0..N {
                let mut sum = response[j][0] * q[0];
                for l in 1..N {
                    sum += response[j][l] * q[l];
                }
                a[j] = a0[j] + sum;
            }
            if K > 0 {
                // The centred rates, as `ParticleDashpots::solve` forms them.
                let mut rhs = [0.0; K];
                for i in 0..K {
                    for l in 0..N {
                        rhs[i] += rates[i][l] * (v[l] + a[l] * half);
                    }
                }
                let mut power = 0.0;
                for i in 0..K {
                    let mut sigma = inverse[i][0] * rhs[0];
                    for m in 1..K {
                        sigma += inverse[i][m] * rhs[m];
                    }
                    let force = c[i] * sigma;
                    for l in 0..N {
                        a[l] -= pushes[i][l] * force;
                    }
                    power += force * sigma;
                }
                dissipated += 0.5 * h * (last_power + power);
                last_power = power;
            }
            for l in 0..N {
                v[l] += a[l] * h;
                compensated_add(&mut q[l], &mut carry[l], v[l] * h);
            }
            increments += 1;
        }
        if K == 0 {
            last_power = 0.0;
        }
        let widen = |x: [f64; N]| -> [f64; MAX_DOFS] {
            std::array::from_fn(|l| if l < N { x[l] } else { 0.0 })
        };
        Batch {
            increments,
            motion: widen(q),
            carry: widen(carry),
            velocities: widen(v),
            dissipated,
            last_power,
        }
    }
}
