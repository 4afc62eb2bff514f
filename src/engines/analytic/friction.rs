//! Coulomb friction in closed form: one particle on the plane face of a held body.
//!
//! # Scope
//!
//! - every body held still in every DOF in every step, and every step dynamic;
//! - one contact pair, planar, closed at t = 0, with friction (μ_s, μ_k), whose node is the
//!   particle: a free node with a mass, held in no DOF;
//! - every other node immobile: on a body, or a free node held still in every translation;
//! - point loads on the particle (loads elsewhere act on immobile nodes), constant or scaled by a
//!   tabular amplitude, whose resultant F(t) presses it into the face at every time of the run:
//!   N(t) = −n·F(t) > 0, n the face's outward normal;
//! - at most one spring, `fixed_direction` from the particle to another node, its direction d
//!   in the face's plane; no dashpot;
//! - the initial velocity v₀ in the face's plane, and v₀, d, the constant loads' tangential part
//!   and each amplitude-scaled load's tangential part (F_t = F + (−n·F) n) on one line e of
//!   that plane (always so in 2D).
//!
//! Anything else is refused, with the reason.
//!
//! # Model
//!
//! The particle stays on the face (N stays pressing) and moves along e: u = x e. With
//! f(t) = F_t(t)·e, k the spring's stiffness (0 without one) and m the particle's mass,
//!
//! - slipping along s = ±1: m ẍ = f − k x − s μ_k N;
//! - at rest: x stays while |f − k x| ≤ μ_s N (stick), else it slips along sgn(f − k x).
//!
//! The amplitudes' times cut the run into segments over which f and N are linear in time (one
//! segment where every load is constant). Within a segment each stick and slip phase has a
//! closed form, and so do its end: the stop of a slip, the break-away of a stick, or the
//! segment's end (`friction_phases`). Each output row is evaluated from the start
//! state of the phase it falls in. Outputs: displacement and velocity of the particle along a
//! direction from x e and ẋ e, every other node's 0, rotations 0, the contact force N(t), the
//! gap 0, and `valid` 1.

use super::friction_phases::{Line, Segment, state_at};
use super::{columns_history, unsupported};
use crate::engines::{EngineError, History};
use crate::scene::{
    Amplitude, Attachment, Connection, ContactState, Dof, GEOMETRY_TOLERANCE, NodeId, PointLoad,
    Probe, Scene, StepKind, parallel,
};
use nalgebra::Vector3;

/// Solve a friction scene in its scope (see the module doc) exactly.
pub fn solve(scene: &Scene) -> Result<History, EngineError> {
    let setup = Setup::of(scene)?;
    let phases = setup.line.phases(scene.duration())?;
    let history = columns_history(scene, &scene.output_times(), |_, t| {
        let (x, v) = state_at(&phases, t);
        // + 0.0 writes a signed zero (a direction's negative part times x = 0) as 0.
        (scene.columns.iter())
            .map(|c| setup.probe(&c.probe, t, x, v) + 0.0)
            .collect()
    });
    Ok(history)
}

/// The scene reduced to its line: the particle, the face's normal n, the loads on the particle,
/// the line e and the motion along it.
struct Setup {
    particle: NodeId,
    n: Vector3<f64>,
    loads: Vec<PointLoad>,
    e: Vector3<f64>,
    line: Line,
}

impl Setup {
    /// The scope checked (see the module doc) and the line set up.
    fn of(scene: &Scene) -> Result<Self, EngineError> {
        held_still(scene)?;
        let [contact] = scene.contacts.as_slice() else {
            return refuse("one contact pair");
        };
        let (Some(friction), Some((_, n))) = (contact.friction, contact.plane()) else {
            return refuse("a planar contact pair with friction");
        };
        if contact.initially == ContactState::Open {
            return refuse("a contact closed at t = 0");
        }
        let particle = contact.node;
        others_immobile(scene, particle)?;
        let loads: Vec<PointLoad> = scene
            .loads
            .iter()
            .filter(|l| l.node == particle)
            .cloned()
            .collect();
        let v0 = in_plane_velocity(scene, particle, &n)?;
        let spring = spring(scene, particle, &n)?;
        let mut candidates = vec![(
            "the spring's direction",
            spring.map_or(Vector3::zeros(), |s| s.1),
        )];
        candidates.extend(tangential_parts(&loads, &n));
        candidates.push(("the initial velocity", v0));
        let e = line(&candidates)?;
        let line = Line {
            mass: scene.nodes[particle].mass,
            stiffness: spring.map_or(0.0, |s| s.0),
            v0: v0.dot(&e),
            friction,
            segments: segments(&loads, &n, &e, scene.duration())?,
        };
        Ok(Setup {
            particle,
            n,
            loads,
            e,
            line,
        })
    }

