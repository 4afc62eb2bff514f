//! Build and step a rapier world from a [`Plan`](super::plan::Plan): written once as a macro, instantiated for
//! `rapier2d`, `rapier2d-f64`, `rapier3d` and `rapier3d-f64` 0.36, and with the
//! `rapier-versions` feature for `rapier2d-f64` and `rapier3d-f64` 0.34 and 0.35; what differs
//! between the releases is in `release_helpers!`.
//!
//! Per step: every dynamic body's user forces are reset and each point load is added at its
//! material point's current world position (constant direction, so the load moves with the
//! body); the world steps; the state of every body and the normal impulse of every contact pair
//! are read back in f64. The collision detection runs once before the first step so that the
//! contact pairs exist from it on. Between dynamic steps the step's ground joints are replaced and the
//! velocity components it holds are zeroed.

use super::MatchedSettings;
use super::plan::BodyState;

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
    /// needed (a control experiment on the other releases; see [`release_helpers`]).
    pub zero_step_first: bool,
    /// What the reported contact impulses are multiplied by (1, or a control experiment's
    /// reading of them).
    pub impulse_scale: f64,
    /// Gyroscopic forces on every rigid body (`None`: the release's default, off on 0.34 and
    /// on from 0.35; a control experiment sets it).
    pub gyroscopic: Option<bool>,
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

macro_rules! dimension_helpers {
    (2) => {
        fn vector(v: &Vector3<f64>) -> rp::math::Vector {
            rp::math::Vector::new(v.x as Real, v.y as Real)
        }
        fn unvector(v: rp::math::Vector) -> Vector3<f64> {
            Vector3::new(v.x as f64, v.y as f64, 0.0)
        }
        fn angular(w: &Vector3<f64>) -> rp::math::AngVector {
            w.z as Real
        }
        fn unangular(w: rp::math::AngVector) -> Vector3<f64> {
            Vector3::new(0.0, 0.0, w as f64)
        }
        fn rotation(q: &UnitQuaternion<f64>) -> rp::math::Rotation {
            rp::math::Rotation::new((2.0 * q.k.atan2(q.w)) as Real)
        }
        fn unrotation(r: &rp::math::Rotation) -> UnitQuaternion<f64> {
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), r.angle() as f64)
        }
        fn axis(i: usize) -> Result<(JointAxesMask, JointAxis), EngineError> {
            Ok(match i {
                0 => (JointAxesMask::LIN_X, JointAxis::LinX),
                1 => (JointAxesMask::LIN_Y, JointAxis::LinY),
                5 => (JointAxesMask::ANG_X, JointAxis::AngX),
                _ => {
                    return Err(EngineError::Unsupported(format!(
                        "rapier: joint axis {i} does not exist in 2D"
                    )));
                }
            })
        }
        fn cuboid(half: &Vector3<f64>) -> ColliderBuilder {
            ColliderBuilder::cuboid(half.x as Real, half.y as Real)
        }
        /// A plane body has no gyroscopic torque.
        fn gyroscopic(b: RigidBodyBuilder, _: Option<bool>) -> RigidBodyBuilder {
            b
        }
        fn mass_properties(
            com: &Vector3<f64>,
            mass: f64,
            inertia: &nalgebra::Matrix3<f64>,
        ) -> MassProperties {
            MassProperties::new(vector(com), mass as Real, inertia[(2, 2)] as Real)
        }
    };
    (3) => {
        fn vector(v: &Vector3<f64>) -> rp::math::Vector {
            rp::math::Vector::new(v.x as Real, v.y as Real, v.z as Real)
        }
        fn unvector(v: rp::math::Vector) -> Vector3<f64> {
            Vector3::new(v.x as f64, v.y as f64, v.z as f64)
        }
        fn angular(w: &Vector3<f64>) -> rp::math::AngVector {
            vector(w)
        }
        fn unangular(w: rp::math::AngVector) -> Vector3<f64> {
            unvector(w)
        }
        fn rotation(q: &UnitQuaternion<f64>) -> rp::math::Rotation {
            rp::math::Rotation::from_xyzw(q.i as Real, q.j as Real, q.k as Real, q.w as Real)
                .normalize()
        }
        fn unrotation(r: &rp::math::Rotation) -> UnitQuaternion<f64> {
            UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
                r.w as f64, r.x as f64, r.y as f64, r.z as f64,
            ))
        }
        fn axis(i: usize) -> Result<(JointAxesMask, JointAxis), EngineError> {
            Ok(match i {
                0 => (JointAxesMask::LIN_X, JointAxis::LinX),
                1 => (JointAxesMask::LIN_Y, JointAxis::LinY),
                2 => (JointAxesMask::LIN_Z, JointAxis::LinZ),
                3 => (JointAxesMask::ANG_X, JointAxis::AngX),
                4 => (JointAxesMask::ANG_Y, JointAxis::AngY),
                5 => (JointAxesMask::ANG_Z, JointAxis::AngZ),
                _ => unreachable!("joint axes are 0..6"),
            })
        }
        fn cuboid(half: &Vector3<f64>) -> ColliderBuilder {
            ColliderBuilder::cuboid(half.x as Real, half.y as Real, half.z as Real)
        }
        /// Gyroscopic forces as `on` says (`None`: the release's default).
        fn gyroscopic(b: RigidBodyBuilder, on: Option<bool>) -> RigidBodyBuilder {
            match on {
                Some(on) => b.gyroscopic_forces_enabled(on),
                None => b,
            }
        }
        fn mass_properties(
            com: &Vector3<f64>,
            mass: f64,
            inertia: &nalgebra::Matrix3<f64>,
        ) -> MassProperties {
            let column = |j: usize| {
                vector(&Vector3::new(
                    inertia[(0, j)],
                    inertia[(1, j)],
                    inertia[(2, j)],
                ))
            };
            MassProperties::with_inertia_matrix(
                vector(com),
                mass as Real,
                rp::math::Matrix::from_cols(column(0), column(1), column(2)),
            )
        }
    };
}

