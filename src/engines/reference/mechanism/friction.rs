//! Coulomb friction of the closed pairs, each in its [`Grip`].
//!
//! A stuck pair's velocity at its contact point relative to the body it touches, V
//! ([`super::touch`]; a particle: ṗ − v − ω × (p − x)), has no tangential part: its tangential
//! rows (one per unit tangent t, t·V) join the constraints, and their multipliers λ_t are the
//! tangential force on the node (on a ball, at its contact point: it rolls), held while
//! |λ_t| ≤ μ_s λ_n.
//!
//! A sliding node is pushed by μ_k λ_n against its slip, direction d, and the body by the
//! reaction at the contact point (a ball's friction acts at its contact point, so it also
//! spins the ball); the friction depends on the normal multiplier, so the normal's column in
//! the equations carries it: with D the row of d·V,
//!
//!   [[A, −(B − μ_k D T)ᵀ], [B, 0]] [ẇ; λ] = [b; −Ġu].
//!
//! The slip direction is the relative tangential velocity v_t's, extended smoothly through its
//! zero so that a stop is an event found by bisection like the others:
//! d = (σ v_t + η s)/|σ v_t + η s|, s the direction the slip had at the last accepted
//! integration step, σ = sign(v_t·s), η = [`DIRECTION_FLOOR`] × the largest velocity
//! coordinate. Below η, v_t's own direction is round-off (a node that has just started to slip
//! from rest moves along s). Where v_t stays on one line (2D, and 3D slides whose tangential
//! forces keep to the sliding line) d = s exactly; where it turns, d differs from v_t/|v_t| by
//! η/|v_t| times the turn over one step.

use super::touch::Touch;
use super::{Mechanism, Placement};
use crate::scene::{Dimension, Friction};
use nalgebra::{DMatrix, DVector, Vector3};

/// A closed pair's tangential state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Grip {
    /// No friction: a frictionless pair, or an open one.
    Free,
    /// Sliding, along `reference` (unit, body frame) at the last accepted integration step.
    Slip {
        /// The slip's direction in the body frame.
        reference: Vector3<f64>,
    },
    /// Stuck: the tangential relative velocity is held at zero.
    Stick,
}

/// Below this fraction of the largest velocity coordinate a relative tangential velocity does
/// not choose the slip direction (its own is round-off there).
pub const DIRECTION_FLOOR: f64 = 1e-9;

/// A sliding pair's friction column: its normal multiplier's row in G, the slip direction d
/// (world), d's generalised row D on u, μ_k, and d·v_t.
pub(super) struct SlipColumn {
    pub(super) row: usize,
    pub(super) pair: usize,
    pub(super) direction: Vector3<f64>,
    pub(super) generalized: DVector<f64>,
    pub(super) mu: f64,
    pub(super) speed: f64,
}

impl Mechanism {
    /// Pair `k`'s Coulomb friction, if any.
    pub fn friction(&self, k: usize) -> Option<Friction> {
        self.contacts[k].friction
    }

    /// Whether any pair has friction.
    pub fn has_friction(&self) -> bool {
        self.frictional
    }

    /// Pair `k`'s name.
    pub fn contact_name(&self, k: usize) -> &str {
        &self.contacts[k].name
    }

    /// Pair `k`'s tangential velocity at its contact point relative to the body it touches
    /// (world).
    pub fn slip_velocity(&self, at: &Placement, u: &DVector<f64>, k: usize) -> Vector3<f64> {
        let touch = self.touch(at, u, k);
        touch.tangential(&touch.slip())
    }

    /// Pair `k`'s relative tangential acceleration, the rate of [`Self::slip_velocity`] with
    /// the tangents turning with the body, at velocity u and its rate `rate`.
    pub fn slip_acceleration(
        &self,
        at: &Placement,
        u: &DVector<f64>,
        rate: &DVector<f64>,
        k: usize,
    ) -> Vector3<f64> {
        let touch = self.touch(at, u, k);
        let n = self.velocity_len();
        touch.tangents.iter().fold(Vector3::zeros(), |s, t| {
            let along = touch.row(t, n).dot(rate) + touch.rate(t);
            s + t * along
        })
    }

    /// A world vector at pair `k` in its body's frame.
    pub fn to_body(&self, at: &Placement, k: usize, v: &Vector3<f64>) -> Vector3<f64> {
        at.orientations[self.contacts[k].body].inverse() * v
    }

