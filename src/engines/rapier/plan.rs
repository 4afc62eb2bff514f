//! The scene translated into what a rapier world is made of, once, for every rapier crate.
//!
//! A [`Plan`] is dimension- and precision-independent (f64, 3-vectors; in 2D every z component
//! is zero and rotations are about z): the rapier backends ([`super::backend`]) only turn it
//! into rapier objects. Everything the mapping decides is decided here.
//!
//! # Bodies
//!
//! Body 0 is the ground: one fixed rigid body at the origin with the identity pose, carrying
//! every ground node (free, massless and held in every translation in every step) at its
//! position. Every other free node with mass is a *particle*: a dynamic body with that mass
//! whose rotations are locked, with its origin at the node. Every scene body is a rigid body
//! whose origin is its reference node O and whose local axes are the world axes at t = 0, with
//! the scene's mass properties exactly: mass, local centre of mass = `centre_offset`, inertia
//! about the centre of mass I_G = I_O − m(|c|²1 − c cᵀ) (2D: I_G = I_O,zz − m|c|²). Colliders
//! never contribute mass (density 0).
//!
//! # What a step holds
//!
//! Per dynamic step, in order of faithfulness ([`super::steps`]):
//!
//! - a body the step holds in every DOF is a **fixed body** for the step: it moves no more than
//!   the ground, and no impulse reaches its mass;
//! - a body whose held DOFs are all at its centre of mass along world axes (a particle's node;
//!   a rigid body pinned or sliding at its centre of mass; in 3D, rotations held about all but
//!   one principal axis) has them **locked** (`LockedAxes`), which every rapier solve sees;
//!   both are judged at the pose the static steps leave, so a body that an earlier dynamic
//!   step let turn (or, in 3D, that the static steps turned and that carries a grounded
//!   rotational element) is held by joints instead;
//! - otherwise every node that is held gets a *ground joint*: body 1 the ground, body 2 the
//!   node's body, both joint frames with the node's frame axes, anchored at the node, locking
//!   exactly the DOFs the step holds (a pinned reference node gives a revolute joint, a sliding
//!   one a joint freeing x and rz). A DOF held again after an earlier dynamic step left it free
//!   is held where that step left it: the joint is fitted to the body's pose when its step
//!   starts ([`JointSpec::fitted`]); beside a rotational motor on two free rotations it cannot
//!   be, and the scene is unsupported.
//!
//! A node that carries a grounded spring or dashpot on a free DOF gets a ground joint with a
//! force-based motor on that DOF (target 0 at the undeformed geometry: the ground frame's
//! origin is the node's position at t = 0, moved along the held axes by whatever displacement
//! the static steps left there, so a held DOF is held where it is).
//!
//! Fixed-direction elements become a motor on a joint whose first frame is fixed to the ground
//! (or to a particle, which never rotates) with its x axis along the direction and its origin at
//! the other end's undeformed position, so the joint's x coordinate is the elongation
//! d·(u_B − u_A) and position 0 is unstretched; nothing else is locked. Axial elements become
//! rapier `SpringJoint`s (rest length = undeformed length). Springs and dashpots on the same DOF
//! or between the same nodes share one motor (stiffness = Σk, damping = Σc).
//!
//! # Contact
//!
//! Only where the scene has a contact pair: a cuboid on the body whose outer face is the
//! contact face (a slab `size` thick behind it, in-plane half-extent `size`, where `size` is
//! twice the spread of the body's nodes and the contact node) and a ball of radius
//! r = 1e-3 `size` on the node's body, centred on the node, the slab moved back by r so the
//! two touch exactly at t = 0. A solid (ball, cuboid, capsule) is the parry shape the scene
//! names, shrunk by r so the node itself touches where the solid's surface is (corners rounded
//! by r). Restitution: the pair's, whether it starts open or closed (rapier
//! cannot rest a closed pair of restitution 1: the report shows it with its control).
//! Friction: the pair's kinetic coefficient μ_k on both colliders (rapier's `Average` rule
//! gives the pair (μ_k + μ_k)/2 = μ_k exactly; rapier has one coefficient, so a pair whose
//! static coefficient is larger sticks and breaks away at μ_k), 0 on a frictionless pair. The
//! node's ball never rolls: a particle's rotations are locked.
//!
//! # Steps
//!
//! Static steps (before the first dynamic one) apply their prescribed displacements to the
//! initial positions; a DOF they leave free must carry no force there, or the scene is
//! unsupported (rapier has no static solve). At the start of every dynamic step the velocity
//! components along the DOFs it holds are zeroed, on the reference node's velocities as the
//! scene defines them (the first one after the scene's initial velocities are applied,
//! converted to centre-of-mass velocities v_G = v_O + ω × (R c); [`BodyState::hold`]).

