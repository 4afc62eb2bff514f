//! What the steps do to the plan's bodies: the static steps' placement and the check that they
//! leave no force on a free DOF (rapier has no static solve), the bodies a dynamic step holds in
//! every DOF (fixed bodies for it), and the spring and dashpot groups both need.

use super::plan::{BodyKind, BodySpec, NodeRef, twist, unsupported};
use crate::engines::EngineError;
use crate::scene::{BodyId, Connection, Dimension, Dof, NodeId, Scene, Step};
use nalgebra::{UnitQuaternion, Vector3};

/// A spring or dashpot group: the stiffness and damping summed over elements that act alike.
#[derive(Debug, Clone)]
pub(super) struct Group {
    pub(super) connection: Connection,
    pub(super) stiffness: f64,
    pub(super) damping: f64,
}

fn same_direction(a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
    (a - b).norm() <= 1e-12 || (a + b).norm() <= 1e-12
}

fn same_action(a: &Connection, b: &Connection) -> bool {
    match (a, b) {
        (
            Connection::Grounded { node: n1, dof: d1 },
            Connection::Grounded { node: n2, dof: d2 },
        ) => n1 == n2 && d1 == d2,
        (
            Connection::FixedDirection {
                nodes: a,
                direction: da,
            },
            Connection::FixedDirection {
                nodes: b,
                direction: db,
            },
        ) => {
            ((a[0] == b[0] && a[1] == b[1]) || (a[0] == b[1] && a[1] == b[0]))
                && same_direction(da, db)
        }
        (Connection::Axial { nodes: a }, Connection::Axial { nodes: b }) => {
            (a[0] == b[0] && a[1] == b[1]) || (a[0] == b[1] && a[1] == b[0])
        }
        _ => false,
    }
}

pub(super) fn groups(scene: &Scene) -> Vec<Group> {
    let mut out: Vec<Group> = Vec::new();
    for (list, spring) in [(&scene.springs, true), (&scene.dashpots, false)] {
        for e in list {
            let g = match out
                .iter_mut()
                .position(|g| same_action(&g.connection, &e.connection))
            {
                Some(i) => &mut out[i],
                None => {
                    out.push(Group {
                        connection: e.connection.clone(),
                        stiffness: 0.0,
                        damping: 0.0,
                    });
                    out.last_mut().expect("just pushed")
                }
            };
            if spring {
                g.stiffness += e.coefficient;
            } else {
                g.damping += e.coefficient;
            }
        }
    }
    out
}

/// Displacement state during the static steps: per plan body, origin and orientation.
pub(super) struct Placement {
    pub(super) position: Vec<Vector3<f64>>,
    pub(super) rotation: Vec<UnitQuaternion<f64>>,
}

impl Placement {
    pub(super) fn point(&self, r: &NodeRef) -> Vector3<f64> {
        self.position[r.body] + self.rotation[r.body] * r.local
    }
}

/// Per plan body: whether `step` holds every one of its DOFs (a rigid body's translations and
/// rotations, a particle's translations), by whatever nodes of it: the held directions span
/// them (the rank of their rows [e, p × e] for a translation along e at p, [0, a] for a rotation
/// about a). Such a body moves no more than the ground, so it is a rapier fixed body, whose mass
/// no impact sees; a dynamic body held by joints would take a share of every impulse (the
/// joints are not part of rapier's restitution pass) and its mass would enter.
pub(super) fn held_in_every_dof(
    scene: &Scene,
    step: &Step,
    nodes: &[NodeRef],
    bodies: &[BodySpec],
    placement: &Placement,
) -> Vec<bool> {
    let planar = scene.dimension == Dimension::Two;
    bodies
        .iter()
        .enumerate()
        .map(|(b, spec)| {
            let rigid = match spec.kind {
                BodyKind::Ground => return true,
                BodyKind::Particle => false,
                BodyKind::Rigid => true,
            };
            let mut rows: Vec<[f64; 6]> = Vec::new();
            for c in step.conditions.iter().filter(|c| nodes[c.node].body == b) {
                let frame = scene.nodes[c.node].frame;
                rows.push(match c.dof {
                    Dof::Translation(i) => {
                        let e: Vector3<f64> = frame.column(i).into_owned();
                        // The node's arm from the body's origin, in world axes where the
                        // static steps left the body.
                        let arm = placement.rotation[b] * nodes[c.node].local;
                        let m = arm.cross(&e);
                        [e.x, e.y, e.z, m.x, m.y, m.z]
                    }
                    Dof::Rotation(i) => {
                        let a: Vector3<f64> = frame.column(i).into_owned();
                        [0.0, 0.0, 0.0, a.x, a.y, a.z]
                    }
                });
            }
            // The body's own DOFs: 2D (x, y, rz), 3D all six; a particle its translations.
            let dofs: Vec<usize> = match (planar, rigid) {
                (true, true) => vec![0, 1, 5],
                (true, false) => vec![0, 1],
                (false, true) => (0..6).collect(),
                (false, false) => vec![0, 1, 2],
            };
            let m = nalgebra::DMatrix::from_fn(rows.len(), dofs.len(), |r, k| rows[r][dofs[k]]);
            !rows.is_empty() && m.rank(1e-9 * m.norm().max(f64::MIN_POSITIVE)) == dofs.len()
        })
        .collect()
}

