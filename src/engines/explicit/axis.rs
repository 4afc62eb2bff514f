//! Passes along one axis: when every line spring lies along one coordinate axis, and when every
//! particle is free along one coordinate axis alone.
//!
//! A line spring whose direction is a coordinate axis stretches by that component of its ends'
//! displacements alone and pushes along it alone; a particle held along every coordinate axis
//! but one moves along that one alone. The kernels for them read and write that one component
//! (one slice of the component-wise store, [`Vectors`]), where the general ones form dot
//! products and projections whose other terms are exact zeros: the same arithmetic on the
//! component that moves, bit for bit (a product with an exact 1 or 0 changes nothing), with
//! half the instructions and half the bytes in 2D, a third in 3D. The choice is made once per
//! scene (springs) and per step (particles), so a scene pays one branch per pass for it; a
//! scene with a spring or a particle off the axes takes the general passes throughout.

use super::model::{Forces, GROUND, LineSpring, Vectors};
use super::space::{Lin, Space, compensated_add};

/// The coordinate axis `d` is, if it is exactly one (components 1 and 0).
pub fn axis_of<V: Lin>(d: &V, dim: usize) -> Option<usize> {
    (0..dim).find(|&k| (0..dim).all(|j| d.component(j) == if j == k { 1.0 } else { 0.0 }))
}

/// The one coordinate axis a particle holding `held` moves along, if it holds exactly every
/// other axis.
pub fn free_axis<V: Lin>(held: &[V], dim: usize) -> Option<usize> {
    if held.len() + 1 != dim {
        return None;
    }
    let axes: Vec<usize> = held
        .iter()
        .map(|d| axis_of(d, dim))
        .collect::<Option<_>>()?;
    let free: Vec<usize> = (0..dim).filter(|k| !axes.contains(k)).collect();
    match free[..] {
        [k] => Some(k),
        _ => None,
    }
}

/// A line spring along the axis its set names: 16 bytes.
#[derive(Debug, Clone, Copy)]
pub(super) struct AxisSpring {
    /// Stiffness.
    c: f64,
    /// Particle at end a, or [`GROUND`].
    a: u32,
    /// Particle at end b, or [`GROUND`].
    b: u32,
}

/// The line springs, in the scene's order.
#[derive(Debug, Clone)]
pub(super) enum LineSprings<S: Space> {
    /// Every one along coordinate axis `axis`.
    Axis {
        /// The axis.
        axis: usize,
        /// The springs.
        springs: Vec<AxisSpring>,
    },
    /// Any directions.
    General(Vec<LineSpring<S>>),
}

impl<S: Space> LineSprings<S> {
    /// The springs, along one axis where every one is.
    pub(super) fn new(all: Vec<LineSpring<S>>) -> Self {
        let axis = all.first().and_then(|s| axis_of(&s.direction, S::DIM));
        match axis {
            Some(k) if all.iter().all(|s| axis_of(&s.direction, S::DIM) == Some(k)) => {
                let springs = all.iter().map(|s| AxisSpring {
                    c: s.c,
                    a: s.a,
                    b: s.b,
                });
                LineSprings::Axis {
                    axis: k,
                    springs: springs.collect(),
                }
            }
            _ => LineSprings::General(all),
        }
    }

    /// Every line spring, in the scene's order.
    pub(super) fn iter(&self) -> Box<dyn Iterator<Item = LineSpring<S>> + '_> {
        match self {
            LineSprings::Axis { axis, springs } => {
                let direction = S::V::from_components(|j| if j == *axis { 1.0 } else { 0.0 });
                Box::new(springs.iter().map(move |s| LineSpring {
                    a: s.a,
                    b: s.b,
                    direction,
                    c: s.c,
                }))
            }
            LineSprings::General(springs) => Box::new(springs.iter().copied()),
        }
    }

    /// Add the springs' forces at particle displacements `u` to the particle forces of `out`;
    /// `elastic` with their elastic energy added term by term (unchanged unless `ENERGY`).
    #[inline(always)]
    pub(super) fn add_forces<const ENERGY: bool>(
        &self,
        u: &Vectors<S::V>,
        out: &mut Forces<S>,
        elastic: f64,
    ) -> f64 {
        match self {
            LineSprings::Axis { axis, springs } => {
                out.written[*axis] = true;
                let (u, p) = (u.component(*axis), out.p.component_mut(*axis));
                along_axis::<ENERGY>(springs, u, p, elastic)
            }
            LineSprings::General(springs) => general::<S, ENERGY>(springs, u, out, elastic),
        }
    }
}

