//! The state an increment works on: the configuration (displacements from t = 0 and the
//! bodies' orientations), rates (velocities or accelerations), the forces of one pass, how
//! contact is evaluated, and the counters of what a run evaluated.

use super::space::{BodyInertia, Lin, Space};
use std::marker::PhantomData;

/// One vector per particle, stored by component: every first component, then every second,
/// and so on. A pass that moves particles along one axis streams that component alone, 8 bytes
/// per particle and quantity whatever the dimension. The arithmetic on each component is the
/// vector's own, so the layout changes no result.
#[derive(Debug, Clone, PartialEq)]
pub struct Vectors<V: Lin> {
    data: Vec<f64>,
    len: usize,
    marker: PhantomData<V>,
}

impl<V: Lin> Vectors<V> {
    /// `len` zero vectors.
    pub fn zeros(len: usize) -> Self {
        // Checked: the accessors index `data` unchecked within `V::DIM · len`.
        let size = V::DIM
            .checked_mul(len)
            .expect("a vector store's size in f64s");
        Self {
            data: vec![0.0; size],
            len,
            marker: PhantomData,
        }
    }
    /// Number of vectors.
    pub fn len(&self) -> usize {
        self.len
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    // The accessors below check `i < len` and `k < V::DIM` and then index `data` without a
    // second check: those two put `k · len + i` below `V::DIM · len`, which is `data.len()`
    // (set by `Vectors::zeros`, whose product is checked; `data` is private and nothing
    // resizes it). A bounds check per component, with its index product, would cost a
    // one-particle scene's increment about a tenth of its instructions.

    /// Vector `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> V {
        assert!(i < self.len);
        V::from_components(|k| {
            assert!(k < V::DIM);
            // SAFETY: k < V::DIM and i < len (above).
            unsafe { *self.data.get_unchecked(k * self.len + i) }
        })
    }
    /// Set vector `i`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, v: V) {
        assert!(i < self.len);
        for k in 0..V::DIM {
            // SAFETY: k < V::DIM and i < len.
            unsafe { *self.data.get_unchecked_mut(k * self.len + i) = v.component(k) };
        }
    }
    /// Vector `i` += `v`.
    #[inline(always)]
    pub fn add(&mut self, i: usize, v: V) {
        assert!(i < self.len);
        for k in 0..V::DIM {
            // SAFETY: k < V::DIM and i < len.
            unsafe { *self.data.get_unchecked_mut(k * self.len + i) += v.component(k) };
        }
    }
    /// Vector `i` −= `v`.
    #[inline(always)]
    pub fn sub(&mut self, i: usize, v: V) {
        assert!(i < self.len);
        for k in 0..V::DIM {
            // SAFETY: k < V::DIM and i < len.
            unsafe { *self.data.get_unchecked_mut(k * self.len + i) -= v.component(k) };
        }
    }
    /// Component `k` of every vector.
    #[inline(always)]
    pub fn component(&self, k: usize) -> &[f64] {
        assert!(k < V::DIM);
        // SAFETY: k < V::DIM, so (k + 1) · len ≤ data.len().
        unsafe { self.data.get_unchecked(k * self.len..(k + 1) * self.len) }
    }
    /// Component `k` of every vector, to write.
    #[inline(always)]
    pub fn component_mut(&mut self, k: usize) -> &mut [f64] {
        assert!(k < V::DIM);
        // SAFETY: k < V::DIM, so (k + 1) · len ≤ data.len().
        unsafe {
            self.data
                .get_unchecked_mut(k * self.len..(k + 1) * self.len)
        }
    }
    /// Every component of every vector, by component: for the passes that treat each
    /// component alike (sets of as many vectors share this layout).
    #[inline(always)]
    pub fn flat(&self) -> &[f64] {
        &self.data
    }
    /// [`Vectors::flat`], to write.
    #[inline(always)]
    pub fn flat_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }
    /// The vectors in order.
    pub fn iter(&self) -> impl Iterator<Item = V> + '_ {
        (0..self.len).map(|i| self.get(i))
    }
    /// Copy another set of as many vectors.
    pub fn copy_from(&mut self, other: &Self) {
        self.data.copy_from_slice(&other.data);
    }
    /// Set every vector to zero.
    #[inline(always)]
    pub fn fill_zero(&mut self) {
        fill_zero(&mut self.data, 0.0);
    }
    /// Set component `k` of every vector to zero.
    #[inline(always)]
    pub fn fill_zero_component(&mut self, k: usize) {
        fill_zero(self.component_mut(k), 0.0);
    }
    /// Set every component but `k` of every vector to zero (what a projection onto axis `k`
    /// leaves of them).
    #[inline(always)]
    pub fn fill_zero_except(&mut self, k: usize) {
        for j in (0..V::DIM).filter(|j| *j != k) {
            self.fill_zero_component(j);
        }
    }
}

