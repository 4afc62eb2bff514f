//! The central-difference time loop, as Abaqus/Explicit does it: half-step velocities,
//! `v(n+½) = v(n−½) + h·a(n)`, `x(n+1) = x(n) + h·v(n+½)`, rotations advanced by the exact
//! exponential of the incremental rotation. One increment for every scene the case format
//! allows ([`TimeLoop::increment`]): the force pass over each kind of element, the
//! accelerations (at the velocity the [`VelocityRule`] of the step gives, where forces read
//! it), the update of velocities and positions.

use super::diagnosis::{PAST_LIMIT_GROWTH, PastLimit, growing_mode};
use super::friction::Sticks;
use super::impacts::ImpactWork;
use super::linear::{StableIncrement, static_step};
use super::model::{
    Config, Constraints, ContactMode, Counters, Forces, Model, Point, Rates, SolidPosition,
};
use super::ramps::RampedWork;
use super::rows::{RowSampler, note_impacts};
use super::space::{Lin, Space};
use super::start::consistent_start;
use super::velocity::{AtIncrement, Velocities, VelocityRule, bodies_in_closed_form};
use crate::contract::energy_columns;
use crate::engines::{EngineError, History};
use crate::scene::{
    ContactStart, DEFAULT_SAFETY, DampingTreatment, IncrementRule, Probe, Scene, SceneSettings,
    StepKind, Surface,
};

/// The state at increment n that a velocity rule reads ([`AtIncrement`]), from a
/// [`TimeLoop`] and the constraints `held`. A macro, not a method: it borrows the loop's
/// fields one by one, so that the rule may write the others (its work and accelerations).
macro_rules! at_increment {
    ($loop:expr, $held:expr) => {
        AtIncrement {
            model: $loop.model,
            cfg: &$loop.cfg,
            forces: &$loop.forces,
            v_half: &$loop.v_half,
            acc_prev: &$loop.acc_prev,
            h: $loop.h,
            held: $held,
        }
    };
}

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

/// A run stops as unstable when its kinetic plus elastic energy exceeds this multiple of what
/// it may hold (its initial energy plus the work of the loads). A stable run stays at or below
/// 1× up to the measured energy error of the scheme: at 0.98 of the stable increment on every
/// seed case at most 1.00003× (centred damping, consistent contact start) and 1.29× (lagged
/// damping, whose dashpots see a lagged velocity). An unstable mode grows by |λ| > 1 per
/// increment (1.49 undamped at ω·h = 2.04), so the guard trips within tens of increments of
/// the mode becoming visible; a penalty contact that chatters open and shut at 1.02× stops
/// between 2.2× and 50× (measured), which a guard at 100× let through.
pub const ENERGY_GUARD: f64 = 2.0;

/// How far a stable run's measured energy may stand above its conserved energy at increment
/// ratio `ratio` = h/(2/ω_max): central differences' reading, 1/(1 − ratio²) below 1.
pub use crate::engines::central_difference_energy_reading as measured_energy_allowance;

/// Particle- and body-increments between two looks at the interruption flag (a few
/// milliseconds of work whatever the scene's size; at most [`INTERRUPT_STRIDE`] increments).
const INTERRUPT_WORK: u64 = 1 << 16;

/// Increments between two looks at the interruption flag, at most (a power of two).
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
        let held = model.constraints(step);
        let dense = model.free_dof_count(&held) <= DENSE_LIMIT;
        let bound = if dense {
            None
        } else {
            model.frequency_bound(cfg, &held)
        };
        let stable = if let Some((lambda, gamma)) = bound {
            StableIncrement::from_bound(lambda, gamma, treatment)
        } else {
            let closed = model
                .linearise(cfg, &held, ContactMode::Bilateral, counters)
                .modes();
            let open = if !model.contacts.is_empty() {
                model
                    .linearise(cfg, &held, ContactMode::Off, counters)
                    .modes()
            } else {
                closed.clone()
            };
            StableIncrement::from_modes(&closed, &open, treatment)
        };
        if let Some(s) = stable
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
            let cap = DEFAULT_SAFETY * limit;
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
        IncrementRule::Tolerance(_) => (DEFAULT_SAFETY * limit).min(interval),
    };
    let per_interval = (interval / h - 1e-9).ceil().max(1.0);
    Ok(interval / per_interval)
}

