//! Build and step a rapier world from a [`Plan`]: [`simulate`], written once over the
//! [`World`] trait, which each rapier crate implements ([`super::world`]: 2D and 3D, f32 and
//! f64, 0.34, 0.35 and 0.36).
//!
//! Per step: every dynamic body's user forces are reset and each point load is added at its
//! material point's current world position (constant direction, so the load moves with the
//! body); the world steps; the state of every body and the normal impulse of every contact pair
//! are read back in f64, and on a scene with friction each pair's friction impulses with their
//! points. The collision detection runs once before the first step so that the
//! contact pairs exist from it on. Between dynamic steps the step's ground joints are replaced and the
//! velocity components it holds are zeroed.

use super::MatchedSettings;
use super::plan::{BodyKind, BodySpec, BodyState, ColliderSpec, JointSpec, Plan, StepSpec};
use crate::engines::EngineError;
use nalgebra::Vector3;

/// rapier's default `num_solver_iterations` (substeps).
pub const DEFAULT_SOLVER_ITERATIONS: usize = 4;
/// rapier's default `num_internal_pgs_iterations`.
pub const DEFAULT_PGS_ITERATIONS: usize = 1;

/// How to run.
#[derive(Debug, Clone, Copy)]
pub struct Run {
    /// Time increment.
    pub dt: f64,
    /// Matched settings, or `None` for rapier's defaults.
    pub matched: Option<MatchedSettings>,
    /// Continuous collision detection on the particles (rapier's CCD; off in both
    /// configurations, on for the tunnelling study).
    pub ccd: bool,
    /// A contact softness (Hz, damping ratio 1, for contacts with dynamic and fixed bodies
    /// alike) in place of rapier's default one, for the default configuration's control
    /// experiment (`None`: rapier's own).
    pub default_softness: Option<f64>,
    /// Step by a length of 0 before the contact pairs are registered, as on 0.34, where it is
    /// needed (a control experiment on the other releases; see [`World::ZERO_STEP_ALWAYS`]).
    pub zero_step_first: bool,
    /// What the reported contact impulses are multiplied by (1, or a control experiment's
    /// reading of them).
    pub impulse_scale: f64,
    /// Gyroscopic forces on every rigid body (`None`: the release's default, off on 0.34 and
    /// on from 0.35; a control experiment sets it).
    pub gyroscopic: Option<bool>,
    /// The scene has friction: each step's friction impulses are read back
    /// ([`World::friction_impulses`]), and in 3D the solver uses its Coulomb friction model,
    /// which writes them back (the default simplified model does not).
    pub friction: bool,
}

/// A friction impulse at one contact point: the step's impulse on the ball's body (world,
/// summed over the substeps; the face's body takes its opposite) and the point where it acts
/// (world, where the step's contact detection put it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionImpulse {
    /// Impulse on the ball's body.
    pub impulse: Vector3<f64>,
    /// Contact point.
    pub at: Vector3<f64>,
}

/// A collider's material: rapier combines each coefficient of a contact's two colliders by
/// their average, so both colliders of a pair carry the pair's own.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Material {
    /// Coefficient of restitution.
    pub restitution: f64,
    /// Coefficient of friction (rapier has one: the pair's μ_k; 0: frictionless).
    pub friction: f64,
}

/// The state after a step (or at the start of a dynamic step).
#[derive(Debug, Clone)]
pub struct Record {
    /// Time.
    pub time: f64,
    /// Per plan body (the ground included).
    pub bodies: Vec<BodyState>,
    /// Per contact pair: normal impulse of the step ending here over its length (`None` at the
    /// start of a dynamic step).
    pub contact_force: Option<Vec<f64>>,
    /// Per contact pair, the friction impulses of the step ending here at its contact points
    /// (`None` at the start of a dynamic step and on a scene without friction).
    pub friction: Option<Vec<Vec<FrictionImpulse>>>,
}

/// What a run was: its size and step count (the states themselves go to the recorder as they
/// are produced; none is kept).
#[derive(Debug, Clone)]
pub struct Trace {
    /// Steps taken.
    pub steps: u64,
    /// Colliders in the world.
    pub colliders: usize,
    /// Joints in the world (the last dynamic step's).
    pub joints: usize,
    /// Bodies in the world (the ground included).
    pub bodies: usize,
}

