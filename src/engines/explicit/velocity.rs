//! The accelerations of an increment whose forces read the velocity at time n (dashpots; the
//! centripetal and gyroscopic terms of bodies under finite rotation).
//!
//! The centred treatment uses `v(n) = v(n−½) + (h/2)·a(n)`, which keeps the scheme second
//! order: solved directly where every dashpot joins particles and no body has velocity terms
//! ([`ParticleDashpots`]); in closed form where no dashpot acts and every body with velocity
//! terms turns about one axis, whose centripetal force alone reads the velocity, as ω²
//! ([`Model::centred_bodies_solved`]), wherever the iteration would contract by ½ or less;
//! otherwise by fixed-point iteration from the predictor
//! `v(n−½) + (h/2)·a(n−1)`, and, where that iteration cannot contract because of stiff
//! dashpots, by a direct solve in the free DOFs: the dashpots along directions frozen for the
//! increment make the map affine, and where bodies have velocity terms (centripetal,
//! gyroscopic) these are iterated around the solve, which reads them at the last solution.
//! The lagged treatment uses `v(n−½)` (first order, the classic explicit form).

use super::body_solve::BodyOperator;
use super::centred::ParticleDashpots;
use super::integrate::DENSE_LIMIT;
use super::model::{Config, Constraints, Counters, Forces, Model, Rates, Target};
use super::space::Space;
use crate::engines::EngineError;
use crate::scene::DampingTreatment;
use nalgebra::{DMatrix, DVector};

const MAX_DAMPING_ITERATIONS: usize = 100;

/// The centred velocity iteration stops when v(n) is within this fraction of the largest
/// velocity component of its fixed point (a few units of round-off).
const VELOCITY_TOLERANCE: f64 = 1e-14;

/// What the accelerations of increment n read: the model at x(n) with its position forces,
/// v(n−½) and a(n−1), the increment and the step's constraints. a(n−1) is read only by the
/// iteration's predictor ([`VelocityRule::Iterated`]); under the other rules the time loop
/// keeps it only for the next step ([`super::integrate`]), and it may be older.
pub(super) struct AtIncrement<'a, S: Space, const FINITE: bool> {
    pub(super) model: &'a Model<S, FINITE>,
    pub(super) cfg: &'a Config<S>,
    pub(super) forces: &'a Forces<S>,
    pub(super) v_half: &'a Rates<S>,
    pub(super) acc_prev: &'a Rates<S>,
    pub(super) h: f64,
    pub(super) held: &'a Constraints<S>,
}

/// How one dynamic step finds v(n) and the accelerations at it.
pub(super) enum VelocityRule<S: Space> {
    /// No force reads the velocity: the accelerations follow from the forces.
    Absent,
    /// The lagged treatment: v(n) = v(n−½).
    Lagged,
    /// Centred, every dashpot between particles or a particle and the ground, no body with
    /// velocity terms: solved directly.
    Direct(ParticleDashpots<S>),
    /// Centred, by fixed-point iteration; `affine` where the map is affine in v (the iteration
    /// then stops as soon as it diverges). Where `solvable` (dashpots, few enough free DOFs),
    /// once the iteration fails to contract, `solved` switches the step to the direct solve
    /// in the free `dofs` ([`centred_solve`]).
    Iterated {
        affine: bool,
        solvable: bool,
        solved: bool,
        dofs: Vec<Target<S>>,
    },
}

/// The work space of the velocity solve, kept across increments.
pub(super) struct Velocities<S: Space> {
    /// v(n), as the forces read it.
    pub v_n: Rates<S>,
    guess: Rates<S>,
    /// Forces with the dashpots' added.
    total: Forces<S>,
    directions: Vec<S::V>,
    /// The bodies' solve operators at the increment's configuration, formed once for every
    /// pass of the iteration or the solve.
    operators: Vec<BodyOperator<S>>,
}

