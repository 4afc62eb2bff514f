//! The central-difference time loop, as Abaqus/Explicit does it: half-step velocities,
//! `v(n+½) = v(n−½) + h·a(n)`, `x(n+1) = x(n) + h·v(n+½)`, rotations advanced by the exact
//! exponential of the incremental rotation.
//!
//! Velocity-dependent forces (dashpots; centripetal and gyroscopic terms of bodies under finite
//! rotation) need the velocity at time n. The centred treatment uses
//! `v(n) = (v(n−½) + v(n+½))/2`, solved by fixed-point iteration from the predictor
//! `v(n−½) + (h/2)·a(n−1)`, which keeps the scheme second order; the lagged treatment uses
//! `v(n−½)` (first order, the classic explicit form). Scenes without such forces skip the pass.
//! Where every dashpot joins particles (or a particle and the ground) and no body has
//! velocity terms, the centred velocity is solved directly instead ([`super::centred`]); where
//! there are no dashpots and every body with velocity terms turns about one axis, in closed
//! form ([`Model::centred_single_axis`]). A large scene of particles, springs along fixed
//! lines and loads takes its one-pass increments block by block of springs
//! ([`Model::step_by_blocks`]): one trip through memory instead of a force pass and an
//! update. Such a scene on one coordinate axis, of any size, takes them on one number per
//! particle and quantity ([`Model::step_axial`]).

use super::affine::AffineStep;
use super::blocks::BLOCKS_FROM;
use super::centred::ParticleDashpots;
use super::diagnosis::{PAST_LIMIT_GROWTH, PastLimit, growing_mode};
use super::linear::{StableIncrement, static_step};
use super::model::{Config, Constraints, ContactMode, Counters, Forces, Model, Rates, Target};
use super::space::{Lin, Space};
use super::turning::{Batch, TurningStep};
use crate::contract::ENERGY_COLUMNS;
use crate::engines::{EngineError, History};
use crate::scene::{
    ContactStart, DampingTreatment, IncrementRule, Probe, Scene, SceneSettings, StepKind,
};
use nalgebra::{DMatrix, DVector};

/// The outcome of an explicit run.
pub struct Integration {
    /// Time history.
    pub history: History,
    /// Increment used.
    pub increment: f64,
    /// Increments taken.
    pub steps: u64,
    /// Stable increment (None for a scene with no free DOF).
    pub stable: Option<StableIncrement>,
    /// Work counters.
    pub counters: Counters,
    /// Times at which a contact pair closed (its penalty force turned positive after an
    /// increment without force): the impacts, to the increment.
    pub impacts: Vec<f64>,
}

const MAX_DAMPING_ITERATIONS: usize = 100;

/// The centred velocity iteration stops when v(n) is within this fraction of the largest
/// velocity component of its fixed point (a few units of round-off).
const VELOCITY_TOLERANCE: f64 = 1e-14;

/// A run stops as unstable when its kinetic plus elastic energy exceeds this multiple of what
/// it may hold (its initial energy plus the work of the loads). A stable run stays at or below
/// 1× up to the measured energy error of the scheme: at 0.98 of the stable increment on every
/// seed case at most 1.00003× (centred damping, consistent contact start) and 1.29× (lagged
/// damping, whose dashpots see a lagged velocity). An unstable mode grows by |λ| > 1 per
/// increment (1.49 undamped at ω·h = 2.04), so the guard trips within tens of increments of
/// the mode becoming visible; a penalty contact that chatters open and shut at 1.02× stops
/// between 2.2× and 50× (measured), which a guard at 100× let through.
pub const ENERGY_GUARD: f64 = 2.0;

/// Increments between two looks at the interruption flag.
const INTERRUPT_STRIDE: u64 = 4096;

/// Above this many free DOFs, a scene without bodies or contact takes its stable increment
/// from the element-wise bound ([`Model::frequency_bound`], O(elements)) instead of the
/// assembled eigenproblem (O(DOFs³)). Every seed case is far below it.
pub const DENSE_LIMIT: usize = 256;

/// The stable increment of the scene from configuration `cfg` under each remaining dynamic
/// step's constraints (the smallest over them).
pub fn stable_increment<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    scene: &Scene,
    cfg: &Config<S>,
    from_step: usize,
    treatment: DampingTreatment,
    counters: &mut Counters,
) -> Option<StableIncrement> {
    let mut best: Option<StableIncrement> = None;
    for step in &scene.steps[from_step..] {
        if !matches!(step.kind, StepKind::Dynamic { .. }) {
            continue;
        }
        let held = model.constraints(scene, step);
        if model.free_dofs(&held).len() > DENSE_LIMIT
            && let Some((lambda, gamma)) = model.frequency_bound(cfg, &held)
        {
            if let Some(s) = StableIncrement::from_bound(lambda, gamma, treatment)
                && best.is_none_or(|b| s.increment < b.increment)
            {
                best = Some(s);
            }
            continue;
        }
        let closed = model.linearise(cfg, &held, true, counters).modes();
        let open = if model.contact_count() > 0 {
            model.linearise(cfg, &held, false, counters).modes()
        } else {
            closed.clone()
        };
        if let Some(s) = StableIncrement::from_modes(&closed, &open, treatment)
            && best.is_none_or(|b| s.increment < b.increment)
        {
            best = Some(s);
        }
    }
    best
}