mod bodies;
mod contacts;
mod dynamic_steps;
mod joints;
mod static_steps;

use super::steps::groups;
use crate::engines::EngineError;
use crate::scene::{Attachment, Dimension, Dof, NodeId, Scene, StepKind, Surface};
use dynamic_steps::PlanSoFar;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Which kind of rapier body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// The fixed ground.
    Ground,
    /// A free node with mass: translations only.
    Particle,
    /// A scene body.
    Rigid,
}

/// A rapier body.
#[derive(Debug, Clone)]
pub struct BodySpec {
    /// Kind.
    pub kind: BodyKind,
    /// Mass.
    pub mass: f64,
    /// Centre of mass in body coordinates.
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass, body axes.
    pub inertia: Matrix3<f64>,
    /// Origin at the start of the first dynamic step.
    pub position: Vector3<f64>,
    /// Orientation at the start of the first dynamic step.
    pub rotation: UnitQuaternion<f64>,
    /// Velocity of the centre of mass at the start of the first dynamic step.
    pub linvel: Vector3<f64>,
    /// Angular velocity at the start of the first dynamic step.
    pub angvel: Vector3<f64>,
}

/// Where a scene node lives: a body and a point in its coordinates.
#[derive(Debug, Clone, Copy)]
pub struct NodeRef {
    /// Body index in [`Plan::bodies`].
    pub body: usize,
    /// Point in body coordinates.
    pub local: Vector3<f64>,
}

/// A frame attached to a body, in its coordinates.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// Origin.
    pub origin: Vector3<f64>,
    /// Axes.
    pub rotation: UnitQuaternion<f64>,
}

/// A motor on one joint axis: index 0–2 translations, 3–5 rotations about the frame axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motor {
    /// Joint axis.
    pub axis: usize,
    /// Stiffness (target position 0).
    pub stiffness: f64,
    /// Damping (target velocity 0).
    pub damping: f64,
}

/// What a joint does.
#[derive(Debug, Clone, PartialEq)]
pub enum JointKind {
    /// A generic joint: locked axes (0–2 translations, 3–5 rotations) and force-based motors.
    Generic {
        /// Locked axes.
        locked: [bool; 6],
        /// Motors.
        motors: Vec<Motor>,
    },
    /// A rapier `SpringJoint` between the two frame origins.
    Spring {
        /// Rest length.
        rest: f64,
        /// Stiffness.
        stiffness: f64,
        /// Damping.
        damping: f64,
    },
}

/// A joint between two bodies.
#[derive(Debug, Clone)]
pub struct JointSpec {
    /// First body (the ground, or a body that does not rotate, where it matters).
    pub body1: usize,
    /// Second body.
    pub body2: usize,
    /// Frame on body 1.
    pub frame1: Frame,
    /// Frame on body 2.
    pub frame2: Frame,
    /// Kind.
    pub kind: JointKind,
    /// The DOFs this joint locks that an earlier dynamic step left free (a ground joint of a
    /// later step only): fitted to the body's pose where the step starts
    /// ([`JointSpec::fitted`]), so that they are held where they are.
    pub refit: [bool; 6],
}

