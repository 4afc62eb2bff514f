//! The arithmetic floor of an increment of masses that move along one line: each free along one
//! translation of its frame, all along the same direction, joined to each other and to still
//! nodes by springs along that line (grounded on the translation, or of fixed direction along
//! the line) and one dashpot along it (springs_n2n_b), written out by hand with the state in heap
//! slices.
//!
//! It is the explicit engine's recurrence for such a scene, in the one coordinate each mass has:
//! central differences; each spring's force `k·(s_b − s_a)` from the displacements along the
//! line of its ends (zero at a still node); the centred dashpot solved directly in its rate,
//! `(1 + (h/2)·c·(1/m_a + 1/m_b)) r = w_b − w_a`, `w` the undamped centred velocity
//! `v(n−½) + (h/2)·F/m` (a still end has no 1/m and no w); the half-step velocities restarted
//! from rest at the release; the displacements summed with a compensated (Kahan) addition. An
//! element between two still nodes moves nothing and is left out, as is what records or checks a
//! run (rows, energy). It is written here from the scheme, not taken from the engine, and
//! `tests/floor.rs` checks that the two agree to round-off.

use super::{Release, compensated_add};
use crate::scene::{Connection, Dof, Element, Scene};
use nalgebra::Vector3;
use std::hint::black_box;

/// A spring or dashpot along the line: its ends (a mass's index, or `None` for a still node),
/// its force on end b `−coefficient·(s_b − s_a)` (or of the rates), and on end a the opposite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineElement {
    /// End a and end b.
    pub ends: [Option<usize>; 2],
    /// Stiffness (N/m) or damping (N·s/m).
    pub coefficient: f64,
}

/// Masses on one line, on springs and one dashpot along it, released from rest.
#[derive(Debug, Clone, PartialEq)]
pub struct LineOscillator {
    /// The masses that move (kg).
    pub masses: Vec<f64>,
    /// Their displacements along the line at the release (m).
    pub released_from: Vec<f64>,
    /// The springs on them, in the scene's order.
    pub springs: Vec<LineElement>,
    /// The dashpot.
    pub dashpot: LineElement,
    /// Duration of the dynamic step (s).
    pub duration: f64,
}

/// The state after a run: each mass's displacement along the line and half-step velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct LineState {
    /// Displacements (m).
    pub displacements: Vec<f64>,
    /// Velocities at the last half step (m/s).
    pub velocities: Vec<f64>,
}

/// A node the dynamic step moves: its free translation and that translation's direction.
type Moving = (usize, Dof, Vector3<f64>);

impl LineOscillator {
    /// The masses a scene describes, when it is exactly that: no bodies, contacts, loads or
    /// initial velocities, the centred dashpot treatment, a static step then a dynamic one;
    /// every node the dynamic step moves has mass, is free along one translation of its frame
    /// whose direction is the same for all, is held in the others in both steps, and is held or
    /// has that translation prescribed in the static step; every node the dynamic step does not
    /// move is held in every translation in both steps (still); every spring and the one dashpot
    /// with a moving end act along the line (grounded on a mass's free translation, or of fixed
    /// direction along the line), and every other joins still nodes alone.
    pub fn of(scene: &Scene) -> Option<Self> {
        let (steps, duration) = Release::of(scene)?;
        let still = |node: usize| steps.still(node);
        let mut moving: Vec<Moving> = Vec::new();
        let mut released_from = Vec::new();
        for node in 0..scene.nodes.len() {
            if still(node) {
                continue;
            }
            let (dof, along, start) = steps.free_translation(node)?;
            moving.push((node, dof, along));
            released_from.push(start.unwrap_or(0.0));
        }
        let line = moving.first()?.2;
        if moving.iter().any(|m| m.2 != line) {
            return None;
        }
        let springs = Self::elements(&scene.springs, &moving, &still, line)?;
        let [dashpot] = Self::elements(&scene.dashpots, &moving, &still, line)?[..] else {
            return None;
        };
        Some(Self {
            masses: moving.iter().map(|m| scene.nodes[m.0].mass).collect(),
            released_from,
            springs,
            dashpot,
            duration,
        })
    }

