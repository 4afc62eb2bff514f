//! A ball (a disc in 2D) launched on the plane face of a held body, in closed form: it slides,
//! and friction at its contact point slows it and spins it up until it rolls.
//!
//! # Scope
//!
//! - every step dynamic; every body but the ball's held still in every DOF in every step;
//! - one contact pair, closed at t = 0, whose node carries a ball of radius R against a plane
//!   face (outward normal n), with friction (μ_s, μ_k);
//! - the node is the reference node of the ball's body, held in no DOF, at the body's centre
//!   of mass; no other node of that body is loaded or read; every free node held still;
//! - no spring, no dashpot; constant loads on the ball's centre whose resultant F presses it into
//!   the face: N = −n·F > 0;
//! - the tangential load F_t = F + N n, the initial velocity v₀ (in the face's plane) and the
//!   initial slip of the contact point s₀ = v₀ + ω₀ × (−R n) on one line e of the face's plane;
//!   ω₀ about the axis a = n × e, a principal axis of the body's inertia (I_a about it).
//!
//! Anything else is refused, with the reason.
//!
//! # Model
//!
//! Along e, with f the friction force on the contact point, the centre moves as
//! m v̇ = F_t + f and the spin about a as I_a ω̇ = −R f; the contact point slips at s = v − R ω,
//! so ṡ = F_t/m + f/m* with 1/m* = 1/m + R²/I_a: the slip is the motion of a particle of mass
//! m* under the load (m*/m) F_t and Coulomb friction on N, which [`Line`] solves by its stick
//! (rolling) and slip phases. With X(t) = ∫s and S(t) = s from there, the friction impulse is
//! J = m*(S − s₀) − (m*/m) F_t t, and
//!
//! - centre velocity v = v₀ + (F_t t + J)/m and displacement u = v₀ t + F_t t²/(2m) + ∫J/m;
//! - rotation about a: φ = ω₀ t − (R/I_a) ∫J, with ∫J = m*(X − s₀ t) − (m*/m) F_t t²/2.
//!
//! Launched without spin on a plane under its weight alone (F_t = 0), it rolls from
//! t* = s₀ m*/(μ_k N): a disc (I = mR²/2, m* = m/3) at v₀/(3 μ_k g) with 2v₀/3, a ball
//! (I = 2mR²/5, m* = 2m/7) at 2v₀/(7 μ_k g) with 5v₀/7. Outputs: the centre's displacement and
//! velocity from u e and v e, the ball's rotation about an axis parallel to a from φ (0 about an
//! axis across it), every other node and body 0, the contact force N, the gap 0, `valid` 1.

use super::columns_history;
use super::friction::{line, refuse, still};
use super::friction_phases::{Line, Segment, state_at};
use crate::engines::{EngineError, History};
use crate::scene::{
    Attachment, BodyId, ContactState, Dimension, Dof, GEOMETRY_TOLERANCE, NodeId, Probe, Scene,
    StepKind, parallel,
};
use nalgebra::Vector3;

/// Solve a rolling scene in its scope (see the module doc) exactly.
pub fn solve(scene: &Scene) -> Result<History, EngineError> {
    let rolling = Rolling::of(scene)?;
    let phases = rolling.slip_line().phases(scene.duration())?;
    let history = columns_history(scene, &scene.output_times(), |_, t| {
        let (x, s) = state_at(&phases, t);
        let motion = rolling.motion(t, x, s);
        // + 0.0 writes a signed zero as 0.
        (scene.columns.iter())
            .map(|c| rolling.probe(&c.probe, &motion) + 0.0)
            .collect()
    });
    Ok(history)
}

/// The scene reduced to the ball's motion along e and its spin about a.
struct Rolling {
    body: BodyId,
    centre: NodeId,
    e: Vector3<f64>,
    a: Vector3<f64>,
    mass: f64,
    inertia: f64,
    radius: f64,
    /// F_t·e.
    tangential: f64,
    /// N.
    normal: f64,
    /// v₀·e and ω₀·a.
    v0: f64,
    omega0: f64,
    friction: crate::scene::Friction,
}