impl JointSpec {
    /// This ground joint fitted to body 2's state `s` where its step starts, for the DOFs in
    /// [`JointSpec::refit`] (body 1 is the ground, at the identity pose, and `frame1`'s axes
    /// are the node's frame R_t).
    ///
    /// - A translation held again: the ground frame's origin moved along that axis to the
    ///   node's position now (along the free axes it stays where a grounded motor measures
    ///   from).
    /// - A rotation held again: the body's frame set to q_s⁻¹·T·R_t, with q_s the body's
    ///   orientation now, so that at the start the joint reads R_t⁻¹·T·R_t, a rotation about
    ///   its free axis only: none about a held one.
    ///   With one rotation left free, about the world axis a, T is the body's twist about a
    ///   since t = 0, so that a grounded motor on it goes on reading the total twist (the body
    ///   then turns about a only: q = R_a(Δ)·q_s); with more, T is the identity, and the plan
    ///   refuses a rotational motor there.
    pub fn fitted(&self, s: &BodyState) -> JointSpec {
        let JointKind::Generic { locked, .. } = &self.kind else {
            return self.clone();
        };
        let mut out = self.clone();
        let axes = self.frame1.rotation;
        let x = s.point(&self.frame2.origin);
        for i in (0..3).filter(|&i| self.refit[i]) {
            let e = axes * Vector3::ith(i, 1.0);
            out.frame1.origin += e * e.dot(&(x - self.frame1.origin));
        }
        if self.refit[3..].iter().any(|&r| r) {
            // In 2D only rz is ever locked, so holding it again leaves rx and ry "free": T = 1.
            let free: Vec<usize> = (0..3).filter(|&i| !locked[3 + i]).collect();
            let turn = match free[..] {
                [f] => {
                    let a = axes * Vector3::ith(f, 1.0);
                    UnitQuaternion::from_scaled_axis(a * twist(&s.rotation, &a))
                }
                _ => UnitQuaternion::identity(),
            };
            out.frame2.rotation = s.rotation.inverse() * turn * axes;
        }
        out
    }
}

/// A velocity component a dynamic step holds (zeroed at its start).
#[derive(Debug, Clone, Copy)]
pub enum HeldVelocity {
    /// Translation of a body point along a world direction.
    Translation {
        /// Body.
        body: usize,
        /// Point in body coordinates.
        local: Vector3<f64>,
        /// World direction.
        direction: Vector3<f64>,
    },
    /// Rotation of a body about a world axis.
    Rotation {
        /// Body.
        body: usize,
        /// World axis.
        axis: Vector3<f64>,
    },
}

/// A dynamic step.
#[derive(Debug, Clone)]
pub struct StepSpec {
    /// Duration.
    pub duration: f64,
    /// The ground joints of this step.
    pub joints: Vec<JointSpec>,
    /// Held velocity components, zeroed at the start.
    pub held: Vec<HeldVelocity>,
    /// Per plan body: held in every DOF in this step, so a rapier fixed body for its duration
    /// (the ground always is).
    pub fixed: Vec<bool>,
    /// Per plan body: the world axes its `LockedAxes` lock in this step (0–2 translations of the
    /// centre of mass, 3–5 rotations; [`super::steps::locked_axes`]), what it holds that way
    /// rather than by a joint.
    pub locks: Vec<[bool; 6]>,
}

/// A collider shape.
#[derive(Debug, Clone)]
pub enum Shape {
    /// Ball of a radius.
    Ball(f64),
    /// Cuboid with half extents along its frame axes (2D: z unused).
    Cuboid(Vector3<f64>),
    /// Capsule along its frame's y axis: half height of the segment, radius.
    Capsule(f64, f64),
    /// The convex hull of these points (2D: z unused).
    ConvexHull(Vec<Vector3<f64>>),
}

/// A collider.
#[derive(Debug, Clone)]
pub struct ColliderSpec {
    /// Body.
    pub body: usize,
    /// Shape.
    pub shape: Shape,
    /// Pose on the body.
    pub frame: Frame,
}

/// A contact pair's colliders and geometry.
#[derive(Debug, Clone)]
pub struct ContactSpec {
    /// Index of the ball (on the node's body) in [`Plan::colliders`].
    pub ball: usize,
    /// Index of the slab (on the face's body).
    pub slab: usize,
    /// The node.
    pub node: NodeId,
    /// The face's body.
    pub body: usize,
    /// The surface in the face body's coordinates (its reference node at the origin).
    pub surface: Surface,
    /// The radius of the scene's ball on the node (0: the node touches; the collider's
    /// small ball then stands for the node).
    pub node_radius: f64,
    /// Coefficient of restitution (rapier's `restitution` on both colliders, averaged).
    pub restitution: f64,
    /// Coefficient of friction: the pair's μ_k, 0 where frictionless (rapier's `friction` on
    /// both colliders, averaged: exactly μ_k).
    pub friction: f64,
}