    /// The elements of `elements` with a moving end, in order, as [`LineElement`]s; None when
    /// one does not act along `line` or joins a node that is neither moving nor still.
    fn elements(
        elements: &[Element],
        moving: &[Moving],
        still: &dyn Fn(usize) -> bool,
        line: Vector3<f64>,
    ) -> Option<Vec<LineElement>> {
        let index = |node: usize| moving.iter().position(|m| m.0 == node);
        // A node as an end: Some(Some(mass)) moving, Some(None) still, None neither.
        let end = |node: usize| match index(node) {
            Some(i) => Some(Some(i)),
            None => still(node).then_some(None),
        };
        let mut out = Vec::new();
        for element in elements {
            let ends = match element.connection {
                Connection::Grounded { node, dof } => match index(node) {
                    Some(i) if moving[i].1 == dof => [None, Some(i)],
                    Some(_) => return None,
                    None if still(node) => continue,
                    None => return None,
                },
                Connection::FixedDirection { nodes, direction }
                    if direction == line || direction == -line =>
                {
                    [end(nodes[0])?, end(nodes[1])?]
                }
                Connection::FixedDirection { nodes, .. } | Connection::Axial { nodes } => {
                    if still(nodes[0]) && still(nodes[1]) {
                        continue;
                    }
                    return None;
                }
            };
            if ends != [None, None] {
                out.push(LineElement {
                    ends,
                    coefficient: element.coefficient,
                });
            }
        }
        Some(out)
    }

    /// The state after `steps` increments of `h`, the state and the element lists in heap
    /// slices, one pass per stage: the springs' forces, the accelerations, the dashpot's
    /// centred correction, the motion.
    pub fn in_slices(&self, h: f64, steps: u64) -> LineState {
        let n = black_box(self.masses.len());
        let mut u = self.released_from.clone();
        let (mut carry, mut v) = (vec![0.0; n], vec![0.0; n]);
        let (mut force, mut acceleration) = (vec![0.0; n], vec![0.0; n]);
        let inverse_mass: Vec<f64> = self.masses.iter().map(|m| 1.0 / m).collect();
        let springs = self.springs.clone();
        let dashpots = vec![self.dashpot; black_box(1)];
        let at = |s: &[f64], end: Option<usize>| end.map_or(0.0, |i| s[i]);
        let accelerations = |u: &[f64], force: &mut [f64], acc: &mut [f64]| {
            force.iter_mut().for_each(|f| *f = 0.0);
            for s in &springs {
                let f = s.coefficient * (at(u, s.ends[1]) - at(u, s.ends[0]));
                for (end, f) in s.ends.iter().zip([f, -f]) {
                    if let Some(i) = end {
                        force[*i] += f;
                    }
                }
            }
            for i in 0..acc.len() {
                acc[i] = force[i] * inverse_mass[i];
            }
        };
        // v(−½) = v(0) − (h/2)·a(0), from rest (the dashpot's force is zero at rest).
        accelerations(&u, &mut force, &mut acceleration);
        for i in 0..n {
            v[i] = acceleration[i] * (-0.5 * h);
        }
        for _ in 0..steps {
            accelerations(&u, &mut force, &mut acceleration);
            for d in &dashpots {
                let c = d.coefficient;
                let (mut compliance, mut rate) = (1.0, 0.0);
                for (end, sign) in d.ends.iter().zip([-1.0, 1.0]) {
                    if let Some(i) = *end {
                        compliance += 0.5 * h * c * inverse_mass[i];
                        rate += sign * (v[i] + acceleration[i] * (0.5 * h));
                    }
                }
                let force = c * (rate / compliance);
                for (end, sign) in d.ends.iter().zip([1.0, -1.0]) {
                    if let Some(i) = *end {
                        acceleration[i] += sign * force * inverse_mass[i];
                    }
                }
            }
            for i in 0..n {
                v[i] += acceleration[i] * h;
                compensated_add(&mut u[i], &mut carry[i], v[i] * h);
            }
        }
        LineState {
            displacements: u,
            velocities: v,
        }
    }
}
