//! A rigid body's accelerations from the load on it, under the constraints of a step.

use super::space::{BodyInertia, Lin, Space};

/// One body's solve with its constraints and operator bound together:
/// [`BodyOperator::solve`] for a body and constraints given once, as a caller solving one body
/// alone reads it (the engine keeps each body's operator and calls [`BodyOperator::solve`]).
pub struct BodySolve<'a, S: Space> {
    body: &'a BodyInertia<S>,
    held_translations: &'a [S::V],
    free_rotations: &'a [S::W],
    operator: BodyOperator<S>,
}

/// The rigid-body equations of one body at the reference node,
/// `m a + m α×c = f`, `m c×a + I_O α = m_O`, with the accelerations along the held translation
/// axes (orthonormal, `held_translations`) forced to zero and α confined to the span of the
/// free rotation axes g_i (orthonormal), factorised once for the body's configuration so that
/// several loads can be solved against one factorisation (every pass of an increment's centred
/// velocity iteration, and every increment of a step where the operator does not change).
///
/// Block elimination: with Q the projector onto the free translations, `a = Q(f/m − α×c)`, and
/// α = Σ s_j g_j solves the reduced rotational system on the free axes,
/// `Σ_j (g_i·I_O g_j − m w_i·w_j) s_j = g_i·m_O − f·w_i` with `w_i = Q(g_i × c)` (Q symmetric
/// and idempotent: `g_i·(c × Q(g_j × c)) = w_i·w_j`, `g_i·(c × Q f) = f·w_i`); then
/// `a = Q f/m − Σ s_j w_j`. The system is at most 3×3 and positive definite for a body with
/// mass (about the centre of mass when no translation is held). A non-positive pivot (only a
/// diverged, non-finite state gives one) yields non-finite accelerations, which the time loop
/// reports as a failed run.
///
/// The operator depends on the body's mass properties and constraints only, not on the loads:
/// it is formed once per step where it does not change over the step (every body under small
/// rotations; under finite rotation a body that turns about one axis, pinned at its reference
/// node or with its mass centre there; `Constraints::body_operators`), otherwise once per
/// configuration.
#[derive(Debug, Clone, Copy)]
pub struct BodyOperator<S: Space> {
    /// `w_i = Q(g_i × c)`, the translation each unit rotation rate drags through the held
    /// directions' complement (zero for a pinned reference node).
    drag: [S::V; 3],
    /// The reduced operator on the free axes, factorised by [`factorise`]: on one axis the
    /// reciprocal of its value, on more its Cholesky factor L (L Lᵀ) with reciprocal diagonal;
    /// NaN where it is not positive definite.
    factor: [[f64; 3]; 3],
}

impl<'a, S: Space> BodySolve<'a, S> {
    /// Factorise the reduced rotational operator of body `b` under its constraints.
    #[inline]
    pub fn new(
        b: &'a BodyInertia<S>,
        held_translations: &'a [S::V],
        free_rotations: &'a [S::W],
    ) -> Self {
        Self::with(
            b,
            held_translations,
            free_rotations,
            BodyOperator::of(b, held_translations, free_rotations),
        )
    }

    /// The solve of body `b` with its operator already formed (by [`BodyOperator::of`] for
    /// the same mass properties and constraints).
    #[inline]
    pub fn with(
        b: &'a BodyInertia<S>,
        held_translations: &'a [S::V],
        free_rotations: &'a [S::W],
        operator: BodyOperator<S>,
    ) -> Self {
        BodySolve {
            body: b,
            held_translations,
            free_rotations,
            operator,
        }
    }
}

impl<S: Space> BodyOperator<S> {
    /// Factorise the reduced rotational operator of body `b` under its constraints.
    #[inline(always)]
    pub fn of(b: &BodyInertia<S>, held_translations: &[S::V], free_rotations: &[S::W]) -> Self {
        let mut drag = [S::V::zero(); 3];
        let pinned = held_translations.len() == S::DIM;
        if !pinned {
            for (w, g) in drag.iter_mut().zip(free_rotations) {
                *w = project(held_translations, S::cross(g, &b.centre));
            }
        }
        let n = free_rotations.len();
        let mut a = [[0.0; 3]; 3];
        if n == 1 {
            // Every planar body and every body turning about one axis: written out.
            let g = &free_rotations[0];
            a[0][0] = b.axial(g);
            if !pinned {
                a[0][0] -= b.mass * drag[0].dot(&drag[0]);
            }
        } else if n > 1 {
            let inertia = b.world();
            for j in 0..n {
                let column = S::inertia_apply(&inertia, &free_rotations[j]);
                for i in 0..=j {
                    let mut e = free_rotations[i].dot(&column);
                    if !pinned {
                        e -= b.mass * drag[i].dot(&drag[j]);
                    }
                    a[i][j] = e;
                    a[j][i] = e;
                }
            }
        }
        BodyOperator {
            drag,
            factor: factorise(n, &a),
        }
    }
}

