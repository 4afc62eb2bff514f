//! Building a validated [`Scene`] from a parsed [`CaseFile`]: every physical check a case must
//! pass, each error naming the key path of the offending field.

use super::file::*;
use crate::contract;
use crate::scene::*;
use nalgebra::{Matrix3, Vector3};
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

struct Builder<'a> {
    dim: Dimension,
    node_index: HashMap<&'a str, NodeId>,
    body_index: HashMap<&'a str, BodyId>,
}

impl<'a> Builder<'a> {
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

    /// The surface of a contact pair: a plane, or a solid with positive extents.
    fn surface(&self, field: &str, c: &ContactPairTable) -> Result<Surface, SceneError> {
        let shape = c.shape.as_deref().unwrap_or("plane");
        let allowed: &[&str] = match shape {
            "plane" => &["face_point", "face_normal"],
            "ball" => &["centre", "radius"],
            "cuboid" => &["centre", "half_extents"],
            "capsule" => &["centre", "radius", "half_height"],
            "convex" => &["centre", "vertices"],
            other => {
                return err(
                    format!("{field}.shape"),
                    format!("`{other}`: use plane, ball, cuboid, capsule or convex"),
                );
            }
        };
        let given = [
            ("face_point", c.face_point.is_some()),
            ("face_normal", c.face_normal.is_some()),
            ("centre", c.centre.is_some()),
            ("radius", c.radius.is_some()),
            ("half_extents", c.half_extents.is_some()),
            ("half_height", c.half_height.is_some()),
            ("vertices", c.vertices.is_some()),
        ];
        for (key, present) in given {
            if present && !allowed.contains(&key) {
                return err(
                    format!("{field}.{key}"),
                    format!(
                        "a {shape} contact has no `{key}`; it takes {}",
                        allowed.join(" and ")
                    ),
                );
            }
        }
        for key in allowed {
            if !given.iter().any(|(k, present)| k == key && *present) {
                return err(
                    format!("{field}.{key}"),
                    format!("a {shape} contact needs `{key}`"),
                );
            }
        }
        let centre = || {
            self.vector(
                &format!("{field}.centre"),
                c.centre.as_deref().unwrap_or_default(),
            )
        };
        let radius = || {
            self.positive(
                &format!("{field}.radius"),
                c.radius.unwrap_or_default(),
                "a radius",
            )
        };
        Ok(match shape {
            "plane" => Surface::Plane {
                point: self.vector(
                    &format!("{field}.face_point"),
                    c.face_point.as_deref().unwrap_or_default(),
                )?,
                normal: self.unit(
                    &format!("{field}.face_normal"),
                    c.face_normal.as_deref().unwrap_or_default(),
                )?,
            },
            "ball" => Surface::Solid {
                solid: Solid::Ball { radius: radius()? },
                centre: centre()?,
            },
            "cuboid" => {
                let key = format!("{field}.half_extents");
                let h = self.vector(&key, c.half_extents.as_deref().unwrap_or_default())?;
                for i in 0..self.dim.count() {
                    self.positive(&key, h[i], "every half extent")?;
                }
                Surface::Solid {
                    solid: Solid::Cuboid { half_extents: h },
                    centre: centre()?,
                }
            }
            "convex" => {
                let corners = c
                    .vertices
                    .as_deref()
                    .unwrap_or_default()
                    .iter()
                    .enumerate()
                    .map(|(i, v)| self.vector(&format!("{field}.vertices[{i}]"), v))
                    .collect::<Result<Vec<_>, _>>()?;
                let polytope = match Polytope::new(&corners, self.dim == Dimension::Two) {
                    Ok(p) => p,
                    Err(e) => {
                        let at = match e {
                            polytope::PolytopeError::NotCorner { index, .. }
                            | polytope::PolytopeError::Straight { index, .. }
                            | polytope::PolytopeError::Repeated { index, .. } => {
                                format!("{field}.vertices[{index}]")
                            }
                            _ => format!("{field}.vertices"),
                        };
                        return err(at, e.to_string());
                    }
                };
                Surface::Solid {
                    solid: Solid::Convex {
                        polytope: std::sync::Arc::new(polytope),
                    },
                    centre: centre()?,
                }
            }
            _ => Surface::Solid {
                solid: Solid::Capsule {
                    half_height: self.positive(
                        &format!("{field}.half_height"),
                        c.half_height.unwrap_or_default(),
                        "a half height",
                    )?,
                    radius: radius()?,
                },
                centre: centre()?,
            },
        })
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

/// How an error message names a surface.
fn surface_name(surface: &Surface) -> String {
    match surface {
        Surface::Plane { .. } => "face".into(),
        Surface::Solid { solid, .. } => format!("{}'s surface", solid.name()),
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

    // Frames.
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

    // Nodes.
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

    // Bodies.
    let mut bodies = Vec::with_capacity(case.bodies.len());
    for (i, body) in case.bodies.iter().enumerate() {
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
            Some(v) => inertia(&b, &format!("{field}.inertia"), v)?,
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
        bodies.push(RigidBody {
            name: body.id.clone(),
            reference,
            mass,
            centre_offset: first / mass,
            inertia: inertia_o,
        });
    }

    // Elements.
    let elements = |list: &[ElementTable],
                    label: &str,
                    coefficient_key: &str|
     -> Result<Vec<Element>, SceneError> {
        let mut out = Vec::new();
        for (i, e) in list.iter().enumerate() {
            let field = format!("{label}s[{i}]");
            let value = match (coefficient_key, e.stiffness, e.damping) {
                ("stiffness", Some(k), None) => k,
                ("damping", None, Some(c)) => c,
                _ => {
                    return err(
                        &field,
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
            let connection = match e.kind.as_str() {
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
            };
            out.push(Element {
                name: e.id.clone().unwrap_or_else(|| format!("{label}-{i}")),
                connection,
                coefficient: value,
            });
        }
        Ok(out)
    };
    let springs = elements(&case.springs, "spring", "stiffness")?;
    let dashpots = elements(&case.dashpots, "dashpot", "damping")?;

    // Contacts.
    let mut contacts = Vec::new();
    for (i, c) in case.contacts.iter().enumerate() {
        let field = format!("contacts[{i}]");
        let node = b.node(&format!("{field}.node"), &c.node)?;
        let body = b.body(&format!("{field}.body"), &c.body)?;
        if nodes[node].attachment != Attachment::Free {
            return err(
                format!("{field}.node"),
                "the contact node must be an independent node, not part of a body",
            );
        }
        let surface = b.surface(&field, c)?;
        let initially = match c.initially.as_deref() {
            None | Some("closed") => ContactState::Closed,
            Some("open") => ContactState::Open,
            Some(other) => {
                return err(
                    format!("{field}.initially"),
                    format!("`{other}`: use closed (the node starts on the surface) or open"),
                );
            }
        };
        let restitution = match c.restitution {
            None => 1.0,
            Some(e) if e.is_finite() && (0.0..=1.0).contains(&e) => {
                in_range(&format!("{field}.restitution"), e)?
            }
            Some(e) => {
                return err(
                    format!("{field}.restitution"),
                    format!("a coefficient of restitution is in [0, 1], got {e}"),
                );
            }
        };
        let (gap, _) = surface_distance(&surface, &nodes[node].position);
        let scale = 1.0
            + nodes[node].position.norm().max(match surface {
                Surface::Plane { point, .. } => point.norm(),
                Surface::Solid { centre, .. } => centre.norm(),
            });
        let on_it = gap.abs() <= 1e-9 * scale;
        match initially {
            ContactState::Closed if !on_it => {
                return err(
                    format!("{field}.node"),
                    format!(
                        "node `{}` is {gap:e} from the {} at t = 0; a closed contact must start on it (or say `initially = \"open\"`)",
                        c.node,
                        surface_name(&surface)
                    ),
                );
            }
            ContactState::Open if gap <= 0.0 || on_it => {
                return err(
                    format!("{field}.node"),
                    format!(
                        "node `{}` is {} the {} at t = 0 (gap {gap:e}); an open contact must start clear of it (or say `initially = \"closed\"` for a node on it)",
                        c.node,
                        if on_it { "on" } else { "inside" },
                        surface_name(&surface)
                    ),
                );
            }
            _ => {}
        }
        identifier(&format!("{field}.id"), &c.id)?;
        if contacts.iter().any(|p: &ContactPair| p.name == c.id) {
            return err(
                format!("{field}.id"),
                format!("`{}` is defined twice", c.id),
            );
        }
        contacts.push(ContactPair {
            name: c.id.clone(),
            node,
            body,
            surface,
            initially,
            restitution,
        });
    }

    // Loads and initial velocities.
    let mut loads = Vec::new();
    for (i, l) in case.loads.iter().enumerate() {
        loads.push(PointLoad {
            node: b.node(&format!("loads[{i}].node"), &l.node)?,
            force: b.vector(&format!("loads[{i}].force"), &l.force)?,
        });
    }
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

    // Steps.
    if case.steps.is_empty() {
        return err("steps", "a case needs at least one dynamic step");
    }
    let mut steps = Vec::new();
    for (i, s) in case.steps.iter().enumerate() {
        let field = format!("steps[{i}]");
        let kind = match (s.kind.as_str(), s.duration) {
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
        };
        let mut conditions: Vec<BoundaryCondition> = Vec::new();
        let mut add = |c: BoundaryCondition, field: &str| -> Result<(), SceneError> {
            if let Some(prev) = conditions
                .iter()
                .find(|p| p.node == c.node && p.dof == c.dof)
            {
                if prev.value != c.value {
                    return err(
                        field,
                        format!(
                            "{} of node `{}` is both held and prescribed in this step",
                            c.dof, nodes[c.node].name
                        ),
                    );
                }
                return Ok(());
            }
            conditions.push(c);
            Ok(())
        };
        for (j, n) in case.nodes.iter().enumerate() {
            if n.fixed {
                for dof in Dof::all(dim, false) {
                    add(
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
        let dof_allowed = |node: NodeId, dof: Dof, field: &str| -> Result<(), SceneError> {
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
        };
        for (j, h) in s.hold.iter().enumerate() {
            let hf = format!("{field}.hold[{j}]");
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
                Dof::all(dim, rotations)
            } else {
                h.dofs
                    .iter()
                    .map(|d| b.dof(&format!("{hf}.dofs"), d))
                    .collect::<Result<Vec<_>, _>>()?
            };
            for dof in dofs {
                dof_allowed(node, dof, &format!("{hf}.dofs"))?;
                add(
                    BoundaryCondition {
                        node,
                        dof,
                        value: None,
                    },
                    &format!("{hf}.dofs"),
                )?;
            }
        }
        for (j, p) in s.prescribe.iter().enumerate() {
            let pf = format!("{field}.prescribe[{j}]");
            if matches!(kind, StepKind::Dynamic { .. }) {
                return err(
                    pf,
                    "prescribed displacements are supported in static steps only; hold the DOF in the dynamic step",
                );
            }
            let node = b.node(&format!("{pf}.node"), &p.node)?;
            let dof = b.dof(&format!("{pf}.dof"), &p.dof)?;
            dof_allowed(node, dof, &format!("{pf}.dof"))?;
            if !p.value.is_finite() {
                return err(format!("{pf}.value"), "must be finite");
            }
            in_range(&format!("{pf}.value"), p.value)?;
            add(
                BoundaryCondition {
                    node,
                    dof,
                    value: Some(p.value),
                },
                &format!("{pf}.dof"),
            )?;
        }
        steps.push(Step { kind, conditions });
    }
    if !steps
        .iter()
        .any(|s| matches!(s.kind, StepKind::Dynamic { .. }))
    {
        return err("steps", "a case needs at least one dynamic step");
    }

    // Every free DOF of a dynamic step needs mass.
    for (si, step) in steps.iter().enumerate() {
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
        for (bi, body) in bodies.iter().enumerate() {
            if dim == Dimension::Three || body.inertia[(2, 2)] > 0.0 {
                // 3D: checked below per free rotation.
            }
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
    }

    // Initial velocities act at the first dynamic step: not along a DOF held there.
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

    // A load must act on some free DOF in some dynamic step, or it does nothing.
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

    // Output.
    if case.output.rows < contract::MIN_ROWS {
        return err(
            "output.rows",
            format!("is {}; the contract needs at least 200", case.output.rows),
        );
    }
    let mut columns = Vec::new();
    for (i, c) in case.output.columns.iter().enumerate() {
        let field = format!("output.columns[{i}]");
        let set = [
            c.displacement.is_some(),
            c.velocity.is_some(),
            c.rotation.is_some(),
            c.contact_force.is_some(),
            c.gap.is_some(),
            c.zero.is_some(),
        ]
        .iter()
        .filter(|x| **x)
        .count();
        if set != 1 {
            return err(
                &field,
                "give exactly one of displacement, velocity, rotation, contact_force, gap, zero",
            );
        }
        let direction = |c: &ColumnTable| -> Result<Vector3<f64>, SceneError> {
            match &c.direction {
                Some(d) => b.unit(&format!("{field}.direction"), d),
                None => err(
                    format!("{field}.direction"),
                    "this column needs `direction`",
                ),
            }
        };
        let probe = if let Some(n) = &c.displacement {
            Probe::Displacement {
                node: b.node(&format!("{field}.displacement"), n)?,
                direction: direction(c)?,
            }
        } else if let Some(n) = &c.velocity {
            Probe::Velocity {
                node: b.node(&format!("{field}.velocity"), n)?,
                direction: direction(c)?,
            }
        } else if let Some(name) = &c.rotation {
            let axis = match (&c.axis, dim) {
                (None, _) => Vector3::z(),
                (Some(_), Dimension::Two) => {
                    return err(
                        format!("{field}.axis"),
                        "a 2D rotation is about z; drop `axis`",
                    );
                }
                (Some(a), Dimension::Three) => b.unit(&format!("{field}.axis"), a)?,
            };
            Probe::Rotation {
                body: b.body(&format!("{field}.rotation"), name)?,
                axis,
            }
        } else if let Some((key, name)) = c
            .contact_force
            .as_ref()
            .map(|n| ("contact_force", n))
            .or(c.gap.as_ref().map(|n| ("gap", n)))
        {
            let Some(k) = contacts.iter().position(|p| &p.name == name) else {
                return err(
                    format!("{field}.{key}"),
                    format!("names contact `{name}`, which the case does not define"),
                );
            };
            if key == "gap" {
                Probe::Gap { contact: k }
            } else {
                Probe::ContactForce { contact: k }
            }
        } else {
            Probe::Zero {
                reason: c.zero.clone().unwrap_or_default(),
            }
        };
        identifier(&format!("{field}.name"), &c.name)?;
        if c.name == "t"
            || contract::ENERGY_COLUMNS.contains(&c.name.as_str())
            || c.name == contract::VALID_COLUMN
        {
            return err(
                format!("{field}.name"),
                format!(
                    "`{}` is a column an engine adds (t, {}, {}); choose another name",
                    c.name,
                    contract::ENERGY_COLUMNS.join(", "),
                    contract::VALID_COLUMN
                ),
            );
        }
        if columns.iter().any(|x: &Column| x.name == c.name) {
            return err(
                format!("{field}.name"),
                format!("`{}` is already a column", c.name),
            );
        }
        columns.push(Column {
            name: c.name.clone(),
            probe,
        });
    }
    let contract = contract::columns(family);
    for (i, name) in contract.iter().enumerate() {
        let got = columns.get(i).map(|c| c.name.as_str());
        if got != Some(*name) {
            return err(
                format!("output.columns[{i}]"),
                format!(
                    "is {}, but column {} of a {} case must be `{name}` (the contract: {})",
                    got.map_or("missing".to_string(), |g| format!("`{g}`")),
                    i + 1,
                    family.name(),
                    contract.join(", ")
                ),
            );
        }
    }

    // Settings.
    let t = &case.time;
    if t.tolerance.is_some()
        && (t.increment.is_some() || t.accuracy.is_some() || t.safety.is_some())
    {
        return err(
            "time.tolerance",
            "chooses the increment itself: give no `increment`, `accuracy` or `safety` with it",
        );
    }
    if t.safety.is_some() && (t.increment.is_some() || t.accuracy.is_some()) {
        return err(
            "time.safety",
            "applies only when neither `increment` nor `accuracy` is given; remove one",
        );
    }
    let increment = match (t.increment, t.accuracy) {
        (Some(_), Some(_)) => {
            return err("time", "give `increment` or `accuracy`, not both");
        }
        (Some(h), None) => IncrementRule::Given(b.positive("time.increment", h, "an increment")?),
        (None, Some(a)) => {
            IncrementRule::Accuracy(b.positive("time.accuracy", a, "an accuracy")?)
        }
        (None, None) if t.tolerance.is_some() => IncrementRule::Tolerance(b.positive(
            "time.tolerance",
            t.tolerance.unwrap_or(0.0),
            "a tolerance",
        )?),
        (None, None) => {
            let safety = t.safety.unwrap_or(DEFAULT_SAFETY);
            if !(safety > 0.0 && safety <= 1.0) {
                return err("time.safety", format!("must be in (0, 1], got {safety}"));
            }
            in_range("time.safety", safety)?;
            IncrementRule::Stable { safety }
        }
    };
    let damping = match t.damping.as_deref() {
        None | Some("centred") => DampingTreatment::Centred,
        Some("lagged") => DampingTreatment::Lagged,
        Some(other) => return err("time.damping", format!("`{other}`: use centred or lagged")),
    };
    let c = &case.contact;
    let penalty = match (c.penalty_stiffness, c.penalty_ratio) {
        (Some(_), Some(_)) => {
            return err(
                "contact",
                "give `penalty_stiffness` or `penalty_ratio`, not both",
            );
        }
        (Some(k), None) => {
            PenaltyRule::Stiffness(b.positive("contact.penalty_stiffness", k, "k_p")?)
        }
        (None, Some(r)) => PenaltyRule::Ratio(b.positive("contact.penalty_ratio", r, "a ratio")?),
        (None, None) => PenaltyRule::Ratio(DEFAULT_PENALTY_RATIO),
    };
    let contact_start = match c.start.as_deref() {
        None | Some("consistent") => ContactStart::Consistent,
        Some("touching") => ContactStart::Touching,
        Some(other) => {
            return err(
                "contact.start",
                format!("`{other}`: use consistent or touching"),
            );
        }
    };

    let mut tolerances = std::collections::BTreeMap::new();
    for (engine, value) in &case.tolerances {
        let field = format!("tolerances.{engine}");
        let v = number(&field, value)?;
        tolerances.insert(engine.clone(), b.positive(&field, v, "a tolerance")?);
    }

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
        settings: SceneSettings {
            increment,
            damping,
            penalty,
            contact_start,
        },
        tolerances,
        sweep: case.sweep,
    })
}

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
