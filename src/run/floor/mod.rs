//! The arithmetic floor of one increment: the explicit scheme's recurrence for a seed scene,
//! written out by hand, so a benchmark can say how far the general engine is from the
//! arithmetic it must do. Here the simplest, a mass on a spring and dashpot to the ground or a
//! held node; in [`LineOscillator`] masses that move along one line on springs and a dashpot
//! along it; in [`AxialOscillator`] masses on springs and a dashpot whose lines turn, in
//! [`PinnedBody`] a body turning about a pin, in [`SlidingBody`] a body that slides and turns
//! with its mass centre off its reference node or on it, in [`TurningBody3d`] the sliding and
//! the pinned body in 3D, with the arithmetic of a 3D engine.
//!
//! The recurrence is the one the explicit engine runs on such a scene: central differences
//! with the centred dashpot treatment (the dashpot's rate solves
//! `(1 + (h/2)·c/m) r = v(n−½) + (h/2)·F/m`), the half-step velocity restarted from rest at the
//! release (`v(−½) = −(h/2)·a(0)`), and the displacement summed with a compensated (Kahan)
//! addition. It is written here from the scheme, not taken from the engine, and
//! `tests/floor.rs` checks that the two agree to round-off.
//!
//! Two forms of the same arithmetic:
//! - [`DampedOscillator::in_registers`]: the state in local variables, which the compiler
//!   keeps in registers; only the dependent chain of the increment is left (the latency floor);
//! - [`DampedOscillator::in_slices`]: the state in heap slices of a length known only at run
//!   time, in the fewest passes an engine driven by a scene needs (forces from an element list
//!   with node indices, then the dashpots' centred forces, then one pass over the particles).
//!   What one pass computes reaches the next through memory.

use crate::scene::{
    BoundaryCondition, Connection, ContactPair, DampingTreatment, Dimension, Dof, Element,
    RigidBody, Scene, Step, StepKind,
};
use nalgebra::Vector3;
use std::hint::black_box;

/// One mass on a spring and a dashpot acting on the same translation, grounded or joining it to
/// a held node, released from rest at a displacement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DampedOscillator {
    /// Mass (kg).
    pub mass: f64,
    /// Spring stiffness (N/m).
    pub stiffness: f64,
    /// Dashpot coefficient (N·s/m).
    pub damping: f64,
    /// Displacement at the release (m).
    pub released_from: f64,
    /// Duration of the dynamic step (s).
    pub duration: f64,
}

