//! The [`World`](super::backend::World) trait on each rapier crate: `rapier2d`, `rapier2d-f64`,
//! `rapier3d` and `rapier3d-f64` 0.36, and with the `rapier-versions` feature `rapier2d-f64`
//! and `rapier3d-f64` 0.34 and 0.35. The crates share their API, so one implementation is
//! written once and instantiated for each (`world!`); what differs between dimensions is in
//! `dimension_helpers!`, between releases in `release_helpers!`. Each implementation converts
//! the plan's f64 to the crate's `Real` and back and builds the crate's own objects (bodies,
//! colliders, joints, integration parameters, the release's contact detection); what is done
//! with them, in which order, is [`simulate`](super::backend::simulate), written once.

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
        /// The friction impulse on a manifold's first body (world) from its tangent impulse:
        /// rapier's tangent is `orthonormal_basis` of the force direction −normal.
        fn friction_impulse(
            normal: rp::math::Vector,
            impulse: &TangentImpulse<Real>,
        ) -> Vector3<f64> {
            let [t] = (-normal).orthonormal_basis();
            unvector(t * impulse[0])
        }
        /// One friction model in 2D.
        fn coulomb_friction(_: &mut IntegrationParameters) {}
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
        /// The friction impulse on a manifold's first body (world) from its tangent impulse:
        /// rapier's tangents are t1 = `orthonormal_vector` of the force direction d = −normal
        /// and d × t1 (0.35 and 0.36; 0.34 takes t1 along the slip velocity the solver starts
        /// from where it exceeds 1e-4 m/s, which this basis does not follow).
        fn friction_impulse(
            normal: rp::math::Vector,
            impulse: &TangentImpulse<Real>,
        ) -> Vector3<f64> {
            let d = -normal;
            let t1 = d.orthonormal_vector();
            unvector(t1 * impulse[0] + d.cross(t1) * impulse[1])
        }
        /// The Coulomb friction model: one friction constraint per contact point, whose step
        /// impulse rapier writes back to the point (the default simplified model writes back
        /// only the last substep's, for warm-starting; on a manifold of one point, which every
        /// pair here is, the two models solve the same constraint).
        fn coulomb_friction(p: &mut IntegrationParameters) {
            p.friction_model = rp::dynamics::FrictionModel::Coulomb;
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

/// What differs between the rapier releases a world is built on.
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
///   the pipeline asserts it has one): the world is first stepped by a length of 0 with every
///   collider's groups emptied, which puts each body in an island and touches
///   nothing else, the velocities (that step zeroes them) restored after the detection
///   (`ZERO_STEP_ALWAYS`). On 0.35 and 0.36 the same construct ([`Run::zero_step_first`]) gives
///   bit-identical histories (`tests/versions.rs`).
macro_rules! release_helpers {
    (current) => {
        release_helpers!(static_softness);
        release_helpers!(solver_manifolds);
        fn detect(world: &mut PhysicsWorld) {
            world.detect_collisions(&(), &());
        }
        fn quarantined(world: &PhysicsWorld) -> bool {
            !world.quarantine().is_empty()
        }
        const ZERO_STEP_ALWAYS: bool = false;
    };
    (v0_35) => {
        release_helpers!(static_softness);
        release_helpers!(solver_manifolds);
        fn quarantined(world: &PhysicsWorld) -> bool {
            !world.quarantine().is_empty()
        }
        release_helpers!(collision_pipeline);
        const ZERO_STEP_ALWAYS: bool = false;
    };
    (v0_34) => {
        fn set_softness(p: &mut IntegrationParameters, softness: SpringCoefficients<Real>) {
            p.contact_softness = softness;
        }
        fn set_recycling(_: &mut IntegrationParameters, _: bool) {}
        fn quarantined(_: &PhysicsWorld) -> bool {
            false
        }
        fn solver_manifolds(pair: &ContactPair) -> &[ContactManifold] {
            &pair.manifolds
        }
        release_helpers!(collision_pipeline);
        const ZERO_STEP_ALWAYS: bool = true;
    };
    (solver_manifolds) => {
        /// The manifolds the solver wrote its impulses to.
        fn solver_manifolds(pair: &ContactPair) -> &[ContactManifold] {
            pair.solver_manifolds()
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
    (zero_step) => {
        /// Step by a length of 0 with no collider in any group (see [`release_helpers`]).
        fn zero_step(world: &mut PhysicsWorld) {
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

macro_rules! world {
    ($name:ident, $module:ident, $krate:ident, $dim:tt, $release:tt) => {
        pub use $module::World as $name;

        /// A world of one rapier crate.
        mod $module {
            use crate::engines::EngineError;
            use crate::engines::rapier::backend::FrictionImpulse;
            use crate::engines::rapier::backend::{Material, Run};
            use crate::engines::rapier::plan::{
                BodyKind, BodySpec, BodyState, ColliderSpec, Frame, JointKind, JointSpec, Shape,
            };
            use nalgebra::{UnitQuaternion, Vector3};
            use rp::dynamics::{
                CoefficientCombineRule, GenericJoint, GenericJointBuilder, ImpulseJointHandle,
                IntegrationParameters, JointAxesMask, JointAxis, LockedAxes, MassProperties,
                MotorModel, RigidBodyBuilder, RigidBodyHandle, RigidBodyType, SpringCoefficients,
                SpringJointBuilder,
            };
            use rp::geometry::{
                ColliderBuilder, ColliderHandle, ContactManifold, ContactPair, Group,
                InteractionGroups, InteractionTestMode,
            };
            use rp::math::{Real, TangentImpulse};
            use rp::pipeline::PhysicsWorld;
            use rp::utils::OrthonormalBasis;
            use $krate as rp;

            dimension_helpers!($dim);
            release_helpers!($release);
            release_helpers!(zero_step);

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

            /// Integration parameters of a run.
            fn parameters(run: &Run) -> IntegrationParameters {
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
                if run.friction {
                    coulomb_friction(&mut p);
                }
                p
            }

            /// A rapier world, its bodies and colliders in the plan's order.
            pub struct World {
                world: PhysicsWorld,
                bodies: Vec<RigidBodyHandle>,
                colliders: Vec<ColliderHandle>,
            }

            impl super::super::backend::World for World {
                type Joint = ImpulseJointHandle;
                const ZERO_STEP_ALWAYS: bool = ZERO_STEP_ALWAYS;

                fn new(run: &Run) -> Self {
                    let mut world = PhysicsWorld::default();
                    world.gravity = rp::math::Vector::ZERO;
                    world.integration_parameters = parameters(run);
                    World {
                        world,
                        bodies: Vec::new(),
                        colliders: Vec::new(),
                    }
                }

                fn insert_body(&mut self, b: &BodySpec, run: &Run) {
                    let at = rp::math::Pose::from_parts(vector(&b.position), rotation(&b.rotation));
                    let builder = match b.kind {
                        BodyKind::Ground => RigidBodyBuilder::fixed().pose(at),
                        BodyKind::Particle => RigidBodyBuilder::dynamic()
                            .pose(at)
                            .lock_rotations()
                            .additional_mass(b.mass as Real)
                            .linvel(vector(&b.linvel))
                            .ccd_enabled(run.ccd)
                            .can_sleep(false),
                        BodyKind::Rigid => gyroscopic(RigidBodyBuilder::dynamic(), run.gyroscopic)
                            .pose(at)
                            .additional_mass_properties(mass_properties(&b.com, b.mass, &b.inertia))
                            .linvel(vector(&b.linvel))
                            .angvel(angular(&b.angvel))
                            .can_sleep(false),
                    };
                    self.bodies.push(self.world.insert_body(builder));
                }

                fn insert_collider(
                    &mut self,
                    c: &ColliderSpec,
                    material: Material,
                    group: u32,
                ) -> Result<(), EngineError> {
                    let group = Group::from_bits_truncate(group);
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
                    .friction(material.friction as Real)
                    .friction_combine_rule(CoefficientCombineRule::Average)
                    .restitution(material.restitution as Real)
                    .collision_groups(InteractionGroups::new(
                        group,
                        group,
                        InteractionTestMode::And,
                    ));
                    let world = &mut self.world;
                    let parent = self.bodies[c.body];
                    let handle =
                        world
                            .colliders
                            .insert_with_parent(builder, parent, &mut world.bodies);
                    self.colliders.push(handle);
                    Ok(())
                }

                fn velocities(&self) -> Vec<(Vector3<f64>, Vector3<f64>)> {
                    let bodies = self.bodies.iter().map(|h| &self.world.bodies[*h]);
                    bodies
                        .map(|b| (unvector(b.linvel()), unangular(b.angvel())))
                        .collect()
                }

                fn zero_step(&mut self) {
                    zero_step(&mut self.world);
                }

                fn detect(&mut self) {
                    detect(&mut self.world);
                }

                fn insert_joint(&mut self, spec: &JointSpec) -> Result<Self::Joint, EngineError> {
                    let data = joint(spec)?;
                    let (a, b) = (self.bodies[spec.body1], self.bodies[spec.body2]);
                    Ok(self.world.impulse_joints.insert(a, b, data, true))
                }

                fn remove_joint(&mut self, joint: Self::Joint) {
                    self.world.impulse_joints.remove(joint, true);
                }

                fn state(&self, b: usize) -> BodyState {
                    let rb = &self.world.bodies[self.bodies[b]];
                    BodyState {
                        position: unvector(rb.translation()),
                        rotation: unrotation(rb.rotation()),
                        linvel: unvector(rb.linvel()),
                        angvel: unangular(rb.angvel()),
                    }
                }

                fn set_velocity(
                    &mut self,
                    b: usize,
                    linvel: &Vector3<f64>,
                    angvel: Option<&Vector3<f64>>,
                ) {
                    let rb = &mut self.world.bodies[self.bodies[b]];
                    rb.set_linvel(vector(linvel), true);
                    if let Some(w) = angvel {
                        rb.set_angvel(angular(w), true);
                    }
                }

                fn set_fixed(&mut self, b: usize) {
                    let rb = &mut self.world.bodies[self.bodies[b]];
                    rb.set_body_type(RigidBodyType::Fixed, true);
                }

                fn set_dynamic(&mut self, b: usize, rotations_locked: bool, locks: &[bool; 6]) {
                    let rb = &mut self.world.bodies[self.bodies[b]];
                    rb.set_body_type(RigidBodyType::Dynamic, true);
                    let mut axes = if rotations_locked {
                        LockedAxes::ROTATION_LOCKED
                    } else {
                        LockedAxes::empty()
                    };
                    for (k, flag) in LOCKS.iter().enumerate() {
                        if locks[k] {
                            axes |= *flag;
                        }
                    }
                    rb.set_locked_axes(axes, true);
                }

                fn set_increment(&mut self, h: f64) {
                    self.world.integration_parameters.dt = h as Real;
                }

                fn clear_forces(&mut self, b: usize) {
                    // `reset_forces` clears the force only: the torque that
                    // `add_force_at_point` adds needs its own reset.
                    let rb = &mut self.world.bodies[self.bodies[b]];
                    rb.reset_forces(false);
                    rb.reset_torques(false);
                }

                fn add_force_at_point(
                    &mut self,
                    b: usize,
                    force: &Vector3<f64>,
                    at: &Vector3<f64>,
                ) {
                    let rb = &mut self.world.bodies[self.bodies[b]];
                    rb.add_force_at_point(vector(force), vector(at), false);
                }

                fn step(&mut self) {
                    self.world.step();
                }

                fn contact_impulse(&self, a: usize, b: usize) -> f64 {
                    let (a, b) = (self.colliders[a], self.colliders[b]);
                    let pair = self.world.narrow_phase.contact_pair(a, b);
                    pair.map_or(0.0, |p| p.total_impulse_magnitude() as f64)
                }

                fn friction_impulses(&self, a: usize, b: usize) -> Vec<FrictionImpulse> {
                    let (a, b) = (self.colliders[a], self.colliders[b]);
                    let Some(pair) = self.world.narrow_phase.contact_pair(a, b) else {
                        return Vec::new();
                    };
                    // The impulses are on the pair's first collider's body.
                    let sign = if pair.collider1 == a { 1.0 } else { -1.0 };
                    let pose = self.world.colliders[pair.collider1].position();
                    let points = solver_manifolds(pair).iter().flat_map(|m| {
                        let normal = m.data.normal;
                        m.points.iter().map(move |p| FrictionImpulse {
                            impulse: sign * friction_impulse(normal, &p.data.tangent_impulse),
                            at: unvector(pose.transform_point(p.local_p1)),
                        })
                    });
                    points.collect()
                }

                fn quarantined(&self) -> bool {
                    quarantined(&self.world)
                }

                fn counts(&self) -> (usize, usize, usize) {
                    let w = &self.world;
                    (w.colliders.len(), w.impulse_joints.len(), w.bodies.len())
                }
            }
        }
    };
}

world!(R2F32, r2_f32, rapier2d, 2, current);
world!(R2F64, r2_f64, rapier2d_f64, 2, current);
world!(R3F32, r3_f32, rapier3d, 3, current);
world!(R3F64, r3_f64, rapier3d_f64, 3, current);
#[cfg(feature = "rapier-versions")]
world!(R2F64V034, r2_f64_v0_34, rapier2d_f64_v0_34, 2, v0_34);
#[cfg(feature = "rapier-versions")]
world!(R3F64V034, r3_f64_v0_34, rapier3d_f64_v0_34, 3, v0_34);
#[cfg(feature = "rapier-versions")]
world!(R2F64V035, r2_f64_v0_35, rapier2d_f64_v0_35, 2, v0_35);
#[cfg(feature = "rapier-versions")]
world!(R3F64V035, r3_f64_v0_35, rapier3d_f64_v0_35, 3, v0_35);