/// Choose the increment: the rule, never above the stable one, then shortened so that it
/// divides the output interval exactly (rows fall on steps; no interpolation). The stability
/// studies' rules ([`IncrementRule::Exact`], [`IncrementRule::StableRatio`]) are taken exactly.
pub(crate) fn choose_increment(
    rule: IncrementRule,
    stable: Option<&StableIncrement>,
    duration: f64,
    interval: f64,
) -> Result<f64, EngineError> {
    let limit = stable.map_or(f64::INFINITY, |s| s.increment);
    let h = match rule {
        IncrementRule::Given(h) => {
            if h > limit * (1.0 + 1e-12) {
                return Err(EngineError::UnstableIncrement {
                    requested: h,
                    stable: limit,
                });
            }
            h
        }
        IncrementRule::Forced(h) => h,
        // Stability studies: exactly the increment asked for, rows interpolated.
        IncrementRule::Exact(h) => return Ok(h),
        IncrementRule::StableRatio(r) => {
            return match stable {
                Some(s) => Ok(r * s.increment),
                None => Err(EngineError::Unsupported(
                    "--increment-ratio needs a stable increment, and this scene has none (no free DOF with stiffness)".into(),
                )),
            };
        }
        IncrementRule::Accuracy(eps) => {
            let cap = crate::scene::DEFAULT_SAFETY * limit;
            match stable {
                Some(s) if s.omega_structure > 0.0 => (24.0 * eps
                    / (s.omega_structure.powi(3) * duration))
                    .sqrt()
                    .min(cap),
                _ => cap.min(interval),
            }
        }
        IncrementRule::Stable { safety } => (safety * limit).min(interval),
        // Resolved by the engine's pilot runs (`on_request`) before it integrates; as an
        // estimate without them, the default fraction of the stable increment.
        IncrementRule::Tolerance(_) => (crate::scene::DEFAULT_SAFETY * limit).min(interval),
    };
    let per_interval = (interval / h - 1e-9).ceil().max(1.0);
    Ok(interval / per_interval)
}

/// Contact forces that make every gap's second derivative vanish (the rigid model's forces at
/// this state), the accelerations they give, and B = ∂(gap accelerations)/∂(forces).
/// `tau` (the increment) bounds the finite-difference interval of a solid's gap acceleration.
fn consistent_forces<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &Config<S>,
    vel: &Rates<S>,
    held: &Constraints<S>,
    tau: f64,
    counters: &mut Counters,
) -> Option<(DVector<f64>, Rates<S>, DMatrix<f64>)> {
    let n = model.contact_count();
    let response = |given: &[f64], counters: &mut Counters| -> (DVector<f64>, Rates<S>) {
        let mut f = model.zero_forces();
        model.forces(cfg, ContactMode::Given(given), &mut f, counters);
        if model.has_dashpots() {
            model.damping(cfg, vel, &mut f, counters);
        }
        let mut acc = model.zero_rates();
        model.accelerations(cfg, &f, vel, held, &mut acc, counters);
        (
            DVector::from_fn(n, |k, _| model.gap_acceleration(cfg, vel, &acc, k, tau)),
            acc,
        )
    };
    let zero = vec![0.0; n];
    let (a0, _) = response(&zero, counters);
    let mut b = DMatrix::zeros(n, n);
    for j in 0..n {
        let mut unit = zero.clone();
        unit[j] = 1.0;
        b.set_column(j, &(response(&unit, counters).0 - &a0));
    }
    let f = b.clone().lu().solve(&(-a0))?.map(|x| x.max(0.0));
    let (_, acc) = response(f.as_slice(), counters);
    Some((f, acc, b))
}

/// Start penalty contacts where the rigid model is, so the penalty mode starts nearly
/// unexcited instead of ringing with amplitudes λ0, λ̇0/ω_p and λ̈0/ω_p².
///
/// With the penalty, λ = −k_p d, and the gap obeys d̈ = A + B λ; the rigid model's force
/// λ_r = −B⁻¹A. Expanding the penalty solution about it gives λ = λ_r − (k_p B)⁻¹ λ̈_r + …, so
/// the start sets the penetration to carry λ_r(0) − (k_p B)⁻¹ λ̈_r(0) and the gap rate to
/// −λ̇_r(0)/k_p, led by the increment's own lag (below). λ̇_r and λ̈_r are central differences
/// of the rigid force along the trajectory extrapolated ±τ (τ = the increment).
fn consistent_start<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &mut Config<S>,
    vel: &mut Rates<S>,
    held: &Constraints<S>,
    tau: f64,
    counters: &mut Counters,
) {
    // Two passes: moving the node changes the springs attached to it slightly.
    for _ in 0..2 {
        let Some((f, _, _)) = consistent_forces(model, cfg, vel, held, tau, counters) else {
            return;
        };
        for (k, fk) in f.iter().enumerate() {
            model.set_penetration(cfg, k, fk / model.penalty);
        }
    }
    let Some((f0, acc, b)) = consistent_forces(model, cfg, vel, held, tau, counters) else {
        return;
    };
    // Along the rigid trajectory, extrapolated ±τ. The rigid force depends on velocities
    // (centripetal and Coriolis terms of the gap under finite rotation), so the velocity must be
    // extrapolated to second order: the jerk comes from a first pass.
    let mut at = |s: f64, jerk: &Rates<S>| {
        let (c, v) = model.extrapolate(cfg, vel, &acc, jerk, s);
        consistent_forces(model, &c, &v, held, tau, counters)
    };
    let zero = model.zero_rates();
    let (Some((_, acc_ahead, _)), Some((_, acc_behind, _))) = (at(tau, &zero), at(-tau, &zero))
    else {
        return;
    };
    let jerk = acc_ahead.plus(-1.0, &acc_behind).plus(0.0, &zero);
    let jerk = zero.plus(0.5 / tau, &jerk);
    let (Some((ahead, _, _)), Some((behind, _, _))) = (at(tau, &jerk), at(-tau, &jerk)) else {
        return;
    };
    let rate = (&ahead - &behind) / (2.0 * tau);
    let curvature = (&ahead - &f0 * 2.0 + &behind) / (tau * tau);
    let correction = (b * model.penalty)
        .lu()
        .solve(&curvature)
        .unwrap_or_else(|| DVector::zeros(f0.len()));
    for k in 0..model.contact_count() {
        if f0[k] > 0.0 {
            model.set_penetration(cfg, k, (f0[k] - correction[k]) / model.penalty);
            // The leapfrog's smooth solution through (q₀, v₀) moves at q̇(0) = v₀ − (h²/6)·q⃛
            // (its first increment is q₀ + h v₀ + (h²/2) a₀, without the cubic term), so its
            // gap rate is ∂g·v₀ − (h²/6)·∂g·q⃛. Where the gap is linear in the coordinates
            // ∂g·q⃛ is the rigid gap's third derivative, ≈ 0; under finite rotation it is not
            // (the gap's curvature terms), and without this lead the penalty mode rings with
            // a force amplitude ≈ ω_p m h²·∂g·q⃛/6, which grows like √k_p at a fixed h.
            let lead = tau * tau / 6.0 * model.gap_rate(cfg, &jerk, k);
            model.set_gap_rate(cfg, vel, k, -rate[k] / model.penalty + lead);
        }
    }
    model.enforce(vel, held);
}

