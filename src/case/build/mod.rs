//! Building a validated [`Scene`] from a parsed [`CaseFile`]: every physical check a case must
//! pass, each error naming the key path of the offending field.
//!
//! The scene is built in the order of the file's sections, each in its module: `nodes`
//! (frames, nodes and their point masses), `bodies`, `elements` (springs and dashpots),
//! `contacts`, `loads` (loads and initial velocities), `steps`, `output` (the columns)
//! and `settings` (time, contact, tolerances). The first error found is the one returned.

mod bodies;
mod contacts;
mod elements;
mod loads;
mod nodes;
mod output;
mod settings;
mod steps;

use super::file::*;
use crate::scene::*;
use nalgebra::Vector3;
use std::collections::HashMap;

fn err<T>(field: impl Into<String>, message: impl Into<String>) -> Result<T, SceneError> {
    Err(SceneError {
        field: field.into(),
        message: message.into(),
    })
}

/// The largest magnitude a physical number may have (masses, stiffnesses, loads, coordinates,
/// durations, ...): products of a few of them stay finite in f64, so no frequency, energy or
/// increment computed from a valid scene overflows.
pub const MAX_MAGNITUDE: f64 = 1e100;
/// The smallest non-zero magnitude a physical number may have (no denormals, and quotients of
/// a few of them stay finite).
pub const MIN_MAGNITUDE: f64 = 1e-100;

/// A finite number, zero or of magnitude within [`MIN_MAGNITUDE`, `MAX_MAGNITUDE`].
fn in_range(field: &str, v: f64) -> Result<f64, SceneError> {
    if !v.is_finite() {
        return err(field, format!("must be a finite number, got {v}"));
    }
    if v != 0.0 && !(MIN_MAGNITUDE..=MAX_MAGNITUDE).contains(&v.abs()) {
        return err(
            field,
            format!(
                "{v:e} is outside the supported magnitude range [{MIN_MAGNITUDE:e}, {MAX_MAGNITUDE:e}] (or 0); rescale the units"
            ),
        );
    }
    Ok(v)
}

/// An id used in file names and CSV headers: `[A-Za-z0-9_-]+`.
fn identifier(field: &str, id: &str) -> Result<(), SceneError> {
    if id.is_empty()
        || !id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        return err(
            field,
            format!("`{id}` is not a valid id: use letters, digits, `_` and `-` only"),
        );
    }
    Ok(())
}

/// What every section's checks read: the dimension, and the index of every node and body id.
struct Builder<'a> {
    dim: Dimension,
    node_index: HashMap<&'a str, NodeId>,
    body_index: HashMap<&'a str, BodyId>,
}