impl<S: Space> Velocities<S> {
    /// Exchange the bodies' rates of `v_n` and `guess` (the particles' stay).
    fn swap_bodies(&mut self) {
        std::mem::swap(&mut self.v_n.b, &mut self.guess.b);
        std::mem::swap(&mut self.v_n.w, &mut self.guess.w);
    }
    /// v(n) shaped like the model; the solve's work space is made by the first increment that
    /// needs it ([`Velocities::shaped`]), so a scene whose forces never read the velocity holds
    /// none.
    pub(super) fn new<const FINITE: bool>(model: &Model<S, FINITE>) -> Self {
        Velocities {
            v_n: model.zero_rates(),
            guess: Rates::zeros(0, 0),
            total: Forces::zeros(0, 0, 0),
            directions: Vec::new(),
            operators: Vec::new(),
        }
    }

    /// The work space shaped like the model.
    fn shaped<const FINITE: bool>(&mut self, model: &Model<S, FINITE>) -> &mut Self {
        let shape = (
            model.particles.len(),
            model.bodies.len(),
            model.contacts.len(),
        );
        if (
            self.total.p.len(),
            self.total.b.len(),
            self.total.contact.len(),
        ) != shape
        {
            self.guess = model.zero_rates();
            self.total = model.zero_forces();
        }
        self
    }
}

impl<S: Space> VelocityRule<S> {
    /// Whether any force reads the velocity (otherwise v(n) is formed only for a row).
    pub(super) fn reads_velocity(&self) -> bool {
        !matches!(self, VelocityRule::Absent)
    }

    /// The rule of a step under `held` from configuration `cfg` at increment `h`.
    pub(super) fn of<const FINITE: bool>(
        model: &Model<S, FINITE>,
        cfg: &Config<S>,
        held: &Constraints<S>,
        h: f64,
        treatment: DampingTreatment,
    ) -> Self {
        let velocity_terms = held.any_velocity_terms();
        if !model.has_dashpots() && !velocity_terms {
            return VelocityRule::Absent;
        }
        if treatment == DampingTreatment::Lagged {
            return VelocityRule::Lagged;
        }
        if model.has_dashpots()
            && !velocity_terms
            && let Some(mut dashpots) = ParticleDashpots::of(model)
        {
            dashpots.prepare(model, cfg, held, h);
            return VelocityRule::Direct(dashpots);
        }
        let dofs = model.free_dofs(held);
        let solvable = model.has_dashpots() && dofs.len() <= DENSE_LIMIT;
        VelocityRule::Iterated {
            affine: solvable && !velocity_terms,
            solvable,
            solved: false,
            dofs,
        }
    }

    /// The accelerations at increment time t = n·h into `acc`; v(n) into `work.v_n`. Returns
    /// the dashpots' dissipation power.
    pub(super) fn accelerations<const FINITE: bool>(
        &mut self,
        at: &AtIncrement<S, FINITE>,
        work: &mut Velocities<S>,
        acc: &mut Rates<S>,
        counters: &mut Counters,
    ) -> Result<f64, EngineError> {
        let (model, cfg, forces) = (at.model, at.cfg, at.forces);
        let (v_half, h, held) = (at.v_half, at.h, at.held);
        match self {
            // v(n) is formed only where a row reads it (`VelocityRule::reads_velocity`).
            VelocityRule::Absent => {
                model.accelerations(cfg, forces, v_half, held, acc, counters);
                Ok(0.0)
            }
            VelocityRule::Lagged => {
                let work = work.shaped(model);
                work.v_n.clone_from(v_half);
                work.total.copy_from(forces);
                if !model.has_dashpots() {
                    model.accelerations(cfg, forces, &work.v_n, held, acc, counters);
                    return Ok(0.0);
                }
                model.damping(cfg, &work.v_n, &mut work.total, counters);
                model.accelerations(cfg, &work.total, &work.v_n, held, acc, counters);
                Ok(work.total.dissipation)
            }
            VelocityRule::Direct(dashpots) => Ok(dashpots.solve(at, acc, &mut work.v_n, counters)),
            VelocityRule::Iterated {
                affine,
                solvable,
                solved,
                dofs,
            } => {
                let work = work.shaped(model);
                model.dashpot_directions(cfg, &mut work.directions);
                model.body_operators(cfg, held, &mut work.operators);
                if !*solved {
                    if iterate(at, *affine, work, acc, counters) {
                        // Without dashpots nothing dissipates (`work.total` is not used).
                        return Ok(if model.has_dashpots() {
                            work.total.dissipation
                        } else {
                            0.0
                        });
                    }
                    // Stiff dashpots (h·|M⁻¹C|/2 ≥ 1): the iteration cannot contract, but
                    // with few enough free DOFs it is solved directly from now on.
                    if !*solvable {
                        return Err(not_converged(model.has_dashpots(), dofs.len(), h));
                    }
                    *solved = true;
                }
                centred_solve(at, !*affine, dofs, work, acc, counters)?;
                Ok(work.total.dissipation)
            }
        }
    }
}

