//! Steps: static or dynamic, and the DOFs each holds or prescribes; every DOF a dynamic step
//! leaves free must have mass.

use super::{Builder, err, in_range};
use crate::case::file::{CaseFile, HoldTable, PrescribeTable, StepTable};
use crate::scene::*;

/// The case's steps, in file order; at least one is dynamic.
pub(super) fn steps(b: &Builder, case: &CaseFile, nodes: &[Node]) -> Result<Vec<Step>, SceneError> {
    if case.steps.is_empty() {
        return err("steps", "a case needs at least one dynamic step");
    }
    let mut steps = Vec::new();
    for (i, s) in case.steps.iter().enumerate() {
        steps.push(step(b, case, nodes, i, s)?);
    }
    if !steps
        .iter()
        .any(|s| matches!(s.kind, StepKind::Dynamic { .. }))
    {
        return err("steps", "a case needs at least one dynamic step");
    }
    Ok(steps)
}

/// Step `i`: its kind, and its conditions: the fixed nodes' translations, then what it holds,
/// then what it prescribes.
fn step(
    b: &Builder,
    case: &CaseFile,
    nodes: &[Node],
    i: usize,
    s: &StepTable,
) -> Result<Step, SceneError> {
    let field = format!("steps[{i}]");
    let kind = step_kind(b, &field, s)?;
    let mut conditions = Conditions {
        nodes,
        list: Vec::new(),
    };
    for (j, n) in case.nodes.iter().enumerate() {
        if n.fixed {
            for dof in Dof::all(b.dim, false) {
                conditions.add(
                    BoundaryCondition {
                        node: j,
                        dof,
                        value: None,
                    },
                    &format!("nodes[{j}].fixed"),
                )?;
            }
        }
    }
    for (j, h) in s.hold.iter().enumerate() {
        hold(b, &format!("{field}.hold[{j}]"), h, &mut conditions)?;
    }
    for (j, p) in s.prescribe.iter().enumerate() {
        prescribe(
            b,
            &format!("{field}.prescribe[{j}]"),
            p,
            kind,
            &mut conditions,
        )?;
    }
    Ok(Step {
        kind,
        conditions: conditions.list,
    })
}

/// A step's kind: static (no duration) or dynamic (a positive duration).
fn step_kind(b: &Builder, field: &str, s: &StepTable) -> Result<StepKind, SceneError> {
    Ok(match (s.kind.as_str(), s.duration) {
        ("static", None) => StepKind::Static,
        ("static", Some(_)) => {
            return err(
                format!("{field}.duration"),
                "a static step takes no duration",
            );
        }
        ("dynamic", Some(d)) => StepKind::Dynamic {
            duration: b.positive(&format!("{field}.duration"), d, "a duration")?,
        },
        ("dynamic", None) => {
            return err(
                format!("{field}.duration"),
                "a dynamic step needs `duration`",
            );
        }
        (other, _) => {
            return err(
                format!("{field}.kind"),
                format!("`{other}`: use static or dynamic"),
            );
        }
    })
}

/// The conditions of one step as they are added.
struct Conditions<'n> {
    nodes: &'n [Node],
    list: Vec<BoundaryCondition>,
}

impl Conditions<'_> {
    /// Add `c`: a DOF held twice is held once; a DOF held and prescribed, or prescribed two
    /// values, is an error at `field`.
    fn add(&mut self, c: BoundaryCondition, field: &str) -> Result<(), SceneError> {
        if let Some(prev) = self
            .list
            .iter()
            .find(|p| p.node == c.node && p.dof == c.dof)
        {
            if prev.value != c.value {
                return err(
                    field,
                    format!(
                        "{} of node `{}` is both held and prescribed in this step",
                        c.dof, self.nodes[c.node].name
                    ),
                );
            }
            return Ok(());
        }
        self.list.push(c);
        Ok(())
    }
}

/// The DOFs a hold names (`["all"]`: every DOF of its node), each one the node has.
fn hold(
    b: &Builder,
    hf: &str,
    h: &HoldTable,
    conditions: &mut Conditions,
) -> Result<(), SceneError> {
    let nodes = conditions.nodes;
    let node = b.node(&format!("{hf}.node"), &h.node)?;
    let rotations = matches!(nodes[node].attachment, Attachment::Reference(_));
    let dofs = if h.dofs.is_empty() {
        return err(
            format!("{hf}.dofs"),
            "is empty: name the held DOFs (ux, uy, uz, rx, ry, rz) or [\"all\"]",
        );
    } else if h.dofs.iter().any(|d| d == "all") {
        if h.dofs.len() > 1 {
            return err(
                format!("{hf}.dofs"),
                "\"all\" already holds every DOF; give it alone",
            );
        }
        Dof::all(b.dim, rotations)
    } else {
        h.dofs
            .iter()
            .map(|d| b.dof(&format!("{hf}.dofs"), d))
            .collect::<Result<Vec<_>, _>>()?
    };
    for dof in dofs {
        dof_allowed(nodes, node, dof, &format!("{hf}.dofs"))?;
        conditions.add(
            BoundaryCondition {
                node,
                dof,
                value: None,
            },
            &format!("{hf}.dofs"),
        )?;
    }
    Ok(())
}

