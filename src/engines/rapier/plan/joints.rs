//! The permanent joints: fixed-direction elements as a motor along the direction, axial
//! elements as rapier spring joints.

use super::super::steps::Group;
use super::{BodyKind, BodySpec, Frame, JointKind, JointSpec, Motor, NodeRef, unsupported, x_to};
use crate::engines::EngineError;
use crate::scene::{Connection, NodeId, Scene};
use nalgebra::{UnitQuaternion, Vector3};

/// The joints every step has: one per fixed-direction or axial element group between two
/// bodies (grounded groups are the steps' business).
pub(super) fn permanent(
    scene: &Scene,
    nodes: &[NodeRef],
    bodies: &[BodySpec],
    element_groups: &[Group],
) -> Result<Vec<JointSpec>, EngineError> {
    let mut permanent = Vec::new();
    for g in element_groups {
        let joint = match &g.connection {
            Connection::Grounded { .. } => None,
            Connection::FixedDirection {
                nodes: pair,
                direction,
            } => fixed_direction(scene, nodes, bodies, g, pair, direction)?,
            Connection::Axial { nodes: pair } => axial(scene, nodes, g, pair)?,
        };
        permanent.extend(joint);
    }
    Ok(permanent)
}

/// A fixed-direction group as a joint whose first frame does not rotate (on the ground or a
/// particle), its x axis along the direction and its origin at the other end's undeformed
/// position, with a motor on x; `None` between nodes of one body.
fn fixed_direction(
    scene: &Scene,
    nodes: &[NodeRef],
    bodies: &[BodySpec],
    g: &Group,
    pair: &[NodeId; 2],
    direction: &Vector3<f64>,
) -> Result<Option<JointSpec>, EngineError> {
    let dim = scene.dimension;
    let (ra, rb) = (nodes[pair[0]], nodes[pair[1]]);
    if ra.body == rb.body {
        return Ok(None);
    }
    let steady = |r: &NodeRef| bodies[r.body].kind != BodyKind::Rigid;
    // Body 1 must not rotate: the ground, or a particle.
    let (a, b) = if ra.body == 0 || (rb.body != 0 && steady(&ra)) {
        (pair[0], pair[1])
    } else if steady(&rb) {
        (pair[1], pair[0])
    } else {
        return unsupported(format!(
            "a fixed-direction element between nodes `{}` and `{}` of two rotating bodies (its direction needs a non-rotating frame)",
            scene.nodes[pair[0]].name, scene.nodes[pair[1]].name
        ));
    };
    let (ra, rb) = (nodes[a], nodes[b]);
    let (xa, xb) = (scene.nodes[a].position, scene.nodes[b].position);
    let rotation = x_to(direction, dim);
    Ok(Some(JointSpec {
        body1: ra.body,
        body2: rb.body,
        frame1: Frame {
            origin: ra.local + (xb - xa),
            rotation,
        },
        frame2: Frame {
            origin: rb.local,
            rotation,
        },
        kind: JointKind::Generic {
            locked: [false; 6],
            motors: vec![Motor {
                axis: 0,
                stiffness: g.stiffness,
                damping: g.damping,
            }],
        },
        refit: [false; 6],
    }))
}

/// An axial group as a rapier spring joint of the undeformed length; `None` between nodes of
/// one body.
fn axial(
    scene: &Scene,
    nodes: &[NodeRef],
    g: &Group,
    pair: &[NodeId; 2],
) -> Result<Option<JointSpec>, EngineError> {
    let (mut a, mut b) = (pair[0], pair[1]);
    if nodes[b].body == 0 {
        std::mem::swap(&mut a, &mut b);
    }
    let (ra, rb) = (nodes[a], nodes[b]);
    if ra.body == rb.body {
        return Ok(None);
    }
    let rest = (scene.nodes[b].position - scene.nodes[a].position).norm();
    if rest <= 0.0 {
        return unsupported(format!(
            "axial element between coincident nodes `{}` and `{}`",
            scene.nodes[a].name, scene.nodes[b].name
        ));
    }
    Ok(Some(JointSpec {
        body1: ra.body,
        body2: rb.body,
        frame1: Frame {
            origin: ra.local,
            rotation: UnitQuaternion::identity(),
        },
        frame2: Frame {
            origin: rb.local,
            rotation: UnitQuaternion::identity(),
        },
        kind: JointKind::Spring {
            rest,
            stiffness: g.stiffness,
            damping: g.damping,
        },
        refit: [false; 6],
    }))
}
