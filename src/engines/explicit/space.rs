//! Planar and spatial kinematics behind one trait, so the engine is written once and a 2D case
//! compiles to 2D arithmetic only (no 3D rotation, no 6×6 solve).

use crate::scene::Solid;
use nalgebra::{Matrix3, SVector, UnitQuaternion, Vector2, Vector3};
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
    + PartialEq
{
    /// Number of components.
    const DIM: usize;
    /// The zero value.
    fn zero() -> Self;
    /// The value whose component `k` is `f(k)`.
    fn from_components(f: impl Fn(usize) -> f64) -> Self;
    /// Inner product.
    fn dot(&self, other: &Self) -> f64;
    /// Component `k` (`k` below the dimension).
    fn component(&self, k: usize) -> f64;
    /// Component `k`, to write (`k` below the dimension).
    fn component_mut(&mut self, k: usize) -> &mut f64;
}

impl Lin for f64 {
    const DIM: usize = 1;
    fn zero() -> Self {
        0.0
    }
    fn from_components(f: impl Fn(usize) -> f64) -> Self {
        f(0)
    }
    fn dot(&self, other: &Self) -> f64 {
        self * other
    }
    fn component(&self, _: usize) -> f64 {
        *self
    }
    fn component_mut(&mut self, _: usize) -> &mut f64 {
        self
    }
}

macro_rules! lin_vector {
    ($t:ty, $dim:literal) => {
        impl Lin for $t {
            const DIM: usize = $dim;
            fn zero() -> Self {
                <$t>::zeros()
            }
            #[inline(always)]
            fn from_components(f: impl Fn(usize) -> f64) -> Self {
                <$t>::from_fn(|k, _| f(k))
            }
            fn dot(&self, other: &Self) -> f64 {
                nalgebra::Matrix::dot(self, other)
            }
            #[inline(always)]
            fn component(&self, k: usize) -> f64 {
                self[k]
            }
            #[inline(always)]
            fn component_mut(&mut self, k: usize) -> &mut f64 {
                &mut self[k]
            }
        }
    };
}
lin_vector!(Vector2<f64>, 2);
lin_vector!(Vector3<f64>, 3);

/// Kahan summation step: `x += dx`, carrying the rounding error in `carry` (the sum is
/// `x − carry`).
#[inline]
pub fn compensated_add<T: Lin>(x: &mut T, carry: &mut T, dx: T) {
    let y = dx - *carry;
    let t = *x + y;
    *carry = (t - *x) - y;
    *x = t;
}

/// Mass properties of a body about its reference node: the mass, the centre of mass in world
/// axes, and the inertia in the body's axes with the orientation that turns those into the
/// world's. The inertia is not turned into world axes up front (R I Rᵀ, about 100 flops in 3D):
/// the body solve needs it only on the free rotation axes, and a body turning about one axis g
/// only g·I g, which one rotation of g into the body's axes gives ([`BodyInertia::axial`]).
#[derive(Debug, Clone, Copy)]
pub struct BodyInertia<S: Space> {
    /// Mass.
    pub mass: f64,
    /// Centre of mass relative to the reference node (world axes).
    pub centre: S::V,
    /// Inertia about the reference node, in the body's axes.
    pub inertia: S::Inertia,
    /// Body axes to world axes; `None` where they coincide (the model's body at rest, and
    /// every body under small rotation).
    pub orientation: Option<S::R>,
}

impl<S: Space> BodyInertia<S> {
    /// `g·I g` in world axes, for a world axis `g`.
    #[inline]
    pub fn axial(&self, g: &S::W) -> f64 {
        let u = match &self.orientation {
            None => *g,
            Some(r) => S::unrotate_angular(r, g),
        };
        u.dot(&S::inertia_apply(&self.inertia, &u))
    }

    /// `I ω` in world axes, for a world angular vector `ω`.
    #[inline]
    pub fn apply(&self, w: &S::W) -> S::W {
        match &self.orientation {
            None => S::inertia_apply(&self.inertia, w),
            Some(r) => S::rotate_angular(
                r,
                &S::inertia_apply(&self.inertia, &S::unrotate_angular(r, w)),
            ),
        }
    }

