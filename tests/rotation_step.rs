//! One increment of rotation from rest orientation, against the library's sine and cosine: the
//! explicit engine takes them from Taylor series that keep fewer terms at smaller angles, and
//! every form must agree with `f64::sin_cos` to round-off on both sides of each switch. Also
//! one increment from turned orientations: in 2D against the library's sine and cosine (from
//! exact and general orientations, and with a carry to take off), in 3D against
//! nalgebra's quaternion product; and the 3D orientation's R − 1 against nalgebra's rotation
//! matrix.

use crosscheck::engines::explicit::space::{Heading, Orientation, Planar, Space, Spatial};
use nalgebra::{UnitQuaternion, Vector2, Vector3};

/// Angles (rad) on both sides of the series' switches (a = 2.2e-4 and 6.3e-3 for the
/// argument of the series; the 3D quaternion takes half the increment's angle, so its series
/// end, at an increment of 1e-2 as in 2D, comes before its second switch), on both sides of
/// the series' end, and 8 per decade from 1e-12 to 1.
fn angles() -> Vec<f64> {
    let mut angles = vec![
        2.2e-4, 2.25e-4, 4.4e-4, 4.5e-4, 6.3e-3, 6.35e-3, 9.99e-3, 1.001e-2,
    ];
    angles.extend((0..=96).map(|i| 10f64.powf(-12.0 + f64::from(i) / 8.0)));
    angles
}

/// The increment's angle (rad) from which the rotation update takes the library's sine and
/// cosine instead of the series.
const SERIES_END: f64 = 1e-2;

/// Both sides within an ulp or so of the exact value (the series' few roundings, the
/// library's own): 2ε of the larger.
fn close(a: f64, b: f64) -> bool {
    within(a, b, 2.0)
}

/// |a − b| within `ulps`·ε of the larger.
fn within(a: f64, b: f64, ulps: f64) -> bool {
    (a - b).abs() <= ulps * f64::EPSILON * a.abs().max(b.abs())
}

/// cos − 1 of the carried value, exact: `versine − carry` with `versine` the summed cos − 1
/// (the 2D orientation keeps it; for the 3D quaternion's w it is w − 1, exact by Sterbenz's
/// lemma, as w is summed from 1 with compensation), so it is compared with −2 sin²(x/2)
/// relative to itself, where a series that kept too few terms shows (comparing cos with cos x
/// would hide any error below an ulp of 1); 4ε, as the reference itself takes three roundings.
fn versine_close(versine: f64, carry: f64, x: f64) -> bool {
    let half = (0.5 * x).sin();
    within(versine - carry, -2.0 * half * half, 4.0)
}

#[test]
fn planar_increment_matches_the_library() {
    for x in angles() {
        for x in [x, -x] {
            let mut carry = [0.0; 2];
            let r = Planar::advance_compensated(&Planar::identity(), &mut carry, &x);
            // The carried value is r − carry (from rest both sums are exact: the carry is 0).
            let s = r.sin() - carry[1];
            assert!(
                close(s, x.sin()),
                "sin at {x:e}: {s:e} against {:e}",
                x.sin()
            );
            assert!(
                versine_close(r.versine(), carry[0], x),
                "cos − 1 at {x:e}: {:e}",
                r.versine() - carry[0]
            );
        }
    }
}

/// From the three other exact unit orientations (a quarter, a half and three quarters turn),
/// where sin and cos − 1 of the increment trade places and signs: the update's terms in s,
/// which vanish from rest, carry the increment here, so a slip in any of them fails. The
/// orientation's change (r − r₀) − carry is exact where |x| ≤ π/6 (r₀'s versine and sine are
/// 0, ±1 or −2, so r − r₀ is exact by Sterbenz's lemma) and within half an ulp of itself
/// beyond, and is compared relative to itself within 4ε, as from rest.
#[test]
fn planar_increment_from_a_turned_orientation() {
    for (c, s) in [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)] {
        let start = Heading::from_versine_sine(c - 1.0, s);
        for x in angles() {
            for x in [x, -x] {
                let mut carry = [0.0; 2];
                let r = Planar::advance_compensated(&start, &mut carry, &x);
                let got = (
                    (r.versine() - (c - 1.0)) - carry[0],
                    (r.sin() - s) - carry[1],
                );
                let half = (0.5 * x).sin();
                let (sin, versine) = (x.sin(), -2.0 * half * half);
                // (c + i s)(cos x + i sin x) − (c + i s), with c, s ∈ {0, ±1}.
                let expected = (c * versine - s * sin, s * versine + c * sin);
                assert!(
                    within(got.0, expected.0, 4.0) && within(got.1, expected.1, 4.0),
                    "from ({c}, {s}) by {x:e}: {got:?} against {expected:?}"
                );
            }
        }
    }
}

