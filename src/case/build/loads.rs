//! Loads, and initial velocities; each must do something in the steps the case runs.

use super::{Builder, err, in_range};
use crate::case::file::CaseFile;
use crate::scene::*;
use nalgebra::Vector3;

/// The case's point loads, in file order.
pub(super) fn loads(b: &Builder, case: &CaseFile) -> Result<Vec<PointLoad>, SceneError> {
    let mut loads = Vec::new();
    for (i, l) in case.loads.iter().enumerate() {
        let field = format!("loads[{i}].amplitude");
        let amplitude = match &l.amplitude {
            Some(table) => Some(amplitude(&field, table, case)?),
            None => None,
        };
        loads.push(PointLoad {
            node: b.node(&format!("loads[{i}].node"), &l.node)?,
            force: b.vector(&format!("loads[{i}].force"), &l.force)?,
            amplitude,
        });
    }
    Ok(loads)
}

/// A load's amplitude table: at least two `[t, a]` points, times ≥ 0 and strictly
/// increasing, values finite and not all 0; only in a case whose steps are all dynamic (a
/// static step's loads are constant).
fn amplitude(field: &str, table: &[Vec<f64>], case: &CaseFile) -> Result<Amplitude, SceneError> {
    if case.steps.iter().any(|s| s.kind != "dynamic") {
        return err(
            field,
            "a load with an amplitude needs every step to be dynamic (a static step's loads are constant)",
        );
    }
    if table.len() < 2 {
        return err(
            field,
            format!(
                "has {} point(s); give at least two [t, a] points (a constant load needs no amplitude)",
                table.len()
            ),
        );
    }
    let mut points = Vec::with_capacity(table.len());
    for (j, p) in table.iter().enumerate() {
        let at = format!("{field}[{j}]");
        let &[t, a] = p.as_slice() else {
            return err(at, format!("has {} numbers; each point is [t, a]", p.len()));
        };
        let (t, a) = (in_range(&at, t)?, in_range(&at, a)?);
        if t < 0.0 {
            return err(at, format!("time {t} is before the start (t = 0)"));
        }
        if let Some(&(before, _)) = points.last()
            && t <= before
        {
            return err(
                at,
                format!(
                    "time {t} does not increase (the point before is at {before}); times must increase strictly"
                ),
            );
        }
        points.push((t, a));
    }
    if points.iter().all(|(_, a)| *a == 0.0) {
        return err(
            field,
            "is 0 at every point, so the load does nothing; remove it",
        );
    }
    Ok(Amplitude { points })
}

/// The case's initial velocities, in file order: at free or reference nodes (angular ones at
/// reference nodes only), at most one per node.
pub(super) fn initial_velocities(
    b: &Builder,
    case: &CaseFile,
    nodes: &[Node],
) -> Result<Vec<InitialVelocity>, SceneError> {
    let mut initial_velocities = Vec::new();
    for (i, v) in case.initial_velocities.iter().enumerate() {
        let field = format!("initial_velocities[{i}]");
        let node = b.node(&format!("{field}.node"), &v.node)?;
        if matches!(nodes[node].attachment, Attachment::OnBody(_)) {
            return err(
                format!("{field}.node"),
                "give a body's initial velocity at its reference node",
            );
        }
        let velocity = match &v.velocity {
            Some(x) => b.vector(&format!("{field}.velocity"), x)?,
            None => Vector3::zeros(),
        };
        let angular = match &v.angular {
            Some(w) => {
                if !matches!(nodes[node].attachment, Attachment::Reference(_)) {
                    return err(
                        format!("{field}.angular"),
                        "only a body's reference node has an angular velocity",
                    );
                }
                b.angular(&format!("{field}.angular"), w)?
            }
            None => Vector3::zeros(),
        };
        if initial_velocities
            .iter()
            .any(|v: &InitialVelocity| v.node == node)
        {
            return err(
                format!("{field}.node"),
                format!("node `{}` already has an initial velocity", v.node),
            );
        }
        initial_velocities.push(InitialVelocity {
            node,
            velocity,
            angular,
        });
    }
    Ok(initial_velocities)
}

/// Initial velocities act at the first dynamic step: not along a DOF held there.
pub(super) fn initial_velocities_move_free_dofs(
    steps: &[Step],
    nodes: &[Node],
    initial_velocities: &[InitialVelocity],
) -> Result<(), SceneError> {
    if let Some(first) = steps
        .iter()
        .find(|s| matches!(s.kind, StepKind::Dynamic { .. }))
    {
        for (vi, iv) in initial_velocities.iter().enumerate() {
            let frame = &nodes[iv.node].frame;
            for c in first.conditions.iter().filter(|c| c.node == iv.node) {
                let axis = frame.column(c.dof.axis()).into_owned();
                let (along, key) = match c.dof {
                    Dof::Translation(_) => (iv.velocity.dot(&axis), "velocity"),
                    Dof::Rotation(_) => (iv.angular.dot(&axis), "angular"),
                };
                if along != 0.0 {
                    return err(
                        format!("initial_velocities[{vi}].{key}"),
                        format!(
                            "moves node `{}` along {}, which the first dynamic step holds; make that component 0",
                            nodes[iv.node].name, c.dof
                        ),
                    );
                }
            }
        }
    }
    Ok(())
}

/// A load must act on some free DOF in some dynamic step, or it does nothing.
pub(super) fn loads_act_on_free_dofs(
    dim: Dimension,
    steps: &[Step],
    nodes: &[Node],
    bodies: &[RigidBody],
    loads: &[PointLoad],
) -> Result<(), SceneError> {
    for (li, load) in loads.iter().enumerate() {
        if load.force == Vector3::zeros() {
            return err(
                format!("loads[{li}].force"),
                "is zero; give a non-zero force or remove the load",
            );
        }
        let node = &nodes[load.node];
        let (anchor, arm, translations_of) = match node.attachment {
            Attachment::Free => (load.node, Vector3::zeros(), load.node),
            Attachment::Reference(b) | Attachment::OnBody(b) => {
                let r = bodies[b].reference;
                (r, node.position - nodes[r].position, r)
            }
        };
        let moment = arm.cross(&load.force);
        let rotations = !matches!(node.attachment, Attachment::Free);
        let works = steps.iter().any(|step| {
            matches!(step.kind, StepKind::Dynamic { .. })
                && Dof::all(dim, rotations).into_iter().any(|dof| {
                    let held = step
                        .conditions
                        .iter()
                        .any(|c| c.node == anchor && c.dof == dof);
                    let axis = nodes[translations_of].frame.column(dof.axis()).into_owned();
                    let along = match dof {
                        Dof::Translation(_) => load.force.dot(&axis),
                        Dof::Rotation(_) => moment.dot(&axis),
                    };
                    !held && along.abs() > 0.0
                })
        });
        if !works {
            return err(
                format!("loads[{li}].force"),
                format!(
                    "acts on node `{}` only along held DOFs in every dynamic step, so it does nothing; free a DOF it acts on or remove it",
                    node.name
                ),
            );
        }
    }
    Ok(())
}