    /// The inertia tensor in world axes.
    #[inline]
    pub fn world(&self) -> S::Inertia {
        match &self.orientation {
            None => self.inertia,
            Some(r) => S::rotate_inertia(r, &self.inertia),
        }
    }
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
    /// `r x − x`, the displacement of a body-frame offset `x` by the rotation, computed from
    /// the rotation's small parts (the sine, the quaternion's vector) so that it keeps their
    /// relative precision: `rotate(r, x) − x` cancels to an absolute error of ε|x| per
    /// evaluation, which a penalty stiffness multiplies into force noise that rings the
    /// contact mode.
    fn turned(r: &Self::R, x: &Self::V) -> Self::V;
    /// Rotate an inertia tensor into the world.
    fn rotate_inertia(r: &Self::R, i: &Self::Inertia) -> Self::Inertia;
    /// Apply an inertia tensor to an angular vector.
    fn inertia_apply(i: &Self::Inertia, w: &Self::W) -> Self::W;
    /// The rounding carry of an orientation's components under compensated summation.
    type Carry: Copy + Debug + Default + Send + Sync;
    /// Exact incremental rotation: orientation after rotating by the rotation vector `dtheta`
    /// (world axes) from `r`, added to `r`'s components as a small increment with Kahan
    /// compensation in `carry` (and pulled back to unit norm in the same increment). Summed
    /// plainly, each increment's rounding would walk the angle by ε per increment, and a
    /// penalty stiffness turns that walk into contact force noise.
    fn advance_compensated(r: &Self::R, carry: &mut Self::Carry, dtheta: &Self::W) -> Self::R;
    /// [`Space::advance_compensated`] without a carry to keep (a one-off turn).
    fn advance(r: &Self::R, dtheta: &Self::W) -> Self::R {
        Self::advance_compensated(r, &mut Self::Carry::default(), dtheta)
    }
    /// Rotation angle of `r` about a unit world axis (twist angle, in (−π, π]).
    fn twist(r: &Self::R, axis: &Self::W) -> f64;
    /// ω × x.
    fn cross(w: &Self::W, x: &Self::V) -> Self::V;
    /// x × f (a moment).
    fn moment(x: &Self::V, f: &Self::V) -> Self::W;
    /// Gyroscopic moment ω × (I ω), given I ω (zero in 2D).
    fn gyroscopic(w: &Self::W, iw: &Self::W) -> Self::W;
    /// Rotate a body-frame angular vector into the world (2D: unchanged).
    fn rotate_angular(r: &Self::R, w: &Self::W) -> Self::W;
    /// Rotate a world angular vector into the body frame (2D: unchanged).
    fn unrotate_angular(r: &Self::R, w: &Self::W) -> Self::W;
    /// An orthonormal basis of the rotation axes left free by the held ones (orthonormal).
    fn free_rotations(held: &[Self::W]) -> Vec<Self::W>;
    /// Rotate a world vector into the body frame (the inverse of [`Space::rotate`]).
    fn unrotate(r: &Self::R, x: &Self::V) -> Self::V;
    /// A parry shape of this space, shared (cheap to clone, `Send + Sync`).
    type Shape: Clone + Debug + Send + Sync;
    /// A solid as parry builds it in this space (centred at its own origin).
    fn solid(solid: &Solid) -> Self::Shape;
    /// The smallest half extent of a solid's bounding box.
    fn thinnest(solid: &Self::Shape) -> f64;
    /// Signed distance (negative inside) from `local` (relative to the solid's centre, in its
    /// axes) to the solid's boundary, and the outward unit normal there: parry's point
    /// projection.
    fn solid_gap(shape: &Self::Shape, local: &Self::V) -> (f64, Self::V);
    /// Whether the segment from `from` to `to` (local, as in [`Space::solid_gap`]) passes
    /// through the solid: parry's ray cast.
    fn crosses(shape: &Self::Shape, from: &Self::V, to: &Self::V) -> bool;
}