/// The centre's displacement and velocity along e and the rotation about a at one time.
struct Motion {
    u: f64,
    v: f64,
    phi: f64,
}

impl Rolling {
    /// The scope checked (see the module doc).
    fn of(scene: &Scene) -> Result<Self, EngineError> {
        let [pair] = scene.contacts.as_slice() else {
            return refuse("one contact pair");
        };
        let (Some(friction), Some((_, n)), true) = (pair.friction, pair.plane(), pair.rolls())
        else {
            return refuse("a ball against a plane face, with friction");
        };
        if pair.initially == ContactState::Open {
            return refuse("a contact closed at t = 0");
        }
        let Attachment::Reference(body) = scene.nodes[pair.node].attachment else {
            return refuse("the ball centred on its body's reference node");
        };
        let centre = pair.node;
        scope_around(scene, body, centre)?;
        let force: Vector3<f64> = scene
            .loads
            .iter()
            .filter(|l| l.node == centre)
            .map(|l| l.force)
            .sum();
        let normal = -n.dot(&force);
        if normal <= 0.0 {
            return refuse("loads that press the ball into the face");
        }
        let (v0, w0) = initial_velocity(scene, centre);
        if n.dot(&v0).abs() > GEOMETRY_TOLERANCE * v0.norm() {
            return refuse("an initial velocity in the face's plane");
        }
        let radius = pair.node_radius;
        let slip0 = v0 + w0.cross(&(-radius * n));
        let e = line(&[
            ("the loads' tangential part", force + normal * n),
            ("the initial velocity", v0),
            ("the contact point's initial slip", slip0),
        ])?;
        if e.norm() == 0.0 {
            return refuse("a motion along the face (nothing moves the ball)");
        }
        let a = n.cross(&e);
        if w0.norm() > 0.0 && !parallel(&w0, &a) {
            return refuse("an initial spin about the axis across the slip in the face's plane");
        }
        let askew = scene.columns.iter().any(|c| match c.probe {
            Probe::Rotation { body: b, axis } => {
                b == body && !parallel(&axis, &a) && axis.dot(&a).abs() > GEOMETRY_TOLERANCE
            }
            _ => false,
        });
        if askew {
            return refuse("the ball's rotation read about its spin axis or across it");
        }
        Ok(Rolling {
            body,
            centre,
            e,
            a,
            mass: scene.bodies[body].mass,
            inertia: principal_inertia(scene, body, &a)?,
            radius,
            tangential: (force + normal * n).dot(&e),
            normal,
            v0: v0.dot(&e),
            omega0: w0.dot(&a),
            friction,
        })
    }

    /// 1/m* = 1/m + R²/I_a: the mass the friction force moves at the contact point.
    fn slip_mass(&self) -> f64 {
        1.0 / (1.0 / self.mass + self.radius * self.radius / self.inertia)
    }

    /// The contact point's slip as a particle's motion: mass m*, load (m*/m) F_t, friction on N.
    fn slip_line(&self) -> Line {
        let m = self.slip_mass();
        Line {
            mass: m,
            stiffness: 0.0,
            v0: self.v0 - self.radius * self.omega0,
            friction: self.friction,
            segments: vec![Segment {
                start: 0.0,
                end: f64::INFINITY,
                f0: m / self.mass * self.tangential,
                f1: 0.0,
                n0: self.normal,
                n1: 0.0,
            }],
        }
    }

    /// The motion at t from the slip's travel x and speed s there.
    fn motion(&self, t: f64, x: f64, s: f64) -> Motion {
        let (m, m_slip, f_t) = (self.mass, self.slip_mass(), self.tangential);
        let s0 = self.v0 - self.radius * self.omega0;
        let impulse = m_slip * (s - s0) - m_slip / m * f_t * t;
        let impulse_integral = m_slip * (x - s0 * t) - m_slip / m * f_t * t * t / 2.0;
        Motion {
            u: self.v0 * t + f_t * t * t / (2.0 * m) + impulse_integral / m,
            v: self.v0 + (f_t * t + impulse) / m,
            phi: self.omega0 * t - self.radius / self.inertia * impulse_integral,
        }
    }

