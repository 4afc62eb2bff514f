//! Runs: consecutive line springs, and consecutive particles, that one kernel steps.
//!
//! A line spring whose direction is a coordinate axis stretches by that component of its ends'
//! displacements alone and pushes along it alone; a particle held along every coordinate axis
//! but one moves along that one alone. Their kernels read and write that one component of each
//! vector, where the general ones form dot products and projections whose other terms are exact
//! zeros: the same arithmetic on the component that moves, bit for bit (a product with an exact
//! 1 or 0 changes nothing), with half the instructions in 2D and a third in 3D. The runs keep
//! the scene's order, so every force is summed in the order the general pass sums it.

use super::model::{Forces, GROUND, LineSpring, Vectors};
use super::space::{Lin, Space, compensated_add};
use std::ops::Range;

/// Consecutive items that one kernel takes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Run<K> {
    /// The items' indices.
    pub range: Range<usize>,
    /// Their kernel.
    pub kernel: K,
}

/// The runs of `items` under `kernel`, in order: each as long as the kernel stays the same.
pub fn runs<T, K: PartialEq>(items: &[T], kernel: impl Fn(&T) -> K) -> Vec<Run<K>> {
    let mut out: Vec<Run<K>> = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let k = kernel(item);
        match out.last_mut() {
            Some(run) if run.kernel == k => run.range.end = i + 1,
            _ => out.push(Run {
                range: i..i + 1,
                kernel: k,
            }),
        }
    }
    out
}

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

/// `body(k)` with `k` a constant in each arm, so that an inlined kernel indexes one component
/// without a runtime index.
#[inline(always)]
pub fn on_axis<R>(k: usize, mut body: impl FnMut(usize) -> R) -> R {
    match k {
        0 => body(0),
        1 => body(1),
        _ => body(2),
    }
}

/// How a run of line springs is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineKernel {
    /// Along coordinate axis `k`, both ends particles.
    Axis(usize),
    /// Along coordinate axis `k`, an end on the ground.
    AxisGrounded(usize),
    /// Any other direction.
    General,
}

/// A line spring along a coordinate axis (which its run says): 16 bytes.
#[derive(Debug, Clone, Copy)]
pub(super) struct AxisSpring {
    /// Stiffness.
    c: f64,
    /// Particle at end a, or [`GROUND`].
    a: u32,
    /// Particle at end b, or [`GROUND`].
    b: u32,
}

/// The line springs in runs by kernel: those along a coordinate axis as [`AxisSpring`]s, the
/// others as they are, each list in the scene's order.
#[derive(Debug, Clone)]
pub(super) struct LineSprings<S: Space> {
    along: Vec<AxisSpring>,
    other: Vec<LineSpring<S>>,
    /// The runs; an axis kernel's range is in `along`, the general kernel's in `other`.
    runs: Vec<Run<LineKernel>>,
}

impl<S: Space> LineSprings<S> {
    /// The springs and their runs.
    pub(super) fn new(all: Vec<LineSpring<S>>) -> Self {
        let kernel = |s: &LineSpring<S>| match axis_of(&s.direction, S::DIM) {
            Some(k) if s.a != GROUND && s.b != GROUND => LineKernel::Axis(k),
            Some(k) => LineKernel::AxisGrounded(k),
            None => LineKernel::General,
        };
        let mut runs = runs(&all, kernel);
        let (mut along, mut other) = (Vec::new(), Vec::new());
        for run in &mut runs {
            let springs = &all[run.range.clone()];
            let list_len = if run.kernel == LineKernel::General {
                other.extend_from_slice(springs);
                other.len()
            } else {
                along.extend(springs.iter().map(|s| AxisSpring {
                    c: s.c,
                    a: s.a,
                    b: s.b,
                }));
                along.len()
            };
            run.range = list_len - springs.len()..list_len;
        }
        Self { along, other, runs }
    }

