//! Planar and spatial kinematics behind one trait, so the engine is written once and a 2D case
//! compiles to 2D arithmetic only (no 3D rotation, no 6×6 solve).

use nalgebra::{Matrix3, Matrix6, UnitComplex, UnitQuaternion, Vector2, Vector3, Vector6};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A linear quantity: translations (`Vector2`/`Vector3`) and angular quantities (`f64`/`Vector3`).
pub trait Lin:
    Copy
    + Debug
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
{
    /// The zero value.
    fn zero() -> Self;
    /// Inner product.
    fn dot(&self, other: &Self) -> f64;
}

impl Lin for f64 {
    fn zero() -> Self {
        0.0
    }
    fn dot(&self, other: &Self) -> f64 {
        self * other
    }
}

macro_rules! lin_vector {
    ($t:ty) => {
        impl Lin for $t {
            fn zero() -> Self {
                <$t>::zeros()
            }
            fn dot(&self, other: &Self) -> f64 {
                nalgebra::Matrix::dot(self, other)
            }
        }
    };
}
lin_vector!(Vector2<f64>);
lin_vector!(Vector3<f64>);

/// Mass properties of a body in world axes, about its reference node.
#[derive(Debug, Clone, Copy)]
pub struct BodyInertia<S: Space> {
    /// Mass.
    pub mass: f64,
    /// Centre of mass relative to the reference node.
    pub centre: S::V,
    /// Inertia about the reference node.
    pub inertia: S::Inertia,
}

/// A space: its vectors, angular quantities, orientations and rigid-body algebra.
pub trait Space: Copy + Debug + Send + Sync + 'static {
    /// Translational vector.
    type V: Lin;
    /// Angular vector (2D: a scalar about z).
    type W: Lin;
    /// Orientation.
    type R: Copy + Debug + Send + Sync;
    /// Inertia tensor representation.
    type Inertia: Copy + Debug + Send + Sync;
    /// Number of translational components.
    const DIM: usize;
    /// Number of rotational components.
    const ROT: usize;

    /// Drop to this space from a scene 3-vector.
    fn v(x: &Vector3<f64>) -> Self::V;
    /// Back to a 3-vector.
    fn v3(x: &Self::V) -> Vector3<f64>;
    /// Angular from a scene 3-vector (2D: its z component).
    fn w(x: &Vector3<f64>) -> Self::W;
    /// Angular to a 3-vector.
    fn w3(x: &Self::W) -> Vector3<f64>;
    /// Inertia from a scene tensor.
    fn inertia(i: &Matrix3<f64>) -> Self::Inertia;
    /// Identity orientation.
    fn identity() -> Self::R;
    /// Rotate a body-frame vector into the world.
    fn rotate(r: &Self::R, x: &Self::V) -> Self::V;
    /// Rotate an inertia tensor into the world.
    fn rotate_inertia(r: &Self::R, i: &Self::Inertia) -> Self::Inertia;
    /// Apply an inertia tensor to an angular vector.
    fn inertia_apply(i: &Self::Inertia, w: &Self::W) -> Self::W;
    /// Exact incremental rotation: orientation after rotating by the rotation vector `dtheta`
    /// (world axes) from `r`.
    fn advance(r: &Self::R, dtheta: &Self::W) -> Self::R;
    /// Rotation angle of `r` about a unit world axis (twist angle, in (−π, π]).
    fn twist(r: &Self::R, axis: &Self::W) -> f64;
    /// ω × x.
    fn cross(w: &Self::W, x: &Self::V) -> Self::V;
    /// x × f (a moment).
    fn moment(x: &Self::V, f: &Self::V) -> Self::W;
    /// Gyroscopic moment ω × (I ω) (zero in 2D).
    fn gyroscopic(w: &Self::W, i: &Self::Inertia) -> Self::W;
    /// Solve the rigid-body equations at the reference node,
    /// `[m, −m[c]×; m[c]×, I] [a; α] = [f; m_O]`, with the accelerations along the held
    /// translation and rotation axes (orthonormal) forced to zero. Non-finite input gives
    /// non-finite accelerations.
    fn solve_body(
        inertia: &BodyInertia<Self>,
        held_translations: &[Self::V],
        held_rotations: &[Self::W],
        force: &Self::V,
        moment: &Self::W,
    ) -> (Self::V, Self::W);
}

