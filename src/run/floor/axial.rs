//! The arithmetic floor of an increment whose dashpot turns with its nodes: a 2D mass free
//! along one direction, pulled from a held node by an axial spring and an axial dashpot
//! (springs_grounded_c), written out by hand with the state in heap slices.
//!
//! It is the explicit engine's recurrence for such a scene: central differences; the axial
//! spring's force along the current line, 1/|l| formed as |l|·(1/|l|²); the projection that
//! removes the held direction; the centred dashpot solved directly in its rate along the
//! current line `l` (taken over its length at t = 0, so no square root on the chain):
//! `(|l|² + (h/2)·c·l·g) σ = l·w`, `g = P l / m`, `w` the undamped centred velocity; the
//! half-step velocity restarted from rest at the release; the displacement summed with a
//! compensated (Kahan) addition. A spring or dashpot between two held nodes moves nothing and
//! is left out, as is what records or checks a run (rows, energy). It is written here from
//! the scheme, not taken from the engine, and `tests/floor.rs` checks that the two agree to
//! round-off.

use super::compensated_add;
use crate::scene::{Connection, DampingTreatment, Dof, Element, Scene, StepKind};
use nalgebra::Vector2;
use std::hint::black_box;

/// A mass free along one direction, on an axial spring and an axial dashpot from a held node,
/// released from rest at a displacement along that direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxialOscillator {
    /// Mass (kg).
    pub mass: f64,
    /// Spring stiffness (N/m).
    pub stiffness: f64,
    /// Dashpot coefficient (N·s/m).
    pub damping: f64,
    /// From the held node to the mass at t = 0 (m).
    pub span: Vector2<f64>,
    /// The direction the mass is held in (unit).
    pub held: Vector2<f64>,
    /// The mass's displacement at the release (m).
    pub released_from: Vector2<f64>,
    /// Duration of the dynamic step (s).
    pub duration: f64,
}

/// The state after a run: the mass's displacement and half-step velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxialState {
    /// Displacement (m).
    pub displacement: Vector2<f64>,
    /// Velocity at the last half step (m/s).
    pub velocity: Vector2<f64>,
}

impl AxialOscillator {
    /// The oscillator a scene describes, when it is exactly that: 2D, no bodies, contacts,
    /// loads or initial velocities, the centred dashpot treatment, a static step then a
    /// dynamic one; in the dynamic step one massive node moves, held in its frame's uy alone
    /// and released from the static step's prescribed ux; one axial spring and one axial
    /// dashpot join it to a node held in every direction; every other element joins two held
    /// nodes.
    pub fn of(scene: &Scene) -> Option<Self> {
        if scene.dimension != crate::scene::Dimension::Two
            || scene.settings.damping != DampingTreatment::Centred
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
        let holds = |node: usize, dof: Dof| {
            dynamic
                .conditions
                .iter()
                .any(|c| c.node == node && c.dof == dof && c.value.is_none())
        };
        let fixed = |node: usize| {
            let held = |k| holds(node, Dof::Translation(k));
            held(0) && held(1)
        };
        let moving: Vec<usize> = (0..scene.nodes.len()).filter(|n| !fixed(*n)).collect();
        let [node] = moving.as_slice() else {
            return None;
        };
        let node = *node;
        if !holds(node, Dof::Translation(1)) || scene.nodes[node].mass <= 0.0 {
            return None;
        }
        let spring = Self::element_on(&scene.springs, node, &fixed)?;
        let dashpot = Self::element_on(&scene.dashpots, node, &fixed)?;
        let anchor = match spring.connection {
            Connection::Axial { nodes } => nodes[0] + nodes[1] - node,
            _ => return None,
        };
        if dashpot.connection != spring.connection {
            return None;
        }
        let release = static_step
            .conditions
            .iter()
            .find(|c| c.node == node && c.dof == Dof::Translation(0))?
            .value?;
        let frame = &scene.nodes[node].frame;
        let (along, held) = (frame.column(0), frame.column(1));
        let (x, x_anchor) = (scene.nodes[node].position, scene.nodes[anchor].position);
        Some(Self {
            mass: scene.nodes[node].mass,
            stiffness: spring.coefficient,
            damping: dashpot.coefficient,
            span: Vector2::new(x.x - x_anchor.x, x.y - x_anchor.y),
            held: Vector2::new(held.x, held.y),
            released_from: Vector2::new(along.x, along.y) * release,
            duration,
        })
    }