/// Configuration, as displacements from t = 0 (so round-off is relative to the motion, not to
/// the coordinates: the penalty multiplies position errors by k_p).
#[derive(Debug, Clone)]
pub struct Config<S: Space> {
    /// Particle displacements.
    pub u: Vectors<S::V>,
    /// Reference node displacements.
    pub bu: Vec<S::V>,
    /// Body orientations (finite rotation).
    pub br: Vec<S::R>,
    /// The rounding carry of each orientation's components (compensated summation of the
    /// increments' turns).
    pub br_carry: Vec<S::Carry>,
    /// Body rotation vectors (small rotation).
    pub bth: Vec<S::W>,
    /// Mass properties of each body at this configuration (centre in world axes, inertia in
    /// the body's axes with the orientation), kept in step with `br` by every method that
    /// rotates a body (finite rotation; the unrotated ones under small rotation).
    pub inertia: Vec<BodyInertia<S>>,
}

/// Velocities or accelerations of every particle and body.
#[derive(Debug, Clone)]
pub struct Rates<S: Space> {
    /// Particles.
    pub p: Vectors<S::V>,
    /// Body reference nodes.
    pub b: Vec<S::V>,
    /// Body angular.
    pub w: Vec<S::W>,
}

impl<S: Space> Rates<S> {
    /// All zero.
    pub fn zeros(particles: usize, bodies: usize) -> Self {
        Self {
            p: Vectors::zeros(particles),
            b: vec![S::V::zero(); bodies],
            w: vec![S::W::zero(); bodies],
        }
    }
    /// `self + s · other`.
    pub fn plus(&self, s: f64, other: &Self) -> Self {
        let mut out = self.clone();
        out.set_plus(self, s, other);
        out
    }
    /// In place: `self = a + s · b`.
    #[inline]
    pub fn set_plus(&mut self, a: &Self, s: f64, b: &Self) {
        self.set_plus_particles(a, s, b);
        self.set_plus_bodies(a, s, b);
    }
    /// [`Rates::set_plus`] for the particles alone.
    #[inline(always)]
    pub(super) fn set_plus_particles(&mut self, a: &Self, s: f64, b: &Self) {
        plus_into(self.p.flat_mut(), a.p.flat(), s, b.p.flat());
    }
    /// [`Rates::set_plus`] for the bodies alone.
    #[inline(always)]
    pub fn set_plus_bodies(&mut self, a: &Self, s: f64, b: &Self) {
        plus_into(&mut self.b, &a.b, s, &b.b);
        plus_into(&mut self.w, &a.w, s, &b.w);
    }
    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        let finite = |a: S::V| a.dot(&a).is_finite();
        (0..self.p.len()).all(|i| finite(self.p.get(i)))
            && self.b.iter().all(|a| finite(*a))
            && self.w.iter().all(|a| a.dot(a).is_finite())
    }
    /// Largest Euclidean norm of any particle's, body's or angular difference, and the largest
    /// such norm of `self` (square roots taken once, of the maxima).
    #[inline]
    pub fn max_difference(&self, other: &Self) -> (f64, f64) {
        let (mut d, mut m) = self.particle_differences(other);
        let bodies = self.b.len();
        let (b, w, ow) = (&other.b[..bodies], &self.w[..bodies], &other.w[..bodies]);
        for (i, a) in self.b.iter().enumerate() {
            let (e, f) = (*a - b[i], w[i] - ow[i]);
            note_largest(&mut d, &mut m, e.dot(&e), a.dot(a));
            note_largest(&mut d, &mut m, f.dot(&f), w[i].dot(&w[i]));
        }
        (d.sqrt(), m.sqrt())
    }
    /// The particles' part of [`Rates::max_difference`], before its square roots: the largest
    /// squared norm of a particle's difference, and of a particle's rate in `self`.
    #[inline(always)]
    pub(super) fn particle_differences(&self, other: &Self) -> (f64, f64) {
        let (mut d, mut m) = (0.0, 0.0);
        let (a, b, len) = (self.p.flat(), other.p.flat(), self.p.len());
        let b = &b[..a.len()];
        for i in 0..len {
            // Each particle's components in the order its vector's `dot` adds them.
            let (mut e2, mut a2) = (0.0, 0.0);
            for k in 0..S::V::DIM {
                let (x, y) = (a[k * len + i], b[k * len + i]);
                let e = x - y;
                if k == 0 {
                    (e2, a2) = (e * e, x * x);
                } else {
                    (e2, a2) = (e2 + e * e, a2 + x * x);
                }
            }
            note_largest(&mut d, &mut m, e2, a2);
        }
        (d, m)
    }
}

/// `out = a + s · b`, element by element, for slices as long as `out`.
#[inline(always)]
fn plus_into<T: Lin>(out: &mut [T], a: &[T], s: f64, b: &[T]) {
    let (a, b) = (&a[..out.len()], &b[..out.len()]);
    for i in 0..out.len() {
        out[i] = a[i] + b[i] * s;
    }
}