/// What differs between the rapier releases the backend is built on.
///
/// - 0.36 (`current`) registers the contact pairs before the first step with
///   `PhysicsWorld::detect_collisions` and reports a quarantine.
/// - 0.35 has no `detect_collisions`: its `CollisionPipeline` registers the pairs (the same
///   broad and narrow phases).
/// - 0.34 has no quarantine (a non-finite state is caught by the finiteness check alone), no
///   `static_contact_softness` (one softness for every contact; the matched
///   configuration sets both to one value anyway) and no contact recycling (the matched
///   configuration turns it off). Its `CollisionPipeline` takes the bodies' pending changes
///   without clearing their marks, so a body that is not yet in an island never gets one (and
///   the pipeline asserts it has one): [`before_joints`] first steps the world by a length of
///   0 with every collider's groups emptied, which puts each body in an island and touches
///   nothing else, the velocities (that step zeroes them) restored after the detection. On 0.35
///   and 0.36 the same construct ([`Run::zero_step_first`]) gives bit-identical histories
///   (`tests/versions.rs`).
macro_rules! release_helpers {
    (current) => {
        release_helpers!(static_softness);
        fn detect(world: &mut PhysicsWorld) {
            world.detect_collisions(&(), &());
        }
        fn quarantined(world: &PhysicsWorld) -> bool {
            !world.quarantine().is_empty()
        }
        release_helpers!(zero_step_on_request);
    };
    (v0_35) => {
        release_helpers!(static_softness);
        fn quarantined(world: &PhysicsWorld) -> bool {
            !world.quarantine().is_empty()
        }
        release_helpers!(collision_pipeline);
        release_helpers!(zero_step_on_request);
    };
    (v0_34) => {
        fn set_softness(p: &mut IntegrationParameters, softness: SpringCoefficients<Real>) {
            p.contact_softness = softness;
        }
        fn set_recycling(_: &mut IntegrationParameters, _: bool) {}
        fn quarantined(_: &PhysicsWorld) -> bool {
            false
        }
        release_helpers!(collision_pipeline);
        fn before_joints(world: &mut PhysicsWorld, _: &Run) -> Velocities {
            zero_step(world)
        }
    };
    (static_softness) => {
        fn set_softness(p: &mut IntegrationParameters, softness: SpringCoefficients<Real>) {
            p.contact_softness = softness;
            p.static_contact_softness = softness;
        }
        fn set_recycling(p: &mut IntegrationParameters, recycling: bool) {
            p.contact_recycling = recycling;
        }
    };
    (zero_step_on_request) => {
        fn before_joints(world: &mut PhysicsWorld, run: &Run) -> Velocities {
            if run.zero_step_first {
                zero_step(world)
            } else {
                Vec::new()
            }
        }
    };
    (zero_step) => {
        /// Step by a length of 0 with no collider in any group (see [`release_helpers`]);
        /// the velocities to restore after the detection.
        fn zero_step(world: &mut PhysicsWorld) -> Velocities {
            let velocities: Velocities = world
                .bodies
                .iter()
                .map(|(h, b)| (h, b.linvel(), b.angvel()))
                .collect();
            let handles: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
            let groups: Vec<InteractionGroups> = handles
                .iter()
                .map(|h| world.colliders[*h].collision_groups())
                .collect();
            for h in &handles {
                world.colliders[*h].set_collision_groups(InteractionGroups::none());
            }
            let dt = world.integration_parameters.dt;
            world.integration_parameters.dt = 0.0;
            world.step();
            world.integration_parameters.dt = dt;
            for (h, g) in handles.iter().zip(groups) {
                world.colliders[*h].set_collision_groups(g);
            }
            velocities
        }
    };
    (collision_pipeline) => {
        fn detect(world: &mut PhysicsWorld) {
            rp::pipeline::CollisionPipeline::new().step(
                world.integration_parameters.prediction_distance(),
                &mut world.islands,
                &mut world.broad_phase,
                &mut world.narrow_phase,
                &mut world.bodies,
                &mut world.colliders,
                &(),
                &(),
            );
        }
    };
}