/// 2D: x, y and rotation about z.
#[derive(Debug, Clone, Copy)]
pub struct Planar;

/// 3D.
#[derive(Debug, Clone, Copy)]
pub struct Spatial;

impl Space for Planar {
    type V = Vector2<f64>;
    type W = f64;
    type R = UnitComplex<f64>;
    type Inertia = f64;
    const DIM: usize = 2;
    const ROT: usize = 1;

    fn v(x: &Vector3<f64>) -> Self::V {
        Vector2::new(x.x, x.y)
    }
    fn v3(x: &Self::V) -> Vector3<f64> {
        Vector3::new(x.x, x.y, 0.0)
    }
    fn w(x: &Vector3<f64>) -> Self::W {
        x.z
    }
    fn w3(x: &Self::W) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, *x)
    }
    fn inertia(i: &Matrix3<f64>) -> Self::Inertia {
        i[(2, 2)]
    }
    fn identity() -> Self::R {
        UnitComplex::identity()
    }
    fn rotate(r: &Self::R, x: &Self::V) -> Self::V {
        r * x
    }
    fn rotate_inertia(_: &Self::R, i: &Self::Inertia) -> Self::Inertia {
        *i
    }
    fn inertia_apply(i: &Self::Inertia, w: &Self::W) -> Self::W {
        i * w
    }
    fn advance(r: &Self::R, dtheta: &Self::W) -> Self::R {
        UnitComplex::new(r.angle() + dtheta)
    }
    fn twist(r: &Self::R, axis: &Self::W) -> f64 {
        r.angle() * axis
    }
    fn cross(w: &Self::W, x: &Self::V) -> Self::V {
        Vector2::new(-w * x.y, w * x.x)
    }
    fn moment(x: &Self::V, f: &Self::V) -> Self::W {
        x.x * f.y - x.y * f.x
    }
    fn gyroscopic(_: &Self::W, _: &Self::Inertia) -> Self::W {
        0.0
    }
    fn solve_body(
        b: &BodyInertia<Self>,
        held_translations: &[Self::V],
        held_rotations: &[Self::W],
        force: &Self::V,
        moment: &Self::W,
    ) -> (Self::V, Self::W) {
        let (m, c) = (b.mass, b.centre);
        // Work in a translation basis whose leading axes are the held ones.
        let (e0, e1) = match held_translations {
            [] | [_, _] => (Vector2::x(), Vector2::y()),
            [h] => (*h, Vector2::new(-h.y, h.x)),
            _ => unreachable!("at most two held translations in 2D"),
        };
        let basis = [e0, e1];
        let held = [
            !held_translations.is_empty(),
            held_translations.len() == 2,
            !held_rotations.is_empty(),
        ];
        // Coupling column: the force row's α-coefficient is m (ẑ × c) = m(−c_y, c_x).
        let coupling = Vector2::new(-c.y, c.x) * m;
        let mut a = nalgebra::Matrix3::zeros();
        let mut rhs = nalgebra::Vector3::new(basis[0].dot(force), basis[1].dot(force), *moment);
        for i in 0..2 {
            a[(i, i)] = m;
            a[(i, 2)] = basis[i].dot(&coupling);
            a[(2, i)] = a[(i, 2)];
        }
        a[(2, 2)] = b.inertia;
        for (k, h) in held.iter().enumerate() {
            if *h {
                for j in 0..3 {
                    a[(k, j)] = 0.0;
                    a[(j, k)] = 0.0;
                }
                a[(k, k)] = 1.0;
                rhs[k] = 0.0;
            }
        }
        // The matrix is positive definite on the free DOFs (validated); only a diverged,
        // non-finite state fails here, and it yields non-finite accelerations that the time
        // loop reports as a failed run.
        let Some(chol) = a.cholesky() else {
            return (Vector2::repeat(f64::NAN), f64::NAN);
        };
        let x = chol.solve(&rhs);
        (basis[0] * x[0] + basis[1] * x[1], x[2])
    }
}

fn skew(c: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -c.z, c.y, c.z, 0.0, -c.x, -c.y, c.x, 0.0)
}