/// Where no dashpot acts and every body whose rate its forces read turns about one axis: the
/// bodies' accelerations into `acc` and their v(n) into `work.v_n`, in closed form, as
/// [`iterate_bodies`] takes them ([`Model::centred_bodies_solved`]), bit for bit; the particles'
/// are left to the caller, since no force on them reads the velocity. False, with nothing
/// counted, where the closed form does not apply at this increment (the iteration then runs).
pub(super) fn bodies_in_closed_form<S: Space, const FINITE: bool>(
    at: &AtIncrement<S, FINITE>,
    work: &mut Velocities<S>,
    acc: &mut Rates<S>,
    counters: &mut Counters,
) -> bool {
    let (model, cfg, held) = (at.model, at.cfg, at.held);
    debug_assert!(!model.has_dashpots());
    let work = work.shaped(model);
    model.body_operators(cfg, held, &mut work.operators);
    let (state, rates) = ((cfg, at.forces, held), (at.v_half, at.h));
    let before = *counters;
    if model.centred_bodies_solved(state, &work.operators, rates, &mut work.v_n, acc, counters) {
        return true;
    }
    *counters = before;
    false
}

/// Why the centred velocity iteration's failure ends the run: stiff dashpots in a scene with
/// more free DOFs than a direct solve takes, or, without dashpots, velocity terms too fast for
/// the increment.
fn not_converged(dashpots: bool, dofs: usize, h: f64) -> EngineError {
    EngineError::Failed(if dashpots {
        format!(
            "centred velocity iteration did not converge: the dashpots are too stiff for increment {h:e} and the scene's {dofs} free DOFs are more than a direct solve takes ({DENSE_LIMIT}); use damping = \"lagged\" or a smaller increment"
        )
    } else {
        format!(
            "centred velocity iteration did not converge: the bodies' centripetal and gyroscopic terms change too fast for increment {h:e}; use a smaller increment"
        )
    })
}

/// Whether an iteration that moved its iterate by `change` (after `previous`) has met its
/// tolerance on velocities of largest component `size`. The iteration contracts by ρ per pass
/// (ρ estimated as change / previous change), so the iterate just made is within
/// ρ/(1−ρ) · change of the fixed point; with ρ < ½ that test reads
/// change² ≤ tol·size·(previous − change).
fn converged(change: f64, previous: f64, size: f64) -> bool {
    let tolerance = VELOCITY_TOLERANCE * size;
    let contracting = 2.0 * change < previous;
    change <= tolerance || (contracting && change * change <= tolerance * (previous - change))
}