    /// A probe's value in `motion`.
    fn probe(&self, probe: &Probe, motion: &Motion) -> f64 {
        match probe {
            Probe::Displacement { node, direction } if *node == self.centre => {
                direction.dot(&self.e) * motion.u
            }
            Probe::Velocity { node, direction } if *node == self.centre => {
                direction.dot(&self.e) * motion.v
            }
            Probe::Rotation { body, axis } if *body == self.body => axis.dot(&self.a) * motion.phi,
            Probe::ContactForce { .. } => self.normal,
            // Every other node and body is still; the ball stays on the face.
            _ => 0.0,
        }
    }
}

/// Around the ball: every step dynamic, every other body held still, every free node held
/// still, no spring or dashpot, its centre at its centre of mass and held in no DOF, and no other
/// node of its body loaded or read.
fn scope_around(scene: &Scene, body: BodyId, centre: NodeId) -> Result<(), EngineError> {
    if scene.steps.iter().any(|s| s.kind == StepKind::Static) {
        return refuse("dynamic steps only (a static step)");
    }
    let all = Dof::all(scene.dimension, true);
    if let Some(other) = (scene.bodies.iter().enumerate())
        .find(|(b, other)| *b != body && !still(scene, other.reference, &all))
    {
        return refuse(format!(
            "every body but the ball's held in every DOF in every step (`{}` is not)",
            other.1.name
        ));
    }
    let translations = Dof::all(scene.dimension, false);
    if let Some(free) = (scene.nodes.iter().enumerate())
        .find(|(i, n)| n.attachment == Attachment::Free && !still(scene, *i, &translations))
    {
        return refuse(format!(
            "every free node held still (`{}` is not)",
            free.1.name
        ));
    }
    if !(scene.springs.is_empty() && scene.dashpots.is_empty()) {
        return refuse("no spring or dashpot");
    }
    if scene.has_amplitudes() {
        return refuse("constant loads on the ball");
    }
    let held = (scene.steps.iter()).any(|s| s.conditions.iter().any(|c| c.node == centre));
    let b = &scene.bodies[body];
    let scale = 1.0 + scene.nodes[centre].position.norm();
    if held || b.centre_offset.norm() > GEOMETRY_TOLERANCE * scale {
        return refuse("the ball's centre at its centre of mass, held in no DOF");
    }
    let elsewhere =
        |node: NodeId| node != centre && scene.nodes[node].attachment == Attachment::OnBody(body);
    let read = scene.columns.iter().any(|c| match c.probe {
        Probe::Displacement { node, .. } | Probe::Velocity { node, .. } => elsewhere(node),
        _ => false,
    });
    if read || scene.loads.iter().any(|l| elsewhere(l.node)) {
        return refuse("loads and outputs at the ball's centre only");
    }
    Ok(())
}

/// The ball centre's initial velocity and spin.
fn initial_velocity(scene: &Scene, centre: NodeId) -> (Vector3<f64>, Vector3<f64>) {
    (scene.initial_velocities.iter())
        .filter(|iv| iv.node == centre)
        .fold((Vector3::zeros(), Vector3::zeros()), |(v, w), iv| {
            (v + iv.velocity, w + iv.angular)
        })
}

/// The body's moment of inertia about `a`, which must be a principal axis (2D: about z).
fn principal_inertia(scene: &Scene, body: BodyId, a: &Vector3<f64>) -> Result<f64, EngineError> {
    let inertia = scene.bodies[body].inertia;
    if scene.dimension == Dimension::Two {
        return Ok(inertia[(2, 2)]);
    }
    let turned = inertia * a;
    let about = a.dot(&turned);
    if (turned - about * a).norm() > GEOMETRY_TOLERANCE * inertia.norm() {
        return refuse("the axis the slip turns the ball about a principal axis of its inertia");
    }
    Ok(about)
}