impl DampedOscillator {
    /// The oscillator a scene describes, when it is exactly that: one node moves in the dynamic
    /// step, along one translation of its frame (its others held in both steps), has mass and
    /// is released from rest at the value the static step prescribes on that translation; one
    /// spring and one dashpot act on it, each grounded on that translation or joining the node
    /// along its direction to a node held where it starts in both steps; every other spring or
    /// dashpot joins held nodes alone and moves nothing (springs_grounded_a: grounded
    /// elements; springs_grounded_b: fixed-direction elements to a held node, beside a spring
    /// between two held nodes).
    pub fn of(scene: &Scene) -> Option<Self> {
        let (steps, duration) = Release::of(scene)?;
        let still = |node: usize| steps.still(node);
        let moving: Vec<usize> = (0..scene.nodes.len())
            .filter(|n| !steps.translations().all(|d| holds(steps.dynamic, *n, d)))
            .collect();
        let [node] = moving[..] else {
            return None;
        };
        let (dof, along, start) = steps.free_translation(node)?;
        let released_from = start?;
        // Whether an element acts on the node along `dof` (Some(true)), joins still nodes
        // alone (Some(false)), or is neither (None: not this system).
        let acts = |e: &Element| match e.connection {
            Connection::Grounded { node: n, dof: d } if n == node => (d == dof).then_some(true),
            Connection::Grounded { node: n, .. } => still(n).then_some(false),
            Connection::FixedDirection { nodes, direction } if nodes.contains(&node) => {
                let other = if nodes[0] == node { nodes[1] } else { nodes[0] };
                let aligned = direction == along || direction == -along;
                (aligned && still(other)).then_some(true)
            }
            Connection::FixedDirection { nodes, .. } | Connection::Axial { nodes } => {
                (still(nodes[0]) && still(nodes[1])).then_some(false)
            }
        };
        let acting = |elements: &'_ [Element]| -> Option<Vec<f64>> {
            let mut out = Vec::new();
            for e in elements {
                if acts(e)? {
                    out.push(e.coefficient);
                }
            }
            Some(out)
        };
        let (springs, dashpots) = (acting(&scene.springs)?, acting(&scene.dashpots)?);
        let (&[stiffness], &[damping]) = (&springs[..], &dashpots[..]) else {
            return None;
        };
        Some(Self {
            mass: scene.nodes[node].mass,
            stiffness,
            damping,
            released_from,
            duration,
        })
    }

    /// Displacement and half-step velocity after `steps` increments of `h`, the state in
    /// registers.
    pub fn in_registers(&self, h: f64, steps: u64) -> (f64, f64) {
        let inverse_mass = 1.0 / self.mass;
        let (k, c) = (self.stiffness, self.damping);
        let mut u = self.released_from;
        let mut carry = 0.0;
        // v(−½) = v(0) − (h/2)·a(0), from rest (the dashpot's force is zero at rest).
        let mut v_half = -(0.5 * h) * (-k * u * inverse_mass);
        let diagonal = 1.0 + 0.5 * h * c * inverse_mass;
        for _ in 0..steps {
            let mut a = -k * u * inverse_mass;
            let rate = (v_half + a * (0.5 * h)) / diagonal;
            a -= inverse_mass * (c * rate);
            v_half += a * h;
            compensated_add(&mut u, &mut carry, v_half * h);
        }
        (u, v_half)
    }

    /// [`DampedOscillator::in_registers`] with the state in heap slices of a length the
    /// compiler does not know, in the fewest passes a scene-driven step needs: clear the
    /// forces, accumulate the springs' (from an element list with node indices), the
    /// dashpots' centred forces (which need every other force on their nodes first), then
    /// accelerations, velocities and compensated positions in one pass over the particles.
    pub fn in_slices(&self, h: f64, steps: u64) -> (f64, f64) {
        let n = black_box(1usize);
        let mut u = vec![self.released_from; n];
        let mut carry = vec![0.0; n];
        let mut v_half = vec![0.0; n];
        let mut force = vec![0.0; n];
        let mut dashpot_force = vec![0.0; n];
        let inverse_mass = vec![1.0 / self.mass; n];
        // The element lists: (node, coefficient).
        let springs = vec![(0usize, self.stiffness); n];
        let dashpots = vec![(0usize, self.damping); n];
        for i in 0..n {
            v_half[i] = -(0.5 * h) * (-self.stiffness * u[i] * inverse_mass[i]);
        }
        for _ in 0..steps {
            force.iter_mut().for_each(|f| *f = 0.0);
            for &(node, k) in &springs {
                force[node] -= k * u[node];
            }
            for &(node, c) in &dashpots {
                let v_n = v_half[node] + force[node] * inverse_mass[node] * (0.5 * h);
                let rate = v_n / (1.0 + 0.5 * h * c * inverse_mass[node]);
                dashpot_force[node] = c * rate;
            }
            for i in 0..n {
                let a = force[i] * inverse_mass[i] - inverse_mass[i] * dashpot_force[i];
                v_half[i] += a * h;
                let dx = v_half[i] * h;
                compensated_add(&mut u[i], &mut carry[i], dx);
            }
        }
        (u[0], v_half[0])
    }
}

/// The static and the dynamic step of a scene a floor takes ([`released`]), as the damped and
/// the line oscillator read its nodes' conditions.
struct Release<'a> {
    scene: &'a Scene,
    static_step: &'a Step,
    dynamic: &'a Step,
}

impl<'a> Release<'a> {
    /// The scene's two steps and the dynamic step's duration, where [`released`] takes it.
    fn of(scene: &'a Scene) -> Option<(Self, f64)> {
        let (static_step, dynamic, duration) = released(scene)?;
        let steps = Self {
            scene,
            static_step,
            dynamic,
        };
        Some((steps, duration))
    }

    /// The translations of the scene's dimension.
    fn translations(&self) -> impl Iterator<Item = Dof> + use<> {
        (0..self.scene.dimension.count()).map(Dof::Translation)
    }

    /// Whether `node` is held in every translation in both steps.
    fn still(&self, node: usize) -> bool {
        let both = |d: Dof| holds(self.static_step, node, d) && holds(self.dynamic, node, d);
        self.translations().all(both)
    }

    /// The one translation `node` moves along in the dynamic step, when the node has mass, is
    /// held in its other translations in both steps and is released on this one (the dynamic
    /// step neither holds nor prescribes it): the translation, its direction in world axes, and
    /// the value the static step prescribes on it (None where the static step holds it). None
    /// where the static step has no condition on it.
    fn free_translation(&self, node: usize) -> Option<(Dof, Vector3<f64>, Option<f64>)> {
        let (scene, static_step, dynamic) = (self.scene, self.static_step, self.dynamic);
        let free: Vec<Dof> = self
            .translations()
            .filter(|d| !holds(dynamic, node, *d))
            .collect();
        let [dof @ Dof::Translation(axis)] = free[..] else {
            return None;
        };
        let across_held = self
            .translations()
            .all(|d| d == dof || holds(static_step, node, d));
        let prescribed = dynamic
            .conditions
            .iter()
            .any(|c| c.node == node && c.dof == dof);
        if scene.nodes[node].mass <= 0.0 || !across_held || prescribed {
            return None;
        }
        let start = static_step
            .conditions
            .iter()
            .find(|c| c.node == node && c.dof == dof)?;
        let along = scene.nodes[node].frame.column(axis).into_owned();
        Some((dof, along, start.value))
    }
}

