//! The plan's bodies: the ground, one rigid body per scene body (its mass properties about
//! its centre of mass), one particle per free node with mass; where each node lives; and the
//! bodies' initial velocities.

use super::{BodyKind, BodySpec, NodeRef, is_ground, unsupported};
use crate::engines::EngineError;
use crate::scene::{Attachment, Dimension, RigidBody, Scene};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// The ground (body 0) and the scene's rigid bodies, with the plan body of each scene body.
pub(super) fn bodies(scene: &Scene) -> Result<(Vec<BodySpec>, Vec<usize>), EngineError> {
    let mut bodies = vec![BodySpec {
        kind: BodyKind::Ground,
        mass: 0.0,
        com: Vector3::zeros(),
        inertia: Matrix3::zeros(),
        position: Vector3::zeros(),
        rotation: UnitQuaternion::identity(),
        linvel: Vector3::zeros(),
        angvel: Vector3::zeros(),
    }];
    let mut body_of_scene_body: Vec<usize> = Vec::with_capacity(scene.bodies.len());
    for b in &scene.bodies {
        body_of_scene_body.push(bodies.len());
        bodies.push(rigid_body(scene, b)?);
    }
    Ok((bodies, body_of_scene_body))
}

/// A scene body as a rapier rigid body: its origin at the reference node, its inertia moved to
/// the centre of mass (which must leave a rigid body's mass properties).
fn rigid_body(scene: &Scene, b: &RigidBody) -> Result<BodySpec, EngineError> {
    let dim = scene.dimension;
    let c = b.centre_offset;
    let parallel = match dim {
        Dimension::Two => {
            let mut m = Matrix3::zeros();
            m[(2, 2)] = b.mass * (c.x * c.x + c.y * c.y);
            m
        }
        Dimension::Three => b.mass * (Matrix3::identity() * c.norm_squared() - c * c.transpose()),
    };
    let inertia = b.inertia - parallel;
    let check = match dim {
        Dimension::Two => inertia[(2, 2)] > 0.0,
        Dimension::Three => inertia
            .symmetric_eigenvalues()
            .iter()
            .all(|&e| e > -1e-12 * inertia.norm()),
    };
    if b.mass <= 0.0 || !check {
        return unsupported(format!(
            "body `{}`: mass {} and inertia about the centre of mass {} are not a rigid body's",
            b.name, b.mass, inertia
        ));
    }
    Ok(BodySpec {
        kind: BodyKind::Rigid,
        mass: b.mass,
        com: c,
        inertia,
        position: scene.nodes[b.reference].position,
        rotation: UnitQuaternion::identity(),
        linvel: Vector3::zeros(),
        angvel: Vector3::zeros(),
    })
}

/// Where each scene node lives (a particle body is added for each free node with mass).
pub(super) fn nodes(
    scene: &Scene,
    bodies: &mut Vec<BodySpec>,
    body_of_scene_body: &[usize],
) -> Result<Vec<NodeRef>, EngineError> {
    let mut nodes = Vec::with_capacity(scene.nodes.len());
    for (id, n) in scene.nodes.iter().enumerate() {
        nodes.push(match n.attachment {
            Attachment::Free if is_ground(scene, id) => NodeRef {
                body: 0,
                local: n.position,
            },
            Attachment::Free if n.mass > 0.0 => {
                bodies.push(BodySpec {
                    kind: BodyKind::Particle,
                    mass: n.mass,
                    com: Vector3::zeros(),
                    inertia: Matrix3::zeros(),
                    position: n.position,
                    rotation: UnitQuaternion::identity(),
                    linvel: Vector3::zeros(),
                    angvel: Vector3::zeros(),
                });
                NodeRef {
                    body: bodies.len() - 1,
                    local: Vector3::zeros(),
                }
            }
            Attachment::Free => {
                return unsupported(format!(
                    "node `{}` has no mass and is not held in every translation in every step (a rapier body needs mass)",
                    n.name
                ));
            }
            Attachment::Reference(b) | Attachment::OnBody(b) => NodeRef {
                body: body_of_scene_body[b],
                local: n.position - scene.nodes[scene.bodies[b].reference].position,
            },
        });
    }
    Ok(nodes)
}

/// Initial velocities (centre-of-mass velocities for rigid bodies), at the bodies' pose when
/// the first dynamic step starts.
pub(super) fn initial_velocities(scene: &Scene, nodes: &[NodeRef], bodies: &mut [BodySpec]) {
    for iv in &scene.initial_velocities {
        let r = nodes[iv.node];
        if r.body == 0 {
            continue;
        }
        let body = &mut bodies[r.body];
        match body.kind {
            BodyKind::Particle => body.linvel = iv.velocity,
            BodyKind::Rigid => {
                let arm = body.rotation * (body.com - r.local);
                body.linvel = iv.velocity + iv.angular.cross(&arm);
                body.angvel = iv.angular;
            }
            BodyKind::Ground => {}
        }
    }
}