    /// The one axial element of `elements` on `node`, from a node held in every direction,
    /// when every other joins two held nodes.
    fn element_on<'a>(
        elements: &'a [Element],
        node: usize,
        fixed: &dyn Fn(usize) -> bool,
    ) -> Option<&'a Element> {
        let mut found = None;
        for element in elements {
            let Connection::Axial { nodes } = element.connection else {
                return None;
            };
            match (nodes.contains(&node), found) {
                (false, _) if nodes.iter().all(|n| fixed(*n)) => {}
                (true, None) if fixed(nodes[0] + nodes[1] - node) && nodes[0] != nodes[1] => {
                    found = Some(element);
                }
                _ => return None,
            }
        }
        found
    }

    /// The state after `steps` increments of `h`, the state and the element lists in heap
    /// slices of a length the compiler does not know, one pass per stage: the springs'
    /// forces, the accelerations (the held direction removed), the dashpots' centred
    /// correction, the motion.
    pub fn in_slices(&self, h: f64, steps: u64) -> AxialState {
        let one = black_box(1usize);
        let mut u = vec![self.released_from; one];
        let mut carry = vec![Vector2::zeros(); one];
        let mut v = vec![Vector2::zeros(); one];
        let mut force = vec![Vector2::zeros(); one];
        let mut acceleration = vec![Vector2::zeros(); one];
        let inverse_mass = vec![1.0 / self.mass; one];
        let held = vec![self.held; one];
        // The element lists: (node, span at t = 0, its length, coefficient).
        let length = self.span.dot(&self.span).sqrt();
        let springs = vec![(0usize, self.span, length, self.stiffness); one];
        let dashpots = vec![(0usize, self.span, 1.0 / length, self.damping); one];
        let project = |a: Vector2<f64>, n: &Vector2<f64>| a - n * n.dot(&a);
        let accelerations = |u: &[Vector2<f64>], force: &mut [Vector2<f64>], acc: &mut [_]| {
            force.iter_mut().for_each(|f| *f = Vector2::zeros());
            for &(node, span, length, k) in &springs {
                let l = span + u[node];
                let square = l.dot(&l);
                let len = square.sqrt();
                force[node] -= l * (len * (1.0 / square)) * (k * (len - length));
            }
            for i in 0..acc.len() {
                acc[i] = project(force[i] * inverse_mass[i], &held[i]);
            }
        };
        // v(−½) = v(0) − (h/2)·a(0), from rest (the dashpot's force is zero at rest).
        accelerations(&u, &mut force, &mut acceleration);
        for i in 0..one {
            v[i] = acceleration[i] * (-0.5 * h);
        }
        for _ in 0..steps {
            accelerations(&u, &mut force, &mut acceleration);
            for &(node, span, scale, c) in &dashpots {
                let l = (span + u[node]) * scale;
                let g = project(l * inverse_mass[node], &held[node]);
                let w = v[node] + acceleration[node] * (0.5 * h);
                let sigma = l.dot(&w) / (l.dot(&l) + 0.5 * h * c * l.dot(&g));
                acceleration[node] -= g * (c * sigma);
            }
            for i in 0..one {
                v[i] += acceleration[i] * h;
                for k in 0..2 {
                    compensated_add(&mut u[i][k], &mut carry[i][k], v[i][k] * h);
                }
            }
        }
        AxialState {
            displacement: u[0],
            velocity: v[0],
        }
    }
}
