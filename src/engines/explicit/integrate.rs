//! The central-difference time loop, as Abaqus/Explicit does it: half-step velocities,
//! `v(n+½) = v(n−½) + h·a(n)`, `x(n+1) = x(n) + h·v(n+½)`, rotations advanced by the exact
//! exponential of the incremental rotation.
//!
//! Velocity-dependent forces (dashpots; centripetal and gyroscopic terms of bodies under finite
//! rotation) need the velocity at time n. The centred treatment uses
//! `v(n) = (v(n−½) + v(n+½))/2`, solved by fixed-point iteration from the predictor
//! `v(n−½) + (h/2)·a(n−1)`, which keeps the scheme second order; the lagged treatment uses
//! `v(n−½)` (first order, the classic explicit form). Scenes without such forces skip the pass.

use super::linear::{StableIncrement, static_step};
use super::model::{Config, Constraints, ContactMode, Counters, Forces, Model, Rates};
use super::space::{Lin, Space};
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
}

const MAX_DAMPING_ITERATIONS: usize = 100;

/// The centred velocity iteration stops when v(n) is within this fraction of the largest
/// velocity component of its fixed point (a few units of round-off).
const VELOCITY_TOLERANCE: f64 = 1e-14;

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
/// divides the output interval exactly (rows fall on steps; no interpolation).
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
fn consistent_forces<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &Config<S>,
    vel: &Rates<S>,
    held: &Constraints<S>,
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
            DVector::from_fn(n, |k, _| model.gap_acceleration(cfg, vel, &acc, k)),
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
/// −λ̇_r(0)/k_p. λ̇_r and λ̈_r are central differences of the rigid force along the trajectory
/// extrapolated ±τ (τ = the increment).
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
        let Some((f, _, _)) = consistent_forces(model, cfg, vel, held, counters) else {
            return;
        };
        for (k, fk) in f.iter().enumerate() {
            model.set_penetration(cfg, k, fk / model.penalty);
        }
    }
    let Some((f0, acc, b)) = consistent_forces(model, cfg, vel, held, counters) else {
        return;
    };
    // Along the rigid trajectory, extrapolated ±τ. The rigid force depends on velocities
    // (centripetal and Coriolis terms of the gap under finite rotation), so the velocity must be
    // extrapolated to second order: the jerk comes from a first pass.
    let mut at = |s: f64, jerk: &Rates<S>| {
        let (c, v) = model.extrapolate(cfg, vel, &acc, jerk, s);
        consistent_forces(model, &c, &v, held, counters)
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
            model.set_gap_rate(cfg, vel, k, -rate[k] / model.penalty);
        }
    }
    model.enforce(vel, held);
}

