//! The arithmetic floor of an increment with an axial dashpot: 2D masses, each free along one
//! direction, joined to each other and to held nodes by axial springs and one axial dashpot
//! (springs_grounded_c, springs_n2n_c), written out by hand with the state in heap slices.
//!
//! It is the explicit engine's recurrence for such a scene: central differences; each axial
//! spring's force along its current line, 1/|l| formed as |l|·(1/|l|²); the projection that
//! removes each mass's held direction; the centred dashpot solved directly in its rate:
//! `(|l|² + (h/2)·c·Σ e·g) σ = Σ e·w` over its moving ends, `e = ∓l` at end a and b,
//! `g = P e / m`, `w` the undamped centred velocity. Where every mass the dashpot moves is held
//! across its line at the release (the seed cases), the line cannot turn: it is the unit line
//! there, and `g` and the system's one entry are formed once for the run; otherwise it is the
//! current line `l` (taken over its length at t = 0, so no square root on the chain), formed at
//! every increment. The half-step velocities restart from rest at the release; the
//! displacements are summed with a compensated (Kahan) addition. A spring between two held
//! nodes moves nothing and is left out, as is what records or checks a run (rows, energy). It
//! is written here from the scheme, not taken from the engine, and `tests/floor.rs` checks
//! that the two agree to round-off.

use super::{compensated_add, released};
use crate::scene::{Connection, Dimension, Dof, Element, Scene, Step};
use nalgebra::Vector2;
use std::hint::black_box;

/// A mass free along one direction of the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineMass {
    /// Mass (kg).
    pub mass: f64,
    /// The direction it is held in (unit).
    pub held: Vector2<f64>,
    /// Its displacement at the release (m).
    pub released_from: Vector2<f64>,
}

/// An axial spring or dashpot: its ends (a mass's index, or `None` for a held node), the span
/// from end a to end b at t = 0, its coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxialElement {
    /// End a and end b.
    pub ends: [Option<usize>; 2],
    /// From end a to end b at t = 0 (m).
    pub span: Vector2<f64>,
    /// Stiffness (N/m) or damping (N·s/m).
    pub coefficient: f64,
}

/// Masses on axial springs and one axial dashpot, released from rest.
#[derive(Debug, Clone, PartialEq)]
pub struct AxialOscillator {
    /// The masses that move.
    pub masses: Vec<LineMass>,
    /// The springs on them, in the scene's order.
    pub springs: Vec<AxialElement>,
    /// The dashpot.
    pub dashpot: AxialElement,
    /// Duration of the dynamic step (s).
    pub duration: f64,
}

/// A moving end of a dashpot on a fixed line: the mass, the line's sign at that end `e`, and
/// the acceleration `g = P e / m` a unit force along it gives the mass.
type DashpotEnd = (usize, Vector2<f64>, Vector2<f64>);

/// The state after a run: each mass's displacement and half-step velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct AxialState {
    /// Displacements (m).
    pub displacements: Vec<Vector2<f64>>,
    /// Velocities at the last half step (m/s).
    pub velocities: Vec<Vector2<f64>>,
}

impl AxialOscillator {
    /// The masses a scene describes, when it is exactly that: 2D, no bodies, contacts, loads
    /// or initial velocities, the centred dashpot treatment, a static step then a dynamic one;
    /// every node the dynamic step moves has mass, is held in its frame's uy alone, and is held
    /// or has its ux prescribed in the static step; every spring and the one dashpot are axial
    /// and have a moving end, or join two held nodes.
    pub fn of(scene: &Scene) -> Option<Self> {
        if scene.dimension != Dimension::Two {
            return None;
        }
        let (static_step, dynamic, duration) = released(scene)?;
        let holds = |node: usize, dof: Dof| super::holds(dynamic, node, dof);
        let moves =
            |node: usize| !(holds(node, Dof::Translation(0)) && holds(node, Dof::Translation(1)));
        let moving: Vec<usize> = (0..scene.nodes.len()).filter(|n| moves(*n)).collect();
        let mut masses = Vec::with_capacity(moving.len());
        for &node in &moving {
            masses.push(Self::mass(
                scene,
                static_step,
                node,
                holds(node, Dof::Translation(1)),
            )?);
        }
        let index = |node: usize| moving.iter().position(|n| *n == node);
        let springs = Self::elements(scene, &scene.springs, &index)?;
        let [dashpot] = Self::elements(scene, &scene.dashpots, &index)?[..] else {
            return None;
        };
        Some(Self {
            masses,
            springs,
            dashpot,
            duration,
        })
    }