/// From a general orientation against the library's cosine and sine of the summed angle:
/// within 4ε of 1 (the library's roundings of θ₀ + x and of its cosine and sine, and the
/// update's), where the orientation's norm correction acts too (|r₀| misses 1 by an ulp or so).
#[test]
fn planar_increment_adds_the_angle() {
    for start in [0.3, 2.0, -1.2, 4.0] {
        let r0 = Heading::new(start);
        for x in angles() {
            for x in [x, -x] {
                let mut carry = [0.0; 2];
                let r = Planar::advance_compensated(&r0, &mut carry, &x);
                let (cos, sin) = ((start + x).cos(), (start + x).sin());
                let got = (1.0 + (r.versine() - carry[0]), r.sin() - carry[1]);
                assert!(
                    (got.0 - cos).abs() <= 4.0 * f64::EPSILON
                        && (got.1 - sin).abs() <= 4.0 * f64::EPSILON,
                    "from {start} by {x:e}: {got:?} against ({cos}, {sin})"
                );
            }
        }
    }
}

/// With a carry of a few ulps, as the compensated sum leaves it: the carried orientation
/// (c, s) − k misses unit norm by −2(c·k₀ + s·k₁), and the update must take its carry off and
/// restore the norm (its factor 1 − excess/2). From the exact orientations (c, s ∈ {0, ±1},
/// where c² + s² = 1 exactly) the change δ = (r − r₀) − carry′ (exact, as the compensated sum
/// leaves it) is, in exact arithmetic,
///   δ_c = c·(cos x − 1) − s·sin x + (c·(c·k₀ + s·k₁) − k₀),
///   δ_s = s·(cos x − 1) + c·sin x + (s·(c·k₀ + s·k₁) − k₁),
/// with the brackets exact here; compared relative to itself within 4ε. A carry added instead
/// of taken off, its two parts swapped, or the norm correction taken with c and s swapped is
/// off by a carry, which at these angles is more than 4ε of δ.
#[test]
fn planar_increment_takes_off_its_carry() {
    let carry = [3.3e-17, -7.7e-17];
    for (c, s) in [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)] {
        let start = Heading::from_versine_sine(c - 1.0, s);
        for x in angles() {
            for x in [x, -x] {
                let mut low = carry;
                let r = Planar::advance_compensated(&start, &mut low, &x);
                let got = ((r.versine() - (c - 1.0)) - low[0], (r.sin() - s) - low[1]);
                let half = (0.5 * x).sin();
                let (sin, versine) = (x.sin(), -2.0 * half * half);
                let along = c * carry[0] + s * carry[1];
                let expected = (
                    (c * versine - s * sin) + (c * along - carry[0]),
                    (s * versine + c * sin) + (s * along - carry[1]),
                );
                assert!(
                    within(got.0, expected.0, 4.0) && within(got.1, expected.1, 4.0),
                    "from ({c}, {s}) by {x:e}: {got:?} against {expected:?}"
                );
            }
        }
    }
}

#[test]
fn spatial_increment_matches_the_library() {
    let axis = Vector3::new(1.0, -2.0, 2.0) / 3.0;
    for x in angles() {
        let mut carry = [0.0; 4];
        let r = Spatial::advance_compensated(&Spatial::identity(), &mut carry, &(axis * x));
        let q = r.quaternion();
        let (sin, cos) = (0.5 * x).sin_cos();
        if x < SERIES_END {
            assert!(
                versine_close(q.w - 1.0, carry[3], 0.5 * x),
                "w − 1 at {x:e}: {:e}",
                (q.w - 1.0) - carry[3]
            );
        } else {
            // Past the series the 3D update forms cos − 1 from the library's cosine: w itself
            // is then within an ulp, not its difference from 1.
            assert!(
                close(q.w - carry[3], cos),
                "w at {x:e}: {} against {cos:e}",
                q.w
            );
        }
        for k in 0..3 {
            let expected = sin * axis[k];
            assert!(
                close(q.imag()[k] - carry[k], expected),
                "v[{k}] at {x:e}: {} against {expected:e}",
                q.imag()[k]
            );
        }
    }
}