impl<S: Space> BodySolve<'_, S> {
    /// The accelerations `(a, α)` of the reference node under `force` and `moment`.
    #[inline(always)]
    pub fn solve(&self, force: &S::V, moment: &S::W) -> (S::V, S::W) {
        let constraints = (self.held_translations, self.free_rotations);
        self.operator.solve(self.body, constraints, force, moment)
    }
}

impl<S: Space> BodyOperator<S> {
    /// The accelerations `(a, α)` of the reference node of body `body` under `force` and
    /// `moment`, with this operator formed for its mass properties and constraints (the held
    /// translations and the free rotations).
    #[inline(always)]
    pub fn solve(
        &self,
        body: &BodyInertia<S>,
        (held_translations, free_rotations): (&[S::V], &[S::W]),
        force: &S::V,
        moment: &S::W,
    ) -> (S::V, S::W) {
        let n = free_rotations.len();
        let pinned = held_translations.len() == S::DIM;
        if n == 1 {
            // One free axis g (α = s·g), as in `BodyOperator::of`, written out (the reciprocal
            // pivot is NaN where the factorisation failed).
            let (g, inverse) = (&free_rotations[0], self.factor[0][0]);
            if pinned {
                return (S::V::zero(), *g * (g.dot(moment) * inverse));
            }
            let s = (g.dot(moment) - force.dot(&self.drag[0])) * inverse;
            let a = project(held_translations, *force) * (1.0 / body.mass);
            return (a - self.drag[0] * s, *g * s);
        }
        let mut r = [0.0; 3];
        for ((r, g), w) in r.iter_mut().zip(free_rotations).zip(&self.drag) {
            *r = g.dot(moment);
            if !pinned {
                *r -= force.dot(w);
            }
        }
        let s = substitute(n, &self.factor, &r);
        let (mut a, mut alpha) = (S::V::zero(), S::W::zero());
        if !pinned {
            a = project(held_translations, *force) * (1.0 / body.mass);
        }
        for ((g, w), s) in free_rotations.iter().zip(&self.drag).zip(s) {
            alpha += *g * s;
            if !pinned {
                a -= *w * s;
            }
        }
        (a, alpha)
    }
}

/// `v` projected onto the complement of the orthonormal directions `held`.
#[inline]
pub(super) fn project<V: Lin>(held: &[V], v: V) -> V {
    let mut v = v;
    for d in held {
        v -= *d * d.dot(&v);
    }
    v
}

/// Factorise the symmetric n×n system `a` (n ≤ 3): for n = 1 the reciprocal of its value, for
/// more its Cholesky factor L (L Lᵀ, by hand) with the reciprocals of its diagonal stored in
/// place of the diagonal; NaN in the first entry where it is not positive definite. Storing
/// reciprocals moves the divisions (about 13 cycles each, against 4 for a product) from the
/// solves, which sit on the time loop's chain of dependent operations after the forces, to
/// the factorisation, which only needs the orientation and runs beside the force pass.
#[inline]
#[allow(clippy::needless_range_loop)] // index notation of the factorisation
fn factorise(n: usize, a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut l = [[0.0; 3]; 3];
    if n == 1 {
        l[0][0] = pivot_reciprocal(a[0][0]);
        return l;
    }
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d -= l[j][k] * l[j][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            l[0][0] = f64::NAN;
            return l;
        }
        let inverse = 1.0 / d.sqrt();
        l[j][j] = inverse;
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            l[i][j] = s * inverse;
        }
    }
    l
}

/// The reciprocal of a one-axis operator `a`, as [`factorise`] stores it: NaN where `a` is not
/// positive and finite (NaN, or an infinite value whose reciprocal would be a finite zero),
/// which the time loop reports as a failed run.
#[inline]
pub(super) fn pivot_reciprocal(a: f64) -> f64 {
    // a is positive and finite exactly where a and 1/a are both positive (1/∞ = 0; NaN fails
    // both): two comparisons, where `is_finite`'s test of the exponent bits takes a dozen
    // integer instructions and two branches.
    let reciprocal = 1.0 / a;
    if (a > 0.0) & (reciprocal > 0.0) {
        reciprocal
    } else {
        f64::NAN
    }
}

/// Solve the system factorised by [`factorise`] for the right-hand side `r` (NaN where the
/// factorisation failed).
#[inline]
#[allow(clippy::needless_range_loop)] // index notation of the substitutions
fn substitute(n: usize, l: &[[f64; 3]; 3], r: &[f64; 3]) -> [f64; 3] {
    let mut x = [0.0; 3];
    if n == 0 {
        return x;
    }
    if l[0][0].is_nan() {
        return [f64::NAN; 3];
    }
    if n == 1 {
        x[0] = r[0] * l[0][0];
        return x;
    }
    let mut y = [0.0; 3];
    for i in 0..n {
        let mut s = r[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s * l[i][i];
    }
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k][i] * x[k];
        }
        x[i] = s * l[i][i];
    }
    x
}