    /// The moving node `node` as a [`LineMass`], when it has mass, is held in its frame's uy
    /// alone (`held`) and starts where `static_step` holds or prescribes it.
    fn mass(scene: &Scene, static_step: &Step, node: usize, held: bool) -> Option<LineMass> {
        let at = |dof: Dof| {
            static_step
                .conditions
                .iter()
                .find(|c| c.node == node && c.dof == dof)
        };
        let release = at(Dof::Translation(0))?.value.unwrap_or(0.0);
        if !held || scene.nodes[node].mass <= 0.0 || at(Dof::Translation(1)).is_none() {
            return None;
        }
        let frame = &scene.nodes[node].frame;
        let (along, held) = (frame.column(0), frame.column(1));
        Some(LineMass {
            mass: scene.nodes[node].mass,
            held: Vector2::new(held.x, held.y),
            released_from: Vector2::new(along.x, along.y) * release,
        })
    }

    /// The axial elements of `elements` with a moving end (`index`: a node's mass), in order;
    /// None when one is not axial.
    fn elements(
        scene: &Scene,
        elements: &[Element],
        index: &dyn Fn(usize) -> Option<usize>,
    ) -> Option<Vec<AxialElement>> {
        let mut out = Vec::new();
        for element in elements {
            let Connection::Axial { nodes } = element.connection else {
                return None;
            };
            let ends = [index(nodes[0]), index(nodes[1])];
            if ends == [None, None] {
                continue;
            }
            let (a, b) = (
                scene.nodes[nodes[0]].position,
                scene.nodes[nodes[1]].position,
            );
            out.push(AxialElement {
                ends,
                span: Vector2::new(b.x - a.x, b.y - a.y),
                coefficient: element.coefficient,
            });
        }
        Some(out)
    }