    /// A vector of pair `k`'s body frame in the world.
    pub fn to_world(&self, at: &Placement, k: usize, v: &Vector3<f64>) -> Vector3<f64> {
        at.orientations[self.contacts[k].body] * v
    }

    /// The number of tangential rows of the stuck pairs.
    pub(super) fn stick_rows(&self, active: &[bool], grips: &[Grip]) -> usize {
        let per_pair = match self.dimension {
            Dimension::Two => 1,
            Dimension::Three => 2,
        };
        active
            .iter()
            .zip(grips)
            .filter(|(a, g)| **a && **g == Grip::Stick)
            .count()
            * per_pair
    }

    /// The stuck pairs' tangential rows into G and Ġu from row `first` on. A stuck node does
    /// not move on the body (ṡ = 0), so its tangents turn with the body; the curvature's term,
    /// second order in the relative velocity that the constraint holds at zero, is left out.
    pub(super) fn add_stick_rows(
        &self,
        at: &Placement,
        u: &DVector<f64>,
        (active, grips): (&[bool], &[Grip]),
        g: &mut DMatrix<f64>,
        gdot_u: &mut DVector<f64>,
        first: usize,
    ) {
        let mut row = first;
        for k in 0..self.contacts.len() {
            if !(active[k] && grips[k] == Grip::Stick) {
                continue;
            }
            let touch = self.touch(at, u, k);
            for t in &touch.tangents {
                touch.add_row(g, row, t);
                gdot_u[row] = touch.rate(t);
                row += 1;
            }
        }
    }

    /// The friction columns of the sliding pairs.
    pub(super) fn slip_columns(
        &self,
        at: &Placement,
        u: &DVector<f64>,
        active: &[bool],
        grips: &[Grip],
    ) -> Vec<SlipColumn> {
        let mut columns = Vec::new();
        let mut row = 0;
        for k in 0..self.contacts.len() {
            if !active[k] {
                continue;
            }
            if let (Grip::Slip { reference }, Some(f)) = (grips[k], self.contacts[k].friction) {
                let touch = self.touch(at, u, k);
                let v_t = touch.tangential(&touch.slip());
                let direction = slip_direction(&touch, &v_t, &reference, u.amax());
                columns.push(SlipColumn {
                    row,
                    pair: k,
                    direction,
                    generalized: touch.row(&direction, self.velocity_len()),
                    mu: f.kinetic_coefficient,
                    speed: direction.dot(&v_t),
                });
            }
            row += 1;
        }
        columns
    }

    /// The friction force on each pair's node, from the normal forces `contact`, the stuck
    /// pairs' multipliers `sticking` (in row order) and the sliding pairs' columns, and the
    /// power the sliding pairs dissipate.
    pub(super) fn friction_forces(
        &self,
        at: &Placement,
        (active, grips): (&[bool], &[Grip]),
        contact: &[f64],
        sticking: &[f64],
        slips: &[SlipColumn],
    ) -> (Vec<Vector3<f64>>, f64) {
        let mut forces = vec![Vector3::zeros(); self.contacts.len()];
        let mut multipliers = sticking.iter();
        for k in 0..self.contacts.len() {
            if active[k] && grips[k] == Grip::Stick {
                for t in &self.tangents(at, k) {
                    forces[k] += t * multipliers.next().copied().unwrap_or(0.0);
                }
            }
        }
        let mut power = 0.0;
        for s in slips {
            let normal = contact[s.pair];
            forces[s.pair] = -s.direction * (s.mu * normal);
            power += s.mu * normal * s.speed;
        }
        (forces, power)
    }
}

/// The slip direction d (world) of a pair with relative tangential velocity `v_t` whose slip
/// had direction `reference` (body frame) at the last accepted step, `scale` the largest
/// velocity coordinate (see the module's doc).
fn slip_direction(
    touch: &Touch,
    v_t: &Vector3<f64>,
    reference: &Vector3<f64>,
    scale: f64,
) -> Vector3<f64> {
    let s = touch.tangential(&(touch.rot * reference));
    let sigma = if v_t.dot(&s) < 0.0 { -1.0 } else { 1.0 };
    let d = v_t * sigma + s * (DIRECTION_FLOOR * scale);
    let norm = d.norm();
    if norm > 0.0 {
        d / norm
    } else {
        s.try_normalize(0.0).unwrap_or(s)
    }
}