impl<'a> Builder<'a> {
    /// The builder of `case` in `dim`: every node and body id valid and defined once.
    fn new(case: &'a CaseFile, dim: Dimension) -> Result<Builder<'a>, SceneError> {
        let mut b = Builder {
            dim,
            node_index: HashMap::new(),
            body_index: HashMap::new(),
        };
        for (i, n) in case.nodes.iter().enumerate() {
            identifier(&format!("nodes[{i}].id"), &n.id)?;
            if b.node_index.insert(n.id.as_str(), i).is_some() {
                return err(
                    format!("nodes[{i}].id"),
                    format!("`{}` is defined twice", n.id),
                );
            }
        }
        for (i, body) in case.bodies.iter().enumerate() {
            identifier(&format!("bodies[{i}].id"), &body.id)?;
            if b.body_index.insert(body.id.as_str(), i).is_some() {
                return err(
                    format!("bodies[{i}].id"),
                    format!("`{}` is defined twice", body.id),
                );
            }
        }
        Ok(b)
    }

    fn vector(&self, field: &str, v: &[f64]) -> Result<Vector3<f64>, SceneError> {
        let v = self.components(field, v)?;
        for x in v.iter() {
            in_range(field, *x)?;
        }
        Ok(v)
    }

    /// The right number of finite components, any magnitude.
    fn components(&self, field: &str, v: &[f64]) -> Result<Vector3<f64>, SceneError> {
        if v.len() != self.dim.count() {
            return err(
                field,
                format!(
                    "has {} components; a {}D case needs {}",
                    v.len(),
                    self.dim.count(),
                    self.dim.count()
                ),
            );
        }
        if v.iter().any(|x| !x.is_finite()) {
            return err(field, "has a non-finite component");
        }
        Ok(Vector3::new(
            v[0],
            v[1],
            if v.len() == 3 { v[2] } else { 0.0 },
        ))
    }

    /// A direction: any finite, non-zero vector, scaled by its largest component before it is
    /// normalised (no overflow or underflow whatever its magnitude).
    fn unit(&self, field: &str, v: &[f64]) -> Result<Vector3<f64>, SceneError> {
        let v = self.components(field, v)?;
        let scale = v.amax();
        if scale == 0.0 {
            return err(field, "is a zero vector; a direction is needed");
        }
        let v = v / scale;
        Ok(v / v.norm())
    }

    fn node(&self, field: &str, name: &str) -> Result<NodeId, SceneError> {
        self.node_index.get(name).copied().map_or_else(
            || {
                err(
                    field,
                    format!("names node `{name}`, which the case does not define"),
                )
            },
            Ok,
        )
    }

    fn body(&self, field: &str, name: &str) -> Result<BodyId, SceneError> {
        self.body_index.get(name).copied().map_or_else(
            || {
                err(
                    field,
                    format!("names body `{name}`, which the case does not define"),
                )
            },
            Ok,
        )
    }

    fn dof(&self, field: &str, name: &str) -> Result<Dof, SceneError> {
        let Some(dof) = Dof::parse(name) else {
            return err(
                field,
                format!("`{name}` is not a DOF; use ux, uy, uz, rx, ry or rz"),
            );
        };
        if self.dim == Dimension::Two && !matches!(dof, Dof::Translation(0 | 1) | Dof::Rotation(2))
        {
            return err(
                field,
                format!("`{name}` does not exist in 2D; use ux, uy or rz"),
            );
        }
        Ok(dof)
    }

    fn positive(&self, field: &str, v: f64, what: &str) -> Result<f64, SceneError> {
        if !(v.is_finite() && v > 0.0) {
            return err(
                field,
                format!("{what} must be a finite number > 0, got {v}"),
            );
        }
        in_range(field, v)
    }

    fn angular(&self, field: &str, v: &toml::Value) -> Result<Vector3<f64>, SceneError> {
        match (self.dim, v) {
            (Dimension::Two, toml::Value::Float(_) | toml::Value::Integer(_)) => {
                Ok(Vector3::new(0.0, 0.0, number(field, v)?))
            }
            (Dimension::Three, toml::Value::Array(a)) => {
                let comps = a
                    .iter()
                    .map(|x| number(field, x))
                    .collect::<Result<Vec<_>, _>>()?;
                self.vector(field, &comps)
            }
            (Dimension::Two, _) => err(field, "in 2D an angular velocity is a number (about z)"),
            (Dimension::Three, _) => err(field, "in 3D an angular velocity is [wx, wy, wz]"),
        }
    }
}

fn number(field: &str, v: &toml::Value) -> Result<f64, SceneError> {
    match v {
        toml::Value::Float(x) if x.is_finite() => in_range(field, *x),
        toml::Value::Integer(i) => in_range(field, *i as f64),
        _ => err(field, format!("expected a finite number, got `{v}`")),
    }
}

/// Validate a parsed case file into a scene. `stem` is the file stem the id must match.
pub fn scene(case: &CaseFile, stem: Option<&str>) -> Result<Scene, SceneError> {
    let (family, dim) = heading(case, stem)?;
    let b = Builder::new(case, dim)?;
    let frames = nodes::frames(&b, case)?;
    let mut nodes = nodes::nodes(&b, case, &frames)?;
    let bodies = bodies::bodies(&b, case, &mut nodes)?;
    let springs = elements::elements(&b, &nodes, &case.springs, "spring", "stiffness")?;
    let dashpots = elements::elements(&b, &nodes, &case.dashpots, "dashpot", "damping")?;
    let contacts = contacts::contacts(&b, case, &nodes)?;
    let loads = loads::loads(&b, case)?;
    let initial_velocities = loads::initial_velocities(&b, case, &nodes)?;
    let steps = steps::steps(&b, case, &nodes)?;
    steps::every_free_dof_has_mass(dim, &steps, &nodes, &bodies)?;
    loads::initial_velocities_move_free_dofs(&steps, &nodes, &initial_velocities)?;
    loads::loads_act_on_free_dofs(dim, &steps, &nodes, &bodies, &loads)?;
    let columns = output::columns(&b, case, family, &contacts)?;
    let settings = settings::settings(&b, case)?;
    let tolerances = settings::tolerances(&b, case)?;
    Ok(Scene {
        id: case.id.clone(),
        title: case.title.clone(),
        family,
        dimension: dim,
        nodes,
        bodies,
        springs,
        dashpots,
        contacts,
        loads,
        initial_velocities,
        steps,
        output_rows: case.output.rows,
        columns,
        settings,
        tolerances,
        sweep: case.sweep,
    })
}

/// The case's id (which must match the file stem, when there is one), family and dimension.
fn heading(case: &CaseFile, stem: Option<&str>) -> Result<(Family, Dimension), SceneError> {
    identifier("id", &case.id)?;
    if let Some(stem) = stem
        && stem != case.id
    {
        return err(
            "id",
            format!(
                "is `{}` but the file is `{stem}.toml`; they must match",
                case.id
            ),
        );
    }
    let family = match case.family.as_str() {
        "rigid_body" => Family::RigidBody,
        "springs" => Family::Springs,
        other => {
            return err(
                "family",
                format!("`{other}`: use `rigid_body` or `springs`"),
            );
        }
    };
    let dim = match case.dimension {
        2 => Dimension::Two,
        3 => Dimension::Three,
        d => return err("dimension", format!("is {d}; use 2 or 3")),
    };
    Ok((family, dim))
}