/// From a turned orientation the increment composes on the world side, exp(dθ/2) ⊗ q (the
/// rotation vector is in world axes): against nalgebra's quaternion product, component by
/// component within 4ε (|q| = 1; the series' and the product's few roundings), at every angle
/// above and about three tilted axes. From rest (above) the product's cross terms vanish; here
/// they do not, so a reversed product or a sign slip in them fails.
#[test]
fn spatial_increment_composes_on_the_world_side() {
    let start = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -1.1, 0.7));
    let axes = [
        Vector3::new(1.0, -2.0, 2.0) / 3.0,
        Vector3::new(0.0, 0.6, 0.8),
        Vector3::new(-0.48, 0.6, 0.64),
    ];
    for axis in axes {
        for x in angles() {
            let mut carry = [0.0; 4];
            let dtheta = axis * x;
            let r = Spatial::advance_compensated(&Orientation::new(start), &mut carry, &dtheta);
            let expected = UnitQuaternion::from_scaled_axis(dtheta) * start;
            for (k, low) in carry.iter().enumerate() {
                let got = r.quaternion().coords[k] - low;
                assert!(
                    (got - expected.coords[k]).abs() <= 4.0 * f64::EPSILON,
                    "component {k} at {x:e} about {axis:?}: {got} against {}",
                    expected.coords[k]
                );
            }
        }
    }
}

/// The orientation's R − 1 against nalgebra's rotation matrix: a body point turned into the
/// world and back within 4ε of |x| (three products and two sums per entry), and, at small
/// angles, the displacement (R − 1) x within 4ε of itself against sin θ a×x + 2 sin²(θ/2)
/// a×(a×x), where forming R x − x would cancel.
#[test]
fn spatial_rotations_match_the_rotation_matrix() {
    let x = Vector3::new(0.7, -1.9, 0.4);
    let axis = Vector3::new(-0.48, 0.6, 0.64);
    for angle in angles() {
        let q = UnitQuaternion::from_scaled_axis(axis * angle);
        let r = Orientation::new(q);
        let matrix = q.to_rotation_matrix();
        let (world, back) = (Spatial::rotate(&r, &x), Spatial::unrotate(&r, &x));
        assert!(
            (world - matrix * x).norm() <= 4.0 * f64::EPSILON * x.norm(),
            "{angle:e}"
        );
        assert!(
            (back - matrix.inverse() * x).norm() <= 4.0 * f64::EPSILON * x.norm(),
            "{angle:e}"
        );
        if angle < 1e-2 {
            let (sin, half) = (angle.sin(), (0.5 * angle).sin());
            let expected = axis.cross(&x) * sin + axis.cross(&axis.cross(&x)) * (2.0 * half * half);
            let turned = Spatial::turned(&r, &x);
            assert!(
                (turned - expected).norm() <= 4.0 * f64::EPSILON * expected.norm(),
                "turned at {angle:e}: {turned:?} against {expected:?}"
            );
        }
    }
}