/// The signed gap at `local` and the outward unit normal there, from `at`, parry's point
/// projection as (signed distance, vector from the nearest boundary point to `local`): that
/// vector, turned outward where `local` is inside, or on the boundary itself (where it vanishes)
/// the signed distance's gradient by central differences over 1e-7 of the solid's `size`.
fn gap_and_normal<const D: usize>(
    local: &SVector<f64, D>,
    size: impl Fn() -> f64,
    at: impl Fn(&SVector<f64, D>) -> (f64, SVector<f64, D>),
) -> (f64, SVector<f64, D>) {
    let (gap, delta) = at(local);
    let norm = delta.norm();
    if norm > 0.0 {
        let n = delta / norm;
        return (gap, if gap < 0.0 { -n } else { n });
    }
    let e = 1e-7 * size();
    let n = SVector::<f64, D>::from_fn(|i, _| {
        let step = SVector::<f64, D>::from_fn(|j, _| if i == j { e } else { 0.0 });
        at(&(local + step)).0 - at(&(local - step)).0
    });
    (gap, n / n.norm())
}

/// Below this angle (rad) the increment's rotation takes its sine and cosine from their
/// Taylor series (exact to round-off there) instead of the library functions.
const SMALL_ANGLE: f64 = 1e-2;

/// Below these values of y = a², the series below leave out their highest terms: every term
/// left out is then under a fifth of an ulp of the result (sin(a)/a ≈ 1 and cos(a) − 1 ≈ −y/2),
/// and the chain of dependent operations, on the time loop's critical path through the
/// orientation, is two or three steps shorter. Per-increment angles of an explicit run are
/// small (h·|ω| below the stability limit), so the shortest form is the common one.
///
/// At y < `TWO_TERMS` (a < 2.2e-4) sin(a)/a keeps 1 − y/6 (the next term, y²/120, is below
/// 2.1e-17) and cos(a) − 1 keeps −y/2 + y²/24 (the next, y³/720, is below 7e-18 of y/2);
/// at y < `THREE_TERMS` (a < 6.3e-3) they keep one term more (the next, y³/5040 and
/// y⁴/40320, are below 1.3e-17 and 3.2e-18 of y/2).
const TWO_TERMS: f64 = 5e-8;
/// See [`TWO_TERMS`].
const THREE_TERMS: f64 = 4e-5;

/// Taylor coefficients of sin(a)/a − 1 in y = a²: −1/6, 1/120, −1/5040, 1/362880.
const SINC: [f64; 4] = [-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362_880.0];
/// Taylor coefficients of cos(a) − 1 in y = a².
const COS: [f64; 4] = [-0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40_320.0];
/// The same for half the angle of a rotation vector dθ, in y = |dθ|² (a = |dθ|/2, a² = y/4):
/// ½ sin(a)/a − ½ (the quaternion's vector part per unit dθ, less ½) and cos(a) − 1, the
/// factor a²⁽ᵏ⁾ → yᵏ/4ᵏ folded into the coefficients, so that no product forms a² first.
const HALF_SINC: [f64; 4] = [
    -1.0 / 48.0,
    1.0 / 3840.0,
    -1.0 / 645_120.0,
    1.0 / 185_794_560.0,
];
/// See [`HALF_SINC`].
const HALF_COS: [f64; 4] = [-1.0 / 8.0, 1.0 / 384.0, -1.0 / 46_080.0, 1.0 / 10_321_920.0];

/// `y (c₀ + y (c₁ + …))` through the first `terms` coefficients, by Horner's rule.
#[inline(always)]
fn polynomial(y: f64, c: &[f64; 4], terms: usize) -> f64 {
    let mut p = c[terms - 1];
    for k in (0..terms - 1).rev() {
        p = c[k] + y * p;
    }
    y * p
}