/// An orthonormal basis whose leading vectors are the given orthonormal ones.
fn basis_with(leading: &[Vector3<f64>]) -> Matrix3<f64> {
    let mut cols: Vec<Vector3<f64>> = leading.to_vec();
    for e in [Vector3::x(), Vector3::y(), Vector3::z()] {
        if cols.len() == 3 {
            break;
        }
        let mut v = e;
        for c in &cols {
            v -= c * c.dot(&v);
        }
        if v.norm() > 1e-6 {
            cols.push(v.normalize());
        }
    }
    Matrix3::from_columns(&cols)
}

impl Space for Spatial {
    type V = Vector3<f64>;
    type W = Vector3<f64>;
    type R = UnitQuaternion<f64>;
    type Inertia = Matrix3<f64>;
    const DIM: usize = 3;
    const ROT: usize = 3;

    fn v(x: &Vector3<f64>) -> Self::V {
        *x
    }
    fn v3(x: &Self::V) -> Vector3<f64> {
        *x
    }
    fn w(x: &Vector3<f64>) -> Self::W {
        *x
    }
    fn w3(x: &Self::W) -> Vector3<f64> {
        *x
    }
    fn inertia(i: &Matrix3<f64>) -> Self::Inertia {
        *i
    }
    fn identity() -> Self::R {
        UnitQuaternion::identity()
    }
    fn rotate(r: &Self::R, x: &Self::V) -> Self::V {
        r * x
    }
    fn rotate_inertia(r: &Self::R, i: &Self::Inertia) -> Self::Inertia {
        let m = r.to_rotation_matrix();
        m.matrix() * i * m.matrix().transpose()
    }
    fn inertia_apply(i: &Self::Inertia, w: &Self::W) -> Self::W {
        i * w
    }
    fn advance(r: &Self::R, dtheta: &Self::W) -> Self::R {
        let q = UnitQuaternion::from_scaled_axis(*dtheta) * r;
        // Keep the unit norm exact against round-off drift.
        UnitQuaternion::new_normalize(q.into_inner())
    }
    fn twist(r: &Self::R, axis: &Self::W) -> f64 {
        let q = r.quaternion();
        2.0 * q.vector().dot(axis).atan2(q.w)
    }
    fn cross(w: &Self::W, x: &Self::V) -> Self::V {
        w.cross(x)
    }
    fn moment(x: &Self::V, f: &Self::V) -> Self::W {
        x.cross(f)
    }
    fn gyroscopic(w: &Self::W, i: &Self::Inertia) -> Self::W {
        w.cross(&(i * w))
    }
    fn solve_body(
        b: &BodyInertia<Self>,
        held_translations: &[Self::V],
        held_rotations: &[Self::W],
        force: &Self::V,
        moment: &Self::W,
    ) -> (Self::V, Self::W) {
        let m = b.mass;
        let sc = skew(&b.centre);
        let tb = basis_with(held_translations);
        let rb = basis_with(held_rotations);
        // Full matrix in world axes, then in the (held-first) bases.
        let mut full = Matrix6::zeros();
        full.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * m));
        full.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-sc * m));
        full.fixed_view_mut::<3, 3>(3, 0).copy_from(&(sc * m));
        full.fixed_view_mut::<3, 3>(3, 3).copy_from(&b.inertia);
        let mut t = Matrix6::zeros();
        t.fixed_view_mut::<3, 3>(0, 0).copy_from(&tb);
        t.fixed_view_mut::<3, 3>(3, 3).copy_from(&rb);
        let mut a = t.transpose() * full * t;
        let mut rhs =
            t.transpose() * Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
        let held: Vec<usize> = (0..held_translations.len())
            .chain((0..held_rotations.len()).map(|k| 3 + k))
            .collect();
        for &k in &held {
            for j in 0..6 {
                a[(k, j)] = 0.0;
                a[(j, k)] = 0.0;
            }
            a[(k, k)] = 1.0;
            rhs[k] = 0.0;
        }
        let Some(chol) = a.cholesky() else {
            return (Vector3::repeat(f64::NAN), Vector3::repeat(f64::NAN));
        };
        let x = t * chol.solve(&rhs);
        (
            Vector3::new(x[0], x[1], x[2]),
            Vector3::new(x[3], x[4], x[5]),
        )
    }
}