/// A rapier world, as [`simulate`] uses it: the plan's bodies, colliders and joints by their
/// index in the plan, every quantity in f64 (converted to and from the crate's own precision).
pub trait World: Sized {
    /// A joint in the world.
    type Joint;
    /// Whether the release needs the step of length 0 before its contact pairs are registered
    /// (0.34; a control experiment on the others: [`Run::zero_step_first`]).
    const ZERO_STEP_ALWAYS: bool;
    /// An empty world with the run's integration parameters and no gravity.
    fn new(run: &Run) -> Self;
    /// Add a body (the next index).
    fn insert_body(&mut self, body: &BodySpec, run: &Run);
    /// Add a collider on its body (the next index), with its material and its collision group
    /// (a bit mask: it touches only colliders of the same group).
    fn insert_collider(
        &mut self,
        collider: &ColliderSpec,
        material: Material,
        group: u32,
    ) -> Result<(), EngineError>;
    /// Every body's linear and angular velocity, in order.
    fn velocities(&self) -> Vec<(Vector3<f64>, Vector3<f64>)>;
    /// Step by a length of 0 with no collider in any group (which zeroes the velocities).
    fn zero_step(&mut self);
    /// Register the contact pairs (the broad and narrow phases, without a step).
    fn detect(&mut self);
    /// Add a joint between its bodies.
    fn insert_joint(&mut self, spec: &JointSpec) -> Result<Self::Joint, EngineError>;
    /// Remove a joint.
    fn remove_joint(&mut self, joint: Self::Joint);
    /// Body `b`'s state.
    fn state(&self, b: usize) -> BodyState;
    /// Set body `b`'s velocity (and its angular velocity where given).
    fn set_velocity(&mut self, b: usize, linvel: &Vector3<f64>, angvel: Option<&Vector3<f64>>);
    /// Make body `b` fixed (which zeroes its velocity).
    fn set_fixed(&mut self, b: usize);
    /// Make body `b` dynamic with these world axes locked (translations x, y, z, rotations x, y,
    /// z), every rotation where `rotations_locked`.
    fn set_dynamic(&mut self, b: usize, rotations_locked: bool, locks: &[bool; 6]);
    /// The length of the next step.
    fn set_increment(&mut self, h: f64);
    /// Clear body `b`'s user force and torque.
    fn clear_forces(&mut self, b: usize);
    /// Add a force at a world point of body `b`.
    fn add_force_at_point(&mut self, b: usize, force: &Vector3<f64>, at: &Vector3<f64>);
    /// One step.
    fn step(&mut self);
    /// The normal impulse of the last step between colliders `a` and `b` (0 without a pair).
    fn contact_impulse(&self, a: usize, b: usize) -> f64;
    /// The friction impulses of the last step between colliders `a` and `b`, one per contact
    /// point of the pair, on `a`'s body (none without a pair).
    fn friction_impulses(&self, a: usize, b: usize) -> Vec<FrictionImpulse>;
    /// Whether the solver quarantined a body (0.35 on; never on 0.34).
    fn quarantined(&self) -> bool;
    /// Colliders, joints and bodies in the world.
    fn counts(&self) -> (usize, usize, usize);
}

/// Build the world and step it through every dynamic step, handing each state to `record` as
/// it is produced (in time order; a step boundary comes twice: the end of one step, then the
/// start of the next).
pub fn simulate<W: World>(
    plan: &Plan,
    run: &Run,
    record: &mut dyn FnMut(Record) -> Result<(), EngineError>,
) -> Result<Trace, EngineError> {
    let mut world = build::<W>(plan, run)?;
    let mut step_joints: Vec<W::Joint> = Vec::new();
    let mut steps = 0u64;
    let mut t0 = 0.0;
    for step in &plan.steps {
        for j in step_joints.drain(..) {
            world.remove_joint(j);
        }
        for j in &step.joints {
            // Held again after a step that left it free: held where it is.
            let joint = if j.refit.iter().any(|&r| r) {
                world.insert_joint(&j.fitted(&world.state(j.body2)))?
            } else {
                world.insert_joint(j)?
            };
            step_joints.push(joint);
        }
        hold(&mut world, plan, step);
        record(Record {
            time: t0,
            bodies: read(&world, plan),
            contact_force: None,
            friction: None,
        })?;
        steps += run_step(&mut world, plan, run, (step, t0), steps, record)?;
        t0 += step.duration;
    }
    let (colliders, joints, bodies) = world.counts();
    Ok(Trace {
        steps,
        colliders,
        joints,
        bodies,
    })
}