/// The fixed-point iteration v ← v(n−½) + (h/2)·a(v) from the predictor
/// v(n−½) + (h/2)·a(n−1). True when it met its tolerance (v(n) in `work.v_n`, the
/// accelerations in `acc`, with dashpots the dissipation in `work.total`); it gives up early where it
/// diverges and `stop_diverging`.
fn iterate<S: Space, const FINITE: bool>(
    at: &AtIncrement<S, FINITE>,
    stop_diverging: bool,
    work: &mut Velocities<S>,
    acc: &mut Rates<S>,
    counters: &mut Counters,
) -> bool {
    let (model, cfg, forces) = (at.model, at.cfg, at.forces);
    let (v_half, acc_prev, h, held) = (at.v_half, at.acc_prev, at.h, at.held);
    work.guess.set_plus(v_half, 0.5 * h, acc_prev);
    if !model.has_dashpots() {
        return iterate_bodies(at, work, acc, counters);
    }
    let mut previous_change = 0.0;
    for pass in 0..MAX_DAMPING_ITERATIONS {
        work.total.copy_from(forces);
        let (directions, guess) = (&work.directions, &work.guess);
        model.damping_along(cfg, directions, guess, &mut work.total, counters);
        let (total, operators) = (&work.total, &work.operators);
        model.accelerations_with(cfg, total, guess, held, operators, acc, counters);
        work.v_n.set_plus(v_half, 0.5 * h, acc);
        let (change, size) = work.v_n.max_difference(&work.guess);
        // ρ ≈ (h/2)·|∂a/∂v| ([`converged`]).
        if converged(change, previous_change, size) {
            return true;
        }
        if stop_diverging && pass >= 3 && change > previous_change {
            return false;
        }
        previous_change = change;
        // The new iterate is the next pass's guess.
        std::mem::swap(&mut work.v_n, &mut work.guess);
    }
    std::mem::swap(&mut work.v_n, &mut work.guess);
    false
}

/// [`iterate`] where no dashpot acts, from the predictor in `work.guess`: the velocity enters
/// through the bodies' centripetal and gyroscopic terms alone, so the particles' accelerations
/// and centred velocities are formed once, from the position forces. Where every body that
/// reads the velocity turns about one axis the bodies' rates are then solved in closed form
/// ([`Model::centred_bodies_solved`]); otherwise every pass runs over the bodies alone
/// ([`Model::centred_body_pass`]). After the first pass a particle's change is
/// exactly 0 and its size the same, as the general iteration finds them: the same iterates and
/// stop, bit for bit. It is not given up early where it diverges: without dashpots there is no
/// direct solve to turn to ([`VelocityRule::of`]).
fn iterate_bodies<S: Space, const FINITE: bool>(
    at: &AtIncrement<S, FINITE>,
    work: &mut Velocities<S>,
    acc: &mut Rates<S>,
    counters: &mut Counters,
) -> bool {
    let (model, cfg, forces) = (at.model, at.cfg, at.forces);
    let (v_half, h, held) = (at.v_half, at.h, at.held);
    model.particle_accelerations(forces, held, acc);
    work.v_n.set_plus_particles(v_half, 0.5 * h, acc);
    let (operators, state) = (&work.operators, (cfg, forces, held));
    if model.centred_bodies_solved(state, operators, (v_half, h), &mut work.v_n, acc, counters) {
        return true;
    }
    let (mut particle_change, particle_size) = work.v_n.particle_differences(&work.guess);
    let mut previous_change = 0.0;
    for pass in 0..MAX_DAMPING_ITERATIONS {
        let (guess, v_n, operators) = (&work.guess, &mut work.v_n, &work.operators);
        let state = (cfg, forces, held);
        let (d, m) =
            model.centred_body_pass(state, operators, (v_half, h), guess, v_n, acc, counters);
        let (change, size) = (d.max(particle_change).sqrt(), m.max(particle_size).sqrt());
        if converged(change, previous_change, size) {
            return true;
        }
        previous_change = change;
        if pass == 0 {
            // From here the particles' iterate is their centred velocity in both sets.
            work.guess.p.copy_from(&work.v_n.p);
            particle_change = 0.0;
        }
        work.swap_bodies();
    }
    work.swap_bodies();
    false
}