/// Springs along one axis, with `u` and `p` that axis's components of the displacements and
/// forces: the general pass's arithmetic on that component.
#[inline(always)]
fn along_axis<const ENERGY: bool>(
    springs: &[AxisSpring],
    u: &[f64],
    p: &mut [f64],
    mut elastic: f64,
) -> f64 {
    let end = |i: u32| if i == GROUND { 0.0 } else { u[i as usize] };
    for s in springs {
        let e = end(s.b) - end(s.a);
        if ENERGY {
            elastic += 0.5 * s.c * e * e;
        }
        let f = s.c * e;
        if s.a != GROUND {
            p[s.a as usize] += f;
        }
        if s.b != GROUND {
            p[s.b as usize] += -f;
        }
    }
    elastic
}

/// Springs of any direction.
#[inline(always)]
fn general<S: Space, const ENERGY: bool>(
    springs: &[LineSpring<S>],
    u: &Vectors<S::V>,
    out: &mut Forces<S>,
    mut elastic: f64,
) -> f64 {
    let end = |i: u32| {
        if i == GROUND {
            S::V::zero()
        } else {
            u.get(i as usize)
        }
    };
    for s in springs {
        let e = s.direction.dot(&(end(s.b) - end(s.a)));
        if ENERGY {
            elastic += 0.5 * s.c * e * e;
        }
        let f = s.direction * (s.c * e);
        if s.a != GROUND {
            out.add_particle(s.a as usize, f);
        }
        if s.b != GROUND {
            out.add_particle(s.b as usize, -f);
        }
    }
    elastic
}

/// How a step's particles are stepped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParticleKernel {
    /// Every one free along coordinate axis `k` alone, or held along every coordinate axis
    /// (stepped along `k` with no inverse mass: [`super::model::Constraints::along_inverse_masses`]).
    Along(usize),
    /// Any other freedoms (each particle's projection).
    General,
}

/// One particle's part of an increment along the one axis it is free on (or, with
/// `inverse_mass` 0, held on), on that component: the acceleration f·(1/m) (the general
/// projection leaves that component as it is and the others exactly 0; of a held particle,
/// ±0 for a finite force), then v(n+½) and x(n+1), the force cleared. Returns the
/// acceleration.
#[inline(always)]
pub fn step_along(
    x: &mut f64,
    carry: &mut f64,
    v: &mut f64,
    f: &mut f64,
    inverse_mass: f64,
    h: f64,
) -> f64 {
    let a = *f * inverse_mass;
    *f = 0.0;
    move_along(x, carry, v, a, h);
    a
}