/// The refusal of a run whose contact node went through its solid: penalty contact cannot
/// catch a node that moves past the solid's half thickness `depth` in one increment or before
/// the penalty stops it, so it names the speed and what would catch it: an increment under
/// depth/(2v) and a penalty stiffness over m(2v/depth)².
fn through_solid(scene: &Scene, k: usize, speed: f64, h: f64, t: f64) -> EngineError {
    let pair = &scene.contacts[k];
    let node = &scene.nodes[pair.node];
    let crate::scene::Surface::Solid { solid, .. } = &pair.surface else {
        unreachable!("only solids are watched")
    };
    let (shape, depth) = (solid.name(), solid.half_thickness());
    let needed_h = depth / (2.0 * speed);
    let needed_k = node.mass * (2.0 * speed / depth).powi(2);
    EngineError::Failed(format!(
        "contact `{}`: node `{}` went through the {shape} (half thickness {depth:e}) at t = {t:e}, moving {speed:e} relative to it with increment {h:e}; penalty contact catches it only with an increment below {needed_h:e} (--increment) and a penalty stiffness above {needed_k:e} (--penalty)",
        pair.name, node.name
    ))
}

/// Run a scene through all its steps; where `batched_steps`, a small step with affine forces
/// as an [`AffineStep`], and one with a body turning about one axis under finite rotation as
/// a [`TurningStep`], between output rows.
pub fn integrate<S: Space, const FINITE: bool>(
    scene: &Scene,
    settings: &SceneSettings,
    batched_steps: bool,
) -> Result<Integration, EngineError> {
    let penalty = if scene.contacts.is_empty() {
        0.0
    } else {
        scene.penalty_stiffness(settings.penalty)
    };
    let model = Model::<S, FINITE>::compile(scene, penalty);
    let mut counters = Counters::default();
    let mut cfg = model.initial_config();
    let mut vel = model.zero_rates();
    let duration = scene.duration();
    let interval = duration / (scene.output_rows - 1) as f64;
    let times = scene.output_times();

    let columns: Vec<String> = std::iter::once("t".to_string())
        .chain(scene.columns.iter().map(|c| c.name.clone()))
        .chain(ENERGY_COLUMNS.iter().map(|s| s.to_string()))
        .collect();
    let mut rows: Vec<Vec<f64>> = Vec::with_capacity(scene.output_rows);
    let mut previous_rotation: Vec<f64> = vec![0.0; scene.columns.len()];

    let mut h = 0.0;
    let mut stable = None;
    let mut started = false;
    let mut n_global: u64 = 0;
    let mut energy0 = 0.0;
    let mut dissipated = 0.0;
    let mut last_power = 0.0;
    let mut cfg_start = cfg.clone();
    let mut past_limit: Option<PastLimit<S>> = None;
    let mut forces = model.zero_forces();
    // The forces `Model::step_by_blocks` sums (zero between its increments).
    let mut pending = model.zero_forces();
    let by_blocks = model.can_step_by_blocks() && model.particles.len() >= BLOCKS_FROM;
    let mut total: Forces<S> = model.zero_forces();
    let mut acc = model.zero_rates();
    let mut acc_prev = model.zero_rates();
    let mut v_n = model.zero_rates();
    let mut v_guess = model.zero_rates();
    let mut v_half = model.zero_rates();
    let mut v_next = model.zero_rates();
    let mut carry = model.zero_rates();
    let mut directions = Vec::new();
    // Dashpots between particles only: the centred velocity is solved directly (formed per
    // step, from the step's model).
    let mut particle_dashpots;
    let mut sampler = RowSampler::new(&times, interval, interval);
    // Solid contacts are watched for a node going through its solid.
    let solids = model.has_solids();
    let (mut solid_before, mut solid_now) = (Vec::new(), Vec::new());
    // Whether each pair pressed at the last increment (None before the first), and the
    // impacts: the increments where a pair that did not press starts to.
    let mut pressed: Vec<Option<bool>> = vec![None; model.contact_count()];
    let mut impacts = Vec::new();
    let mut watching = false;
    if settings.damping == DampingTreatment::Lagged && model.has_contact_dashpots() {
        return Err(EngineError::Unsupported(
            "lagged damping with a contact dashpot (a contact with restitution below 1): the stable increment is computed with the contact open, where its dashpot does not act; use centred damping".into(),
        ));
    }

    for (si, step) in scene.steps.iter().enumerate() {
        let mut held = model.constraints(scene, step);
        let StepKind::Dynamic {
            duration: step_duration,
        } = step.kind
        else {
            static_step(&model, &mut cfg, &held, &mut counters)?;
            continue;
        };
        if !started {
            for iv in &scene.initial_velocities {
                match model.points[iv.node] {
                    super::model::Point::Particle(i) => vel.p[i] = S::v(&iv.velocity),
                    super::model::Point::Body { body, .. } => {
                        vel.b[body] = S::v(&iv.velocity);
                        vel.w[body] = S::w(&iv.angular);
                    }
                    super::model::Point::Ground(_) => {}
                }
            }
            stable = stable_increment(&model, scene, &cfg, si, settings.damping, &mut counters);
            h = choose_increment(settings.increment, stable.as_ref(), duration, interval)?;
            sampler = RowSampler::new(&times, interval, h);
            if !sampler.on_steps
                && scene.steps[si + 1..]
                    .iter()
                    .any(|s| matches!(s.kind, StepKind::Dynamic { .. }))
            {
                return Err(EngineError::Unsupported(format!(
                    "increment {h:e} does not divide the output interval {interval:e}, and the scene has more than one dynamic step: a stability study's increment must divide every step but the last"
                )));
            }
        }
        model.enforce(&mut vel, &held);
        if !started {
            // The consistent start carries the rigid model's persistent contact forces, which
            // treat every pair as closed: only when every pair starts closed. A scene with a
            // pair open at t = 0 starts as it is.
            if model.contact_count() > 0
                && model.closed_only()
                && settings.contact_start == ContactStart::Consistent
            {
                consistent_start(&model, &mut cfg, &mut vel, &held, h, &mut counters);
            }
            cfg_start = cfg.clone();
            // Only above the stable increment (a stability study), and only where the scene's
            // modes are computed at all (not above the dense limit).
            if stable.is_some_and(|s| h > s.increment * (1.0 + 1e-12))
                && model.free_dofs(&held).len() <= DENSE_LIMIT
            {
                past_limit = PastLimit::new(&model, &cfg, &held, h, settings.damping);
            }
        }
        // An axial element that cannot turn in this step acts along its fixed line: no square
        // root or division per increment (`Model::with_lines_held`; the same to round-off).
        let lines_held = model.with_lines_held(&cfg, &held);
        let model = lines_held.as_ref().unwrap_or(&model);
        counters.held_lines += model.held_lines() as u64;
        particle_dashpots = ParticleDashpots::of(model);
        model.fix_single_axis_operators(&cfg, &mut held);
        // A scene of particles and springs that all lie along one axis, of any size, takes its
        // one-pass increments by blocks on a one-dimensional store, written back before any
        // other increment reads the state (faster than the two passes even in cache).
        let mut axial = if model.can_step_by_blocks() {
            model.axial_store(&held)
        } else {
            None
        };
        let velocity_pass = model.has_dashpots() || held.any_velocity_terms();
        // Without centripetal or gyroscopic terms the centred velocity map is affine (the
        // dashpots act along directions frozen for the increment), so when its fixed-point
        // iteration cannot contract it is solved directly in the free DOFs.
        let dofs = model.free_dofs(&held);
        let affine =
            model.has_dashpots() && !held.any_velocity_terms() && dofs.len() <= DENSE_LIMIT;
        let mut affine_solve = false;
        let direct =
            particle_dashpots.is_some() && model.has_dashpots() && !held.any_velocity_terms();
        if direct && let Some(dashpots) = particle_dashpots.as_mut() {
            dashpots.prepare(model, &cfg, &held, h);
        }
        // A small step whose forces are affine runs its increments between output rows as a
        // recurrence in its free DOFs, the state in registers (`AffineStep`; the same to
        // round-off).
        let affine_step = if batched_steps {
            AffineStep::of(
                model,
                &held,
                particle_dashpots.as_ref().filter(|_| direct),
                settings.damping,
            )
        } else {
            None
        };
        // Under finite rotation, a small step with one body turning about one axis runs its
        // increments between output rows with the state in locals (`TurningStep`: its turn
        // about the axis, the same to round-off, or the general path's increments bit for bit).
        let turning_step = if batched_steps && affine_step.is_none() {
            TurningStep::of(model, &held, settings.damping)
        } else {
            None
        };
        // Without dashpots and with every turning body on one free axis, the centred velocity
        // has a closed form (`Model::centred_single_axis`).
        let single_axis = settings.damping == DampingTreatment::Centred
            && !model.has_dashpots()
            && held.any_velocity_terms()
            && model.single_axis(&held);
        // Rows fall on increments unless a stability study asked for an increment that does
        // not divide the output interval; then every increment is a row for the sampler, and
        // the last dynamic step runs past its end to the first increment after it.
        let on_steps = sampler.on_steps;
        let stride = if on_steps {
            (interval / h).round() as u64
        } else {
            1
        };
        let steps_here = if on_steps {
            (step_duration / h).round() as u64
        } else {
            (step_duration / h - 1e-9).ceil() as u64
        };
        let first = n_global;
        let last_step = si + 1 == scene.steps.len()
            || scene.steps[si + 1..]
                .iter()
                .all(|s| !matches!(s.kind, StepKind::Dynamic { .. }));

        let mut next = first;
        while next <= first + steps_here {
            let n = next;
            next += 1;
            if n == first + steps_here && !last_step {
                break; // the next step starts from this configuration
            }
            if n.is_multiple_of(INTERRUPT_STRIDE) && crate::interrupt::requested() {
                return Err(EngineError::Failed(format!("interrupted at increment {n}")));
            }
            let restart = !started || n == first;
            // The affine step takes every increment up to the next that restarts, writes a row,
            // is one of the step's last two or checks for an interrupt.
            if let Some(recurrence) = affine_step.as_ref()
                && !restart
                && !n.is_multiple_of(stride)
                && n + 1 < first + steps_here
                && let Some(bounds) = {
                    // The held lines are checked on the current state.
                    if let Some(store) = axial.as_mut() {
                        store.write_back::<S>(&mut cfg.u, &mut carry.p, &mut v_half.p);
                    }
                    recurrence.bounds(model, &cfg)
                }
            {
                let end = (n / stride + 1) * stride;
                let end = end
                    .min(first + steps_here - 1)
                    .min((n / INTERRUPT_STRIDE + 1) * INTERRUPT_STRIDE);
                model.forces_with::<false>(
                    &cfg,
                    ContactMode::Unilateral,
                    &mut forces,
                    &mut counters,
                );
                // Each contact stays on its side through the batch: only its start can press
                // anew.
                note_impacts(&mut pressed, &forces.contact, (n, h), &mut impacts);
                let solved = if recurrence.solves_bodies() {
                    model.accelerations(&cfg, &forces, &v_half, &held, &mut acc, &mut counters);
                    Some(&acc)
                } else {
                    None
                };
                let taken = recurrence.advance(
                    &mut cfg,
                    &mut carry,
                    &mut v_half,
                    &forces,
                    solved,
                    &bounds,
                    h,
                    end - n,
                    &mut dissipated,
                    &mut last_power,
                    &mut counters,
                );
                next = n + taken;
                continue;
            }
            if let Some(turning) = turning_step.as_ref()
                && !restart
                && !n.is_multiple_of(stride)
                && n + 1 < first + steps_here
            {
                let end = (n / stride + 1) * stride;
                let end = end
                    .min(first + steps_here - 1)
                    .min((n / INTERRUPT_STRIDE + 1) * INTERRUPT_STRIDE);
                let taken = turning.advance(
                    Batch {
                        model,
                        held: &held,
                        cfg: &mut cfg,
                        carry: &mut carry,
                        v_half: &mut v_half,
                        h,
                        n,
                        count: end - n,
                        pressed: &mut pressed,
                        impacts: &mut impacts,
                    },
                    &mut counters,
                );
                // None taken: the increment's centred rate has no real value, or its operator
                // on the axis is not positive and finite, which the general path reports.
                if taken > 0 {
                    last_power = 0.0;
                    next = n + taken;
                    continue;
                }
            }
            // An increment that restarts nothing, has no velocity-dependent force, writes no
            // row and is neither the step's last nor the one before it (whose acceleration
            // starts the next step) needs no acceleration kept: it runs in one pass.
            let one_pass = !restart
                && !velocity_pass
                && !n.is_multiple_of(stride)
                && n + 1 < first + steps_here;
            // A scene of particles, springs along fixed lines and loads: forces and update block
            // by block of springs, each particle's data touched while in cache; on one number
            // per particle where they all lie on one axis (any size), on the 2D or 3D store
            // where the scene is large.
            if one_pass && let Some(store) = axial.as_mut() {
                if model.step_axial(store, &cfg, &carry, h, &v_half, &held, &mut counters) {
                    last_power = 0.0;
                    continue;
                }
                axial = None;
            }
            if one_pass && by_blocks {
                model.step_by_blocks(
                    &mut cfg,
                    &mut carry,
                    h,
                    &mut v_half,
                    &held,
                    &mut pending,
                    &mut counters,
                );
                last_power = 0.0;
                continue;
            }
            if let Some(store) = axial.as_mut() {
                store.write_back::<S>(&mut cfg.u, &mut carry.p, &mut v_half.p);
            }
            // Only an increment that writes a row reads the elastic energy.
            if n.is_multiple_of(stride) {
                model.forces(&cfg, ContactMode::Unilateral, &mut forces, &mut counters);
            } else {
                model.forces_with::<false>(
                    &cfg,
                    ContactMode::Unilateral,
                    &mut forces,
                    &mut counters,
                );
            }
            note_impacts(&mut pressed, &forces.contact, (n, h), &mut impacts);
            if solids {
                model.solid_positions(&cfg, &mut solid_now);
                if watching && let Some((k, moved)) = model.through_solid(&solid_before, &solid_now)
                {
                    return Err(through_solid(scene, k, moved / h, h, n as f64 * h));
                }
                std::mem::swap(&mut solid_before, &mut solid_now);
                watching = true;
            }
            // Otherwise the one-pass increment: accelerations, velocities and positions in
            // one pass over the particles, after the force pass.
            if one_pass {
                model.step(
                    &mut cfg,
                    &mut carry,
                    h,
                    &forces,
                    &mut v_half,
                    &held,
                    &mut acc,
                    &mut counters,
                );
                last_power = 0.0;
                continue;
            }
            // The same increment where the centred velocity is solved directly (dashpots
            // between particles; or bodies turning about one axis each, without dashpots): the
            // accelerations at the centred velocity, then velocities and positions in one pass
            // (the centred velocity itself is not kept).
            if !restart
                && (direct || single_axis)
                && settings.damping == DampingTreatment::Centred
                && !n.is_multiple_of(stride)
                && n + 1 < first + steps_here
            {
                let power = centred_directly(
                    model,
                    &cfg,
                    &forces,
                    &v_half,
                    h,
                    &held,
                    particle_dashpots.as_mut().filter(|_| direct),
                    &mut acc,
                    None,
                    &mut counters,
                )
                .ok_or_else(|| no_centred_rate(n as f64 * h, h))?;
                // Never a restart, so n > 0.
                dissipated += 0.5 * h * (last_power + power);
                model.advance_by(
                    &mut cfg,
                    &mut carry,
                    h,
                    &acc,
                    &mut v_half,
                    &held,
                    &mut counters,
                );
                last_power = power;
                continue;
            }
            let mut power = 0.0;
            // At t = 0 and at every step boundary v(n) is known (at a boundary: the previous
            // step completed, v(n−½) + (h/2)·a(n−1), then the new constraints applied), so the
            // half-step sequence restarts: v(n+½) = v(n) + (h/2)·a(n). Kicking a released DOF
            // by a full h·a(n) instead would make the scheme first order.
            if restart {
                if started {
                    vel = v_half.plus(0.5 * h, &acc_prev);
                    model.enforce(&mut vel, &held);
                }
                total.copy_from(&forces);
                if model.has_dashpots() {
                    model.damping(&cfg, &vel, &mut total, &mut counters);
                    power = total.dissipation;
                }
                model.accelerations(&cfg, &total, &vel, &held, &mut acc, &mut counters);
                v_n = vel.clone();
                v_half = vel.plus(-0.5 * h, &acc);
                started = true;
            }
            if !restart {
                if !velocity_pass {
                    model.accelerations(&cfg, &forces, &v_half, &held, &mut acc, &mut counters);
                } else {
                    match settings.damping {
                        DampingTreatment::Lagged => {
                            v_n.clone_from(&v_half);
                            total.copy_from(&forces);
                            if model.has_dashpots() {
                                model.damping(&cfg, &v_n, &mut total, &mut counters);
                                power = total.dissipation;
                            }
                            model.accelerations(&cfg, &total, &v_n, &held, &mut acc, &mut counters);
                        }
                        DampingTreatment::Centred if direct || single_axis => {
                            power = centred_directly(
                                model,
                                &cfg,
                                &forces,
                                &v_half,
                                h,
                                &held,
                                particle_dashpots.as_mut().filter(|_| direct),
                                &mut acc,
                                Some(&mut v_n),
                                &mut counters,
                            )
                            .ok_or_else(|| no_centred_rate(n as f64 * h, h))?;
                        }
                        DampingTreatment::Centred => {
                            model.dashpot_directions(&cfg, &mut directions);
                            if !affine_solve {
                                v_guess.set_plus(&v_half, 0.5 * h, &acc_prev);
                                let mut converged = false;
                                let mut previous_change = 0.0;
                                for pass in 0..MAX_DAMPING_ITERATIONS {
                                    // Without dashpots the velocity enters through the
                                    // centripetal and gyroscopic terms only: the position
                                    // forces serve every pass as they are.
                                    let applied = if model.has_dashpots() {
                                        total.copy_from(&forces);
                                        model.damping_along(
                                            &cfg,
                                            &directions,
                                            &v_guess,
                                            &mut total,
                                            &mut counters,
                                        );
                                        power = total.dissipation;
                                        &total
                                    } else {
                                        &forces
                                    };
                                    model.accelerations(
                                        &cfg,
                                        applied,
                                        &v_guess,
                                        &held,
                                        &mut acc,
                                        &mut counters,
                                    );
                                    v_n.set_plus(&v_half, 0.5 * h, &acc);
                                    let (change, size) = v_n.max_difference(&v_guess);
                                    std::mem::swap(&mut v_n, &mut v_guess);
                                    // The iteration contracts by ρ per pass (ρ ≈ (h/2)·|∂a/∂v|,
                                    // estimated as change / previous change), so the iterate just
                                    // made is within ρ/(1−ρ) · change of the fixed point. With
                                    // ρ < ½ that test reads change² ≤ tol·size·(previous − change).
                                    let tolerance = VELOCITY_TOLERANCE * size;
                                    let contracting = 2.0 * change < previous_change;
                                    let bound_met =
                                        change * change <= tolerance * (previous_change - change);
                                    let diverging = pass >= 3 && change > previous_change;
                                    previous_change = change;
                                    if change <= tolerance || (contracting && bound_met) {
                                        converged = true;
                                        break;
                                    }
                                    if diverging && affine {
                                        break;
                                    }
                                }
                                std::mem::swap(&mut v_n, &mut v_guess);
                                // Stiff dashpots (h·|M⁻¹C|/2 ≥ 1): the iteration
                                // cannot contract, but where the map is affine it is solved
                                // directly from now on.
                                if !converged && affine {
                                    affine_solve = true;
                                } else if !converged {
                                    return Err(EngineError::Failed(format!(
                                        "centred velocity iteration did not converge at t = {:e}: the dashpots are too stiff for increment {h:e}; use damping = \"lagged\" or a smaller increment",
                                        n as f64 * h
                                    )));
                                }
                            }
                            if affine_solve {
                                centred_affine(
                                    model,
                                    &cfg,
                                    &forces,
                                    &directions,
                                    &v_half,
                                    h,
                                    &held,
                                    &dofs,
                                    &mut total,
                                    &mut acc,
                                    &mut v_n,
                                    &mut counters,
                                )?;
                                power = total.dissipation;
                            }
                        }
                    }
                }
            }
            if n > 0 {
                dissipated += 0.5 * h * (last_power + power);
            }
            v_next.set_plus(&v_half, h, &acc);
            if n.is_multiple_of(stride) {
                if !velocity_pass && n > 0 {
                    v_n.set_plus(&v_half, 0.5 * h, &acc);
                }
                let kinetic = model.kinetic_energy(&cfg, &v_n);
                if n == 0 {
                    energy0 = kinetic + forces.elastic;
                }
                let work = model.external_work(&cfg, &cfg_start);
                let mut row = Vec::with_capacity(columns.len());
                row.push(if on_steps {
                    times[((n / stride) as usize).min(times.len() - 1)]
                } else {
                    n as f64 * h
                });
                for (ci, c) in scene.columns.iter().enumerate() {
                    row.push(match &c.probe {
                        Probe::Displacement { node, direction } => {
                            S::v(direction).dot(&model.displacement(&cfg, &model.points[*node]))
                        }
                        Probe::Velocity { node, direction } => {
                            S::v(direction).dot(&model.velocity(&cfg, &v_n, &model.points[*node]))
                        }
                        Probe::Rotation { body, axis } => {
                            let raw = model.rotation_about(&cfg, *body, &S::w(axis));
                            let turns =
                                ((previous_rotation[ci] - raw) / std::f64::consts::TAU).round();
                            let unwrapped = raw + turns * std::f64::consts::TAU;
                            previous_rotation[ci] = unwrapped;
                            unwrapped
                        }
                        Probe::ContactForce { contact } => forces.contact[*contact],
                        Probe::Gap { contact } => model.gap(&cfg, *contact).0,
                        Probe::Zero { .. } => 0.0,
                    });
                }
                let balance = kinetic + forces.elastic + dissipated - work - energy0;
                row.extend([kinetic, forces.elastic, dissipated, work, balance]);
                let unstable = |what: &str| {
                    let limit = stable.map_or("none computed".to_string(), |s| {
                        format!("{:e}, ratio {:.4}", s.increment, h / s.increment)
                    });
                    // The modes of a scene above the dense limit are not computed.
                    let mode = if v_next.is_finite() && dofs.len() <= DENSE_LIMIT {
                        growing_mode(
                            model,
                            scene,
                            &cfg_start,
                            &held,
                            &v_next,
                            h,
                            settings.damping,
                        )
                        .map(|m| match impacts.last() {
                            // Below the mode's limit nothing grows: an impact put the energy in.
                            Some(&at) if h < m.limit => format!("; {}", m.describe_impact(h, at)),
                            _ => format!("; {}", m.describe(h)),
                        })
                        .unwrap_or_default()
                    } else {
                        String::new()
                    };
                    EngineError::Failed(format!(
                        "{what} by t = {:e}: the run is unstable at increment {h:e} (stable increment: {limit}){mode}",
                        row[0]
                    ))
                };
                if row.iter().any(|x| !x.is_finite()) {
                    return Err(unstable("the state became non-finite"));
                }
                // What the run may hold is what it started with plus the work done on it; a
                // stable run stays at or below that (dissipation only removes energy).
                let budget = energy0 + work.abs();
                // Above the stable increment: the modes past their limit may not grow, even
                // where a nonlinearity keeps the total energy under the guard.
                if let Some(watch) = past_limit.as_mut()
                    && let Some(growth) = watch.grown(model, &v_next, 1e-12 * budget)
                {
                    return Err(unstable(&format!(
                        "the modes past their stability limit grew {growth:.3e}-fold in kinetic energy (over {PAST_LIMIT_GROWTH}×)"
                    )));
                }
                if kinetic + forces.elastic > ENERGY_GUARD * budget + f64::MIN_POSITIVE {
                    return Err(unstable(&format!(
                        "energy grew to {:e}, over {ENERGY_GUARD}× the initial energy plus the work of the loads ({budget:e})",
                        kinetic + forces.elastic
                    )));
                }
                sampler.push(row, &mut rows);
            }
            last_power = power;
            if n == first + steps_here {
                break;
            }
            model.advance(&mut cfg, &mut carry, h, &v_next, &held, &mut counters);
            std::mem::swap(&mut v_half, &mut v_next);
            std::mem::swap(&mut acc_prev, &mut acc);
        }
        if let Some(store) = axial.as_mut() {
            store.write_back::<S>(&mut cfg.u, &mut carry.p, &mut v_half.p);
        }
        n_global = first + steps_here;
    }
    Ok(Integration {
        history: History { columns, rows },
        increment: h,
        steps: n_global,
        stable,
        counters,
        impacts,
    })
}

