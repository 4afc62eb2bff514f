//! Contact: per contact pair, a collider on the face's body (a slab behind a plane face, or
//! the solid shrunk by the node's ball) and a ball on the node's body, centred on it: the
//! scene's ball where the node carries one (a body rolling on a face), else a small one.

use super::{ColliderSpec, ContactSpec, Frame, NodeRef, Shape, unsupported, x_to};
use crate::engines::EngineError;
use crate::scene::{Attachment, ContactPair, Dimension, Scene, Solid, Surface};
use nalgebra::{UnitQuaternion, Vector3};

/// The colliders and the contacts between them, two colliders per contact pair: the face's
/// (the slab) then the node's ball.
pub(super) fn colliders(
    scene: &Scene,
    nodes: &[NodeRef],
    body_of_scene_body: &[usize],
) -> Result<(Vec<ColliderSpec>, Vec<ContactSpec>), EngineError> {
    let mut colliders = Vec::new();
    let mut contacts = Vec::new();
    for pair in &scene.contacts {
        let face_body = body_of_scene_body[pair.body];
        if let Some(f) = pair
            .friction
            .filter(|f| f.static_coefficient > f.kinetic_coefficient)
        {
            return unsupported(format!(
                "contact `{}`: static friction {} above kinetic {}; rapier has one friction \
                 coefficient, so the pair would stick and break away at the kinetic one",
                pair.name, f.static_coefficient, f.kinetic_coefficient
            ));
        }
        let r = nodes[pair.node];
        if r.body == face_body {
            return unsupported(format!(
                "contact `{}`: the node is on the face's own body",
                pair.name
            ));
        }
        let origin = scene.nodes[scene.bodies[pair.body].reference].position;
        let size = size(scene, pair);
        let (collider, surface, radius) = match pair.surface.clone() {
            Surface::Plane { point, normal } => {
                // A rolling ball is the scene's, touching the face, on a slab as wide as it
                // could travel; a particle is the centre of a ball of 1e-3 of the scene's size,
                // on a slab of that size set back by the ball's radius.
                let (wide, radius, setback) = if pair.rolls() {
                    (reach(scene, pair, size), pair.node_radius, 0.0)
                } else {
                    (size, 1e-3 * size, 1e-3 * size)
                };
                let (dimension, offset) = (scene.dimension, point - origin);
                let slab = slab(dimension, face_body, offset, normal, size, wide, setback);
                (slab.0, slab.1, radius)
            }
            Surface::Solid { solid, centre } => {
                solid_face(pair, face_body, solid, centre - origin, size)?
            }
        };
        colliders.push(collider);
        colliders.push(ColliderSpec {
            body: r.body,
            shape: Shape::Ball(radius),
            frame: Frame {
                origin: r.local,
                rotation: UnitQuaternion::identity(),
            },
        });
        contacts.push(ContactSpec {
            ball: colliders.len() - 1,
            slab: colliders.len() - 2,
            node: pair.node,
            body: face_body,
            surface,
            node_radius: pair.node_radius,
            restitution: pair.restitution,
            // μ_s = μ_k here (a larger static coefficient is refused above).
            friction: pair.friction.map_or(0.0, |f| f.kinetic_coefficient),
        });
    }
    Ok((colliders, contacts))
}

/// The size of a pair's colliders: twice the spread of the face body's nodes and the contact
/// node about the surface's anchor (never zero).
fn size(scene: &Scene, pair: &ContactPair) -> f64 {
    let spread = scene
        .nodes
        .iter()
        .enumerate()
        .filter(|(i, n)| {
            *i == pair.node
                || matches!(n.attachment, Attachment::Reference(b) | Attachment::OnBody(b) if b == pair.body)
        })
        .map(|(_, n)| (n.position - pair.anchor()).norm())
        .fold(0.0f64, f64::max);
    2.0 * spread.max(f64::MIN_POSITIVE.sqrt())
}

/// How far along a face a rolling pair's ball may travel from the face's anchor within the
/// run: its spread `size`, plus what the initial speeds (a spin at the ball's rim included)
/// and every load on the ball's body (at its largest amplitude) could carry it, as if
/// nothing held it back. The slab under a rolling ball reaches that far, so the ball never
/// rolls off its edge.
fn reach(scene: &Scene, pair: &ContactPair, size: f64) -> f64 {
    let (Attachment::Reference(body) | Attachment::OnBody(body)) =
        scene.nodes[pair.node].attachment
    else {
        return size;
    };
    let on_body = |node: usize| matches!(scene.nodes[node].attachment, Attachment::Reference(b) | Attachment::OnBody(b) if b == body);
    let speed: f64 = (scene.initial_velocities.iter())
        .filter(|v| on_body(v.node))
        .map(|v| v.velocity.norm() + v.angular.norm() * pair.node_radius)
        .sum();
    let force: f64 = (scene.loads.iter())
        .filter(|l| on_body(l.node))
        .map(|l| {
            let scale = l.amplitude.as_ref().map_or(1.0, |a| {
                a.points.iter().map(|p| p.1.abs()).fold(0.0, f64::max)
            });
            l.force.norm() * scale
        })
        .sum();
    let t = scene.duration();
    size + t * speed + 0.5 * t * t * force / scene.bodies[body].mass
}

/// A plane face through `face_point` (body coordinates): a slab `size` thick behind it and
/// `2 wide` across, moved
/// back by `setback` (the small ball that stands for a node, so the two touch exactly at
/// t = 0; 0 under a scene's ball, which touches the face itself); and the face in body
/// coordinates.
fn slab(
    dim: Dimension,
    face_body: usize,
    face_point: Vector3<f64>,
    normal: Vector3<f64>,
    size: f64,
    wide: f64,
    setback: f64,
) -> (ColliderSpec, Surface) {
    (
        ColliderSpec {
            body: face_body,
            shape: Shape::Cuboid(Vector3::new(0.5 * size, wide, wide)),
            frame: Frame {
                origin: face_point - normal * (setback + 0.5 * size),
                rotation: x_to(&normal, dim),
            },
        },
        Surface::Plane {
            point: face_point,
            normal,
        },
    )
}

/// A solid centred at `centre` (body coordinates), shrunk by the node's ball radius, so the
/// ball's centre (the node) touches where it touches the solid itself (corners rounded by the
/// radius); the solid in body coordinates, and the radius.
fn solid_face(
    pair: &ContactPair,
    face_body: usize,
    solid: Solid,
    centre: Vector3<f64>,
    size: f64,
) -> Result<(ColliderSpec, Surface, f64), EngineError> {
    let radius = (1e-3 * size).min(0.1 * solid.half_thickness());
    let shape = match solid {
        Solid::Ball { radius: a } => Shape::Ball(a - radius),
        Solid::Cuboid { half_extents } => {
            Shape::Cuboid(half_extents.map(|h| (h - radius).max(0.0)))
        }
        Solid::Capsule {
            half_height,
            radius: a,
        } => Shape::Capsule(half_height, a - radius),
        Solid::Convex { ref polytope } => match polytope.eroded(radius) {
            Some(corners) => Shape::ConvexHull(corners),
            None => {
                return unsupported(format!(
                    "contact `{}`: the polytope eroded by the node's ball radius \
                     {radius:e} leaves nothing",
                    pair.name
                ));
            }
        },
    };
    Ok((
        ColliderSpec {
            body: face_body,
            shape,
            frame: Frame {
                origin: centre,
                rotation: UnitQuaternion::identity(),
            },
        },
        Surface::Solid { solid, centre },
        radius,
    ))
}