/// A point load.
#[derive(Debug, Clone)]
pub struct LoadSpec {
    /// Body.
    pub body: usize,
    /// Point in body coordinates.
    pub local: Vector3<f64>,
    /// Force (world; at amplitude 1).
    pub force: Vector3<f64>,
    /// How it varies in time (`None`: constant).
    pub amplitude: Option<crate::scene::Amplitude>,
}

/// Everything a rapier world is built from.
#[derive(Debug, Clone)]
pub struct Plan {
    /// 2D or 3D.
    pub dimension: Dimension,
    /// Bodies; 0 is the ground.
    pub bodies: Vec<BodySpec>,
    /// Per scene node.
    pub nodes: Vec<NodeRef>,
    /// Joints present in every dynamic step (fixed-direction and axial elements).
    pub permanent: Vec<JointSpec>,
    /// Dynamic steps in order.
    pub steps: Vec<StepSpec>,
    /// Colliders.
    pub colliders: Vec<ColliderSpec>,
    /// Per scene contact pair.
    pub contacts: Vec<ContactSpec>,
    /// Loads.
    pub loads: Vec<LoadSpec>,
}

/// The state of a body at an instant (f64 whatever the rapier precision).
#[derive(Debug, Clone, Copy)]
pub struct BodyState {
    /// Origin.
    pub position: Vector3<f64>,
    /// Orientation.
    pub rotation: UnitQuaternion<f64>,
    /// Velocity of the centre of mass.
    pub linvel: Vector3<f64>,
    /// Angular velocity.
    pub angvel: Vector3<f64>,
}

impl BodyState {
    /// A body point in world coordinates.
    pub fn point(&self, local: &Vector3<f64>) -> Vector3<f64> {
        self.position + self.rotation * local
    }

    /// Velocity of a body point.
    pub fn velocity(&self, com: &Vector3<f64>, local: &Vector3<f64>) -> Vector3<f64> {
        self.linvel + self.angvel.cross(&(self.rotation * (local - com)))
    }

    /// Linear interpolation (rotations by slerp), s in [0, 1] from `self` to `other`.
    pub fn lerp(&self, other: &BodyState, s: f64) -> BodyState {
        BodyState {
            position: self.position.lerp(&other.position, s),
            rotation: self
                .rotation
                .try_slerp(&other.rotation, s, 1e-12)
                .unwrap_or(other.rotation),
            linvel: self.linvel.lerp(&other.linvel, s),
            angvel: self.angvel.lerp(&other.angvel, s),
        }
    }

    /// Zero the velocity components a step holds (for this body), as the scene defines them:
    /// on the generalised velocities of the body's reference node O, its origin (v_O, ω).
    /// The held rotations are taken out of ω with v_O kept, so the centre of mass's velocity
    /// changes by Δω × (G − O); then the held translations are taken out of their nodes'
    /// velocities.
    pub fn hold(&mut self, com: &Vector3<f64>, held: &[HeldVelocity], me: usize) {
        let g = self.position + self.rotation * com;
        let before = self.angvel;
        for h in held {
            match *h {
                HeldVelocity::Rotation { body, axis } if body == me => {
                    self.angvel -= axis * axis.dot(&self.angvel);
                }
                _ => {}
            }
        }
        let removed = self.angvel - before;
        if removed != Vector3::zeros() {
            self.linvel += removed.cross(&(g - self.position));
        }
        for h in held {
            if let HeldVelocity::Translation {
                body,
                local,
                direction,
            } = *h
                && body == me
            {
                let r = self.rotation * local - (g - self.position);
                let vp = self.linvel + self.angvel.cross(&r);
                self.linvel -= direction * direction.dot(&vp);
            }
        }
    }
}

/// Rotation taking +x to `d` (2D: about z).
pub fn x_to(d: &Vector3<f64>, dimension: Dimension) -> UnitQuaternion<f64> {
    match dimension {
        Dimension::Two => UnitQuaternion::from_axis_angle(&Vector3::z_axis(), d.y.atan2(d.x)),
        Dimension::Three => {
            UnitQuaternion::rotation_between(&Vector3::x(), d).unwrap_or_else(|| {
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
            })
        }
    }
}

/// A node frame (orthonormal, right-handed columns) as a rotation.
pub fn frame_rotation(frame: &Matrix3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(*frame))
}