/// The refusal of a run whose contact node went through its solid: penalty contact cannot
/// catch a node that moves past the solid's half thickness `depth` in one increment or before
/// the penalty stops it, so it names the speed and what would catch it: an increment under
/// depth/(2v) and a penalty stiffness over m(2v/depth)².
fn through_solid(scene: &Scene, k: usize, speed: f64, h: f64, t: f64) -> EngineError {
    let pair = &scene.contacts[k];
    let node = &scene.nodes[pair.node];
    let Surface::Solid { solid, .. } = &pair.surface else {
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

/// The first multiple of `stride` at or after `n` (for a `stride` of 0, `n` itself where it is
/// 0, as `u64::is_multiple_of` reads it); u64::MAX where none is left.
fn next_multiple(n: u64, stride: u64) -> u64 {
    match stride {
        0 if n == 0 => 0,
        0 => u64::MAX,
        _ => n.checked_next_multiple_of(stride).unwrap_or(u64::MAX),
    }
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
    if settings.damping == DampingTreatment::Lagged && model.has_contact_dashpots() {
        return Err(EngineError::Unsupported(
            "lagged damping with a contact dashpot (a contact with restitution below 1): the stable increment is computed with the contact open, where its dashpot does not act; use centred damping".into(),
        ));
    }
    let mut run = TimeLoop::new(&model, scene, settings);
    for (si, step) in scene.steps.iter().enumerate() {
        let held = model.constraints(step);
        match step.kind {
            StepKind::Dynamic { duration } => run.dynamic_step(si, duration, held)?,
            _ => static_step(&model, &mut run.cfg, &held, &mut run.counters)?,
        }
    }
    if let Some(sticks) = &run.sticks {
        run.counters.friction_evaluations = sticks.evaluations;
        run.counters.slip_increments = sticks.slips;
    }
    Ok(Integration {
        history: History {
            columns: run.columns,
            rows: run.rows,
        },
        increment: run.h,
        steps: run.n,
        stable: run.stable,
        counters: run.counters,
        impacts: run.impacts,
    })
}

/// The state of a run between increments.
struct TimeLoop<'a, S: Space, const FINITE: bool> {
    model: &'a Model<S, FINITE>,
    scene: &'a Scene,
    settings: &'a SceneSettings,
    counters: Counters,
    /// Configuration at increment n, and the rounding carry of its compensated sums.
    cfg: Config<S>,
    carry: Rates<S>,
    /// v(n−½), and v(n+½) where the general path forms it apart (the shorter paths update
    /// `v_half` in place).
    v_half: Rates<S>,
    v_next: Rates<S>,
    /// Accelerations at increment n and n − 1. The shorter paths that nothing in their step
    /// reads a(n−1) on ([`TimeLoop::keep_accelerations`]) keep it only for the next step.
    acc: Rates<S>,
    acc_prev: Rates<S>,
    /// Position-dependent forces at increment n.
    forces: Forces<S>,
    /// The stick points of the pairs with friction (`None` without friction).
    sticks: Option<Sticks<S>>,
    /// The work of the loads that vary in time (`None` without them).
    ramped: Option<RampedWork<S>>,
    velocities: Velocities<S>,
    /// Increment, stable increment, and the increments taken.
    h: f64,
    stable: Option<StableIncrement>,
    n: u64,
    started: bool,
    /// Energy at t = 0, and the dashpots' dissipation (trapezoidal in the power).
    energy0: f64,
    dissipated: f64,
    last_power: f64,
    /// Configuration at the start of the first dynamic step (the loads' work is from there).
    cfg_start: Config<S>,
    past_limit: Option<PastLimit<S>>,
    /// Whether each pair pressed at the last increment (None before the first), and the
    /// impacts: the increments where a pair that did not press starts to.
    pressed: Vec<Option<bool>>,
    impacts: Vec<f64>,
    /// The contact pairs' work accounts (from the first increment; none without contact).
    impact_work: Option<ImpactWork>,
    /// Where each solid's contact node was at the last increment (watched for a node going
    /// through its solid).
    solid_before: Vec<Option<SolidPosition<S>>>,
    solid_now: Vec<Option<SolidPosition<S>>>,
    /// Whether any pair's face is a solid's (otherwise nothing is watched).
    solids: bool,
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
    sampler: RowSampler,
    previous_rotation: Vec<f64>,
}

/// One dynamic step as its increments see it.
struct StepPlan<S: Space> {
    held: Constraints<S>,
    velocity: VelocityRule<S>,
    /// Increments between output rows (1 where rows are interpolated).
    stride: u64,
    /// The next increment that writes a row: the next multiple of `stride` (u64::MAX once
    /// none is left), counted forward so that an increment tests it without a division.
    next_row: u64,
    /// The step's first increment and how many it takes.
    first: u64,
    count: u64,
    /// Whether no dynamic step follows (the last runs its final increment's row).
    last: bool,
    /// Whether an increment may take the bodies' centred rates in closed form
    /// ([`TimeLoop::advance_turning`]): no dashpot acts, and every body whose velocity terms
    /// act turns about one axis.
    turning: bool,
}

impl<'a, S: Space, const FINITE: bool> TimeLoop<'a, S, FINITE> {
    fn new(model: &'a Model<S, FINITE>, scene: &'a Scene, settings: &'a SceneSettings) -> Self {
        let interval = scene.duration() / (scene.output_rows - 1) as f64;
        let columns: Vec<String> = std::iter::once("t".to_string())
            .chain(scene.columns.iter().map(|c| c.name.clone()))
            .chain(
                energy_columns(model.has_friction())
                    .iter()
                    .map(|s| s.to_string()),
            )
            .collect();
        let cfg = model.initial_config();
        let sticks = Sticks::new(model, &cfg);
        TimeLoop {
            model,
            scene,
            settings,
            counters: Counters::default(),
            cfg_start: cfg.clone(),
            cfg,
            carry: model.zero_rates(),
            v_half: model.zero_rates(),
            v_next: model.zero_rates(),
            acc: model.zero_rates(),
            acc_prev: model.zero_rates(),
            forces: model.zero_forces(),
            sticks,
            ramped: RampedWork::new(model),
            velocities: Velocities::new(model),
            h: 0.0,
            stable: None,
            n: 0,
            started: false,
            energy0: 0.0,
            dissipated: 0.0,
            last_power: 0.0,
            past_limit: None,
            pressed: vec![None; model.contacts.len()],
            impacts: Vec::new(),
            impact_work: None,
            solid_before: Vec::new(),
            solid_now: Vec::new(),
            solids: model.has_solids(),
            columns,
            rows: Vec::with_capacity(scene.output_rows),
            sampler: RowSampler::new(&scene.output_times(), interval, interval),
            previous_rotation: vec![0.0; scene.columns.len()],
        }
    }

    /// The output interval.
    fn interval(&self) -> f64 {
        self.scene.duration() / (self.scene.output_rows - 1) as f64
    }

    /// At the first dynamic step (index `si`): the initial velocities, the stable increment
    /// and the increment.
    fn start(&mut self, si: usize) -> Result<(), EngineError> {
        let (model, scene) = (self.model, self.scene);
        for iv in &scene.initial_velocities {
            match model.points[iv.node] {
                Point::Particle(i) => self.velocities.v_n.p.set(i, S::v(&iv.velocity)),
                Point::Body { body, .. } => {
                    self.velocities.v_n.b[body] = S::v(&iv.velocity);
                    self.velocities.v_n.w[body] = S::w(&iv.angular);
                }
                Point::Ground(_) => {}
            }
        }
        let treatment = self.settings.damping;
        self.stable = stable_increment(model, scene, &self.cfg, si, treatment, &mut self.counters);
        let (rule, duration, interval) =
            (self.settings.increment, scene.duration(), self.interval());
        self.h = choose_increment(rule, self.stable.as_ref(), duration, interval)?;
        self.sampler = RowSampler::new(&scene.output_times(), interval, self.h);
        if !self.sampler.on_steps && self.dynamic_after(si) {
            return Err(EngineError::Unsupported(format!(
                "increment {:e} does not divide the output interval {interval:e}, and the scene has more than one dynamic step: a stability study's increment must divide every step but the last",
                self.h
            )));
        }
        Ok(())
    }

    /// At the first dynamic step, once its constraints apply: the consistent contact start,
    /// and the watch on the modes past their limit in a stability study.
    fn start_state(&mut self, held: &Constraints<S>) {
        let model = self.model;
        // The consistent start carries the rigid model's persistent contact forces, which
        // treat every pair as closed: only when every pair starts closed. A scene with a
        // pair open at t = 0 starts as it is.
        if !model.contacts.is_empty()
            && model.closed_only()
            && self.settings.contact_start == ContactStart::Consistent
        {
            let v = &mut self.velocities.v_n;
            consistent_start(model, &mut self.cfg, v, held, self.h, &mut self.counters);
        }
        if let Some(sticks) = self.sticks.as_mut() {
            let mut normal = model.zero_forces();
            let (mode, counters) = (ContactMode::Unilateral, &mut self.counters);
            model.forces(&self.cfg, mode, &mut normal, counters);
            model.ramped_forces(&self.cfg, 0.0, &mut normal);
            sticks.start(model, &self.cfg, &self.velocities.v_n, &normal);
        }
        self.cfg_start = self.cfg.clone();
        // Only above the stable increment (a stability study), and only where the scene's
        // modes are computed at all (not above the dense limit).
        if self
            .stable
            .is_some_and(|s| self.h > s.increment * (1.0 + 1e-12))
            && model.free_dof_count(held) <= DENSE_LIMIT
        {
            let treatment = self.settings.damping;
            self.past_limit = PastLimit::new(model, &self.cfg, held, self.h, treatment);
        }
    }

    /// Run dynamic step `si` of `duration` under `held`.
    fn dynamic_step(
        &mut self,
        si: usize,
        duration: f64,
        held: Constraints<S>,
    ) -> Result<(), EngineError> {
        if !self.started {
            self.start(si)?;
        }
        self.model.enforce(&mut self.velocities.v_n, &held);
        if !self.started {
            self.start_state(&held);
        }
        let mut plan = self.plan(si, duration, held);
        // A power of two, so that the look costs a mask, not a division, per increment.
        let size = (self.model.particles.len() + self.model.bodies.len()).max(1) as u64;
        let stride = (INTERRUPT_WORK / size).clamp(1, INTERRUPT_STRIDE);
        let stride = 1u64 << stride.ilog2();
        for n in plan.first..=plan.first + plan.count {
            if n == plan.first + plan.count && !plan.last {
                break; // the next step starts from this configuration
            }
            if n & (stride - 1) == 0 && crate::interrupt::requested() {
                return Err(EngineError::Failed(format!("interrupted at increment {n}")));
            }
            self.increment(n, &mut plan)?;
        }
        self.n = plan.first + plan.count;
        Ok(())
    }

    /// The plan of dynamic step `si` of `duration` under `held`.
    fn plan(&self, si: usize, duration: f64, mut held: Constraints<S>) -> StepPlan<S> {
        let (model, h) = (self.model, self.h);
        model.form_turning_operators(&mut held, &self.cfg);
        let velocity = VelocityRule::of(model, &self.cfg, &held, h, self.settings.damping);
        // Rows fall on increments unless a stability study asked for an increment that does
        // not divide the output interval; then every increment is a row for the sampler, and
        // the last dynamic step runs past its end to the first increment after it.
        let (stride, count) = if self.sampler.on_steps {
            let rounded = |x: f64| x.round() as u64;
            (rounded(self.interval() / h), rounded(duration / h))
        } else {
            (1, (duration / h - 1e-9).ceil() as u64)
        };
        let turning = !model.has_dashpots() && held.velocity_terms_about_one_axis();
        StepPlan {
            turning,
            held,
            velocity,
            stride,
            next_row: next_multiple(self.n, stride),
            first: self.n,
            count,
            last: !self.dynamic_after(si),
        }
    }

    /// Whether a dynamic step follows step `si`.
    fn dynamic_after(&self, si: usize) -> bool {
        let steps = &self.scene.steps[si + 1..];
        steps
            .iter()
            .any(|s| matches!(s.kind, StepKind::Dynamic { .. }))
    }

    /// Increment n: the forces at x(n), the accelerations, a row where one falls, then
    /// v(n+½) and x(n+1) (not after the run's last increment).
    #[inline(always)]
    fn increment(&mut self, n: u64, plan: &mut StepPlan<S>) -> Result<(), EngineError> {
        let (model, h) = (self.model, self.h);
        let row = n == plan.next_row;
        if row {
            plan.next_row = next_multiple(n + 1, plan.stride);
        }
        // Only an increment that writes a row reads the elastic energy.
        let (cfg, mode, counters) = (&self.cfg, ContactMode::Unilateral, &mut self.counters);
        if row {
            model.forces(cfg, mode, &mut self.forces, counters);
        } else {
            model.forces_with::<false>(cfg, mode, &mut self.forces, counters);
        }
        if let Some(ramped) = self.ramped.as_mut() {
            let t = n as f64 * h;
            model.ramped_forces(cfg, t, &mut self.forces);
            ramped.add(model, cfg, t);
        }
        if let Some(sticks) = self.sticks.as_mut() {
            if row {
                model.friction_forces::<true>(cfg, sticks, &mut self.forces);
            } else {
                model.friction_forces::<false>(cfg, sticks, &mut self.forces);
            }
        }
        note_impacts(
            &mut self.pressed,
            &self.forces.contact,
            (n, h),
            &mut self.impacts,
        );
        if !model.contacts.is_empty() {
            let forces = &mut self.forces;
            let work = self
                .impact_work
                .get_or_insert_with(|| ImpactWork::new(model, forces));
            if work.balance(model, &self.cfg, forces, h) {
                self.counters.impact_balances += 1;
            }
        }
        self.watch_solids(n)?;
        let restart = !self.started || n == plan.first;
        let advances = n != plan.first + plan.count;
        if !restart && !row && advances {
            match plan.velocity {
                VelocityRule::Absent => {
                    self.advance_fused(n, plan);
                    return Ok(());
                }
                VelocityRule::Direct(_) => {
                    self.advance_centred(n, plan);
                    return Ok(());
                }
                VelocityRule::Iterated { .. } if plan.turning && self.advance_turning(n, plan) => {
                    return Ok(());
                }
                _ => {}
            }
        }
        let power = if restart {
            self.restart(plan)
        } else {
            let at = at_increment!(self, &plan.held);
            let (work, acc) = (&mut self.velocities, &mut self.acc);
            plan.velocity
                .accelerations(&at, work, acc, &mut self.counters)?
        };
        if n > 0 {
            self.dissipated += 0.5 * h * (self.last_power + power);
        }
        self.v_next.set_plus(&self.v_half, h, &self.acc);
        if row {
            if !plan.velocity.reads_velocity() && !restart {
                self.velocities
                    .v_n
                    .set_plus(&self.v_half, 0.5 * h, &self.acc);
            }
            self.write_row(n, plan)?;
        }
        self.last_power = power;
        if !advances {
            return Ok(());
        }
        model.advance(
            &mut self.cfg,
            &mut self.carry,
            h,
            &self.v_next,
            &plan.held,
            &mut self.counters,
        );
        std::mem::swap(&mut self.v_half, &mut self.v_next);
        std::mem::swap(&mut self.acc_prev, &mut self.acc);
        Ok(())
    }

    /// The rest of increment n where no force reads the velocity and no row falls: the
    /// particles by [`Model::step_particles`] (their half-step velocities updated in place;
    /// along one axis in one pass, their accelerations kept only for the step's last
    /// increment, which the next step restarts from), then the bodies as the general path
    /// takes them.
    fn advance_fused(&mut self, n: u64, plan: &StepPlan<S>) {
        let (model, h, held) = (self.model, self.h, &plan.held);
        let (cfg, carry, acc) = (&mut self.cfg, &mut self.carry, &mut self.acc);
        let (forces, v_half) = (&mut self.forces, &mut self.v_half);
        let last = n + 1 == plan.first + plan.count;
        if last {
            model.step_particles::<true>(cfg, carry, h, forces, held, v_half, acc);
        } else {
            model.step_particles::<false>(cfg, carry, h, forces, held, v_half, acc);
        }
        if !model.bodies.is_empty() {
            let counters = &mut self.counters;
            model.body_accelerations(cfg, forces, v_half, held, acc, counters);
            self.move_bodies(held);
        }
        if n > 0 {
            self.dissipated += 0.5 * h * self.last_power;
        }
        self.last_power = 0.0;
        self.keep_accelerations(last);
    }

    /// After an increment of [`TimeLoop::advance_fused`] or [`TimeLoop::advance_centred`],
    /// whose accelerations (in `acc`) are a(n−1) only to the next step's restart, which
    /// follows the step's `last` increment: their rules ([`VelocityRule::Absent`],
    /// [`VelocityRule::Direct`]) hold for the whole step and read no a(n−1). Kept there,
    /// where they are whole, as the general path keeps them at every increment. Exchanging the
    /// two sets costs an increment of a small scene about 20 instructions.
    fn keep_accelerations(&mut self, last: bool) {
        if last {
            std::mem::swap(&mut self.acc_prev, &mut self.acc);
        }
    }

    /// The rest of increment n where no dashpot acts, the bodies' forces read their rates and
    /// no row falls, where the bodies' centred rates are in closed form
    /// ([`bodies_in_closed_form`]): the bodies' accelerations, then the particles, whose
    /// forces do not read the velocity, by [`Model::step_particles`] (their accelerations kept:
    /// the next increment's iteration, where the closed form does not apply, starts from
    /// them), then the bodies as the general path takes them. The arithmetic of the general
    /// path, bit for bit. False, with nothing done, where the closed form does not apply.
    fn advance_turning(&mut self, n: u64, plan: &StepPlan<S>) -> bool {
        let (model, h, held) = (self.model, self.h, &plan.held);
        let at = at_increment!(self, held);
        let (work, acc) = (&mut self.velocities, &mut self.acc);
        if !bodies_in_closed_form(&at, work, acc, &mut self.counters) {
            return false;
        }
        let (cfg, carry, acc) = (&mut self.cfg, &mut self.carry, &mut self.acc);
        let (forces, v_half) = (&mut self.forces, &mut self.v_half);
        model.step_particles::<true>(cfg, carry, h, forces, held, v_half, acc);
        self.move_bodies(held);
        if n > 0 {
            self.dissipated += 0.5 * h * self.last_power;
        }
        self.last_power = 0.0;
        std::mem::swap(&mut self.acc_prev, &mut self.acc);
        true
    }

    /// The bodies' half-step velocities and configuration from the accelerations in `acc`, as
    /// the general path forms them ([`Model::step_bodies`]; nothing to do in a scene without
    /// bodies).
    #[inline(always)]
    fn move_bodies(&mut self, held: &Constraints<S>) {
        let (model, h) = (self.model, self.h);
        if model.bodies.is_empty() {
            return;
        }
        let state = (&mut self.cfg, &mut self.carry);
        let (v_half, acc) = (&mut self.v_half, &self.acc);
        model.step_bodies(state, h, v_half, acc, held, &mut self.counters);
    }

    /// The rest of increment n where the dashpots' rates are solved directly
    /// ([`VelocityRule::Direct`]) and no row falls: the accelerations at the centred velocity
    /// (the velocity itself is not formed), then the particles by [`Model::move_particles`]
    /// and the bodies as the general path takes them. The arithmetic of the general path,
    /// bit for bit.
    fn advance_centred(&mut self, n: u64, plan: &mut StepPlan<S>) {
        let (model, h) = (self.model, self.h);
        let VelocityRule::Direct(dashpots) = &mut plan.velocity else {
            unreachable!("called for a step whose dashpots are solved directly")
        };
        let at = at_increment!(self, &plan.held);
        let power = dashpots.accelerations(&at, &mut self.acc, &mut self.counters);
        if n > 0 {
            self.dissipated += 0.5 * h * (self.last_power + power);
        }
        self.last_power = power;
        let (held, cfg, carry, acc) = (&plan.held, &mut self.cfg, &mut self.carry, &self.acc);
        model.move_particles(cfg, carry, h, held, &mut self.v_half, acc);
        self.move_bodies(held);
        self.keep_accelerations(n + 1 == plan.first + plan.count);
    }

    /// At t = 0 and at every step boundary v(n) is known (at a boundary: the previous step
    /// completed, v(n−½) + (h/2)·a(n−1), then the new constraints applied), so the half-step
    /// sequence restarts: v(n+½) = v(n) + (h/2)·a(n). Kicking a released DOF by a full h·a(n)
    /// instead would make the scheme first order. Returns the dashpots' power at v(n).
    fn restart(&mut self, plan: &StepPlan<S>) -> f64 {
        let (model, h) = (self.model, self.h);
        let vel = &mut self.velocities.v_n;
        if self.started {
            *vel = self.v_half.plus(0.5 * h, &self.acc_prev);
            model.enforce(vel, &plan.held);
        }
        let mut total = self.forces.clone();
        let mut power = 0.0;
        if model.has_dashpots() {
            model.damping(&self.cfg, vel, &mut total, &mut self.counters);
            power = total.dissipation;
        }
        model.accelerations(
            &self.cfg,
            &total,
            vel,
            &plan.held,
            &mut self.acc,
            &mut self.counters,
        );
        self.v_half = vel.plus(-0.5 * h, &self.acc);
        self.started = true;
        power
    }

    /// Refuse a run whose contact node went through its solid since the last increment.
    fn watch_solids(&mut self, n: u64) -> Result<(), EngineError> {
        let model = self.model;
        if !self.solids {
            return Ok(());
        }
        model.solid_positions(&self.cfg, &mut self.solid_now);
        if !self.solid_before.is_empty()
            && let Some((k, moved)) = model.through_solid(&self.solid_before, &self.solid_now)
        {
            let h = self.h;
            return Err(through_solid(self.scene, k, moved / h, h, n as f64 * h));
        }
        std::mem::swap(&mut self.solid_before, &mut self.solid_now);
        Ok(())
    }

    /// The row of increment n: the probes and the energies; the run refused as unstable where
    /// the state is not finite or the energy grew past what it may hold.
    fn write_row(&mut self, n: u64, plan: &StepPlan<S>) -> Result<(), EngineError> {
        let model = self.model;
        let v_n = &self.velocities.v_n;
        let kinetic = model.kinetic_energy(&self.cfg, v_n);
        if n == 0 {
            self.energy0 = kinetic + self.forces.elastic;
        }
        let mut work = model.external_work(&self.cfg, &self.cfg_start);
        if let Some(ramped) = &self.ramped {
            work += ramped.work;
        }
        let time = if self.sampler.on_steps {
            let times = &self.sampler.times;
            times[((n / plan.stride) as usize).min(times.len() - 1)]
        } else {
            n as f64 * self.h
        };
        let mut row = Vec::with_capacity(self.columns.len());
        row.push(time);
        for (ci, c) in self.scene.columns.iter().enumerate() {
            let value = self.probe(&c.probe, ci);
            row.push(value);
        }
        let elastic = self.forces.elastic;
        let mut balance = kinetic + elastic + self.dissipated - work - self.energy0;
        row.extend([kinetic, elastic, self.dissipated]);
        if let Some(sticks) = &self.sticks {
            balance += sticks.dissipated;
            row.push(sticks.dissipated);
        }
        row.extend([work, balance]);
        self.check_growth(&row, kinetic + elastic, work, plan)?;
        self.sampler.push(row, &mut self.rows);
        Ok(())
    }

    /// One probe's value at the current increment (column `ci`).
    fn probe(&mut self, probe: &Probe, ci: usize) -> f64 {
        let (model, cfg) = (self.model, &self.cfg);
        match probe {
            Probe::Displacement { node, direction } => {
                S::v(direction).dot(&model.displacement(cfg, &model.points[*node]))
            }
            Probe::Velocity { node, direction } => {
                let v = &self.velocities.v_n;
                S::v(direction).dot(&model.velocity(cfg, v, &model.points[*node]))
            }
            Probe::Rotation { body, axis } => {
                let raw = model.rotation_about(cfg, *body, &S::w(axis));
                let turns = ((self.previous_rotation[ci] - raw) / std::f64::consts::TAU).round();
                let unwrapped = raw + turns * std::f64::consts::TAU;
                self.previous_rotation[ci] = unwrapped;
                unwrapped
            }
            Probe::ContactForce { contact } => self.forces.contact[*contact],
            Probe::Gap { contact } => model.gap(cfg, *contact).0,
            Probe::Zero { .. } => 0.0,
        }
    }

    /// Refuse the run as unstable where `row` is not finite, where the modes past their limit
    /// grew (a stability study), or where the kinetic plus elastic `energy` exceeds
    /// [`ENERGY_GUARD`] times what the run may hold: its initial energy plus the loads' `work`
    /// (dissipation only removes energy).
    fn check_growth(
        &mut self,
        row: &[f64],
        energy: f64,
        work: f64,
        plan: &StepPlan<S>,
    ) -> Result<(), EngineError> {
        if row.iter().any(|x| !x.is_finite()) {
            return Err(self.unstable("the state became non-finite", row[0], plan));
        }
        let budget = self.energy0 + work.abs();
        if let Some(watch) = self.past_limit.as_mut()
            && let Some(growth) = watch.grown(self.model, &self.v_next, 1e-12 * budget)
        {
            let what = format!(
                "the modes past their stability limit grew {growth:.3e}-fold in kinetic energy (over {PAST_LIMIT_GROWTH}×)"
            );
            return Err(self.unstable(&what, row[0], plan));
        }
        let ratio = self.stable.map_or(f64::INFINITY, |s| self.h / s.undamped);
        let guard = ENERGY_GUARD * measured_energy_allowance(ratio);
        if energy > guard * budget + f64::MIN_POSITIVE {
            let what = format!(
                "energy grew to {energy:e}, over {guard:.3}× the initial energy plus the work of the loads ({budget:e})"
            );
            return Err(self.unstable(&what, row[0], plan));
        }
        Ok(())
    }

    /// The refusal of an unstable run at time `t`, naming the growing mode where the scene's
    /// modes are computed.
    fn unstable(&self, what: &str, t: f64, plan: &StepPlan<S>) -> EngineError {
        let h = self.h;
        let limit = self.stable.map_or("none computed".to_string(), |s| {
            format!("{:e}, ratio {:.4}", s.increment, h / s.increment)
        });
        let dofs = self.model.free_dof_count(&plan.held);
        let mode = if self.v_next.is_finite() && dofs <= DENSE_LIMIT {
            let treatment = self.settings.damping;
            growing_mode(
                self.model,
                self.scene,
                &self.cfg_start,
                &plan.held,
                &self.v_next,
                h,
                treatment,
            )
            .map(|m| match self.impacts.last() {
                // Below the mode's limit nothing grows: an impact put the energy in.
                Some(&at) if h < m.limit => format!("; {}", m.describe_impact(h, at)),
                _ => format!("; {}", m.describe(h)),
            })
            .unwrap_or_default()
        } else {
            String::new()
        };
        EngineError::Unstable(format!(
            "{what} by t = {t:e}: the run is unstable at increment {h:e} (stable increment: {limit}){mode}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::next_multiple;

    /// The counted-forward row increment is the one a division finds: the first n' ≥ n with
    /// `n'.is_multiple_of(stride)`, for every stride a plan can take (0 included).
    #[test]
    fn next_row_is_the_next_multiple_of_the_stride() {
        for stride in 0..8u64 {
            for n in 0..40u64 {
                let divided = (n..n + 8).find(|m| m.is_multiple_of(stride));
                assert_eq!(
                    next_multiple(n, stride),
                    divided.unwrap_or(u64::MAX),
                    "n = {n}, stride = {stride}"
                );
            }
        }
        // No multiple of 2 at or after u64::MAX: none is left.
        assert_eq!(next_multiple(u64::MAX, 2), u64::MAX);
    }
}
