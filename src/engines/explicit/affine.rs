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
//!
//! Under small rotation (`explicit_small`) a scene with rigid bodies and plane contacts is
//! affine too, in the bodies' translations and rotation vectors, for as long as each contact
//! stays on the side of its gap it started the batch on (pressed: the penalty acts; apart: no
//! force). There the response, each contact's gap per unit motion and its push per unit normal
//! force are formed once per step from the engine's own force pass and body solve (differences
//! on both sides of rest along each DOF, checked to agree). A batch stops before an increment
//! where a contact would change sides; the next starts from the other side with the engine's
//! own force pass, which notes the impact as the general path does. Within a rounding margin
//! of a gap's zero the general path takes the increment.

use super::centred::ParticleDashpots;
use super::model::{
    AffineSpring, Config, Constraints, ContactMode, Counters, Forces, Model, Rates, Target,
};
use super::space::{Lin, Space, compensated_add};
use crate::scene::DampingTreatment;

/// At most this many free DOFs: their displacements, rounding carries and velocities then
/// stay in registers.
pub const MAX_DOFS: usize = 4;
/// At most this many dashpots.
pub const MAX_DASHPOTS: usize = 2;
/// At most this many axial springs held on their lines and contact pairs, together (each
/// checked at every increment).
pub const MAX_SIDES: usize = 8;
/// The motion along each DOF at which a step with bodies forms its response by differences
/// (and its opposite, to check the other side): a power of two, so that the motion itself is
/// exact, and large, so that the forces it makes outweigh the rounding of the loads and forces
/// at rest that the difference removes. The contacts' pushes are formed likewise, from normal
/// forces of PROBE times the largest force at rest.
const PROBE: f64 = 1_048_576.0;
/// How closely the differences on the two sides of rest must agree (relative to the largest
/// entry). That the forces are affine follows from the small-rotation model (fixed arms and
/// normals, forces linear in the displacements and rotation vectors); this check is a safety
/// net that catches a force not affine along a DOF (it cannot see a product of two DOFs).
/// Where the model is affine the two sides agree to round-off, far inside it.
const AFFINE_AGREEMENT: f64 = 1e-9;

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

/// A plane contact pair under small rotation, in the free DOFs.
#[derive(Debug, Clone, Copy)]
struct PlaneContact {
    /// The gap's change per unit motion of each DOF.
    gap_per_motion: [f64; MAX_DOFS],
    /// The acceleration of each DOF per unit normal force (compressive positive).
    push: [f64; MAX_DOFS],
}

/// Where the free DOFs' motion goes back into the state: the DOFs of one particle, one body's
/// translation or one body's rotation, with their unit directions.
#[derive(Debug, Clone)]
enum Group<S: Space> {
    Particle(usize, Vec<(usize, S::V)>),
    Translation(usize, Vec<(usize, S::V)>),
    Rotation(usize, Vec<(usize, S::W)>),
}