/// After a static step's prescriptions: every DOF the step leaves free must carry no force.
pub(super) fn static_check(
    scene: &Scene,
    step: &Step,
    nodes: &[NodeRef],
    placement: &Placement,
    element_groups: &[Group],
    reference_of: &dyn Fn(usize) -> Option<(BodyId, NodeId)>,
) -> Result<(), EngineError> {
    let point = |n: NodeId| placement.point(&nodes[n]);
    let nb = placement.position.len();
    let mut force = vec![Vector3::<f64>::zeros(); nb];
    let mut moment = vec![Vector3::<f64>::zeros(); nb];
    let mut scale = 0.0f64;
    let apply = |n: NodeId,
                 f: Vector3<f64>,
                 force: &mut Vec<Vector3<f64>>,
                 moment: &mut Vec<Vector3<f64>>| {
        let r = nodes[n];
        force[r.body] += f;
        moment[r.body] += (point(n) - placement.position[r.body]).cross(&f);
    };
    for g in element_groups {
        let k = g.stiffness;
        if k == 0.0 {
            continue;
        }
        match &g.connection {
            Connection::Grounded {
                node,
                dof: Dof::Translation(i),
            } => {
                let e: Vector3<f64> = scene.nodes[*node].frame.column(*i).into_owned();
                let f = -k * e.dot(&(point(*node) - scene.nodes[*node].position));
                scale += f.abs();
                apply(*node, e * f, &mut force, &mut moment);
            }
            Connection::Grounded {
                node,
                dof: Dof::Rotation(i),
            } => {
                let a: Vector3<f64> = scene.nodes[*node].frame.column(*i).into_owned();
                let b = nodes[*node].body;
                let m = -k * twist(&placement.rotation[b], &a);
                scale += m.abs();
                moment[b] += a * m;
            }
            Connection::FixedDirection {
                nodes: [a, b],
                direction,
            } => {
                let ua = point(*a) - scene.nodes[*a].position;
                let ub = point(*b) - scene.nodes[*b].position;
                let f = -k * direction.dot(&(ub - ua));
                scale += f.abs();
                apply(*b, direction * f, &mut force, &mut moment);
                apply(*a, -direction * f, &mut force, &mut moment);
            }
            Connection::Axial { nodes: [a, b] } => {
                let d = point(*b) - point(*a);
                let rest = (scene.nodes[*b].position - scene.nodes[*a].position).norm();
                let f = -k * (d.norm() - rest);
                scale += f.abs();
                let n = d / d.norm().max(f64::MIN_POSITIVE);
                apply(*b, n * f, &mut force, &mut moment);
                apply(*a, -n * f, &mut force, &mut moment);
            }
        }
    }
    for l in &scene.loads {
        scale += l.force.norm();
        apply(l.node, l.force, &mut force, &mut moment);
    }
    if scale == 0.0 {
        return Ok(());
    }
    let lever = scene
        .nodes
        .iter()
        .map(|n| n.position.norm())
        .fold(1.0f64, f64::max);
    let tol = 1e-9 * scale;
    for (b, _) in force.iter().enumerate().skip(1) {
        // The node carrying this body's DOFs: the particle's node or the reference node.
        let carrier = match reference_of(b) {
            Some((_, reference)) => reference,
            None => match nodes.iter().position(|r| r.body == b) {
                Some(n) => n,
                None => continue,
            },
        };
        let is_rigid = reference_of(b).is_some();
        for dof in Dof::all(scene.dimension, is_rigid) {
            if step
                .conditions
                .iter()
                .any(|c| c.node == carrier && c.dof == dof)
            {
                continue;
            }
            let (value, limit) = match dof {
                Dof::Translation(i) => (
                    force[b].dot(&scene.nodes[carrier].frame.column(i).into_owned()),
                    tol,
                ),
                Dof::Rotation(i) => (
                    moment[b].dot(&scene.nodes[carrier].frame.column(i).into_owned()),
                    tol * lever,
                ),
            };
            if value.abs() > limit {
                return unsupported(format!(
                    "the static step leaves {dof} of node `{}` free with a resulting force {value:e} (rapier has no static solve; hold or prescribe it)",
                    scene.nodes[carrier].name
                ));
            }
        }
    }
    Ok(())
}