/// What the body floors read first: a scene in `dimension` without dashpots, with one body,
/// one contact pair and one step, a dynamic one; those three and the step's duration.
fn one_body(scene: &Scene, dimension: Dimension) -> Option<(&RigidBody, &ContactPair, &Step, f64)> {
    if scene.dimension != dimension || !scene.dashpots.is_empty() {
        return None;
    }
    let ([body], [contact], [step]) = (
        scene.bodies.as_slice(),
        scene.contacts.as_slice(),
        scene.steps.as_slice(),
    ) else {
        return None;
    };
    let StepKind::Dynamic { duration } = step.kind else {
        return None;
    };
    Some((body, contact, step, duration))
}

/// The first condition `step` puts on `node`'s `dof`, if any.
fn condition(step: &Step, node: usize, dof: Dof) -> Option<&BoundaryCondition> {
    step.conditions
        .iter()
        .find(|c| c.node == node && c.dof == dof)
}

/// Whether `step` holds `node` on `dof` (a condition without a prescribed value).
fn holds(step: &Step, node: usize, dof: Dof) -> bool {
    step.conditions
        .iter()
        .any(|c| c.node == node && c.dof == dof && c.value.is_none())
}

/// A scene of masses, springs and dashpots alone (no bodies, contacts, loads or initial
/// velocities; the centred dashpot treatment) with a static step that sets where they start
/// and a dynamic step that releases them: the two steps and the dynamic step's duration.
fn released(scene: &Scene) -> Option<(&Step, &Step, f64)> {
    if scene.settings.damping != DampingTreatment::Centred
        || !scene.bodies.is_empty()
        || !scene.contacts.is_empty()
        || !scene.loads.is_empty()
        || !scene.initial_velocities.is_empty()
    {
        return None;
    }
    let [static_step, dynamic] = scene.steps.as_slice() else {
        return None;
    };
    let (StepKind::Static, StepKind::Dynamic { duration }) = (static_step.kind, dynamic.kind)
    else {
        return None;
    };
    Some((static_step, dynamic, duration))
}

/// `x += dx` with the rounding error carried to the next addition (Kahan).
#[inline(always)]
fn compensated_add(x: &mut f64, carry: &mut f64, dx: f64) {
    let y = dx - *carry;
    let t = *x + y;
    *carry = (t - *x) - y;
    *x = t;
}

/// A floor's run in heap slices for one scene: the duration of its dynamic step, and a run of
/// so many increments of a given length.
pub struct FloorRun {
    /// Duration of the dynamic step the floor runs (s).
    pub duration: f64,
    run: Box<dyn Fn(f64, u64)>,
}

impl FloorRun {
    /// Run `steps` increments of `h`, the result kept from the optimiser.
    pub fn run(&self, h: f64, steps: u64) {
        (self.run)(h, steps)
    }
}

/// The floor of `scene` in heap slices, where the scene is one a floor is written for.
pub fn in_slices(scene: &Scene) -> Option<FloorRun> {
    fn of<T: 'static, R: 'static>(duration: f64, floor: T, run: fn(&T, f64, u64) -> R) -> FloorRun {
        let run = Box::new(move |h, steps| {
            black_box(run(black_box(&floor), h, steps));
        });
        FloorRun { duration, run }
    }
    if let Some(o) = DampedOscillator::of(scene) {
        return Some(of(o.duration, o, DampedOscillator::in_slices));
    }
    if let Some(s) = AxialOscillator::of(scene) {
        return Some(of(s.duration, s, AxialOscillator::in_slices));
    }
    if let Some(s) = LineOscillator::of(scene) {
        return Some(of(s.duration, s, LineOscillator::in_slices));
    }
    if let Some(b) = PinnedBody::of(scene) {
        return Some(of(b.duration, b, PinnedBody::in_slices));
    }
    if let Some(b) = SlidingBody::of(scene) {
        return Some(of(b.duration, b, SlidingBody::in_slices));
    }
    let b = TurningBody3d::of(scene)?;
    Some(of(b.duration, b, TurningBody3d::in_slices))
}

mod axial;
mod in_turn;
mod line;
mod pinned_body;
mod sliding_body;
mod turning_body3d;
pub use axial::{AxialElement, AxialOscillator, AxialState, LineMass};
pub use in_turn::{InTurn, Pair, REFINEMENT, TimedRun, engines_pair, floor_pair, interleaved};
pub use line::{LineElement, LineOscillator, LineState};
pub use pinned_body::PinnedBody;
pub use sliding_body::{SlidingBody, SlidingState};
pub use turning_body3d::TurningBody3d;