/// The recurrence of one dynamic step (see the module's documentation), formed by
/// [`AffineStep::of`] at the step's start.
#[derive(Debug, Clone)]
pub struct AffineStep<S: Space> {
    /// The free DOFs, grouped by particle, then by body (translations, then rotations).
    dofs: Vec<Target<S>>,
    /// The same DOFs as they go back into the state.
    groups: Vec<Group<S>>,
    /// 1/mass of each DOF's particle (a scene of particles: their accelerations at a batch's
    /// start are formed here; with bodies the caller's body solve forms them).
    inverse_masses: Option<[f64; MAX_DOFS]>,
    /// −M⁻¹K in the free DOFs, every contact apart: the acceleration of DOF j per unit motion
    /// of DOF l.
    response: [[f64; MAX_DOFS]; MAX_DOFS],
    /// The plane contact pairs (bodies only), in the model's order.
    contacts: Vec<PlaneContact>,
    /// The penalty stiffness.
    penalty: f64,
    /// How many bodies, and how many of them turn: the general path counts a solve and an
    /// orientation update per increment for them.
    body_count: u64,
    rotating_count: u64,
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

/// A bound on a batch: it stops before an increment where
/// `pattern · q ≤ limit + 1e-12·Σ|pattern_l q_l|`, with q the motion of the free DOFs since it
/// started (the last term: the rounding of a sum that has grown since the batch started, on top
/// of the margin `limit` holds for the terms at its start).
#[derive(Debug, Clone, Copy, Default)]
struct Side {
    pattern: [f64; MAX_DOFS],
    limit: f64,
}

/// Where a batch from a given state stops, and which contacts press in it
/// ([`AffineStep::bounds`]).
#[derive(Debug, Clone, Copy)]
pub struct Bounds {
    sides: [Side; MAX_SIDES],
    count: usize,
    pressing: [bool; MAX_SIDES],
}

/// The state a batch starts from (in the free DOFs).
struct Start {
    accelerations: [f64; MAX_DOFS],
    velocities: [f64; MAX_DOFS],
    /// The response with the contacts that press in this batch.
    response: [[f64; MAX_DOFS]; MAX_DOFS],
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
    /// centred treatment (`dashpots`, prepared for the step), and at most [`MAX_SIDES`]
    /// axial springs held on their lines. None otherwise.
    ///
    /// A scene with bodies or contacts takes `AffineStep::with_bodies` instead.
    pub fn of<const FINITE: bool>(
        model: &Model<S, FINITE>,
        held: &Constraints<S>,
        dashpots: Option<&ParticleDashpots<S>>,
        damping: DampingTreatment,
    ) -> Option<Self> {
        if !model.bodies.is_empty() || model.contact_count() > 0 {
            return Self::with_bodies(model, held);
        }
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
        if held_lines.len() > MAX_SIDES {
            return None;
        }
        let mut response = [[0.0; MAX_DOFS]; MAX_DOFS];
        for j in 0..n {
            for l in 0..n {
                response[j][l] = -stiffness[j][l] * inverse_masses[j];
            }
        }
        let mut step = AffineStep {
            groups: groups(
                &dofs
                    .iter()
                    .map(|(p, d)| Target::Particle(*p, *d))
                    .collect::<Vec<_>>(),
            ),
            dofs: dofs.iter().map(|(p, d)| Target::Particle(*p, *d)).collect(),
            inverse_masses: Some(inverse_masses),
            response,
            contacts: Vec::new(),
            penalty: 0.0,
            body_count: 0,
            rotating_count: 0,
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
            for (l, (q, d)) in dofs.iter().enumerate() {
                if p == *q {
                    step.rates[i][l] += e.dot(d);
                    step.pushes[i][l] += g.dot(d);
                }
            }
        }
        Some(step)
    }