/// Per plan body, the world axes rapier locks for what `step` holds of it (`LockedAxes`: 0–2
/// translations of the centre of mass, 3–5 rotations), or `None` where a joint must hold it.
///
/// A lock is exact where it says what the scene says: every held DOF of the body is at a point
/// that is its centre of mass (a particle's node; a rigid body's reference node where the centre
/// of mass is there, for a translation), along a world axis; and in 3D, a rotation lock zeroes
/// the locked rows of the inverse inertia, which is the constrained motion only where the
/// locked axes do not couple with the free ones: at most one rotation left free, about a
/// principal axis. A lock, unlike an impulse joint, is part of the body's effective mass, so
/// every solve sees it (rapier's end-of-step restitution pass solves contacts and not joints).
pub(super) fn locked_axes(
    scene: &Scene,
    step: &Step,
    nodes: &[NodeRef],
    bodies: &[BodySpec],
    placement: &Placement,
) -> Vec<Option<[bool; 6]>> {
    // Along a world axis to round-off: a lock holds the world axis exactly.
    let world_axis = |e: &Vector3<f64>| (0..3).find(|&k| e[k].abs() >= 1.0 - 4.0 * f64::EPSILON);
    (0..bodies.len())
        .map(|b| {
            let spec = &bodies[b];
            if spec.kind == BodyKind::Ground {
                return None;
            }
            let reference = scene
                .bodies
                .iter()
                .position(|sb| nodes[sb.reference].body == b)
                .map(|i| &scene.bodies[i]);
            let mut locks = [false; 6];
            for c in step.conditions.iter().filter(|c| nodes[c.node].body == b) {
                let frame = scene.nodes[c.node].frame;
                match (c.dof, reference) {
                    // A particle never rotates: its rotations are not held by anything.
                    (Dof::Rotation(_), None) => {}
                    (Dof::Translation(i), None) => {
                        locks[world_axis(&frame.column(i).into_owned())?] = true;
                    }
                    (dof, Some(sb)) => {
                        if c.node != sb.reference {
                            return None;
                        }
                        let (i, offset) = match dof {
                            Dof::Translation(i) => (i, 0),
                            Dof::Rotation(i) => (i, 3),
                        };
                        if offset == 0 && sb.centre_offset != Vector3::zeros() {
                            return None;
                        }
                        locks[offset + world_axis(&frame.column(i).into_owned())?] = true;
                    }
                }
            }
            if scene.dimension == Dimension::Three && locks[3..].iter().any(|l| *l) {
                let free: Vec<usize> = (0..3).filter(|k| !locks[3 + k]).collect();
                let r = placement.rotation[b].to_rotation_matrix().into_inner();
                let inertia = r * spec.inertia * r.transpose();
                let scale = inertia.norm().max(f64::MIN_POSITIVE);
                let coupled = free.iter().any(|&f| {
                    (0..3).any(|l| locks[3 + l] && inertia[(f, l)].abs() > 1e-12 * scale)
                });
                if free.len() > 1 || coupled {
                    return None;
                }
            }
            Some(locks)
        })
        .collect()
}

/// Whether plan body `b` may be somewhere other than where the static steps left it when a
/// dynamic step starts, so that a fixed body or locks judged at that pose do not apply and
/// joints fitted where the step starts hold it: an earlier dynamic step let it turn
/// (`turned`), or, in 3D, the static steps turned it and it carries a grounded rotational
/// spring or dashpot (whose motor reads the twist only from a joint fitted to the turn).
pub(super) fn moved(
    scene: &Scene,
    nodes: &[NodeRef],
    groups: &[Group],
    placement: &Placement,
    turned: &[bool],
    b: usize,
) -> bool {
    let turned_statically = scene.dimension == Dimension::Three
        && placement.rotation[b].angle() > 0.0
        && groups.iter().any(|g| {
            matches!(g.connection, Connection::Grounded { node, dof: Dof::Rotation(_) }
                if nodes[node].body == b)
        });
    turned[b] || turned_statically
}

/// Whether plan body `b`, not fixed in `step`, turns in it: a rigid body whose reference node
/// the step leaves a rotation free.
pub(super) fn turns(
    scene: &Scene,
    step: &Step,
    nodes: &[NodeRef],
    bodies: &[BodySpec],
    b: usize,
) -> bool {
    let Some(o) = scene
        .bodies
        .iter()
        .find(|sb| nodes[sb.reference].body == b)
        .map(|sb| sb.reference)
    else {
        return false;
    };
    bodies[b].kind == BodyKind::Rigid
        && Dof::all(scene.dimension, true)
            .into_iter()
            .filter(|d| matches!(d, Dof::Rotation(_)))
            .any(|d| !step.conditions.iter().any(|c| c.node == o && c.dof == d))
}