/// Note which contact pairs press at increment `n`, time n·`h` (normal forces `contact`) in
/// `pressed`, and an impact where one that did not press at the last increment noted starts
/// to (the time is formed only then).
///
/// The increment loops call this at every increment, and an impact is rare: the test is
/// inlined and the noting ([`note_start`]) is a cold call, so that the loop neither forms
/// the time nor keeps its registers on the stack around a call it seldom makes.
#[inline(always)]
pub(super) fn note_impacts(
    pressed: &mut [Option<bool>],
    contact: &[f64],
    (n, h): (u64, f64),
    impacts: &mut Vec<f64>,
) {
    for (was, force) in pressed.iter_mut().zip(contact) {
        let now = *force > 0.0;
        if now && *was == Some(false) {
            note_start((n, h), impacts);
        }
        *was = Some(now);
    }
}

/// An impact [`note_impacts`] found: a pair starts to press at increment `n`, time n·`h`.
#[cold]
#[inline(never)]
fn note_start((n, h): (u64, f64), impacts: &mut Vec<f64>) {
    impacts.push(n as f64 * h);
}

/// Turns the rows of increments into output rows: on increments that fall on the output times,
/// row for row; otherwise (a stability study's increment) by quadratic interpolation through
/// the last three increments around each output time (error O(h³) on the accurate modes).
struct RowSampler {
    times: Vec<f64>,
    next: usize,
    /// Whether the increment divides the output interval (rows fall on increments).
    on_steps: bool,
    /// The last (up to) three rows of increments.
    window: std::collections::VecDeque<Vec<f64>>,
    /// Time round-off allowance.
    slack: f64,
}