    /// A probe's value at t with the particle at x e moving at v e.
    fn probe(&self, probe: &Probe, t: f64, x: f64, v: f64) -> f64 {
        match probe {
            Probe::Displacement { node, direction } if *node == self.particle => {
                direction.dot(&self.e) * x
            }
            Probe::Velocity { node, direction } if *node == self.particle => {
                direction.dot(&self.e) * v
            }
            Probe::ContactForce { .. } => -self.n.dot(&resultant(&self.loads, t)),
            // Every other node is immobile; the particle stays on the face.
            Probe::Displacement { .. }
            | Probe::Velocity { .. }
            | Probe::Rotation { .. }
            | Probe::Gap { .. }
            | Probe::Zero { .. } => 0.0,
        }
    }
}

/// The resultant of `loads` at t.
fn resultant(loads: &[PointLoad], t: f64) -> Vector3<f64> {
    loads.iter().map(|l| l.force_at(t)).sum()
}

/// The candidates for the line from the loads (zero where negligible): the constant loads'
/// tangential part, then each amplitude-scaled load's.
fn tangential_parts(loads: &[PointLoad], n: &Vector3<f64>) -> Vec<(&'static str, Vector3<f64>)> {
    let tangential = |force: Vector3<f64>| {
        let part = force - n.dot(&force) * n;
        if part.norm() > GEOMETRY_TOLERANCE * force.norm() {
            part
        } else {
            Vector3::zeros()
        }
    };
    let constant: Vector3<f64> = loads
        .iter()
        .filter(|l| l.amplitude.is_none())
        .map(|l| l.force)
        .sum();
    std::iter::once(("the loads' tangential part", tangential(constant)))
        .chain(
            loads
                .iter()
                .filter(|l| l.amplitude.is_some())
                .map(|l| ("a ramped load's tangential part", tangential(l.force))),
        )
        .collect()
}

/// The segments over which the loads on the particle are linear in time until `end` (the run's
/// end): cut at every amplitude time inside (0, `end`), the last open-ended (linear up to `end`,
/// the only part the phases reach); the normal force must press at every cut and at `end`, so
/// (linear between them) throughout the run.
fn segments(
    loads: &[PointLoad],
    n: &Vector3<f64>,
    e: &Vector3<f64>,
    end: f64,
) -> Result<Vec<Segment>, EngineError> {
    let mut cuts: Vec<f64> = loads
        .iter()
        .filter_map(|l| l.amplitude.as_ref())
        .flat_map(|a| a.points.iter().map(|p| p.0))
        .filter(|t| *t > 0.0 && *t < end)
        .collect();
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    for t in std::iter::once(0.0)
        .chain(cuts.iter().copied())
        .chain([end])
    {
        let normal = -n.dot(&resultant(loads, t));
        if normal <= 0.0 {
            return refuse(format!(
                "loads that press the particle into the face throughout (at t = {t}, their normal component is {:e} outward)",
                -normal
            ));
        }
    }
    let starts = std::iter::once(0.0).chain(cuts.iter().copied());
    let ends = cuts.iter().copied().chain([f64::INFINITY]);
    Ok(starts
        .zip(ends)
        .map(|(start, stop)| {
            let force = resultant(loads, start);
            let n0 = -n.dot(&force);
            // Each amplitude's slope in the segment, where it is linear: at its middle (of the
            // run's rest in the last).
            let middle = 0.5 * (start + stop.min(end));
            let rate: Vector3<f64> = loads
                .iter()
                .filter_map(|l| l.amplitude.as_ref().map(|a| l.force * slope(a, middle)))
                .sum();
            let n1 = -n.dot(&rate);
            Segment {
                start,
                end: stop,
                f0: (force + n0 * n).dot(e),
                f1: (rate + n1 * n).dot(e),
                n0,
                n1,
            }
        })
        .collect())
}

/// The slope of a tabular amplitude at t (0 before its first time and after its last).
fn slope(amplitude: &Amplitude, t: f64) -> f64 {
    let p = &amplitude.points;
    let i = p.partition_point(|(ti, _)| *ti <= t);
    if i == 0 || i == p.len() {
        return 0.0;
    }
    let ((t0, a0), (t1, a1)) = (p[i - 1], p[i]);
    (a1 - a0) / (t1 - t0)
}