    /// The state after `steps` increments of `h`, the state and the element lists in heap
    /// slices, one pass per stage: the springs' forces, the accelerations (each mass's held
    /// direction removed), the dashpot's centred correction, the motion.
    pub fn in_slices(&self, h: f64, steps: u64) -> AxialState {
        let n = black_box(self.masses.len());
        let zeros = vec![Vector2::zeros(); n];
        let mut u: Vec<_> = self.masses.iter().map(|m| m.released_from).collect();
        let (mut carry, mut v) = (zeros.clone(), zeros.clone());
        let (mut force, mut acceleration) = (zeros.clone(), zeros);
        let inverse_mass: Vec<f64> = self.masses.iter().map(|m| 1.0 / m.mass).collect();
        let held: Vec<_> = self.masses.iter().map(|m| m.held).collect();
        // The springs with their lengths at t = 0; the dashpot with one over its length.
        let length = |e: &AxialElement| e.span.dot(&e.span).sqrt();
        let springs: Vec<_> = self.springs.iter().map(|s| (*s, length(s))).collect();
        let dashpots = vec![(self.dashpot, 1.0 / length(&self.dashpot)); black_box(1)];
        let project = |a: Vector2<f64>, n: &Vector2<f64>| a - n * n.dot(&a);
        let at = |u: &[Vector2<f64>], end: Option<usize>| end.map_or(Vector2::zeros(), |i| u[i]);
        let accelerations = |u: &[Vector2<f64>], force: &mut [Vector2<f64>], acc: &mut [_]| {
            force.iter_mut().for_each(|f| *f = Vector2::zeros());
            for (s, length) in &springs {
                let l = s.span + (at(u, s.ends[1]) - at(u, s.ends[0]));
                let square = l.dot(&l);
                let len = square.sqrt();
                let f = l * (len * (1.0 / square)) * (s.coefficient * (len - length));
                for (end, f) in s.ends.iter().zip([f, -f]) {
                    if let Some(i) = end {
                        force[*i] += f;
                    }
                }
            }
            for i in 0..acc.len() {
                acc[i] = project(force[i] * inverse_mass[i], &held[i]);
            }
        };
        // v(−½) = v(0) − (h/2)·a(0), from rest (the dashpot's force is zero at rest).
        accelerations(&u, &mut force, &mut acceleration);
        for i in 0..n {
            v[i] = acceleration[i] * (-0.5 * h);
        }
        let c = self.dashpot.coefficient;
        let fixed = self.fixed_line(&u, &held, &inverse_mass, h);
        for _ in 0..steps {
            accelerations(&u, &mut force, &mut acceleration);
            match &fixed {
                Some((ends, inverse)) => {
                    let centred = |i: usize| v[i] + acceleration[i] * (0.5 * h);
                    let rate: f64 = ends.iter().map(|(i, e, _)| e.dot(&centred(*i))).sum();
                    let sigma = rate * inverse;
                    for (i, _, g) in ends {
                        acceleration[*i] -= g * (c * sigma);
                    }
                }
                None => {
                    for &(d, scale) in &dashpots {
                        let l = (d.span + (at(&u, d.ends[1]) - at(&u, d.ends[0]))) * scale;
                        let moving = d
                            .ends
                            .iter()
                            .zip([-l, l])
                            .filter_map(|(end, e)| Some(((*end)?, e)));
                        let (mut matrix, mut rhs) = (l.dot(&l), 0.0);
                        for (i, e) in moving.clone() {
                            let g = project(e * inverse_mass[i], &held[i]);
                            matrix += 0.5 * h * c * e.dot(&g);
                            rhs += e.dot(&(v[i] + acceleration[i] * (0.5 * h)));
                        }
                        let sigma = rhs / matrix;
                        for (i, e) in moving {
                            acceleration[i] -= project(e * inverse_mass[i], &held[i]) * (c * sigma);
                        }
                    }
                }
            }
            for i in 0..n {
                v[i] += acceleration[i] * h;
                for k in 0..2 {
                    compensated_add(&mut u[i][k], &mut carry[i][k], v[i][k] * h);
                }
            }
        }
        AxialState {
            displacements: u,
            velocities: v,
        }
    }

    /// Where every mass the dashpot moves is held across its line at displacements `u` (a
    /// cosine of at most 1e-14 between the two), its moving ends `(mass, e, g)` along that unit
    /// line, `e = ∓line`, `g = P e / m`, and `1/(1 + (h/2)·c·Σ e·g)`; None otherwise.
    fn fixed_line(
        &self,
        u: &[Vector2<f64>],
        held: &[Vector2<f64>],
        inverse_mass: &[f64],
        h: f64,
    ) -> Option<(Vec<DashpotEnd>, f64)> {
        let d = &self.dashpot;
        let at = |end: Option<usize>| end.map_or(Vector2::zeros(), |i| u[i]);
        let span = d.span + (at(d.ends[1]) - at(d.ends[0]));
        let line = span / span.norm();
        let mut ends = Vec::with_capacity(2);
        let mut entry = 1.0;
        for (end, e) in d.ends.iter().zip([-line, line]) {
            let Some(i) = *end else { continue };
            if held[i].dot(&line).abs() > 1e-14 {
                return None;
            }
            let g = (e - held[i] * held[i].dot(&e)) * inverse_mass[i];
            entry += 0.5 * h * d.coefficient * e.dot(&g);
            ends.push((i, e, g));
        }
        Some((ends, 1.0 / entry))
    }
}
