//! Springs and dashpots: what each joins, and its coefficient.

use super::{Builder, err, in_range};
use crate::case::file::ElementTable;
use crate::scene::*;

/// The springs (`label` "spring", coefficient `stiffness`) or the dashpots ("dashpot",
/// `damping`) of a case, in file order; an unnamed one is named `<label>-<index>`.
pub(super) fn elements(
    b: &Builder,
    nodes: &[Node],
    list: &[ElementTable],
    label: &str,
    coefficient_key: &str,
) -> Result<Vec<Element>, SceneError> {
    let mut out = Vec::new();
    for (i, e) in list.iter().enumerate() {
        let field = format!("{label}s[{i}]");
        let value = coefficient(&field, e, label, coefficient_key)?;
        keys_apply(&field, e, label)?;
        out.push(Element {
            name: e.id.clone().unwrap_or_else(|| format!("{label}-{i}")),
            connection: connection(b, nodes, &field, e, label)?,
            coefficient: value,
        });
    }
    Ok(out)
}

/// An element's one coefficient, `coefficient_key`: finite and >= 0.
fn coefficient(
    field: &str,
    e: &ElementTable,
    label: &str,
    coefficient_key: &str,
) -> Result<f64, SceneError> {
    let value = match (coefficient_key, e.stiffness, e.damping) {
        ("stiffness", Some(k), None) => k,
        ("damping", None, Some(c)) => c,
        _ => {
            return err(
                field,
                format!("a {label} takes exactly one coefficient: `{coefficient_key}`"),
            );
        }
    };
    if !(value.is_finite() && value >= 0.0) {
        return err(
            format!("{field}.{coefficient_key}"),
            format!("must be a finite number >= 0, got {value}"),
        );
    }
    in_range(&format!("{field}.{coefficient_key}"), value)?;
    Ok(value)
}

/// Every key an element gives applies to its kind, and it joins two different nodes.
fn keys_apply(field: &str, e: &ElementTable, label: &str) -> Result<(), SceneError> {
    let stray = match e.kind.as_str() {
        "grounded" => e.direction.as_ref().map(|_| "direction"),
        "fixed_direction" | "axial" => e.dof.as_ref().map(|_| "dof"),
        _ => None,
    }
    .or_else(|| (e.kind == "axial" && e.direction.is_some()).then_some("direction"));
    if let Some(key) = stray {
        return err(
            format!("{field}.{key}"),
            format!("does not apply to a {} {label}; remove it", e.kind),
        );
    }
    if e.nodes.len() == 2 && e.nodes[0] == e.nodes[1] {
        return err(
            format!("{field}.nodes"),
            "joins a node to itself; give two different nodes",
        );
    }
    Ok(())
}

/// What an element joins: one node to the ground along a DOF, two nodes along a fixed
/// direction, or two nodes along the line between them.
fn connection(
    b: &Builder,
    nodes: &[Node],
    field: &str,
    e: &ElementTable,
    label: &str,
) -> Result<Connection, SceneError> {
    let nodes_of = |count: usize| -> Result<Vec<NodeId>, SceneError> {
        if e.nodes.len() != count {
            return err(
                format!("{field}.nodes"),
                format!(
                    "a {} {label} joins {count} node(s), got {}",
                    e.kind,
                    e.nodes.len()
                ),
            );
        }
        e.nodes
            .iter()
            .map(|n| b.node(&format!("{field}.nodes"), n))
            .collect()
    };
    Ok(match e.kind.as_str() {
        "grounded" => {
            let n = nodes_of(1)?[0];
            let Some(dof) = &e.dof else {
                return err(format!("{field}.dof"), "a grounded element needs `dof`");
            };
            let dof = b.dof(&format!("{field}.dof"), dof)?;
            if matches!(dof, Dof::Rotation(_))
                && !matches!(nodes[n].attachment, Attachment::Reference(_))
            {
                return err(
                    format!("{field}.dof"),
                    "a rotational DOF exists only at a body's reference node",
                );
            }
            Connection::Grounded { node: n, dof }
        }
        "fixed_direction" => {
            let ns = nodes_of(2)?;
            let Some(d) = &e.direction else {
                return err(
                    format!("{field}.direction"),
                    "a fixed_direction element needs `direction`",
                );
            };
            Connection::FixedDirection {
                nodes: [ns[0], ns[1]],
                direction: b.unit(&format!("{field}.direction"), d)?,
            }
        }
        "axial" => {
            let ns = nodes_of(2)?;
            if coincident(&nodes[ns[0]].position, &nodes[ns[1]].position) {
                return err(
                    format!("{field}.nodes"),
                    "an axial element needs two nodes at different positions",
                );
            }
            Connection::Axial {
                nodes: [ns[0], ns[1]],
            }
        }
        other => {
            return err(
                format!("{field}.kind"),
                format!("`{other}`: use grounded, fixed_direction or axial"),
            );
        }
    })
}