/// Run a scene through all its steps.
pub fn integrate<S: Space, const FINITE: bool>(
    scene: &Scene,
    settings: &SceneSettings,
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
    let mut forces = model.zero_forces();
    let mut total: Forces<S> = model.zero_forces();
    let mut acc = model.zero_rates();
    let mut acc_prev = model.zero_rates();
    let mut v_n = model.zero_rates();
    let mut v_guess = model.zero_rates();
    let mut v_half = model.zero_rates();
    let mut v_next = model.zero_rates();
    let mut carry = model.zero_rates();
    let mut directions = Vec::new();

    for (si, step) in scene.steps.iter().enumerate() {
        let held = model.constraints(scene, step);
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
        }
        model.enforce(&mut vel, &held);
        if !started {
            if model.contact_count() > 0 && settings.contact_start == ContactStart::Consistent {
                consistent_start(&model, &mut cfg, &mut vel, &held, h, &mut counters);
            }
            cfg_start = cfg.clone();
        }
        let velocity_pass = model.has_dashpots() || held.any_velocity_terms();
        let stride = (interval / h).round() as u64;
        let steps_here = (step_duration / h).round() as u64;
        let first = n_global;
        let last_step = si + 1 == scene.steps.len()
            || scene.steps[si + 1..]
                .iter()
                .all(|s| !matches!(s.kind, StepKind::Dynamic { .. }));

        for n in first..=first + steps_here {
            if n == first + steps_here && !last_step {
                break; // the next step starts from this configuration
            }
            if n % INTERRUPT_STRIDE == 0 && crate::interrupt::requested() {
                return Err(EngineError::Failed(format!("interrupted at increment {n}")));
            }
            model.forces(&cfg, ContactMode::Unilateral, &mut forces, &mut counters);
            let restart = !started || n == first;
            // An increment that restarts nothing, has no velocity-dependent force, writes no
            // row and is neither the step's last nor the one before it (whose acceleration
            // starts the next step): accelerations, velocities and positions in one pass.
            if !restart && !velocity_pass && n % stride != 0 && n + 1 < first + steps_here {
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
                        DampingTreatment::Centred => {
                            v_guess.set_plus(&v_half, 0.5 * h, &acc_prev);
                            model.dashpot_directions(&cfg, &mut directions);
                            let mut converged = false;
                            let mut previous_change = 0.0;
                            for _ in 0..MAX_DAMPING_ITERATIONS {
                                total.copy_from(&forces);
                                if model.has_dashpots() {
                                    model.damping_along(
                                        &cfg,
                                        &directions,
                                        &v_guess,
                                        &mut total,
                                        &mut counters,
                                    );
                                    power = total.dissipation;
                                }
                                model.accelerations(
                                    &cfg,
                                    &total,
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
                                previous_change = change;
                                if change <= tolerance || (contracting && bound_met) {
                                    converged = true;
                                    break;
                                }
                            }
                            std::mem::swap(&mut v_n, &mut v_guess);
                            if !converged {
                                return Err(EngineError::Failed(format!(
                                    "centred velocity iteration did not converge at t = {:e}: the dashpots are too stiff for increment {h:e}; use damping = \"lagged\" or a smaller increment",
                                    n as f64 * h
                                )));
                            }
                        }
                    }
                }
            }
            if n > 0 {
                dissipated += 0.5 * h * (last_power + power);
            }
            v_next.set_plus(&v_half, h, &acc);
            if n % stride == 0 {
                if !velocity_pass && n > 0 {
                    v_n.set_plus(&v_half, 0.5 * h, &acc);
                }
                let row_index = (n / stride) as usize;
                let kinetic = model.kinetic_energy(&cfg, &v_n);
                if n == 0 {
                    energy0 = kinetic + forces.elastic;
                }
                let work = model.external_work(&cfg, &cfg_start);
                let mut row = Vec::with_capacity(columns.len());
                row.push(times[row_index.min(times.len() - 1)]);
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
                        Probe::Zero { .. } => 0.0,
                    });
                }
                let balance = kinetic + forces.elastic + dissipated - work - energy0;
                row.extend([kinetic, forces.elastic, dissipated, work, balance]);
                let unstable = |what: &str| {
                    let limit = stable.map_or("none computed".to_string(), |s| {
                        format!("{:e}", s.increment)
                    });
                    EngineError::Failed(format!(
                        "{what} by t = {:e}: the run is unstable at increment {h:e} (stable increment: {limit})",
                        row[0]
                    ))
                };
                if row.iter().any(|x| !x.is_finite()) {
                    return Err(unstable("the state became non-finite"));
                }
                // What the run may hold is what it started with plus the work done on it; a
                // stable run stays at or below that (dissipation only removes energy).
                let budget = energy0 + work.abs();
                if kinetic + forces.elastic > 100.0 * budget + f64::MIN_POSITIVE {
                    return Err(unstable(&format!(
                        "energy blew up to {:e}, over 100× the initial energy plus the work of the loads ({budget:e})",
                        kinetic + forces.elastic
                    )));
                }
                rows.push(row);
            }
            last_power = power;
            if n == first + steps_here {
                break;
            }
            model.advance(&mut cfg, &mut carry, h, &v_next, &held, &mut counters);
            std::mem::swap(&mut v_half, &mut v_next);
            std::mem::swap(&mut acc_prev, &mut acc);
        }
        n_global = first + steps_here;
    }
    Ok(Integration {
        history: History { columns, rows },
        increment: h,
        steps: n_global,
        stable,
        counters,
    })
}