/// Twist of a rotation about a unit axis, in (−π, π].
pub fn twist(q: &UnitQuaternion<f64>, axis: &Vector3<f64>) -> f64 {
    2.0 * q.vector().dot(axis).atan2(q.w)
}

/// Joint axis index of a DOF.
fn joint_axis(dof: Dof) -> usize {
    match dof {
        Dof::Translation(i) => i,
        Dof::Rotation(i) => 3 + i,
    }
}

pub(super) fn unsupported<T>(message: impl Into<String>) -> Result<T, EngineError> {
    Err(EngineError::Unsupported(format!(
        "rapier: {}",
        message.into()
    )))
}

/// Free, massless and held in every translation in every step.
pub fn is_ground(scene: &Scene, node: NodeId) -> bool {
    scene.nodes[node].attachment == Attachment::Free
        && scene.nodes[node].mass == 0.0
        && scene.steps.iter().all(|s| {
            Dof::all(scene.dimension, false).iter().all(|d| {
                s.conditions
                    .iter()
                    .any(|c| c.node == node && c.dof == *d && c.value.is_none())
            })
        })
}

/// How a body held in every DOF of a step becomes a rapier body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Holding {
    /// A fixed body for the step: what it is, and what the engines run.
    #[default]
    Fixed,
    /// A dynamic body held by a joint to the ground, as any other held DOF: a control
    /// experiment, showing what the joint costs at an impact (rapier's restitution pass solves
    /// the contact without the joint, so the body takes a free body's share of the impulse).
    Joints,
}

/// Build the plan of a scene.
pub fn plan(scene: &Scene) -> Result<Plan, EngineError> {
    plan_with(scene, Holding::Fixed)
}

/// Build the plan of a scene, with bodies held in every DOF made as `holding` says: the bodies
/// and where each node lives, the static steps' placement, the initial velocities, the
/// permanent joints, the dynamic steps, the colliders and the loads, in that order.
pub fn plan_with(scene: &Scene, holding: Holding) -> Result<Plan, EngineError> {
    let first_dynamic = first_dynamic_step(scene)?;
    let (mut bodies, body_of_scene_body) = bodies::bodies(scene)?;
    let nodes = bodies::nodes(scene, &mut bodies, &body_of_scene_body)?;
    let element_groups = groups(scene);
    let placement = static_steps::placement(
        scene,
        first_dynamic,
        &bodies,
        &nodes,
        &body_of_scene_body,
        &element_groups,
    )?;
    for (b, body) in bodies.iter_mut().enumerate() {
        body.position = placement.position[b];
        body.rotation = placement.rotation[b];
    }
    bodies::initial_velocities(scene, &nodes, &mut bodies);
    let permanent = joints::permanent(scene, &nodes, &bodies, &element_groups)?;
    let steps = PlanSoFar {
        scene,
        holding,
        nodes: &nodes,
        bodies: &bodies,
        placement: &placement,
        element_groups: &element_groups,
    }
    .steps(first_dynamic)?;
    let (colliders, contacts) = contacts::colliders(scene, &nodes, &body_of_scene_body)?;
    let loads = scene
        .loads
        .iter()
        .filter(|l| nodes[l.node].body != 0)
        .map(|l| LoadSpec {
            body: nodes[l.node].body,
            local: nodes[l.node].local,
            force: l.force,
            amplitude: l.amplitude.clone(),
        })
        .collect();
    Ok(Plan {
        dimension: scene.dimension,
        bodies,
        nodes,
        permanent,
        steps,
        colliders,
        contacts,
        loads,
    })
}

/// The index of the scene's first dynamic step; no static step may follow one.
fn first_dynamic_step(scene: &Scene) -> Result<usize, EngineError> {
    let first_dynamic = scene
        .steps
        .iter()
        .position(|s| matches!(s.kind, StepKind::Dynamic { .. }))
        .ok_or_else(|| EngineError::Unsupported("rapier: the scene has no dynamic step".into()))?;
    if scene.steps[first_dynamic..]
        .iter()
        .any(|s| s.kind == StepKind::Static)
    {
        return unsupported(
            "a static step after a dynamic one (rapier has no static solve to restart from)",
        );
    }
    Ok(first_dynamic)
}
