//! Coulomb friction in closed form: one particle on the plane face of a held body.
//!
//! # Scope
//!
//! - every body held still in every DOF in every step, and every step dynamic;
//! - one contact pair, planar, closed at t = 0, with friction (μ_s, μ_k), whose node is the
//!   particle: a free node with a mass, held in no DOF;
//! - every other node immobile: on a body, or a free node held still in every translation;
//! - constant point loads on the particle (loads elsewhere act on immobile nodes) whose resultant
//!   F presses it into the face: N = −n·F > 0, n the face's outward normal;
//! - at most one spring, `fixed_direction` from the particle to another node, its direction d
//!   in the face's plane; no dashpot;
//! - the initial velocity v₀ in the face's plane, and v₀, the loads' tangential part
//!   F_t = F + N n and d on one line e of that plane (always so in 2D).
//!
//! Anything else is refused, with the reason.
//!
//! # Model
//!
//! The particle stays on the face (N is constant and pressing) and moves along e: u = x e.
//! With f = F_t·e, k the spring's stiffness (0 without one) and m the particle's mass,
//!
//! - slipping along s = ±1: m ẍ = f − k x − s μ_k N;
//! - at rest: x stays while |f − k x| ≤ μ_s N (stick), else it slips along sgn(f − k x).
//!
//! A slip phase from (x, v) has the closed form
//!
//! - k = 0: uniform acceleration a = (f − s μ_k N)/m; it stops after τ = −v/a when s a < 0
//!   (at x + v τ/2), else never;
//! - k > 0: harmonic at ω = √(k/m) about c = (f − s μ_k N)/k. With z = s(x − c) and
//!   w = s v/ω ≥ 0, s(x − c) = A cos(ωτ − φ), A = √(z² + w²), φ = atan2(w, z) ∈ (0, π]: it
//!   stops after τ = φ/ω at c + s A.
//!
//! At a stop the stick condition decides between rest for good (the loads are constant) and a
//! new slip. Each output row is evaluated from the start state of the phase it falls in.
//! Outputs: displacement and velocity of the particle along a direction from x e and ẋ e,
//! every other node's 0, rotations 0, the contact force N, the gap 0, and `valid` 1.

use super::unsupported;
use crate::contract::VALID_COLUMN;
use crate::engines::{EngineError, History};
use crate::scene::{
    Attachment, Connection, ContactState, Dof, Friction, GEOMETRY_TOLERANCE, NodeId, Probe, Scene,
    StepKind, parallel,
};
use nalgebra::Vector3;

/// The most phases (stick-slip transitions) a scene may have before its duration ends.
const MAX_PHASES: usize = 1_000_000;

/// Solve a friction scene in its scope (see the module doc) exactly.
pub fn solve(scene: &Scene) -> Result<History, EngineError> {
    let setup = Setup::of(scene)?;
    let phases = setup.line.phases(scene.duration())?;
    let times = scene.output_times();
    let rows = times
        .iter()
        .map(|&t| {
            let (x, v) = state_at(&phases, t);
            std::iter::once(t)
                // + 0.0 writes a signed zero (a direction's negative part times x = 0) as 0.
                .chain(
                    scene
                        .columns
                        .iter()
                        .map(|c| setup.probe(&c.probe, x, v) + 0.0),
                )
                .chain(std::iter::once(1.0))
                .collect()
        })
        .collect();
    let columns = std::iter::once("t".to_string())
        .chain(scene.columns.iter().map(|c| c.name.clone()))
        .chain(std::iter::once(VALID_COLUMN.to_string()))
        .collect();
    Ok(History { columns, rows })
}

/// The scene reduced to its line: the particle, the line e and the motion along it.
struct Setup {
    particle: NodeId,
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
        let (force, normal_force) = pressing(scene, particle, &n)?;
        let v0 = in_plane_velocity(scene, particle, &n)?;
        let tangential = force + normal_force * n;
        let spring = spring(scene, particle, &n)?;
        let e = line(&[
            spring.map_or(Vector3::zeros(), |s| s.1),
            if tangential.norm() > GEOMETRY_TOLERANCE * force.norm() {
                tangential
            } else {
                Vector3::zeros()
            },
            v0,
        ])?;
        let line = Line {
            mass: scene.nodes[particle].mass,
            stiffness: spring.map_or(0.0, |s| s.0),
            load: tangential.dot(&e),
            v0: v0.dot(&e),
            friction,
            normal_force,
        };
        Ok(Setup { particle, e, line })
    }

    /// A probe's value with the particle at x e moving at v e.
    fn probe(&self, probe: &Probe, x: f64, v: f64) -> f64 {
        match probe {
            Probe::Displacement { node, direction } if *node == self.particle => {
                direction.dot(&self.e) * x
            }
            Probe::Velocity { node, direction } if *node == self.particle => {
                direction.dot(&self.e) * v
            }
            Probe::ContactForce { .. } => self.line.normal_force,
            // Every other node is immobile; the particle stays on the face.
            Probe::Displacement { .. }
            | Probe::Velocity { .. }
            | Probe::Rotation { .. }
            | Probe::Gap { .. }
            | Probe::Zero { .. } => 0.0,
        }
    }
}