macro_rules! backend {
    ($module:ident, $krate:ident, $dim:tt, $release:tt) => {
        /// The backend on one rapier crate.
        pub mod $module {
            use super::{Record, Run, Trace};
            use crate::engines::EngineError;
            use crate::engines::rapier::plan::{
                BodyKind, BodyState, Frame, JointKind, JointSpec, Plan, Shape,
            };
            use nalgebra::{UnitQuaternion, Vector3};
            use rp::dynamics::{
                GenericJoint, GenericJointBuilder, ImpulseJointHandle, IntegrationParameters,
                JointAxesMask, JointAxis, LockedAxes, MassProperties, MotorModel, RigidBodyBuilder,
                RigidBodyHandle, RigidBodyType, SpringCoefficients, SpringJointBuilder,
            };
            use rp::geometry::{
                ColliderBuilder, ColliderHandle, Group, InteractionGroups, InteractionTestMode,
            };
            use rp::math::Real;
            use rp::pipeline::PhysicsWorld;
            use $krate as rp;

            dimension_helpers!($dim);
            release_helpers!($release);
            release_helpers!(zero_step);

            /// Each body's velocities, kept over a step of length 0.
            type Velocities = Vec<(RigidBodyHandle, rp::math::Vector, rp::math::AngVector)>;

            /// rapier's lock of each world axis: translations x, y, z, rotations x, y, z.
            const LOCKS: [LockedAxes; 6] = [
                LockedAxes::TRANSLATION_LOCKED_X,
                LockedAxes::TRANSLATION_LOCKED_Y,
                LockedAxes::TRANSLATION_LOCKED_Z,
                LockedAxes::ROTATION_LOCKED_X,
                LockedAxes::ROTATION_LOCKED_Y,
                LockedAxes::ROTATION_LOCKED_Z,
            ];

            fn pose(frame: &Frame) -> rp::math::Pose {
                rp::math::Pose::from_parts(vector(&frame.origin), rotation(&frame.rotation))
            }

            fn joint(spec: &JointSpec) -> Result<GenericJoint, EngineError> {
                Ok(match &spec.kind {
                    JointKind::Generic { locked, motors } => {
                        let mut mask = JointAxesMask::empty();
                        for (i, _) in locked.iter().enumerate().filter(|(_, l)| **l) {
                            mask |= axis(i)?.0;
                        }
                        let mut b = GenericJointBuilder::new(mask)
                            .local_frame1(pose(&spec.frame1))
                            .local_frame2(pose(&spec.frame2));
                        for m in motors {
                            let a = axis(m.axis)?.1;
                            b = b
                                .motor_position(a, 0.0, m.stiffness as Real, m.damping as Real)
                                .motor_model(a, MotorModel::ForceBased);
                        }
                        b.build()
                    }
                    JointKind::Spring {
                        rest,
                        stiffness,
                        damping,
                    } => {
                        SpringJointBuilder::new(*rest as Real, *stiffness as Real, *damping as Real)
                            .spring_model(MotorModel::ForceBased)
                            .local_anchor1(vector(&spec.frame1.origin))
                            .local_anchor2(vector(&spec.frame2.origin))
                            .build()
                            .into()
                    }
                })
            }

            fn state(rb: &rp::dynamics::RigidBody) -> BodyState {
                BodyState {
                    position: unvector(rb.translation()),
                    rotation: unrotation(rb.rotation()),
                    linvel: unvector(rb.linvel()),
                    angvel: unangular(rb.angvel()),
                }
            }

            /// Integration parameters of a run.
            pub fn parameters(run: &Run) -> IntegrationParameters {
                let mut p = IntegrationParameters::default();
                p.dt = run.dt as Real;
                if let Some(m) = run.matched {
                    p.num_solver_iterations = m.solver_iterations;
                    p.num_internal_pgs_iterations = m.pgs_iterations;
                    let softness = SpringCoefficients::new(
                        m.contact_frequency as Real,
                        m.contact_damping_ratio as Real,
                    );
                    set_softness(&mut p, softness);
                    p.normalized_allowed_linear_error = m.allowed_linear_error as Real;
                    p.normalized_prediction_distance = m.prediction_distance as Real;
                    set_recycling(&mut p, m.contact_recycling);
                } else if let Some(hz) = run.default_softness {
                    set_softness(&mut p, SpringCoefficients::new(hz as Real, 1.0));
                }
                p
            }

            /// Build the world and step it through every dynamic step, handing each state to
            /// `record` as it is produced (in time order; a step boundary comes twice: the end
            /// of one step, then the start of the next).
            pub fn simulate(
                plan: &Plan,
                run: &Run,
                record: &mut dyn FnMut(Record) -> Result<(), EngineError>,
            ) -> Result<Trace, EngineError> {
                let mut world = PhysicsWorld::default();
                world.gravity = rp::math::Vector::ZERO;
                world.integration_parameters = parameters(run);

                let handles: Vec<RigidBodyHandle> = plan
                    .bodies
                    .iter()
                    .map(|b| {
                        let at =
                            rp::math::Pose::from_parts(vector(&b.position), rotation(&b.rotation));
                        let builder = match b.kind {
                            BodyKind::Ground => RigidBodyBuilder::fixed().pose(at),
                            BodyKind::Particle => RigidBodyBuilder::dynamic()
                                .pose(at)
                                .lock_rotations()
                                .additional_mass(b.mass as Real)
                                .linvel(vector(&b.linvel))
                                .ccd_enabled(run.ccd)
                                .can_sleep(false),
                            BodyKind::Rigid => {
                                gyroscopic(RigidBodyBuilder::dynamic(), run.gyroscopic)
                                    .pose(at)
                                    .additional_mass_properties(mass_properties(
                                        &b.com, b.mass, &b.inertia,
                                    ))
                                    .linvel(vector(&b.linvel))
                                    .angvel(angular(&b.angvel))
                                    .can_sleep(false)
                            }
                        };
                        world.insert_body(builder)
                    })
                    .collect();

                // Each collider takes its pair's restitution (rapier averages the two), and its
                // pair's collision group: a pair's ball touches only its own slab or solid (two
                // pairs on one node would otherwise each push the node off both surfaces; pairs
                // 32 apart share a group).
                let mut restitution = vec![0.0; plan.colliders.len()];
                let mut groups = vec![Group::NONE; plan.colliders.len()];
                for (k, c) in plan.contacts.iter().enumerate() {
                    restitution[c.ball] = c.restitution;
                    restitution[c.slab] = c.restitution;
                    let group = Group::from_bits_truncate(1 << (k % 32));
                    groups[c.ball] = group;
                    groups[c.slab] = group;
                }
                let colliders: Vec<ColliderHandle> = plan
                    .colliders
                    .iter()
                    .enumerate()
                    .map(|(i, c)| {
                        let builder = match &c.shape {
                            Shape::Ball(r) => ColliderBuilder::ball(*r as Real),
                            Shape::Cuboid(half) => cuboid(half),
                            Shape::Capsule(half_height, r) => {
                                ColliderBuilder::capsule_y(*half_height as Real, *r as Real)
                            }
                            Shape::ConvexHull(corners) => {
                                let points: Vec<_> = corners.iter().map(vector).collect();
                                ColliderBuilder::convex_hull(&points).ok_or_else(|| {
                                    EngineError::Unsupported(
                                        "rapier: no convex hull of the eroded polytope".into(),
                                    )
                                })?
                            }
                        }
                        .position(pose(&c.frame))
                        .density(0.0)
                        .friction(0.0)
                        .restitution(restitution[i] as Real)
                        .collision_groups(InteractionGroups::new(
                            groups[i],
                            groups[i],
                            InteractionTestMode::And,
                        ));
                        Ok(world.colliders.insert_with_parent(
                            builder,
                            handles[c.body],
                            &mut world.bodies,
                        ))
                    })
                    .collect::<Result<_, EngineError>>()?;

                let velocities = before_joints(&mut world, run);
                for j in &plan.permanent {
                    let data = joint(j)?;
                    world
                        .impulse_joints
                        .insert(handles[j.body1], handles[j.body2], data, true);
                }

                // Register the contact pairs before the first step: otherwise rapier only finds
                // a new pair during step 1, and that step has no contact constraint.
                detect(&mut world);
                for (h, v, w) in velocities {
                    let rb = &mut world.bodies[h];
                    rb.set_linvel(v, true);
                    rb.set_angvel(w, true);
                }

                let read = |world: &PhysicsWorld| -> Vec<BodyState> {
                    handles.iter().map(|h| state(&world.bodies[*h])).collect()
                };

                let mut step_joints: Vec<ImpulseJointHandle> = Vec::new();
                let mut steps = 0u64;
                let mut t0 = 0.0;
                let dt = run.dt;
                for step in &plan.steps {
                    for h in step_joints.drain(..) {
                        world.impulse_joints.remove(h, true);
                    }
                    for j in &step.joints {
                        // Held again after a step that left it free: held where it is.
                        let data = if j.refit.iter().any(|&r| r) {
                            joint(&j.fitted(&state(&world.bodies[handles[j.body2]])))?
                        } else {
                            joint(j)?
                        };
                        step_joints.push(world.impulse_joints.insert(
                            handles[j.body1],
                            handles[j.body2],
                            data,
                            true,
                        ));
                    }
                    // A body the step holds in every DOF is fixed for its duration (which
                    // zeroes its velocity); the others are dynamic, with what the step holds
                    // zeroed.
                    for (b, spec) in plan.bodies.iter().enumerate() {
                        if spec.kind == BodyKind::Ground {
                            continue;
                        }
                        let rb = &mut world.bodies[handles[b]];
                        if step.fixed[b] {
                            rb.set_body_type(RigidBodyType::Fixed, true);
                            continue;
                        }
                        rb.set_body_type(RigidBodyType::Dynamic, true);
                        let mut axes = if spec.kind == BodyKind::Particle {
                            LockedAxes::ROTATION_LOCKED
                        } else {
                            LockedAxes::empty()
                        };
                        for (k, flag) in LOCKS.iter().enumerate() {
                            if step.locks[b][k] {
                                axes |= *flag;
                            }
                        }
                        rb.set_locked_axes(axes, true);
                        let mut s = state(rb);
                        s.hold(&spec.com, &step.held, b);
                        rb.set_linvel(vector(&s.linvel), true);
                        if spec.kind == BodyKind::Rigid {
                            rb.set_angvel(angular(&s.angvel), true);
                        }
                    }
                    record(Record {
                        time: t0,
                        bodies: read(&world),
                        contact_force: None,
                    })?;

                    let n = ((step.duration / dt) - 1e-9).ceil().max(1.0) as u64;
                    for k in 1..=n {
                        let (h, t) = if k == n {
                            (step.duration - (n - 1) as f64 * dt, t0 + step.duration)
                        } else {
                            (dt, t0 + k as f64 * dt)
                        };
                        world.integration_parameters.dt = h as Real;
                        for (b, spec) in plan.bodies.iter().enumerate() {
                            if spec.kind != BodyKind::Ground {
                                // `reset_forces` clears the force only: the torque that
                                // `add_force_at_point` adds needs its own reset.
                                let rb = &mut world.bodies[handles[b]];
                                rb.reset_forces(false);
                                rb.reset_torques(false);
                            }
                        }
                        for l in &plan.loads {
                            let rb = &mut world.bodies[handles[l.body]];
                            let at = state(rb).point(&l.local);
                            rb.add_force_at_point(vector(&l.force), vector(&at), false);
                        }
                        world.step();
                        steps += 1;
                        // A look at the interruption flag every few milliseconds of work:
                        // every 1024 steps, or sooner as the bodies grow past 16.
                        let stride = (16_384 / handles.len().max(1) as u64).clamp(1, 1024);
                        if steps % stride == 0 && crate::interrupt::requested() {
                            return Err(EngineError::Failed(format!(
                                "interrupted at step {steps}"
                            )));
                        }
                        let bodies = read(&world);
                        let forces: Vec<f64> = plan
                            .contacts
                            .iter()
                            .map(|c| {
                                world
                                    .narrow_phase
                                    .contact_pair(colliders[c.ball], colliders[c.slab])
                                    .map_or(0.0, |p| p.total_impulse_magnitude() as f64)
                                    * run.impulse_scale
                                    / h
                            })
                            .collect();
                        let finite = bodies.iter().all(|s| {
                            s.position.iter().all(|x| x.is_finite())
                                && s.linvel.iter().all(|x| x.is_finite())
                                && s.angvel.iter().all(|x| x.is_finite())
                        }) && forces.iter().all(|f| f.is_finite());
                        if !finite || quarantined(&world) {
                            return Err(EngineError::Unstable(format!(
                                "rapier: the state became non-finite by t = {t:e} (dt = {dt:e})"
                            )));
                        }
                        record(Record {
                            time: t,
                            bodies,
                            contact_force: Some(forces),
                        })?;
                    }
                    t0 += step.duration;
                }
                Ok(Trace {
                    steps,
                    colliders: world.colliders.len(),
                    joints: world.impulse_joints.len(),
                    bodies: world.bodies.len(),
                })
            }
        }
    };
}

backend!(r2_f32, rapier2d, 2, current);
backend!(r2_f64, rapier2d_f64, 2, current);
backend!(r3_f32, rapier3d, 3, current);
backend!(r3_f64, rapier3d_f64, 3, current);
#[cfg(feature = "rapier-versions")]
backend!(r2_f64_v0_34, rapier2d_f64_v0_34, 2, v0_34);
#[cfg(feature = "rapier-versions")]
backend!(r3_f64_v0_34, rapier3d_f64_v0_34, 3, v0_34);
#[cfg(feature = "rapier-versions")]
backend!(r2_f64_v0_35, rapier2d_f64_v0_35, 2, v0_35);
#[cfg(feature = "rapier-versions")]
backend!(r3_f64_v0_35, rapier3d_f64_v0_35, 3, v0_35);