/// One particle's motion along the one axis it is free on, from its acceleration `a` on that
/// component: v(n+½) = v(n−½) + h·a in place, then x(n+1) = x(n) + h·v(n+½) (compensated).
#[inline(always)]
pub fn move_along(x: &mut f64, carry: &mut f64, v: &mut f64, a: f64, h: f64) {
    *v += a * h;
    compensated_add(x, carry, *v * h);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::explicit::model::Motion;
    use crate::engines::explicit::space::{Planar, Spatial};
    use nalgebra::{Vector2, Vector3};

    /// Deterministic values of both signs over several decades.
    fn values(n: usize, seed: u64) -> Vec<f64> {
        let mut x = seed;
        (0..n)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let unit = (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                unit * 10f64.powi((x % 7) as i32 - 3)
            })
            .collect()
    }

    /// A chain of `n` particles between two grounds along `d`.
    fn springs<S: Space>(n: u32, d: S::V) -> Vec<LineSpring<S>> {
        let c = values(n as usize + 2, 7);
        (0..=n)
            .map(|i| LineSpring {
                a: if i == 0 { GROUND } else { i - 1 },
                b: if i == n { GROUND } else { i },
                direction: d,
                c: 1.0 + c[i as usize].abs(),
            })
            .collect()
    }

    /// The axis kernel's forces and energy equal the general kernel's bit for bit, and the
    /// springs come back in the scene's order; one spring off the axis makes the set general.
    fn same_forces<S: Space>(u: Vec<S::V>, d: S::V, other: S::V) {
        let n = u.len();
        let all = springs::<S>(n as u32, d);
        let mut mixed = all.clone();
        mixed[3].direction = other;
        assert!(matches!(LineSprings::new(mixed), LineSprings::General(_)));
        let springs = LineSprings::new(all.clone());
        assert!(matches!(springs, LineSprings::Axis { .. }));
        let back: Vec<_> = springs
            .iter()
            .map(|s| (s.a, s.b, s.c, s.direction))
            .collect();
        let given: Vec<_> = all.iter().map(|s| (s.a, s.b, s.c, s.direction)).collect();
        assert_eq!(back, given);
        let mut positions = Vectors::zeros(n);
        for (i, u) in u.iter().enumerate() {
            positions.set(i, *u);
        }
        let mut by_axis = Forces::<S>::zeros(n, 0, 0);
        let mut by_general = Forces::<S>::zeros(n, 0, 0);
        let e_axis = springs.add_forces::<true>(&positions, &mut by_axis, 0.25);
        let e_general = general::<S, true>(&all, &positions, &mut by_general, 0.25);
        assert_eq!(e_axis.to_bits(), e_general.to_bits());
        for (a, b) in by_axis.p.iter().zip(by_general.p.iter()) {
            for k in 0..S::DIM {
                assert_eq!(
                    a.component(k).to_bits(),
                    b.component(k).to_bits(),
                    "{a:?} {b:?}"
                );
            }
        }
    }

    #[test]
    fn axis_springs_sum_as_the_general_pass() {
        let v = values(64, 3);
        let u2: Vec<Vector2<f64>> = v.chunks(2).map(|c| Vector2::new(c[0], c[1])).collect();
        same_forces::<Planar>(u2, Vector2::x(), Vector2::new(0.6, 0.8));
        let v = values(96, 5);
        let u3: Vec<Vector3<f64>> = v
            .chunks(3)
            .map(|c| Vector3::new(c[0], c[1], c[2]))
            .collect();
        same_forces::<Spatial>(u3.clone(), Vector3::z(), Vector3::new(0.0, 0.6, 0.8));
        same_forces::<Spatial>(u3, Vector3::y(), Vector3::x());
    }

    /// One particle free along one axis steps as the general projection steps it, bit for bit,
    /// its held components left at rest.
    #[test]
    fn a_particle_along_one_axis_steps_as_the_projection_does() {
        let v = values(40, 11);
        let h = 3.0e-4;
        let held = [Vector3::z(), Vector3::x()];
        let motion = Motion::of(&held, 3);
        assert_eq!(free_axis(&held, 3), Some(1));
        for c in v.chunks(5) {
            let along = |x: f64| Vector3::new(0.0, x, 0.0);
            let (mut x, mut carry, mut vel) = (along(c[0]), along(c[1] * 1e-17), along(c[2]));
            let mut f = Vector3::new(c[3], c[4], c[0] * c[4]);
            let m = 1.0 / (0.1 + c[3].abs());
            let (mut x2, mut carry2, mut vel2, f2) = (x, carry, vel, f);
            let a = step_along(&mut x[1], &mut carry[1], &mut vel[1], &mut f[1], m, h);
            let a2 = motion.project(f2 * m);
            vel2 += a2 * h;
            compensated_add(&mut x2, &mut carry2, vel2 * h);
            let a = Vector3::new(0.0, a, 0.0);
            for (p, q) in [(a, a2), (x, x2), (carry, carry2), (vel, vel2)] {
                for k in 0..3 {
                    assert_eq!(p[k].to_bits(), q[k].to_bits(), "{p:?} {q:?}");
                }
            }
            f[0] = 0.0;
            f[2] = 0.0;
            assert_eq!(f, Vector3::zeros());
        }
    }

    #[test]
    fn axes_are_exact_unit_vectors() {
        assert_eq!(axis_of(&Vector2::new(1.0, 0.0), 2), Some(0));
        assert_eq!(axis_of(&Vector3::new(0.0, -0.0, 1.0), 3), Some(2));
        assert_eq!(axis_of(&Vector2::new(-1.0, 0.0), 2), None);
        assert_eq!(axis_of(&Vector2::new(1.0, 1e-300), 2), None);
        let (x, y, z): (Vector3<f64>, Vector3<f64>, Vector3<f64>) =
            (Vector3::x(), Vector3::y(), Vector3::z());
        assert_eq!(free_axis(&[z, x], 3), Some(1));
        assert_eq!(free_axis(&[y, z], 3), Some(0));
        assert_eq!(free_axis(&[x, x], 3), None);
        assert_eq!(free_axis(&[z], 3), None);
        assert_eq!(free_axis(&[Vector2::new(0.6, 0.8)], 2), None);
        assert_eq!(free_axis(&[Vector2::y()], 2), Some(0));
    }
}