/// The resultant load on the particle and the normal force N = −n·F it presses with (> 0).
fn pressing(
    scene: &Scene,
    particle: NodeId,
    n: &Vector3<f64>,
) -> Result<(Vector3<f64>, f64), EngineError> {
    let force: Vector3<f64> = scene
        .loads
        .iter()
        .filter(|l| l.node == particle)
        .map(|l| l.force)
        .sum();
    let normal_force = -n.dot(&force);
    if normal_force <= 0.0 {
        return refuse(format!(
            "loads that press the particle into the face (their normal component is {:e} outward)",
            -normal_force
        ));
    }
    Ok((force, normal_force))
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
fn still(scene: &Scene, node: NodeId, dofs: &[Dof]) -> bool {
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

/// The line the candidates (spring direction, tangential load, initial velocity; zero where
/// absent) lie on: the first nonzero one's direction (any, where all are zero: x stays 0). A
/// candidate off it is refused: the slip direction would turn.
fn line(candidates: &[Vector3<f64>]) -> Result<Vector3<f64>, EngineError> {
    let names = [
        "the spring's direction",
        "the loads' tangential part",
        "the initial velocity",
    ];
    let present: Vec<(usize, Vector3<f64>)> = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.norm() > 0.0)
        .map(|(i, c)| (i, c.normalize()))
        .collect();
    let Some(&(first, e)) = present.first() else {
        return Ok(Vector3::zeros());
    };
    match present.iter().find(|(_, c)| !parallel(c, &e)) {
        Some((i, _)) => refuse(format!(
            "{} and {} on one line (the slip direction would turn)",
            names[first], names[*i]
        )),
        None => Ok(e),
    }
}

/// The motion along the line: m ẍ = f − k x − friction, from x = 0, ẋ = v₀.
#[derive(Debug, Clone, Copy)]
struct Line {
    mass: f64,
    stiffness: f64,
    load: f64,
    v0: f64,
    friction: Friction,
    normal_force: f64,
}

/// A phase's motion, from the state at its start.
#[derive(Debug, Clone, Copy)]
enum Motion {
    /// At rest at x.
    Stick { x: f64 },
    /// Slipping under constant acceleration a.
    Uniform { x: f64, v: f64, a: f64 },
    /// Slipping on the spring: harmonic at ω about a centre.
    Harmonic {
        x: f64,
        v: f64,
        centre: f64,
        omega: f64,
    },
}

impl Motion {
    /// Position and velocity τ after the phase's start.
    fn state(&self, tau: f64) -> (f64, f64) {
        match *self {
            Motion::Stick { x } => (x, 0.0),
            Motion::Uniform { x, v, a } => (x + v * tau + 0.5 * a * tau * tau, v + a * tau),
            Motion::Harmonic {
                x,
                v,
                centre,
                omega,
            } => {
                let (sin, cos) = (omega * tau).sin_cos();
                let y = x - centre;
                (
                    centre + y * cos + v / omega * sin,
                    -y * omega * sin + v * cos,
                )
            }
        }
    }
}

/// A phase: its start time and motion.
#[derive(Debug, Clone, Copy)]
struct Phase {
    start: f64,
    motion: Motion,
}

impl Line {
    /// The phases that start before `end`, in order, each from the state where the previous
    /// one stops.
    fn phases(&self, end: f64) -> Result<Vec<Phase>, EngineError> {
        let mut phases = Vec::new();
        let (mut t, mut x, mut v) = (0.0, 0.0, self.v0);
        loop {
            let s = if v != 0.0 {
                v.signum()
            } else {
                let net = self.load - self.stiffness * x;
                if net.abs() <= self.friction.static_coefficient * self.normal_force {
                    phases.push(Phase {
                        start: t,
                        motion: Motion::Stick { x },
                    });
                    return Ok(phases);
                }
                net.signum()
            };
            let (motion, stop) = self.slip(x, v, s);
            phases.push(Phase { start: t, motion });
            match stop {
                Some((tau, at)) if t + tau <= end => (t, x, v) = (t + tau, at, 0.0),
                _ => return Ok(phases),
            }
            if phases.len() >= MAX_PHASES {
                return refuse(format!(
                    "at most {MAX_PHASES} stick-slip phases (the duration holds more)"
                ));
            }
        }
    }

    /// Slip along `s` from (x, v) (v = 0 or of sign s): the motion and, where it stops, after
    /// how long and where.
    fn slip(&self, x: f64, v: f64, s: f64) -> (Motion, Option<(f64, f64)>) {
        let force = self.load - s * self.friction.kinetic_coefficient * self.normal_force;
        if self.stiffness == 0.0 {
            let a = force / self.mass;
            let stop = (s * a < 0.0).then(|| (-v / a, x - v * v / (2.0 * a)));
            return (Motion::Uniform { x, v, a }, stop);
        }
        let omega = (self.stiffness / self.mass).sqrt();
        let centre = force / self.stiffness;
        let (z, w) = (s * (x - centre), (s * v / omega).abs());
        let stop = (w.atan2(z) / omega, centre + s * z.hypot(w));
        let motion = Motion::Harmonic {
            x,
            v,
            centre,
            omega,
        };
        (motion, Some(stop))
    }
}

/// Position and velocity at t, from the phase it falls in (a phase's start belongs to it).
fn state_at(phases: &[Phase], t: f64) -> (f64, f64) {
    let k = phases.partition_point(|p| p.start <= t).max(1) - 1;
    phases[k].motion.state(t - phases[k].start)
}

fn refuse<T>(what: impl Into<String>) -> Result<T, EngineError> {
    unsupported(format!("the friction closed form needs {}", what.into()))
}