/// The series with coefficients `c` in y, keeping `terms[0]` coefficients below
/// [`TWO_TERMS`], `terms[1]` below [`THREE_TERMS`] and `terms[2]` beyond (`per_a2`: y per a²,
/// 1 for the series in a², 4 for the half-angle ones in |dθ|²).
#[inline(always)]
fn tiered_series(y: f64, c: &[f64; 4], per_a2: f64, terms: [usize; 3]) -> f64 {
    if y < TWO_TERMS * per_a2 {
        polynomial(y, c, terms[0])
    } else if y < THREE_TERMS * per_a2 {
        polynomial(y, c, terms[1])
    } else {
        polynomial(y, c, terms[2])
    }
}

/// sin(a)/a − 1 from the coefficients [`SINC`] (or ½ sin(a)/a − ½ from [`HALF_SINC`], with
/// `per_a2` = 4): through a⁸, one term below [`TWO_TERMS`], two below [`THREE_TERMS`].
#[inline(always)]
fn sinc_minus_one_series(y: f64, c: &[f64; 4], per_a2: f64) -> f64 {
    tiered_series(y, c, per_a2, [1, 2, 4])
}

/// cos(a) − 1, without the cancellation of forming cos(a) first, from the coefficients `c`
/// ([`COS`], or [`HALF_COS`] with `per_a2` = 4): through a⁸, two terms below [`TWO_TERMS`],
/// three below [`THREE_TERMS`].
#[inline(always)]
fn cos_minus_one_series(y: f64, c: &[f64; 4], per_a2: f64) -> f64 {
    tiered_series(y, c, per_a2, [2, 3, 4])
}

/// `(sin x, cos x − 1)`, from the Taylor series for |x| < [`SMALL_ANGLE`] (the terms they
/// leave out are under a fifth of an ulp of the result: [`TWO_TERMS`]) and from −2 sin²(x/2)
/// beyond.
#[inline]
fn sin_cos_minus_one(x: f64) -> (f64, f64) {
    if x.abs() < SMALL_ANGLE {
        let y = x * x;
        let sinc = 1.0 + sinc_minus_one_series(y, &SINC, 1.0);
        (x * sinc, cos_minus_one_series(y, &COS, 1.0))
    } else {
        let half = (0.5 * x).sin();
        (x.sin(), -2.0 * half * half)
    }
}

/// 2D: x, y and rotation about z.
#[derive(Debug, Clone, Copy)]
pub struct Planar;

/// 3D.
#[derive(Debug, Clone, Copy)]
pub struct Spatial;

