//! Contact pairs: a node against a body's surface (a plane or a convex solid), and how the
//! pair starts.

use super::{Builder, err, identifier, in_range};
use crate::case::file::{CaseFile, ContactPairTable};
use crate::scene::*;
use nalgebra::Vector3;

/// The case's contact pairs, in file order, each id defined once.
pub(super) fn contacts(
    b: &Builder,
    case: &CaseFile,
    nodes: &[Node],
) -> Result<Vec<ContactPair>, SceneError> {
    let mut contacts = Vec::new();
    for (i, c) in case.contacts.iter().enumerate() {
        let pair = contact_pair(b, nodes, i, c, &contacts)?;
        contacts.push(pair);
    }
    Ok(contacts)
}

/// Contact pair `i`: an independent node, a body's surface, and how it starts (on the surface
/// or clear of it, as it says); its id not among `earlier`.
fn contact_pair(
    b: &Builder,
    nodes: &[Node],
    i: usize,
    c: &ContactPairTable,
    earlier: &[ContactPair],
) -> Result<ContactPair, SceneError> {
    let field = format!("contacts[{i}]");
    let node = b.node(&format!("{field}.node"), &c.node)?;
    let body = b.body(&format!("{field}.body"), &c.body)?;
    let surface = b.surface(&field, c)?;
    let node_radius = node_radius(b, &field, c, nodes[node].attachment, body, &surface)?;
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
    let restitution = restitution(&field, c)?;
    let friction = friction(&field, c)?;
    starts_as_said(
        &field,
        c,
        &nodes[node].position,
        node_radius,
        &surface,
        initially,
    )?;
    identifier(&format!("{field}.id"), &c.id)?;
    if earlier.iter().any(|p: &ContactPair| p.name == c.id) {
        return err(
            format!("{field}.id"),
            format!("`{}` is defined twice", c.id),
        );
    }
    Ok(ContactPair {
        name: c.id.clone(),
        node,
        node_radius,
        body,
        surface,
        initially,
        restitution,
        friction,
    })
}

/// The radius of the ball a pair's node carries: 0 for an independent node (a particle
/// touches with the node itself); positive for a node of another body than the face's, against
/// a plane (a body's rolling shape).
fn node_radius(
    b: &Builder,
    field: &str,
    c: &ContactPairTable,
    attachment: Attachment,
    face_body: BodyId,
    surface: &Surface,
) -> Result<f64, SceneError> {
    let at = format!("{field}.node_radius");
    let Some(radius) = c.node_radius else {
        if attachment != Attachment::Free {
            return err(
                format!("{field}.node"),
                "a node of a body touches through a ball: give `node_radius` (or use an independent node)",
            );
        }
        return Ok(0.0);
    };
    let radius = b.positive(&at, radius, "a node's radius")?;
    match attachment {
        Attachment::Free => err(
            at,
            "an independent node touches with itself (a particle has no turning); a ball belongs to a body's node",
        ),
        Attachment::Reference(owner) | Attachment::OnBody(owner) if owner == face_body => err(
            format!("{field}.node"),
            "the node is on the face's own body",
        ),
        _ if !matches!(surface, Surface::Plane { .. }) => err(
            at,
            "a node's ball touches a plane face only (give `face_point` and `face_normal`)",
        ),
        _ => Ok(radius),
    }
}

/// A pair's Coulomb friction: `friction = μ` (static and kinetic alike), or `static_friction`
/// with `kinetic_friction` (0 ≤ μ_k ≤ μ_s); none given, or μ = 0: frictionless.
fn friction(field: &str, c: &ContactPairTable) -> Result<Option<Friction>, SceneError> {
    let coefficient = |key: &str, mu: f64| -> Result<f64, SceneError> {
        let at = format!("{field}.{key}");
        if !(mu.is_finite() && mu >= 0.0) {
            return err(
                at,
                format!("a friction coefficient is a finite number ≥ 0, got {mu}"),
            );
        }
        in_range(&at, mu)
    };
    let (mu_s, mu_k) = match (c.friction, c.static_friction, c.kinetic_friction) {
        (None, None, None) => return Ok(None),
        (Some(mu), None, None) => {
            let mu = coefficient("friction", mu)?;
            (mu, mu)
        }
        (Some(_), _, _) => {
            return err(
                format!("{field}.friction"),
                "give either `friction` (static and kinetic alike) or `static_friction` with `kinetic_friction`, not both",
            );
        }
        (None, Some(s), Some(k)) => (
            coefficient("static_friction", s)?,
            coefficient("kinetic_friction", k)?,
        ),
        (None, Some(_), None) => {
            return err(
                format!("{field}.static_friction"),
                "give `kinetic_friction` with it (or `friction` where the two are equal)",
            );
        }
        (None, None, Some(_)) => {
            return err(
                format!("{field}.kinetic_friction"),
                "give `static_friction` with it (or `friction` where the two are equal)",
            );
        }
    };
    if mu_k > mu_s {
        return err(
            format!("{field}.kinetic_friction"),
            format!(
                "the kinetic coefficient {mu_k} exceeds the static one {mu_s}; a sliding node cannot resist more than a stuck one"
            ),
        );
    }
    if mu_s == 0.0 {
        return Ok(None);
    }
    if mu_k == 0.0 {
        return err(
            format!("{field}.kinetic_friction"),
            "is 0 with a static coefficient above 0; a pair that resists sticking resists sliding too (give a kinetic coefficient > 0)",
        );
    }
    Ok(Some(Friction {
        static_coefficient: mu_s,
        kinetic_coefficient: mu_k,
    }))
}