impl RowSampler {
    fn new(times: &[f64], interval: f64, h: f64) -> Self {
        let per = interval / h;
        RowSampler {
            times: times.to_vec(),
            next: 0,
            on_steps: (per - per.round()).abs() <= 1e-9 * per.max(1.0),
            window: std::collections::VecDeque::with_capacity(3),
            slack: 1e-9 * h,
        }
    }

    /// Take the row of the latest increment (time in column 0); write the output rows it
    /// completes.
    fn push(&mut self, row: Vec<f64>, rows: &mut Vec<Vec<f64>>) {
        if self.on_steps {
            rows.push(row);
            return;
        }
        if self.window.len() == 3 {
            self.window.pop_front();
        }
        self.window.push_back(row);
        let latest = self.window.back().map_or(0.0, |r| r[0]);
        while self.next < self.times.len() && self.times[self.next] <= latest + self.slack {
            let t = self.times[self.next];
            let points: Vec<&Vec<f64>> = self.window.iter().collect();
            let weights: Vec<f64> = (0..points.len())
                .map(|i| {
                    (0..points.len())
                        .filter(|&j| j != i)
                        .map(|j| (t - points[j][0]) / (points[i][0] - points[j][0]))
                        .product()
                })
                .collect();
            let mut out: Vec<f64> = (0..points[0].len())
                .map(|c| points.iter().zip(&weights).map(|(p, w)| w * p[c]).sum())
                .collect();
            out[0] = t;
            rows.push(out);
            self.next += 1;
        }
    }
}