/// The world of `plan`: its bodies, its colliders (each with its pair's restitution and
/// group), its permanent joints, and its contact pairs registered before the first step
/// (otherwise rapier only finds a new pair during step 1, and that step has no contact
/// constraint).
fn build<W: World>(plan: &Plan, run: &Run) -> Result<W, EngineError> {
    let mut world = W::new(run);
    for b in &plan.bodies {
        world.insert_body(b, run);
    }
    // Each collider takes its pair's restitution and friction (rapier averages each over the
    // two colliders: the pair's own), and its pair's collision group: a pair's ball touches
    // only its own slab or solid (two pairs on one node would otherwise each push the node off
    // both surfaces; pairs 32 apart share a group).
    let mut materials = vec![Material::default(); plan.colliders.len()];
    let mut groups = vec![0u32; plan.colliders.len()];
    for (k, c) in plan.contacts.iter().enumerate() {
        let material = Material {
            restitution: c.restitution,
            friction: c.friction,
        };
        materials[c.ball] = material;
        materials[c.slab] = material;
        let group = 1 << (k % 32);
        groups[c.ball] = group;
        groups[c.slab] = group;
    }
    for (i, c) in plan.colliders.iter().enumerate() {
        world.insert_collider(c, materials[i], groups[i])?;
    }
    let velocities = if W::ZERO_STEP_ALWAYS || run.zero_step_first {
        let velocities = world.velocities();
        world.zero_step();
        velocities
    } else {
        Vec::new()
    };
    for j in &plan.permanent {
        world.insert_joint(j)?;
    }
    world.detect();
    for (b, (v, w)) in velocities.iter().enumerate() {
        world.set_velocity(b, v, Some(w));
    }
    Ok(world)
}

/// At the start of a dynamic step: a body the step holds in every DOF is fixed for its
/// duration (which zeroes its velocity); the others are dynamic, with what the step holds
/// zeroed.
fn hold<W: World>(world: &mut W, plan: &Plan, step: &StepSpec) {
    for (b, spec) in plan.bodies.iter().enumerate() {
        if spec.kind == BodyKind::Ground {
            continue;
        }
        if step.fixed[b] {
            world.set_fixed(b);
            continue;
        }
        world.set_dynamic(b, spec.kind == BodyKind::Particle, &step.locks[b]);
        let mut s = world.state(b);
        s.hold(&spec.com, &step.held, b);
        let rotates = spec.kind == BodyKind::Rigid;
        world.set_velocity(b, &s.linvel, rotates.then_some(&s.angvel));
    }
}

/// Every body's state.
fn read<W: World>(world: &W, plan: &Plan) -> Vec<BodyState> {
    (0..plan.bodies.len()).map(|b| world.state(b)).collect()
}

/// The increments of one dynamic step (`step` from `t0`; `done` taken before it), each state
/// recorded: the loads applied at their points' current positions, the world stepped, the
/// contact impulses read as forces, and a non-finite state (or a quarantine) refused. The
/// increments it took.
fn run_step<W: World>(
    world: &mut W,
    plan: &Plan,
    run: &Run,
    (step, t0): (&StepSpec, f64),
    done: u64,
    record: &mut dyn FnMut(Record) -> Result<(), EngineError>,
) -> Result<u64, EngineError> {
    let dt = run.dt;
    let n = ((step.duration / dt) - 1e-9).ceil().max(1.0) as u64;
    // A look at the interruption flag every few milliseconds of work: every 1024 steps, or
    // sooner as the bodies grow past 16.
    let stride = (16_384 / plan.bodies.len().max(1) as u64).clamp(1, 1024);
    for k in 1..=n {
        let (h, t) = if k == n {
            (step.duration - (n - 1) as f64 * dt, t0 + step.duration)
        } else {
            (dt, t0 + k as f64 * dt)
        };
        world.set_increment(h);
        for (b, spec) in plan.bodies.iter().enumerate() {
            if spec.kind != BodyKind::Ground {
                world.clear_forces(b);
            }
        }
        for l in &plan.loads {
            let at = world.state(l.body).point(&l.local);
            // A load that varies in time at the step's middle: the step's impulse, exact for
            // an amplitude linear over the step.
            let force = match &l.amplitude {
                Some(a) => l.force * a.at(t - 0.5 * h),
                None => l.force,
            };
            world.add_force_at_point(l.body, &force, &at);
        }
        world.step();
        let steps = done + k;
        if steps.is_multiple_of(stride) && crate::interrupt::requested() {
            return Err(EngineError::Failed(format!("interrupted at step {steps}")));
        }
        let bodies = read(world, plan);
        let forces: Vec<f64> = plan
            .contacts
            .iter()
            .map(|c| world.contact_impulse(c.ball, c.slab) * run.impulse_scale / h)
            .collect();
        let finite = bodies.iter().all(|s| {
            s.position.iter().all(|x| x.is_finite())
                && s.linvel.iter().all(|x| x.is_finite())
                && s.angvel.iter().all(|x| x.is_finite())
        }) && forces.iter().all(|f| f.is_finite());
        if !finite || world.quarantined() {
            return Err(EngineError::Unstable(format!(
                "rapier: the state became non-finite by t = {t:e} (dt = {dt:e})"
            )));
        }
        let friction = run.friction.then(|| {
            (plan.contacts.iter())
                .map(|c| world.friction_impulses(c.ball, c.slab))
                .collect()
        });
        record(Record {
            time: t,
            bodies,
            contact_force: Some(forces),
            friction,
        })?;
    }
    Ok(n)
}