/// A pair's coefficient of restitution: in [0, 1], 1 when not given.
fn restitution(field: &str, c: &ContactPairTable) -> Result<f64, SceneError> {
    Ok(match c.restitution {
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
    })
}

/// A closed pair's node starts on the surface, an open pair's clear of it.
fn starts_as_said(
    field: &str,
    c: &ContactPairTable,
    position: &Vector3<f64>,
    node_radius: f64,
    surface: &Surface,
    initially: ContactState,
) -> Result<(), SceneError> {
    let gap = surface_distance(surface, position).0 - node_radius;
    let what = if node_radius > 0.0 {
        format!("the ball (radius {node_radius}) of node `{}`", c.node)
    } else {
        format!("node `{}`", c.node)
    };
    let scale = 1.0
        + position.norm().max(match surface {
            Surface::Plane { point, .. } => point.norm(),
            Surface::Solid { centre, .. } => centre.norm(),
        });
    let on_it = gap.abs() <= 1e-9 * scale;
    match initially {
        ContactState::Closed if !on_it => {
            return err(
                format!("{field}.node"),
                format!(
                    "{what} is {gap:e} from the {} at t = 0; a closed contact must start on it (or say `initially = \"open\"`)",
                    surface_name(surface)
                ),
            );
        }
        ContactState::Open if gap <= 0.0 || on_it => {
            return err(
                format!("{field}.node"),
                format!(
                    "{what} is {} the {} at t = 0 (gap {gap:e}); an open contact must start clear of it (or say `initially = \"closed\"` for a node on it)",
                    if on_it { "on" } else { "inside" },
                    surface_name(surface)
                ),
            );
        }
        _ => {}
    }
    Ok(())
}

/// How an error message names a surface.
fn surface_name(surface: &Surface) -> String {
    match surface {
        Surface::Plane { .. } => "face".into(),
        Surface::Solid { solid, .. } => format!("{}'s surface", solid.name()),
    }
}

impl Builder<'_> {
    /// The surface of a contact pair: a plane, or a solid with positive extents.
    fn surface(&self, field: &str, c: &ContactPairTable) -> Result<Surface, SceneError> {
        let shape = c.shape.as_deref().unwrap_or("plane");
        let allowed = surface_keys(field, shape)?;
        keys_given(field, shape, allowed, c)?;
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
            "cuboid" => Surface::Solid {
                solid: self.cuboid(field, c)?,
                centre: centre()?,
            },
            "convex" => Surface::Solid {
                solid: self.convex(field, c)?,
                centre: centre()?,
            },
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

    /// A cuboid of positive half extents.
    fn cuboid(&self, field: &str, c: &ContactPairTable) -> Result<Solid, SceneError> {
        let key = format!("{field}.half_extents");
        let h = self.vector(&key, c.half_extents.as_deref().unwrap_or_default())?;
        for i in 0..self.dim.count() {
            self.positive(&key, h[i], "every half extent")?;
        }
        Ok(Solid::Cuboid { half_extents: h })
    }

    /// A convex polytope: the hull of its vertices, every one a corner.
    fn convex(&self, field: &str, c: &ContactPairTable) -> Result<Solid, SceneError> {
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
        Ok(Solid::Convex {
            polytope: std::sync::Arc::new(polytope),
        })
    }
}

/// The keys a contact of `shape` takes.
fn surface_keys(field: &str, shape: &str) -> Result<&'static [&'static str], SceneError> {
    Ok(match shape {
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
    })
}

/// A contact gives every key its shape takes, and no other.
fn keys_given(
    field: &str,
    shape: &str,
    allowed: &[&str],
    c: &ContactPairTable,
) -> Result<(), SceneError> {
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
    Ok(())
}