impl Space for Planar {
    fn unrotate(r: &Self::R, x: &Self::V) -> Self::V {
        let (c, s) = (r.cos(), r.sine);
        Vector2::new(c * x.x + s * x.y, c * x.y - s * x.x)
    }
    fn solid(solid: &Solid) -> Self::Shape {
        use parry2d_f64::shape::SharedShape;
        match *solid {
            Solid::Ball { radius } => SharedShape::ball(radius),
            Solid::Cuboid { half_extents: h } => SharedShape::cuboid(h.x, h.y),
            Solid::Capsule {
                half_height,
                radius,
            } => SharedShape::capsule_y(half_height, radius),
            Solid::Convex { ref polytope } => {
                let corners: Vec<_> = polytope
                    .corners
                    .iter()
                    .map(|c| parry2d_f64::math::Vector::new(c.x, c.y))
                    .collect();
                SharedShape::convex_hull(&corners)
                    .expect("validated: the corners span a convex polygon")
            }
        }
    }
    fn thinnest(shape: &Self::Shape) -> f64 {
        shape.compute_local_aabb().half_extents().min_element()
    }
    fn solid_gap(shape: &Self::Shape, local: &Self::V) -> (f64, Self::V) {
        let size = || shape.compute_local_aabb().half_extents().length();
        gap_and_normal(local, size, |p| {
            let q = parry2d_f64::math::Vector::new(p.x, p.y);
            let projection = shape.project_local_point(q, false);
            let d = q - projection.point;
            let distance = d.length();
            let gap = if projection.is_inside {
                -distance
            } else {
                distance
            };
            (gap, Vector2::new(d.x, d.y))
        })
    }
    fn crosses(shape: &Self::Shape, from: &Self::V, to: &Self::V) -> bool {
        let v = |p: &Vector2<f64>| parry2d_f64::math::Vector::new(p.x, p.y);
        let ray = parry2d_f64::query::Ray::new(v(from), v(to) - v(from));
        shape.intersects_local_ray(&ray, 1.0)
    }
    type V = Vector2<f64>;
    type W = f64;
    type R = Heading;
    type Shape = parry2d_f64::shape::SharedShape;
    type Carry = [f64; 2];
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
        Heading::IDENTITY
    }
    fn rotate(r: &Self::R, x: &Self::V) -> Self::V {
        let (c, s) = (r.cos(), r.sine);
        Vector2::new(c * x.x - s * x.y, s * x.x + c * x.y)
    }
    fn turned(r: &Self::R, x: &Self::V) -> Self::V {
        let (v, s) = (r.versine, r.sine);
        Vector2::new(v * x.x - s * x.y, s * x.x + v * x.y)
    }
    fn rotate_inertia(_: &Self::R, i: &Self::Inertia) -> Self::Inertia {
        *i
    }
    fn inertia_apply(i: &Self::Inertia, w: &Self::W) -> Self::W {
        i * w
    }
    #[inline(always)]
    fn advance_compensated(r: &Self::R, carry: &mut [f64; 2], dtheta: &f64) -> Self::R {
        // The versine v = c − 1 is what is summed (with its carry), so that it keeps its
        // relative precision; c = 1 + v enters only products with small factors (x, y, the
        // excess), where its absolute precision serves.
        let (v, s) = (r.versine, r.sine);
        let c = 1.0 + v;
        let x = *dtheta;
        // The carried value (1 + v, s) − carry misses unit norm by `excess` (a few ulps); the
        // factor 1 − excess/2 restores it (a Newton step for 1/|z|) within the increment.
        // c² + s² − 1 = 2v + v² + s², formed without the 1: near θ = 0, where 2v ≈ −s², its
        // rounding is of the size of s², not of 1, so the correction does not spread an ulp
        // of 1 into the versine.
        let excess = ((2.0 * v + s * s) + v * v) - 2.0 * (c * carry[0] + s * carry[1]);
        let y = x * x;
        if y < TWO_TERMS {
            // The common case (|x| < 2.2e-4): ds = x − x·y/6 and dc = −y/2 + y²/24, as
            // `sin_cos_minus_one` keeps them there, multiplied out into
            //   δv = c·dc − s·ds − c·excess/2
            //      = −s·x + (c·C₀)·y − ((s·S₀)·x)·y + (c·C₁)·y² − c·excess/2
            // (and likewise for s), so that what depends only on the orientation and its
            // carry is formed before x arrives, and the chain of dependent operations from x
            // to the new orientation is 6 steps (x·x, ·y, three sums, the compensated sum)
            // instead of 9. Each bracket is less the carry (Kahan's y in `compensated_add`).
            let y2 = y * y;
            let rest_v = -0.5 * excess * c - carry[0];
            let rest_s = -0.5 * excess * s - carry[1];
            let delta_v = ((rest_v - s * x) + ((c * COS[0]) * y - ((s * SINC[0]) * x) * y))
                + (c * COS[1]) * y2;
            let delta_s = ((rest_s + c * x) + ((s * COS[0]) * y + ((c * SINC[0]) * x) * y))
                + (s * COS[1]) * y2;
            let (v1, s1) = (v + delta_v, s + delta_s);
            carry[0] = (v1 - v) - delta_v;
            carry[1] = (s1 - s) - delta_s;
            return Heading {
                versine: v1,
                sine: s1,
            };
        }
        let (ds, dc) = sin_cos_minus_one(x);
        let radial = dc - 0.5 * excess;
        let (mut v1, mut s1) = (v, s);
        compensated_add(&mut v1, &mut carry[0], c * radial - s * ds);
        compensated_add(&mut s1, &mut carry[1], s * radial + c * ds);
        Heading {
            versine: v1,
            sine: s1,
        }
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
    fn gyroscopic(_: &Self::W, _: &Self::W) -> Self::W {
        0.0
    }
    fn rotate_angular(_: &Self::R, w: &Self::W) -> Self::W {
        *w
    }
    fn unrotate_angular(_: &Self::R, w: &Self::W) -> Self::W {
        *w
    }
    fn free_rotations(held: &[Self::W]) -> Vec<Self::W> {
        if held.is_empty() {
            vec![1.0]
        } else {
            Vec::new()
        }
    }
}