    /// The recurrence of a dynamic step of a scene with bodies or contacts under small
    /// rotation, where its forces are affine while each contact stays on its side: no
    /// dashpot, no solid contact (only planes), 1 to [`MAX_DOFS`] free DOFs whose
    /// accelerations the general path keeps within them, at most [`MAX_SIDES`] contact pairs,
    /// and every body's operator formed once for the step. The response, each contact's gap
    /// per unit motion and its push per unit normal force come from the engine's own force
    /// pass and body solve, as differences at the motions ±[`PROBE`] along each DOF from rest
    /// (and normal forces ±PROBE times the largest force at rest); where the two sides differ
    /// by more than [`AFFINE_AGREEMENT`] the step is declined. None otherwise, and under finite
    /// rotation.
    fn with_bodies<const FINITE: bool>(
        model: &Model<S, FINITE>,
        held: &Constraints<S>,
    ) -> Option<Self> {
        if FINITE
            || model.has_dashpots()
            || model.has_solids()
            || held.any_velocity_terms()
            || model.contact_count() > MAX_SIDES
            || held.body_operators.iter().any(Option::is_none)
        {
            return None;
        }
        let dofs = model.free_dofs(held);
        let n = dofs.len();
        if n == 0 || n > MAX_DOFS {
            return None;
        }
        // Scratch for the differences: none of this is the run's work.
        let mut counters = Counters::default();
        let rest = model.initial_config();
        let still = model.zero_rates();
        let mut forces = model.zero_forces();
        let mut acc = model.zero_rates();
        // The accelerations of the force difference `plus − minus` over `scale`, in the free
        // DOFs; None where the general path's accelerations leave their span.
        let mut response_to = |plus: &Forces<S>, minus: &Forces<S>, scale: f64| {
            let mut f = model.zero_forces();
            for (x, (a, b)) in f.p.iter_mut().zip(plus.p.iter().zip(&minus.p)) {
                *x = (*a - *b) * scale;
            }
            for (x, (a, b)) in f.b.iter_mut().zip(plus.b.iter().zip(&minus.b)) {
                *x = (*a - *b) * scale;
            }
            for (x, (a, b)) in f.m.iter_mut().zip(plus.m.iter().zip(&minus.m)) {
                *x = (*a - *b) * scale;
            }
            model.accelerations(&rest, &f, &still, held, &mut acc, &mut counters);
            let mut along = [0.0; MAX_DOFS];
            let mut within = model.zero_rates();
            for (x, t) in along.iter_mut().zip(&dofs) {
                *x = model.rate_along(&acc, t);
                within = within.plus(*x, &model.unit_rate(t));
            }
            let (off, size) = acc.max_difference(&within);
            (off <= AFFINE_AGREEMENT * size).then_some(along)
        };
        let forces_at = |cfg: &Config<S>, mode: ContactMode, out: &mut Forces<S>| {
            let mut scratch = Counters::default();
            model.forces(cfg, mode, out, &mut scratch);
        };
        let agree = |a: &[f64; MAX_DOFS], b: &[f64; MAX_DOFS]| {
            let size = a.iter().chain(b).fold(0.0_f64, |m, x| m.max(x.abs()));
            a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= AFFINE_AGREEMENT * size)
        };
        forces_at(&rest, ContactMode::Off, &mut forces);
        let at_rest = forces.clone();
        let mut response = [[0.0; MAX_DOFS]; MAX_DOFS];
        let mut gaps = vec![[0.0; MAX_DOFS]; model.contact_count()];
        let (mut plus, mut minus) = (model.zero_forces(), model.zero_forces());
        for (l, t) in dofs.iter().enumerate() {
            let (mut up, mut down) = (rest.clone(), rest.clone());
            model.perturb(&mut up, t, PROBE);
            model.perturb(&mut down, t, -PROBE);
            forces_at(&up, ContactMode::Off, &mut plus);
            forces_at(&down, ContactMode::Off, &mut minus);
            let column = response_to(&plus, &at_rest, 1.0 / PROBE)?;
            if !agree(&column, &response_to(&at_rest, &minus, 1.0 / PROBE)?) {
                return None;
            }
            for (row, x) in response.iter_mut().zip(column) {
                row[l] = x;
            }
            for (k, gap) in gaps.iter_mut().enumerate() {
                let (at, above, below) = (
                    model.gap(&rest, k).0,
                    model.gap(&up, k).0,
                    model.gap(&down, k).0,
                );
                gap[l] = (above - at) / PROBE;
                let other = (at - below) / PROBE;
                let size = gap[l].abs().max(other.abs());
                if (gap[l] - other).abs() > AFFINE_AGREEMENT * size {
                    return None;
                }
            }
        }
        // Each contact's push from normal forces ±`probe`: a power of two at least PROBE times
        // the largest force at rest, so that the rounding of the loads it is summed with is
        // far below it.
        let largest = at_rest.p.iter().chain(&at_rest.b).map(|f| f.dot(f).sqrt());
        let largest = largest.chain(at_rest.m.iter().map(|m| m.dot(m).sqrt()));
        let probe = PROBE * largest.fold(1.0_f64, f64::max).log2().ceil().exp2();
        let mut contacts = Vec::new();
        let none = vec![0.0; model.contact_count()];
        forces_at(&rest, ContactMode::Given(&none), &mut forces);
        for (k, gap_per_motion) in gaps.into_iter().enumerate() {
            let mut given = none.clone();
            given[k] = probe;
            forces_at(&rest, ContactMode::Given(&given), &mut plus);
            given[k] = -probe;
            forces_at(&rest, ContactMode::Given(&given), &mut minus);
            let push = response_to(&plus, &forces, 1.0 / probe)?;
            if !agree(&push, &response_to(&forces, &minus, 1.0 / probe)?) {
                return None;
            }
            contacts.push(PlaneContact {
                gap_per_motion,
                push,
            });
        }
        let rotating_count = held.rotating.iter().filter(|r| **r).count() as u64;
        Some(AffineStep {
            groups: groups(&dofs),
            dofs,
            inverse_masses: None,
            response,
            contacts,
            penalty: model.penalty,
            body_count: model.bodies.len() as u64,
            rotating_count,
            dashpots: 0,
            counts_dashpots: false,
            coefficients: [0.0; MAX_DASHPOTS],
            rates: [[0.0; MAX_DOFS]; MAX_DASHPOTS],
            pushes: [[0.0; MAX_DOFS]; MAX_DASHPOTS],
            inverse: [[0.0; MAX_DASHPOTS]; MAX_DASHPOTS],
            held_lines: Vec::new(),
        })
    }