/// The accelerations at the centred velocity without iterating, and that velocity into `v_n`
/// where one is given: by the particle dashpots' direct solve (`dashpots`) or, without
/// dashpots, by the closed form for bodies turning about one axis
/// ([`Model::centred_single_axis`]). Returns the dashpots' dissipation power, or None where
/// the closed form has no real root (see [`no_centred_rate`]).
#[allow(clippy::too_many_arguments)]
fn centred_directly<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &Config<S>,
    forces: &Forces<S>,
    v_half: &Rates<S>,
    h: f64,
    held: &Constraints<S>,
    dashpots: Option<&mut ParticleDashpots<S>>,
    acc: &mut Rates<S>,
    v_n: Option<&mut Rates<S>>,
    counters: &mut Counters,
) -> Option<f64> {
    if let Some(solve) = dashpots {
        return Some(solve.solve(model, cfg, forces, v_half, h, held, acc, v_n, counters));
    }
    if !model.centred_single_axis(cfg, forces, v_half, held, h, acc, counters) {
        return None;
    }
    if let Some(v_n) = v_n {
        v_n.set_plus(v_half, 0.5 * h, acc);
    }
    Some(0.0)
}

/// The failure of an increment whose centred angular rate has no real value: the
/// centripetal terms grow faster with the rate than the increment can follow (h·|ω| far past
/// the stable range), so no v(n) satisfies the scheme's equation.
fn no_centred_rate(t: f64, h: f64) -> EngineError {
    EngineError::Failed(format!(
        "the centred angular velocity has no real solution at t = {t:e}: the centripetal terms are too strong for increment {h:e}; use a smaller increment or damping = \"lagged\""
    ))
}

/// The centred velocity v(n) = v(n−½) + (h/2)·a(v(n)) solved directly, for a map that is affine
/// in v (dashpots along the `directions` frozen for the increment; no centripetal or gyroscopic
/// term): with g(v) = v(n−½) + (h/2)·a(v) = b + J·v in the free DOFs, (I − J)·v = b, J from
/// g at the unit rates. Leaves `total`, `acc` (and the dissipation in `total`) at the solution.
#[allow(clippy::too_many_arguments)]
fn centred_affine<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &Config<S>,
    forces: &Forces<S>,
    directions: &[S::V],
    v_half: &Rates<S>,
    h: f64,
    held: &Constraints<S>,
    dofs: &[Target<S>],
    total: &mut Forces<S>,
    acc: &mut Rates<S>,
    v_n: &mut Rates<S>,
    counters: &mut Counters,
) -> Result<(), EngineError> {
    let mut map = |v: &Rates<S>, total: &mut Forces<S>, acc: &mut Rates<S>, out: &mut Rates<S>| {
        total.copy_from(forces);
        model.damping_along(cfg, directions, v, total, counters);
        model.accelerations(cfg, total, v, held, acc, counters);
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