/// The centred velocity solved directly in the free `dofs` ([`centred_affine`]). With
/// `velocity_terms` the map is affine only once those terms are frozen: the solve reads them
/// at the last solution (first at the predictor v(n−½) + (h/2)·a(n−1)) and is repeated until
/// v(n) settles ([`converged`]); it contracts by about h·|ω|, the bodies' turning per
/// increment. Leaves `work` and `acc` at the solution.
fn centred_solve<S: Space, const FINITE: bool>(
    at: &AtIncrement<S, FINITE>,
    velocity_terms: bool,
    dofs: &[Target<S>],
    work: &mut Velocities<S>,
    acc: &mut Rates<S>,
    counters: &mut Counters,
) -> Result<(), EngineError> {
    let Velocities {
        v_n,
        guess,
        total,
        directions,
        operators,
    } = work;
    let frozen = (directions.as_slice(), operators.as_slice());
    if !velocity_terms {
        return centred_affine(at, dofs, frozen, None, total, v_n, acc, counters);
    }
    guess.set_plus(at.v_half, 0.5 * at.h, at.acc_prev);
    let mut previous_change = 0.0;
    for _ in 0..MAX_DAMPING_ITERATIONS {
        centred_affine(at, dofs, frozen, Some(guess), total, v_n, acc, counters)?;
        let (change, size) = v_n.max_difference(guess);
        if converged(change, previous_change, size) {
            return Ok(());
        }
        previous_change = change;
        guess.clone_from(v_n);
    }
    Err(not_converged(false, dofs.len(), at.h))
}

/// The centred velocity v(n) = v(n−½) + (h/2)·a(v(n)) solved directly, for a map that is affine
/// in v: dashpots along `directions`, frozen for the increment (with the bodies' solve
/// `operators` at its configuration), and the bodies' centripetal and gyroscopic terms read at
/// `terms` (`None`: the scene has none). With
/// g(v) = v(n−½) + (h/2)·a(v) = b + J·v in the free DOFs, (I − J)·v = b, J from g at the unit
/// rates. Leaves v(n) in `v_n`, the forces and their dissipation in `total` and the
/// accelerations in `acc`, at the solution.
#[allow(clippy::too_many_arguments)]
fn centred_affine<S: Space, const FINITE: bool>(
    at: &AtIncrement<S, FINITE>,
    dofs: &[Target<S>],
    (directions, operators): (&[S::V], &[BodyOperator<S>]),
    terms: Option<&Rates<S>>,
    total: &mut Forces<S>,
    v_n: &mut Rates<S>,
    acc: &mut Rates<S>,
    counters: &mut Counters,
) -> Result<(), EngineError> {
    let (model, cfg, forces) = (at.model, at.cfg, at.forces);
    let (v_half, h, held) = (at.v_half, at.h, at.held);
    let mut map = |v: &Rates<S>, total: &mut Forces<S>, acc: &mut Rates<S>, out: &mut Rates<S>| {
        total.copy_from(forces);
        model.damping_along(cfg, directions, v, total, counters);
        let rates = terms.unwrap_or(v);
        model.accelerations_with(cfg, total, rates, held, operators, acc, counters);
        out.set_plus(v_half, 0.5 * h, acc);
    };
    let n = dofs.len();
    let mut image = model.zero_rates();
    map(&model.zero_rates(), total, acc, &mut image);
    let b = DVector::from_iterator(n, dofs.iter().map(|d| model.rate_along(&image, d)));
    let mut system = DMatrix::identity(n, n);
    for (j, dj) in dofs.iter().enumerate() {
        map(&model.unit_rate(dj), total, acc, &mut image);
        for (i, di) in dofs.iter().enumerate() {
            system[(i, j)] -= model.rate_along(&image, di) - b[i];
        }
    }
    let x = system.lu().solve(&b).ok_or_else(|| {
        EngineError::Failed(format!(
            "centred velocity: I + (h/2)·M⁻¹C is singular at increment {h:e}"
        ))
    })?;
    let mut v = model.zero_rates();
    for (d, xi) in dofs.iter().zip(x.iter()) {
        v = v.plus(*xi, &model.unit_rate(d));
    }
    map(&v, total, acc, v_n);
    Ok(())
}