    /// Whether the accelerations at a batch's start come from the caller's body solve
    /// ([`AffineStep::advance`]'s `solved`).
    pub fn solves_bodies(&self) -> bool {
        self.inverse_masses.is_none()
    }

    /// Where a batch from `cfg` stops: per axial spring held on its line, the stretch at which
    /// its ends would meet (`AffineStep::meet`) plus its margin (`AffineStep::margin`); per
    /// contact pair, the motion at which its gap would come within its rounding margin
    /// (10^-12 of [`Model::gap_size`]) of zero from the side it is on. To each margin the
    /// batch adds 10^-12 of the size its motion since the start gives the sum (`Side`). None
    /// where a held line does not take the line's force at `cfg` by more than the margin (its
    /// length at t = 0 plus its stretch along the line is positive, as `Model::forces_with`
    /// asks) or a contact is within its margin of zero: the general path then takes the
    /// increment.
    pub fn bounds<const FINITE: bool>(
        &self,
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
    ) -> Option<Bounds> {
        let mut bounds = Bounds {
            sides: [Side::default(); MAX_SIDES],
            count: self.held_lines.len() + self.contacts.len(),
            pressing: [false; MAX_SIDES],
        };
        for (side, line) in bounds.sides.iter_mut().zip(&self.held_lines) {
            side.pattern = line.stretch;
            side.limit = self.meet(line, cfg) + self.margin(line, cfg);
            if side.limit >= 0.0 {
                return None;
            }
        }
        let sides = bounds.sides[self.held_lines.len()..].iter_mut();
        for (k, (side, contact)) in sides.zip(&self.contacts).enumerate() {
            let gap = model.gap(cfg, k).0;
            let margin = 1e-12 * model.gap_size(cfg, k);
            // Pressing, it stops where the gap rises to −margin; apart, where it falls to
            // +margin.
            let pressing = gap < 0.0;
            let sign = if pressing { -1.0 } else { 1.0 };
            side.pattern = contact.gap_per_motion.map(|g| sign * g);
            side.limit = -(sign * gap) + margin;
            if side.limit >= 0.0 {
                return None;
            }
            bounds.pressing[k] = pressing;
        }
        Some(bounds)
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
    /// `v_half`, where `forces` are the forces at `cfg`, `solved` the accelerations the
    /// general path's body solve forms from them (given where [`AffineStep::solves_bodies`])
    /// and `bounds` are [`AffineStep::bounds`] at `cfg`; `dissipated` and `last_power` go on as
    /// the time loop keeps them (the dashpots' work and the power of the last increment).
    /// Returns the increments taken, at least one: fewer than `count` only where an axial
    /// spring held on its line would come within the margin of its ends meeting, or a contact
    /// within the margin of its gap's zero.
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &self,
        cfg: &mut Config<S>,
        carry: &mut Rates<S>,
        v_half: &mut Rates<S>,
        forces: &Forces<S>,
        solved: Option<&Rates<S>>,
        bounds: &Bounds,
        h: f64,
        count: u64,
        dissipated: &mut f64,
        last_power: &mut f64,
        counters: &mut Counters,
    ) -> u64 {
        let mut start = Start {
            accelerations: [0.0; MAX_DOFS],
            velocities: [0.0; MAX_DOFS],
            response: self.response,
        };
        for (l, t) in self.dofs.iter().enumerate() {
            start.accelerations[l] = match (self.inverse_masses, t, solved) {
                (Some(m), Target::Particle(p, d), _) => m[l] * d.dot(&forces.p[*p]),
                (None, _, Some(solved)) => rate(solved, t),
                _ => unreachable!("a step with bodies is given the body solve's accelerations"),
            };
            start.velocities[l] = rate(v_half, t);
        }
        // A pressing contact adds its penalty: −k_p·push ⊗ gap.
        for (contact, pressing) in self.contacts.iter().zip(bounds.pressing) {
            if pressing {
                for (row, push) in start.response.iter_mut().zip(contact.push) {
                    for (x, gap) in row.iter_mut().zip(contact.gap_per_motion) {
                        *x -= self.penalty * push * gap;
                    }
                }
            }
        }
        let (n, k) = (self.dofs.len(), self.dashpots);
        let sides = &bounds.sides[..bounds.count];
        macro_rules! dispatch {
            ($(($n:literal, $k:literal)),*) => {
                match (n, k) {
                    $(($n, $k) => self.run::<$n, $k>(&start, sides, count, h, *dissipated, *last_power),)*
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
        // Back into the configuration: each particle's or body's motion along its free axes,
        // added with its rounding carry; its velocity along them replaced, the rest of it kept.
        for group in &self.groups {
            let before = &start.velocities;
            match group {
                Group::Particle(p, axes) => {
                    let (x, c, v) = (&mut cfg.u[*p], &mut carry.p[*p], &mut v_half.p[*p]);
                    put_back(x, c, v, axes, &batch, before);
                }
                Group::Translation(b, axes) => {
                    let (x, c, v) = (&mut cfg.bu[*b], &mut carry.b[*b], &mut v_half.b[*b]);
                    put_back(x, c, v, axes, &batch, before);
                }
                Group::Rotation(b, axes) => {
                    let (x, c, v) = (&mut cfg.bth[*b], &mut carry.w[*b], &mut v_half.w[*b]);
                    put_back(x, c, v, axes, &batch, before);
                }
            }
        }
        *dissipated = batch.dissipated;
        *last_power = batch.last_power;
        let taken = batch.increments;
        counters.affine_increments += taken;
        // Counted as the general path counts its work: the caller's force pass (and body
        // solve) served the first increment.
        counters.force_evaluations += taken - 1;
        counters.contact_evaluations += self.contacts.len() as u64 * (taken - 1);
        counters.body_solves += self.body_count * (taken - 1);
        counters.rotation_updates += self.rotating_count * taken;
        if self.counts_dashpots {
            counters.damping_evaluations += taken;
        }
        taken
    }

    /// [`AffineStep::advance`] with `N` DOFs and `K` dashpots known to the compiler, so that
    /// the state and the step's matrices are held in registers.
    #[inline(never)]
    fn run<const N: usize, const K: usize>(
        &self,
        start: &Start,
        sides: &[Side],
        count: u64,
        h: f64,
        mut dissipated: f64,
        mut last_power: f64,
    ) -> Batch {
        let a0: [f64; N] = std::array::from_fn(|j| start.accelerations[j]);
        let response: [[f64; N]; N] =
            std::array::from_fn(|j| std::array::from_fn(|l| start.response[j][l]));
        let rates: [[f64; N]; K] =
            std::array::from_fn(|i| std::array::from_fn(|l| self.rates[i][l]));
        let pushes: [[f64; N]; K] =
            std::array::from_fn(|i| std::array::from_fn(|l| self.pushes[i][l]));
        let inverse: [[f64; K]; K] =
            std::array::from_fn(|i| std::array::from_fn(|m| self.inverse[i][m]));
        let c: [f64; K] = std::array::from_fn(|i| self.coefficients[i]);
        let mut v: [f64; N] = std::array::from_fn(|j| start.velocities[j]);
        let (mut q, mut carry) = ([0.0; N], [0.0; N]);
        let half = 0.5 * h;
        let mut increments = 0;
        'increments: while increments < count {
            for side in sides {
                let (mut stretch, mut size) = (0.0, 0.0);
                for (e, x) in side.pattern.iter().zip(&q) {
                    stretch += e * x;
                    size += (e * x).abs();
                }
                if stretch <= side.limit + 1e-12 * size {
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

/// The rate of a generalised DOF (as [`Model::rate_along`], which needs no model).
fn rate<S: Space>(rates: &Rates<S>, target: &Target<S>) -> f64 {
    match target {
        Target::Particle(i, d) => d.dot(&rates.p[*i]),
        Target::Translation(b, d) => d.dot(&rates.b[*b]),
        Target::Rotation(b, g) => g.dot(&rates.w[*b]),
    }
}

/// The free DOFs as they go back into the state: consecutive DOFs of one particle, of one
/// body's translation or of one body's rotation together.
fn groups<S: Space>(dofs: &[Target<S>]) -> Vec<Group<S>> {
    let mut out: Vec<Group<S>> = Vec::new();
    for (l, t) in dofs.iter().enumerate() {
        match (out.last_mut(), *t) {
            (Some(Group::Particle(p, axes)), Target::Particle(i, d)) if *p == i => {
                axes.push((l, d))
            }
            (Some(Group::Translation(b, axes)), Target::Translation(i, d)) if *b == i => {
                axes.push((l, d))
            }
            (Some(Group::Rotation(b, axes)), Target::Rotation(i, g)) if *b == i => {
                axes.push((l, g))
            }
            (_, Target::Particle(i, d)) => out.push(Group::Particle(i, vec![(l, d)])),
            (_, Target::Translation(i, d)) => out.push(Group::Translation(i, vec![(l, d)])),
            (_, Target::Rotation(i, g)) => out.push(Group::Rotation(i, vec![(l, g)])),
        }
    }
    out
}

/// One particle's or body's part of a batch back into the state: `x` moves by the motion along
/// `axes` (DOF index and unit direction), added with its rounding carry `carry`; the velocity
/// `v` along them becomes the batch's, the rest of it (along held axes) is kept.
fn put_back<T: Lin>(
    x: &mut T,
    carry: &mut T,
    v: &mut T,
    axes: &[(usize, T)],
    batch: &Batch,
    before: &[f64; MAX_DOFS],
) {
    let (mut motion, mut now, mut was) = (T::zero(), T::zero(), T::zero());
    for &(l, d) in axes {
        motion += d * (batch.motion[l] - batch.carry[l]);
        now += d * batch.velocities[l];
        was += d * before[l];
    }
    compensated_add(x, carry, motion);
    *v = now + (*v - was);
}
