//! One increment of rotation from rest orientation, against the library's sine and cosine: the
//! explicit engine takes them from Taylor series that keep fewer terms at smaller angles, and
//! every form must agree with `f64::sin_cos` to round-off on both sides of each switch.

use crosscheck::engines::explicit::space::{Planar, Space, Spatial};
use nalgebra::{UnitQuaternion, Vector3};

/// Angles (rad) on both sides of the series' switches (a = 2.2e-4 and 6.3e-3 for the
/// argument of the series; the 3D quaternion takes half the increment's angle), past the
/// series (1e-2), and 8 per decade from 1e-12 to 1.
fn angles() -> Vec<f64> {
    let mut angles = vec![
        2.2e-4, 2.25e-4, 4.4e-4, 4.5e-4, 6.3e-3, 6.35e-3, 1.26e-2, 1.27e-2,
    ];
    angles.extend((0..=96).map(|i| 10f64.powf(-12.0 + f64::from(i) / 8.0)));
    angles
}

/// Both sides within an ulp or so of the exact value: ε of the larger (one ulp, two just
/// below a power of two).
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= f64::EPSILON * a.abs().max(b.abs())
}

#[test]
fn planar_increment_matches_the_library() {
    for x in angles() {
        for x in [x, -x] {
            let mut carry = [0.0; 2];
            let r = Planar::advance_compensated(&Planar::identity(), &mut carry, &x);
            // The carried value is r − carry; from rest the carry is the rounding of 1 + (cos − 1).
            let (c, s) = (r.cos_angle() - carry[0], r.sin_angle() - carry[1]);
            let (sin, cos) = x.sin_cos();
            assert!(close(s, sin), "sin at {x:e}: {s:e} against {sin:e}");
            assert!(close(c, cos), "cos at {x:e}: {c:e} against {cos:e}");
        }
    }
}

#[test]
fn spatial_increment_matches_the_library() {
    let axis = Vector3::new(1.0, -2.0, 2.0) / 3.0;
    for x in angles() {
        let mut carry = [0.0; 4];
        let r = Spatial::advance_compensated(&UnitQuaternion::identity(), &mut carry, &(axis * x));
        let q = r.quaternion();
        let (sin, cos) = (0.5 * x).sin_cos();
        assert!(
            close(q.w - carry[3], cos),
            "w at {x:e}: {} against {cos:e}",
            q.w
        );
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
