//! Frames, and nodes with their point masses.

use super::{Builder, err};
use crate::case::file::CaseFile;
use crate::scene::*;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

/// The case's frames by id: each an orthonormal, right-handed basis (columns x, y, z).
pub(super) fn frames<'a>(
    b: &Builder,
    case: &'a CaseFile,
) -> Result<HashMap<&'a str, Matrix3<f64>>, SceneError> {
    let dim = b.dim;
    let mut frames: HashMap<&str, Matrix3<f64>> = HashMap::new();
    for (i, f) in case.frames.iter().enumerate() {
        let field = format!("frames[{i}]");
        let x = b.unit(&format!("{field}.x_axis"), &f.x_axis)?;
        let (y, z) = match (dim, &f.y_axis) {
            (Dimension::Two, None) => {
                let y = Vector3::new(-x.y, x.x, 0.0);
                (y, Vector3::z())
            }
            (Dimension::Two, Some(_)) => {
                return err(format!("{field}.y_axis"), "a 2D frame takes only x_axis");
            }
            (Dimension::Three, Some(y)) => {
                let y = b.unit(&format!("{field}.y_axis"), y)?;
                if parallel(&x, &y) {
                    return err(format!("{field}.y_axis"), "is parallel to x_axis");
                }
                let y = (y - x * x.dot(&y)).normalize();
                (y, x.cross(&y))
            }
            (Dimension::Three, None) => {
                return err(format!("{field}.y_axis"), "a 3D frame needs y_axis");
            }
        };
        if frames
            .insert(f.id.as_str(), Matrix3::from_columns(&[x, y, z]))
            .is_some()
        {
            return err(
                format!("{field}.id"),
                format!("`{}` is defined twice", f.id),
            );
        }
    }
    Ok(frames)
}

/// The case's nodes, in file order, each with the sum of the point masses put on it.
pub(super) fn nodes(
    b: &Builder,
    case: &CaseFile,
    frames: &HashMap<&str, Matrix3<f64>>,
) -> Result<Vec<Node>, SceneError> {
    let mut nodes = Vec::with_capacity(case.nodes.len());
    for (i, n) in case.nodes.iter().enumerate() {
        let field = format!("nodes[{i}]");
        let position = b.vector(&format!("{field}.at"), &n.at)?;
        let attachment = match &n.body {
            None => Attachment::Free,
            Some(name) => Attachment::OnBody(b.body(&format!("{field}.body"), name)?),
        };
        let frame = match &n.frame {
            None => Matrix3::identity(),
            Some(name) => *frames.get(name.as_str()).ok_or_else(|| SceneError {
                field: format!("{field}.frame"),
                message: format!("names frame `{name}`, which the case does not define"),
            })?,
        };
        if n.fixed && n.body.is_some() {
            return err(
                format!("{field}.fixed"),
                "a body's material point cannot be fixed; hold the body's reference node",
            );
        }
        nodes.push(Node {
            name: n.id.clone(),
            position,
            attachment,
            frame,
            mass: 0.0,
        });
    }
    for (i, m) in case.masses.iter().enumerate() {
        let id = b.node(&format!("masses[{i}].node"), &m.node)?;
        nodes[id].mass += b.positive(&format!("masses[{i}].mass"), m.mass, "a mass")?;
    }
    Ok(nodes)
}