    /// Every line spring, in the scene's order.
    pub(super) fn iter(&self) -> impl Iterator<Item = LineSpring<S>> + '_ {
        self.runs.iter().flat_map(|run| {
            let axis = match run.kernel {
                LineKernel::Axis(k) | LineKernel::AxisGrounded(k) => Some(k),
                LineKernel::General => None,
            };
            let (other, along) = match axis {
                None => (&self.other[run.range.clone()], &[][..]),
                Some(_) => (&[][..], &self.along[run.range.clone()]),
            };
            let direction = S::V::from_components(|j| if Some(j) == axis { 1.0 } else { 0.0 });
            other
                .iter()
                .copied()
                .chain(along.iter().map(move |s| LineSpring {
                    a: s.a,
                    b: s.b,
                    direction,
                    c: s.c,
                }))
        })
    }

    /// Add the springs' forces at particle displacements `u` to the particle forces of `out`;
    /// `elastic` with their elastic energy added term by term (unchanged unless `ENERGY`).
    #[inline(always)]
    pub(super) fn add_forces<const ENERGY: bool>(
        &self,
        u: &Vectors<S::V>,
        out: &mut Forces<S>,
        mut elastic: f64,
    ) -> f64 {
        for run in &self.runs {
            let r = run.range.clone();
            elastic = match run.kernel {
                LineKernel::Axis(k) => on_axis(k, |k| {
                    out.written[k] = true;
                    let (u, p) = (u.component(k), out.p.component_mut(k));
                    along_axis::<ENERGY, false>(&self.along[r.clone()], u, p, elastic)
                }),
                LineKernel::AxisGrounded(k) => on_axis(k, |k| {
                    out.written[k] = true;
                    let (u, p) = (u.component(k), out.p.component_mut(k));
                    along_axis::<ENERGY, true>(&self.along[r.clone()], u, p, elastic)
                }),
                LineKernel::General => general::<S, ENERGY>(&self.other[r], u, out, elastic),
            };
        }
        elastic
    }
}

/// Springs along one axis, with `u` and `p` that axis's components of the displacements and
/// forces: the general pass's arithmetic on that component.
#[inline(always)]
fn along_axis<const ENERGY: bool, const GROUNDED: bool>(
    springs: &[AxisSpring],
    u: &[f64],
    p: &mut [f64],
    mut elastic: f64,
) -> f64 {
    let end = |i: u32| {
        if GROUNDED && i == GROUND {
            0.0
        } else {
            u[i as usize]
        }
    };
    for s in springs {
        let e = end(s.b) - end(s.a);
        if ENERGY {
            elastic += 0.5 * s.c * e * e;
        }
        let f = s.c * e;
        if !GROUNDED || s.a != GROUND {
            p[s.a as usize] += f;
        }
        if !GROUNDED || s.b != GROUND {
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

/// How a run of particles is stepped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParticleKernel {
    /// Free along coordinate axis `k` alone.
    Along(usize),
    /// Any other freedom (the projection of its motion).
    General,
}

/// One particle's part of an increment along the one axis it is free on, on that component:
/// the acceleration f·(1/m) (the general projection leaves that component as it is and the
/// others exactly 0), then v(n+½) and x(n+1), the force cleared. Returns the acceleration.
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
    *v += a * h;
    compensated_add(x, carry, *v * h);
    a
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

    /// A chain of `n` particles between two grounds along `d`, mixed with a spring of another
    /// direction, so that the runs change kernel in the middle.
    fn springs<S: Space>(n: u32, d: S::V, other: S::V) -> Vec<LineSpring<S>> {
        let c = values(n as usize + 2, 7);
        let mut out: Vec<LineSpring<S>> = (0..=n)
            .map(|i| LineSpring {
                a: if i == 0 { GROUND } else { i - 1 },
                b: if i == n { GROUND } else { i },
                direction: d,
                c: 1.0 + c[i as usize].abs(),
            })
            .collect();
        out.insert(
            3,
            LineSpring {
                a: 1,
                b: 4,
                direction: other,
                c: 2.5,
            },
        );
        out
    }

    /// The axis kernels' forces and energy equal the general kernel's bit for bit, and the
    /// springs come back in the scene's order.
    fn same_forces<S: Space>(u: Vec<S::V>, d: S::V, other: S::V) {
        let n = u.len();
        let all = springs::<S>(n as u32, d, other);
        let springs = LineSprings::new(all.clone());
        assert!(springs.runs.len() >= 4, "axis, general and grounded runs");
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
        let mut by_runs = Forces::<S>::zeros(n, 0, 0);
        let mut by_general = Forces::<S>::zeros(n, 0, 0);
        let e_runs = springs.add_forces::<true>(&positions, &mut by_runs, 0.25);
        let e_general = general::<S, true>(&all, &positions, &mut by_general, 0.25);
        assert_eq!(e_runs.to_bits(), e_general.to_bits());
        for (a, b) in by_runs.p.iter().zip(by_general.p.iter()) {
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
            let on_axis = |x: f64| Vector3::new(0.0, x, 0.0);
            let (mut x, mut carry, mut vel) = (on_axis(c[0]), on_axis(c[1] * 1e-17), on_axis(c[2]));
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
    fn runs_follow_the_kernel_in_order() {
        let r = runs(&[1, 1, 2, 2, 2, 1], |x| *x);
        let ranges: Vec<_> = r.iter().map(|r| (r.range.clone(), r.kernel)).collect();
        assert_eq!(ranges, vec![(0..2, 1), (2..5, 2), (5..6, 1)]);
        assert!(runs(&[] as &[u8], |x| *x).is_empty());
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