/// The particle's initial velocity, in the face's plane.
fn in_plane_velocity(
    scene: &Scene,
    particle: NodeId,
    n: &Vector3<f64>,
) -> Result<Vector3<f64>, EngineError> {
    let v0: Vector3<f64> = scene
        .initial_velocities
        .iter()
        .filter(|iv| iv.node == particle)
        .map(|iv| iv.velocity)
        .sum();
    if n.dot(&v0).abs() > GEOMETRY_TOLERANCE * v0.norm() {
        return refuse("an initial velocity in the face's plane");
    }
    Ok(v0)
}

/// Every step dynamic, and every body held still (its reference node held at 0 in all DOFs) in
/// every step.
fn held_still(scene: &Scene) -> Result<(), EngineError> {
    if scene.steps.iter().any(|s| s.kind == StepKind::Static) {
        return refuse("dynamic steps only (a static step)");
    }
    for body in &scene.bodies {
        if !still(scene, body.reference, &Dof::all(scene.dimension, true)) {
            return refuse(format!(
                "every body held in every DOF in every step (`{}` is not)",
                body.name
            ));
        }
    }
    Ok(())
}

/// Whether `node` is held at 0 in each of `dofs` in every step.
pub(super) fn still(scene: &Scene, node: NodeId, dofs: &[Dof]) -> bool {
    scene.steps.iter().all(|step| {
        dofs.iter().all(|dof| {
            step.conditions.iter().any(|c| {
                c.node == node && c.dof == *dof && c.value.is_none_or(|value| value == 0.0)
            })
        })
    })
}

/// The particle is a free node with a mass and held in no DOF; every other free node is held
/// still in every translation; there is no dashpot.
fn others_immobile(scene: &Scene, particle: NodeId) -> Result<(), EngineError> {
    let node = &scene.nodes[particle];
    let held = scene
        .steps
        .iter()
        .any(|s| s.conditions.iter().any(|c| c.node == particle));
    if node.attachment != Attachment::Free || node.mass <= 0.0 || held {
        return refuse(format!(
            "a contact node that is a particle: free, with a mass, held in no DOF (`{}` is not)",
            node.name
        ));
    }
    let translations = Dof::all(scene.dimension, false);
    if let Some(other) = scene.nodes.iter().enumerate().find(|(i, n)| {
        *i != particle && n.attachment == Attachment::Free && !still(scene, *i, &translations)
    }) {
        return refuse(format!(
            "one particle (free node `{}` is not held still)",
            other.1.name
        ));
    }
    if let Some(d) = scene.dashpots.first() {
        return refuse(format!("no dashpot (`{}`)", d.name));
    }
    Ok(())
}

/// The spring on the particle, if any: its stiffness and its direction, in the face's plane.
fn spring(
    scene: &Scene,
    particle: NodeId,
    n: &Vector3<f64>,
) -> Result<Option<(f64, Vector3<f64>)>, EngineError> {
    match scene.springs.as_slice() {
        [] => Ok(None),
        [s] => match &s.connection {
            Connection::FixedDirection { nodes, direction }
                if nodes.contains(&particle) && nodes[0] != nodes[1] =>
            {
                if n.dot(direction).abs() > GEOMETRY_TOLERANCE {
                    return refuse(format!(
                        "a spring in the face's plane (`{}` is not)",
                        s.name
                    ));
                }
                Ok(Some((s.coefficient, *direction)))
            }
            _ => refuse(format!(
                "a `fixed_direction` spring from the particle (`{}` is not)",
                s.name
            )),
        },
        _ => refuse("at most one spring"),
    }
}

/// The line the named candidates (zero where absent) lie on: the first nonzero one's direction
/// (any, where all are zero: x stays 0). A candidate off it is refused: the slip direction
/// would turn.
pub(super) fn line(candidates: &[(&str, Vector3<f64>)]) -> Result<Vector3<f64>, EngineError> {
    let present: Vec<(&str, Vector3<f64>)> = candidates
        .iter()
        .filter(|(_, c)| c.norm() > 0.0)
        .map(|(name, c)| (*name, c.normalize()))
        .collect();
    let Some(&(first, e)) = present.first() else {
        return Ok(Vector3::zeros());
    };
    match present.iter().find(|(_, c)| !parallel(c, &e)) {
        Some((other, _)) => refuse(format!(
            "{first} and {other} on one line (the slip direction would turn)"
        )),
        None => Ok(e),
    }
}

pub(super) fn refuse<T>(what: impl Into<String>) -> Result<T, EngineError> {
    unsupported(format!("the friction closed form needs {}", what.into()))
}
