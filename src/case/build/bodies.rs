//! Rigid bodies: their reference nodes, and their mass properties about them.

use super::{Builder, err, number};
use crate::case::file::{BodyTable, CaseFile};
use crate::scene::*;
use nalgebra::{Matrix3, Vector3};

/// The case's rigid bodies, in file order; each one's reference node is marked as such.
pub(super) fn bodies(
    b: &Builder,
    case: &CaseFile,
    nodes: &mut [Node],
) -> Result<Vec<RigidBody>, SceneError> {
    let mut bodies = Vec::with_capacity(case.bodies.len());
    for (i, body) in case.bodies.iter().enumerate() {
        bodies.push(rigid_body(b, case, nodes, i, body)?);
    }
    Ok(bodies)
}

/// Body `i`: its reference node (free, not fixed, of no other body), and its mass, centre and
/// inertia about the reference node from its lumped values and the point masses on its nodes.
fn rigid_body(
    b: &Builder,
    case: &CaseFile,
    nodes: &mut [Node],
    i: BodyId,
    body: &BodyTable,
) -> Result<RigidBody, SceneError> {
    let field = format!("bodies[{i}]");
    let reference = b.node(&format!("{field}.reference"), &body.reference)?;
    match nodes[reference].attachment {
        Attachment::OnBody(other) if other != i => {
            return err(
                format!("{field}.reference"),
                format!("node `{}` already belongs to another body", body.reference),
            );
        }
        Attachment::Reference(_) => {
            return err(
                format!("{field}.reference"),
                format!("node `{}` is already a reference node", body.reference),
            );
        }
        _ => {}
    }
    if case.nodes[reference].fixed {
        return err(
            format!("{field}.reference"),
            "a reference node cannot be `fixed`; hold its DOFs in the steps",
        );
    }
    nodes[reference].attachment = Attachment::Reference(i);
    let lumped_mass = match body.mass {
        Some(m) => b.positive(&format!("{field}.mass"), m, "a mass")?,
        None => 0.0,
    };
    let lumped_inertia = match &body.inertia {
        None => Matrix3::zeros(),
        Some(v) => inertia(b, &format!("{field}.inertia"), v)?,
    };
    let origin = nodes[reference].position;
    let mut mass = lumped_mass + nodes[reference].mass;
    let mut first = Vector3::zeros();
    let mut inertia_o = lumped_inertia;
    for n in nodes.iter() {
        if n.attachment == Attachment::OnBody(i) && n.mass > 0.0 {
            let r = n.position - origin;
            mass += n.mass;
            first += n.mass * r;
            inertia_o += n.mass * (Matrix3::identity() * r.norm_squared() - r * r.transpose());
        }
    }
    if mass <= 0.0 {
        return err(
            format!("{field}.mass"),
            "the body has no mass: give `mass` or put point masses on its nodes",
        );
    }
    Ok(RigidBody {
        name: body.id.clone(),
        reference,
        mass,
        centre_offset: first / mass,
        inertia: inertia_o,
    })
}

/// A body's lumped inertia as the file gives it: in 2D a number (about z), in 3D the
/// diagonal or the full symmetric matrix; positive semi-definite.
fn inertia(b: &Builder, field: &str, v: &toml::Value) -> Result<Matrix3<f64>, SceneError> {
    let bad = || {
        err(
            field,
            match b.dim {
                Dimension::Two => "in 2D the inertia is a number (about z)",
                Dimension::Three => "in 3D the inertia is [Ixx, Iyy, Izz] or a 3×3 matrix",
            },
        )
    };
    let m = match (b.dim, v) {
        (Dimension::Two, toml::Value::Float(_) | toml::Value::Integer(_)) => {
            let i = number(field, v)?;
            Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, i))
        }
        (Dimension::Three, toml::Value::Array(rows)) if rows.len() == 3 => {
            if rows.iter().all(|r| r.is_array()) {
                let mut m = Matrix3::zeros();
                for (i, r) in rows.iter().enumerate() {
                    let r = r.as_array().unwrap();
                    if r.len() != 3 {
                        return bad();
                    }
                    for (j, x) in r.iter().enumerate() {
                        m[(i, j)] = number(field, x)?;
                    }
                }
                if (m - m.transpose()).abs().max() > 1e-12 * m.abs().max() {
                    return err(field, "the inertia matrix must be symmetric");
                }
                m
            } else {
                let d = rows
                    .iter()
                    .map(|x| number(field, x))
                    .collect::<Result<Vec<_>, _>>()?;
                Matrix3::from_diagonal(&Vector3::new(d[0], d[1], d[2]))
            }
        }
        _ => return bad(),
    };
    if m.symmetric_eigenvalues().iter().any(|&e| e < 0.0) {
        return err(field, "the inertia must be positive semi-definite");
    }
    Ok(m)
}