/// `d` and `m` raised to `e2` and `a2` where those are larger (a NaN is passed over).
#[inline(always)]
pub(super) fn note_largest(d: &mut f64, m: &mut f64, e2: f64, a2: f64) {
    *d = d.max(e2);
    *m = m.max(a2);
}

/// Forces on particles and wrenches on bodies (about their reference nodes), plus what the
/// same pass measured.
#[derive(Debug, Clone)]
pub struct Forces<S: Space> {
    /// Particle forces.
    pub p: Vectors<S::V>,
    /// Body forces.
    pub b: Vec<S::V>,
    /// Body moments about the reference node.
    pub m: Vec<S::W>,
    /// Elastic energy of springs and penalty.
    pub elastic: f64,
    /// Dissipation power of dashpots.
    pub dissipation: f64,
    /// Normal force per contact pair (compressive positive).
    pub contact: Vec<f64>,
    /// Signed gap per contact pair where the pass evaluated contact (negative: penetration).
    pub gap: Vec<f64>,
    /// Which components of `p` may be other than zero: those a pass added to since the last
    /// clear and that the pass which consumed the particle forces ([`Model::step_particles`])
    /// did not clear as it read them. [`Forces::clear`] streams through those alone.
    pub(super) written: [bool; 3],
}

impl<S: Space> Forces<S> {
    pub(super) fn zeros(particles: usize, bodies: usize, contacts: usize) -> Self {
        Self {
            p: Vectors::zeros(particles),
            b: vec![S::V::zero(); bodies],
            m: vec![S::W::zero(); bodies],
            elastic: 0.0,
            dissipation: 0.0,
            contact: vec![0.0; contacts],
            gap: vec![0.0; contacts],
            written: [false; 3],
        }
    }
    /// Copy another force set into this one (same shape).
    pub fn copy_from(&mut self, other: &Self) {
        self.p.copy_from(&other.p);
        self.b.copy_from_slice(&other.b);
        self.m.copy_from_slice(&other.m);
        self.contact.copy_from_slice(&other.contact);
        self.gap.copy_from_slice(&other.gap);
        self.elastic = other.elastic;
        self.dissipation = other.dissipation;
        self.written = other.written;
    }
    /// Reset to zero, keeping the allocation.
    #[inline(always)]
    pub fn clear(&mut self) {
        let written = &self.written[..S::V::DIM];
        if written.iter().all(|w| *w) {
            self.p.fill_zero();
        } else {
            for (k, _) in written.iter().enumerate().filter(|(_, w)| **w) {
                self.p.fill_zero_component(k);
            }
        }
        self.written = [false; 3];
        // The bodies' forces and moments in one pass.
        let zero = std::hint::black_box((S::V::zero(), S::W::zero()));
        for (b, m) in self.b.iter_mut().zip(self.m.iter_mut()) {
            (*b, *m) = zero;
        }
        fill_zero(&mut self.contact, 0.0);
        self.elastic = 0.0;
        self.dissipation = 0.0;
    }
}

impl<S: Space> Forces<S> {
    /// Add `f` to particle `i`'s force.
    #[inline(always)]
    pub fn add_particle(&mut self, i: usize, f: S::V) {
        self.p.add(i, f);
        self.written = [true; 3];
    }
}

/// Set every element of `xs` to `zero`, through an opaque copy of it, so that the compiler
/// does not turn the loop into a `memset` call. A `memset` that clears a short slice with one
/// masked AVX-512 store does not forward it to the loads that follow: the force pass that adds
/// into the cleared forces would wait for it to retire.
#[inline(always)]
pub fn fill_zero<T: Copy>(xs: &mut [T], zero: T) {
    let zero = std::hint::black_box(zero);
    for x in xs {
        *x = zero;
    }
}

/// How contact is evaluated.
#[derive(Debug, Clone, Copy)]
pub enum ContactMode<'a> {
    /// Penalty, compression only (the simulation).
    Unilateral,
    /// Penalty acting in tension too (the linearisation about a closed contact).
    Bilateral,
    /// No contact force (the structure alone).
    Off,
    /// Given normal forces instead of the penalty (the consistent start).
    Given(&'a [f64]),
}

/// Work counters: they prove what a run did and did not evaluate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Position-dependent force passes.
    pub force_evaluations: u64,
    /// Contact pair evaluations.
    pub contact_evaluations: u64,
    /// Dashpot passes.
    pub damping_evaluations: u64,
    /// Body orientation updates.
    pub rotation_updates: u64,
    /// Rigid-body acceleration solves (one per load solved against a body's factorisation).
    pub body_solves: u64,
    /// Increments that added a force balancing an impact's work ([`super::impacts`]).
    pub impact_balances: u64,
    /// Friction evaluations of a pair ([`super::friction`]; none without friction).
    pub friction_evaluations: u64,
    /// Increments in which some pair slipped.
    pub slip_increments: u64,
}