/// A prescribed displacement: in a static step, of a DOF its node has, finite.
fn prescribe(
    b: &Builder,
    pf: &str,
    p: &PrescribeTable,
    kind: StepKind,
    conditions: &mut Conditions,
) -> Result<(), SceneError> {
    if matches!(kind, StepKind::Dynamic { .. }) {
        return err(
            pf,
            "prescribed displacements are supported in static steps only; hold the DOF in the dynamic step",
        );
    }
    let node = b.node(&format!("{pf}.node"), &p.node)?;
    let dof = b.dof(&format!("{pf}.dof"), &p.dof)?;
    dof_allowed(conditions.nodes, node, dof, &format!("{pf}.dof"))?;
    if !p.value.is_finite() {
        return err(format!("{pf}.value"), "must be finite");
    }
    in_range(&format!("{pf}.value"), p.value)?;
    conditions.add(
        BoundaryCondition {
            node,
            dof,
            value: Some(p.value),
        },
        &format!("{pf}.dof"),
    )
}

/// A node has the DOF a step constrains: not a body's material point, and a rotation only at a
/// reference node.
fn dof_allowed(nodes: &[Node], node: NodeId, dof: Dof, field: &str) -> Result<(), SceneError> {
    match nodes[node].attachment {
        Attachment::OnBody(_) => err(
            field,
            format!(
                "node `{}` is a material point of a body; constrain the body at its reference node",
                nodes[node].name
            ),
        ),
        Attachment::Free if matches!(dof, Dof::Rotation(_)) => err(
            field,
            format!(
                "node `{}` has no rotational DOF (it is not a reference node)",
                nodes[node].name
            ),
        ),
        _ => Ok(()),
    }
}

/// Every free DOF of a dynamic step needs mass: step by step, the free nodes, then the
/// bodies' free rotations.
pub(super) fn every_free_dof_has_mass(
    dim: Dimension,
    steps: &[Step],
    nodes: &[Node],
    bodies: &[RigidBody],
) -> Result<(), SceneError> {
    for (si, step) in steps.iter().enumerate() {
        free_nodes_have_mass(dim, si, step, nodes)?;
        free_rotations_have_inertia(dim, si, step, nodes, bodies)?;
    }
    Ok(())
}

/// A free node without mass is held in every translation in dynamic step `si`.
fn free_nodes_have_mass(
    dim: Dimension,
    si: usize,
    step: &Step,
    nodes: &[Node],
) -> Result<(), SceneError> {
    for (ni, n) in nodes.iter().enumerate() {
        if n.attachment != Attachment::Free || n.mass > 0.0 {
            continue;
        }
        let held = Dof::all(dim, false)
            .into_iter()
            .all(|d| step.conditions.iter().any(|c| c.node == ni && c.dof == d));
        if !held && matches!(step.kind, StepKind::Dynamic { .. }) {
            return err(
                format!("steps[{si}].hold"),
                format!(
                    "node `{}` has no mass but is not held in every DOF; give it a mass or hold it",
                    n.name
                ),
            );
        }
    }
    Ok(())
}

/// A body has inertia about every rotation step `si` leaves free (in 2D, about z).
fn free_rotations_have_inertia(
    dim: Dimension,
    si: usize,
    step: &Step,
    nodes: &[Node],
    bodies: &[RigidBody],
) -> Result<(), SceneError> {
    for (bi, body) in bodies.iter().enumerate() {
        for axis in 0..3 {
            if dim == Dimension::Two && axis != 2 {
                continue;
            }
            let free = !step
                .conditions
                .iter()
                .any(|c| c.node == body.reference && c.dof == Dof::Rotation(axis));
            let frame = nodes[body.reference].frame;
            let a = frame.column(axis).into_owned();
            if free && (a.transpose() * body.inertia * a)[0] <= 0.0 {
                return err(
                    format!("bodies[{bi}].inertia"),
                    format!(
                        "rotation r{} of body `{}` is free in steps[{si}] but its inertia about that axis is 0: give `inertia`, put point masses on the body, or hold r{}",
                        ["x", "y", "z"][axis],
                        body.name,
                        ["x", "y", "z"][axis]
                    ),
                );
            }
        }
    }
    Ok(())
}