/// A 2D orientation about z by its versine cos θ − 1 and its sine, the two small parts of the
/// rotation near θ = 0, each kept to its own relative precision. A body point is displaced by
/// the rotation as (R − 1) x = (v x − s y, s x + v y) ([`Space::turned`]), without forming
/// cos θ − 1 from cos θ (which cancels to an ulp of 1) or from −sin²θ/(1 + cos θ) (a division
/// on the time loop's chain at every increment): the time loop sums the versine itself. Past a
/// quarter turn the versine's size is that of the cosine (up to 2), and so is its precision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Heading {
    versine: f64,
    sine: f64,
}

impl Heading {
    /// No turn.
    pub const IDENTITY: Heading = Heading {
        versine: 0.0,
        sine: 0.0,
    };

    /// The orientation turned by `angle` (rad) from the x axis.
    pub fn new(angle: f64) -> Self {
        let half = (0.5 * angle).sin();
        Self::from_versine_sine(-2.0 * half * half, angle.sin())
    }

    /// The orientation of versine `versine` (cos θ − 1) and sine `sine`, taken as given (a
    /// point on the unit circle to round-off).
    pub fn from_versine_sine(versine: f64, sine: f64) -> Self {
        Heading { versine, sine }
    }

    /// cos θ − 1.
    #[inline]
    pub fn versine(&self) -> f64 {
        self.versine
    }

    /// sin θ.
    #[inline]
    pub fn sin(&self) -> f64 {
        self.sine
    }

    /// cos θ, 1 + (cos θ − 1) (to an ulp of 1).
    #[inline]
    pub fn cos(&self) -> f64 {
        1.0 + self.versine
    }

    /// θ in (−π, π].
    pub fn angle(&self) -> f64 {
        self.sine.atan2(self.cos())
    }
}

/// A 3D orientation: the unit quaternion the time loop advances, and R − 1, formed from it
/// once per change. A body's points are rotated several times an increment (each load and
/// spring end, each contact's face and normal); R − 1 turns one in 15 flops (18 with the
/// rotated point itself), the quaternion in about 30.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orientation {
    quaternion: UnitQuaternion<f64>,
    /// R − 1 = 2w [v]× + 2 [v]×², from the quaternion's small parts (w, v), so that its
    /// entries keep their relative precision as the rotation goes to zero: `turned` relies on
    /// it (see [`Space::turned`]).
    turn: Matrix3<f64>,
}

impl Orientation {
    /// The orientation of a unit quaternion.
    #[inline]
    pub fn new(quaternion: UnitQuaternion<f64>) -> Self {
        let (w, v) = (quaternion.w, quaternion.imag());
        let (x2, y2, z2) = (2.0 * v.x, 2.0 * v.y, 2.0 * v.z);
        let (xx, yy, zz) = (v.x * x2, v.y * y2, v.z * z2);
        let (xy, xz, yz) = (v.x * y2, v.x * z2, v.y * z2);
        let (wx, wy, wz) = (w * x2, w * y2, w * z2);
        Orientation {
            quaternion,
            turn: Matrix3::new(
                -(yy + zz),
                xy - wz,
                xz + wy,
                xy + wz,
                -(xx + zz),
                yz - wx,
                xz - wy,
                yz + wx,
                -(xx + yy),
            ),
        }
    }

    /// The unit quaternion.
    #[inline]
    pub fn quaternion(&self) -> &UnitQuaternion<f64> {
        &self.quaternion
    }
}