/// The 2D orientation's turns against the library's sine and cosine of its angle, for an
/// orientation the time loop's update reaches (from rest, and from 2 rad, by each angle): a
/// body point turned into the world and back within 4ε of |x| (two products and a sum per
/// component, and the orientation's own roundings), its angle within 2ε of itself, and the
/// displacement (R − 1) x within 4ε of itself against sin θ (−y, x) − 2 sin²(θ/2) (x, y),
/// where forming R x − x would cancel. Below 1e-2 rad from rest the update takes its series,
/// so that check is against an independent form there.
#[test]
fn planar_rotations_match_the_library() {
    let x = Vector2::new(0.7, -1.9);
    for angle in angles() {
        for (start, turn) in [(0.0, angle), (0.0, -angle), (2.0, angle)] {
            let r = Planar::advance(&Heading::new(start), &turn);
            let angle = start + turn;
            let (sin, cos) = angle.sin_cos();
            let world = Vector2::new(cos * x.x - sin * x.y, sin * x.x + cos * x.y);
            let back = Vector2::new(cos * x.x + sin * x.y, cos * x.y - sin * x.x);
            let bound = 4.0 * f64::EPSILON * x.norm();
            assert!(
                (Planar::rotate(&r, &x) - world).norm() <= bound,
                "{angle:e}"
            );
            assert!(
                (Planar::unrotate(&r, &x) - back).norm() <= bound,
                "{angle:e}"
            );
            assert!(
                (r.angle() - angle).abs() <= 2.0 * f64::EPSILON * angle.abs(),
                "{angle:e}"
            );
            let half = (0.5 * angle).sin();
            let expected = Vector2::new(-x.y, x.x) * sin + x * (-2.0 * half * half);
            let turned = Planar::turned(&r, &x);
            assert!(
                (turned - expected).norm() <= 4.0 * f64::EPSILON * expected.norm(),
                "turned at {angle:e}: {turned:?} against {expected:?}"
            );
        }
    }
}

/// Many small increments keep the orientation on the unit circle to the versine's relative
/// precision, also where the path does not retrace itself: 120 000 increments of 1e-8 rad
/// from rest (1.2 mrad out, as a slow pendulum's body turns), then 200 000 of −7e-9 back,
/// through zero to −0.2 mrad.
/// - At every increment the carried versine V agrees with the carried sine S as the unit
///   circle demands, V = −S²/(2 + V), within 16ε of itself: the norm correction each increment
///   takes is formed to an ulp of S², not of 1, so it keeps that even at 1e-8 rad, where the
///   versine is 5e-17. (With the norm excess formed as c² + s² − 1, its rounding an ulp of 1
///   at each increment, the disagreement reaches 10 times the versine: tried.)
/// - On the way out the versine and sine are within 32ε of themselves of −2 sin²(θ/2) and
///   sin θ at the angle summed exactly (θ = k·x, k < 2^17, one rounding): each increment's
///   change is formed to a few ulps of itself and summed with compensation.
/// - Throughout, the sine is within 8ε·(|sin θ| + the angle travelled) of sin θ: each
///   increment's change rounds to a few ulps of itself, and the roundings may lean one way
///   over the path (the exact angle taken in two products and a sum, each rounded).
///
/// Measured: 3.1ε, 3.0ε and 0.5ε.
#[test]
fn planar_versine_keeps_its_precision_over_many_increments() {
    let (out, back) = ((1e-8, 120_000u32), (-7e-9, 200_000u32));
    let (mut r, mut carry) = (Planar::identity(), [0.0; 2]);
    let (mut circle, mut outward, mut sine): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 1..=out.1 + back.1 {
        let (step, theta, travelled) = if k <= out.1 {
            (out.0, f64::from(k) * out.0, f64::from(k) * out.0)
        } else {
            let j = f64::from(k - out.1);
            let far = f64::from(out.1) * out.0;
            (back.0, far + j * back.0, far - j * back.0)
        };
        r = Planar::advance_compensated(&r, &mut carry, &step);
        let (v, s) = (r.versine() - carry[0], r.sin() - carry[1]);
        if v != 0.0 {
            circle = circle.max((v + s * s / (2.0 + v)).abs() / v.abs());
        }
        let half = (0.5 * theta).sin();
        if k <= out.1 {
            let exact = -2.0 * half * half;
            outward = outward.max((v - exact).abs() / exact.abs());
            outward = outward.max((s - theta.sin()).abs() / theta.sin());
        }
        sine = sine.max((s - theta.sin()).abs() / (theta.sin().abs() + travelled));
    }
    assert!(
        circle <= 16.0 * f64::EPSILON,
        "off the unit circle by {circle:e} of the versine"
    );
    assert!(
        outward <= 32.0 * f64::EPSILON,
        "relative error on the way out {outward:e}"
    );
    assert!(
        sine <= 8.0 * f64::EPSILON,
        "sine off by {sine:e} of |sin θ| + travel"
    );
}
