//! The static steps: their prescribed displacements move the bodies, and the DOFs they leave
//! free must carry no force there (rapier has no static solve).

use super::super::steps::{Group, Placement, static_check};
use super::{BodySpec, NodeRef, twist, unsupported};
use crate::engines::EngineError;
use crate::scene::{BodyId, BoundaryCondition, Dof, NodeId, Scene};
use nalgebra::{UnitQuaternion, Vector3};

/// Where the static steps (those before `first_dynamic`) leave the bodies, each step checked
/// for forces on the DOFs it leaves free.
pub(super) fn placement(
    scene: &Scene,
    first_dynamic: usize,
    bodies: &[BodySpec],
    nodes: &[NodeRef],
    body_of_scene_body: &[usize],
    element_groups: &[Group],
) -> Result<Placement, EngineError> {
    let reference_of = |body: usize| -> Option<(BodyId, NodeId)> {
        scene
            .bodies
            .iter()
            .enumerate()
            .find(|(b, _)| body_of_scene_body[*b] == body)
            .map(|(b, sb)| (b, sb.reference))
    };
    let mut placement = Placement {
        position: bodies.iter().map(|b| b.position).collect(),
        rotation: bodies.iter().map(|b| b.rotation).collect(),
    };
    for step in &scene.steps[..first_dynamic] {
        for c in &step.conditions {
            prescribe(scene, nodes, c, &mut placement)?;
        }
        static_check(
            scene,
            step,
            nodes,
            &placement,
            element_groups,
            &reference_of,
        )?;
    }
    Ok(placement)
}

/// A prescribed displacement moves its node's body to it (a ground node may only be
/// prescribed 0); a held DOF changes nothing.
fn prescribe(
    scene: &Scene,
    nodes: &[NodeRef],
    c: &BoundaryCondition,
    placement: &mut Placement,
) -> Result<(), EngineError> {
    let Some(v) = c.value else {
        return Ok(());
    };
    let node = &scene.nodes[c.node];
    let r = nodes[c.node];
    if r.body == 0 {
        if v != 0.0 {
            return unsupported(format!(
                "node `{}` is prescribed a displacement but is ground",
                node.name
            ));
        }
        return Ok(());
    }
    match c.dof {
        Dof::Translation(i) => {
            let e: Vector3<f64> = node.frame.column(i).into_owned();
            let x0 = node.position;
            let current = (placement.point(&r) - x0).dot(&e);
            placement.position[r.body] += e * (v - current);
        }
        Dof::Rotation(i) => {
            let a: Vector3<f64> = node.frame.column(i).into_owned();
            let q = placement.rotation[r.body];
            let change = UnitQuaternion::from_scaled_axis(a * (v - twist(&q, &a)));
            placement.rotation[r.body] = change * q;
        }
    }
    Ok(())
}