/// An orthonormal basis whose leading vectors are the given orthonormal ones, completed by
/// Gram–Schmidt from the coordinate axis that keeps the most after projecting out the columns
/// so far. That residual is at least 1/√3 long (the squared residuals of the three axes sum to
/// the number of columns still missing), so each new column is orthogonal to the others to
/// round-off. Completing from the first axis whose residual merely exceeded a threshold (1e-6)
/// lost precision by that residual's reciprocal: two held axes whose free axis lies 2.2e-5 off
/// a coordinate plane gave one orthogonal to them only to 4e-11.
fn basis_with(leading: &[Vector3<f64>]) -> Matrix3<f64> {
    let mut cols: Vec<Vector3<f64>> = leading.to_vec();
    while cols.len() < 3 {
        let residual = |e: Vector3<f64>| {
            let mut v = e;
            for c in &cols {
                v -= c * c.dot(&v);
            }
            v
        };
        let v = [Vector3::x(), Vector3::y(), Vector3::z()]
            .map(residual)
            .into_iter()
            .fold(Vector3::zeros(), |best, v| {
                if v.norm_squared() > best.norm_squared() {
                    v
                } else {
                    best
                }
            });
        cols.push(v.normalize());
    }
    Matrix3::from_columns(&cols)
}

impl Space for Spatial {
    fn unrotate(r: &Self::R, x: &Self::V) -> Self::V {
        x + r.turn.tr_mul(x)
    }
    fn solid(solid: &Solid) -> Self::Shape {
        use parry3d_f64::shape::SharedShape;
        match *solid {
            Solid::Ball { radius } => SharedShape::ball(radius),
            Solid::Cuboid { half_extents: h } => SharedShape::cuboid(h.x, h.y, h.z),
            Solid::Capsule {
                half_height,
                radius,
            } => SharedShape::capsule_y(half_height, radius),
            Solid::Convex { ref polytope } => {
                let corners: Vec<_> = polytope
                    .corners
                    .iter()
                    .map(|c| parry3d_f64::math::Vector::new(c.x, c.y, c.z))
                    .collect();
                SharedShape::convex_hull(&corners)
                    .expect("validated: the corners span a convex polyhedron")
            }
        }
    }
    fn thinnest(shape: &Self::Shape) -> f64 {
        shape.compute_local_aabb().half_extents().min_element()
    }
    fn solid_gap(shape: &Self::Shape, local: &Self::V) -> (f64, Self::V) {
        let size = || shape.compute_local_aabb().half_extents().length();
        gap_and_normal(local, size, |p| {
            let q = parry3d_f64::math::Vector::new(p.x, p.y, p.z);
            let projection = shape.project_local_point(q, false);
            let d = q - projection.point;
            let distance = d.length();
            let gap = if projection.is_inside {
                -distance
            } else {
                distance
            };
            (gap, Vector3::new(d.x, d.y, d.z))
        })
    }
    fn crosses(shape: &Self::Shape, from: &Self::V, to: &Self::V) -> bool {
        let v = |p: &Vector3<f64>| parry3d_f64::math::Vector::new(p.x, p.y, p.z);
        let ray = parry3d_f64::query::Ray::new(v(from), v(to) - v(from));
        shape.intersects_local_ray(&ray, 1.0)
    }
    type V = Vector3<f64>;
    type W = Vector3<f64>;
    type R = Orientation;
    type Shape = parry3d_f64::shape::SharedShape;
    type Carry = [f64; 4];
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
        Orientation::new(UnitQuaternion::identity())
    }
    fn rotate(r: &Self::R, x: &Self::V) -> Self::V {
        x + r.turn * x
    }
    fn turned(r: &Self::R, x: &Self::V) -> Self::V {
        r.turn * x
    }
    fn rotate_inertia(r: &Self::R, i: &Self::Inertia) -> Self::Inertia {
        // R I Rᵀ written out: T = R I, then the upper triangle of T Rᵀ, mirrored (the result
        // is symmetric by construction; 45 multiply-adds instead of two general products).
        let m = r.turn + Matrix3::identity();
        let t = Matrix3::from_fn(|a, b| {
            m[(a, 0)] * i[(0, b)] + m[(a, 1)] * i[(1, b)] + m[(a, 2)] * i[(2, b)]
        });
        let e = |a: usize, b: usize| {
            t[(a, 0)] * m[(b, 0)] + t[(a, 1)] * m[(b, 1)] + t[(a, 2)] * m[(b, 2)]
        };
        let (xy, xz, yz) = (e(0, 1), e(0, 2), e(1, 2));
        Matrix3::new(e(0, 0), xy, xz, xy, e(1, 1), yz, xz, yz, e(2, 2))
    }
    fn inertia_apply(i: &Self::Inertia, w: &Self::W) -> Self::W {
        i * w
    }
    #[inline(always)]
    fn advance_compensated(r: &Self::R, carry: &mut [f64; 4], dtheta: &Vector3<f64>) -> Self::R {
        // exp(dθ/2) − 1 = (cos(|dθ|/2) − 1, sin(|dθ|/2)/|dθ| · dθ) = (w, (½ + t) dθ).
        let angle2 = dtheta.norm_squared();
        let (w, t) = if angle2 < SMALL_ANGLE * SMALL_ANGLE {
            // Taylor series at a = |dθ|/2 < 5e-3; the terms they leave out are under a fifth
            // of an ulp of the result (`TWO_TERMS`).
            (
                cos_minus_one_series(angle2, &HALF_COS, 4.0),
                sinc_minus_one_series(angle2, &HALF_SINC, 4.0),
            )
        } else {
            let angle = angle2.sqrt();
            let (s, c) = (0.5 * angle).sin_cos();
            (c - 1.0, s / angle - 0.5)
        };
        let quaternion = r.quaternion;
        let q = quaternion.coords;
        // As in 2D: the carried value q − carry misses unit norm by `excess`; the factor
        // 1 − excess/2 restores it within the increment.
        let low = nalgebra::Vector4::from(*carry);
        let excess = (q.norm_squared() - 1.0) - 2.0 * q.dot(&low);
        // The increment (w − excess/2, (½ + t) dθ) ⊗ q, as ½ p + t p + (w − excess/2) q with
        // p = (0, dθ) ⊗ q written out: p needs only dθ, not its length, so the chain of
        // dependent operations from dθ to the new orientation is three steps shorter than
        // forming the increment's quaternion first.
        let (v, s) = (quaternion.imag(), quaternion.w);
        let p = nalgebra::Vector4::new(
            s * dtheta.x + (dtheta.y * v.z - dtheta.z * v.y),
            s * dtheta.y + (dtheta.z * v.x - dtheta.x * v.z),
            s * dtheta.z + (dtheta.x * v.y - dtheta.y * v.x),
            -(dtheta.x * v.x + dtheta.y * v.y + dtheta.z * v.z),
        );
        let dq = (p * 0.5 - q * (0.5 * excess)) + (p * t + q * w);
        let mut out = q;
        for i in 0..4 {
            compensated_add(&mut out[i], &mut carry[i], dq[i]);
        }
        Orientation::new(UnitQuaternion::new_unchecked(nalgebra::Quaternion::from(
            out,
        )))
    }
    fn twist(r: &Self::R, axis: &Self::W) -> f64 {
        let q = r.quaternion;
        2.0 * q.vector().dot(axis).atan2(q.w)
    }
    fn cross(w: &Self::W, x: &Self::V) -> Self::V {
        w.cross(x)
    }
    fn moment(x: &Self::V, f: &Self::V) -> Self::W {
        x.cross(f)
    }
    fn gyroscopic(w: &Self::W, iw: &Self::W) -> Self::W {
        w.cross(iw)
    }
    fn rotate_angular(r: &Self::R, w: &Self::W) -> Self::W {
        Self::rotate(r, w)
    }
    fn unrotate_angular(r: &Self::R, w: &Self::W) -> Self::W {
        Self::unrotate(r, w)
    }
    fn free_rotations(held: &[Self::W]) -> Vec<Self::W> {
        let basis = basis_with(held);
        (held.len()..3)
            .map(|i| basis.column(i).into_owned())
            .collect()
    }
}
