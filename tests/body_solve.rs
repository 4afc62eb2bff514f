//! The explicit engine's reduced body solve (`BodyOperator::solve`, called here through
//! `BodySolve`: block elimination onto the free rotation axes) against the full constrained
//! rigid-body system solved densely: the 6×6 (3D) or 3×3 (2D) mass matrix at the reference
//! node bordered by one row per held direction (Lagrange multipliers), factorised by
//! nalgebra's LU. The two share nothing but the equations they solve.

use crosscheck::engines::explicit::body_solve::{BodyOperator, BodySolve};
use crosscheck::engines::explicit::space::{
    BodyInertia, Heading, Orientation, Planar, Space, Spatial,
};
use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, UnitQuaternion, Vector2, Vector3};
use proptest::prelude::*;

mod common;

/// Round-off of two direct solves of a system whose condition number stays below about 1e4
/// here (masses 0.5–50, inertias ≥ 0.1 about the centre, lever arms ≤ 2): 1e-16 × 1e4 with a
/// margin of 100.
const TOLERANCE: f64 = 1e-10;

/// The full system: unknowns (a, α) and one multiplier per held translation and rotation;
/// `m a − m [c]× α + Σ λ d = f`, `m [c]× a + I α + Σ μ g = M`, `d·a = 0`, `g·α = 0`.
fn dense_3d(
    body: &BodyInertia<Spatial>,
    held_t: &[Vector3<f64>],
    held_r: &[Vector3<f64>],
    force: &Vector3<f64>,
    moment: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let n = 6 + held_t.len() + held_r.len();
    let mut k = DMatrix::<f64>::zeros(n, n);
    let c = body.centre.cross_matrix() * body.mass;
    let inertia = world_inertia(body);
    for i in 0..3 {
        k[(i, i)] = body.mass;
        for j in 0..3 {
            k[(i, 3 + j)] = -c[(i, j)];
            k[(3 + i, j)] = c[(i, j)];
            k[(3 + i, 3 + j)] = inertia[(i, j)];
        }
    }
    for (row, d) in held_t.iter().enumerate() {
        for i in 0..3 {
            k[(6 + row, i)] = d[i];
            k[(i, 6 + row)] = d[i];
        }
    }
    for (row, g) in held_r.iter().enumerate() {
        let row = 6 + held_t.len() + row;
        for i in 0..3 {
            k[(row, 3 + i)] = g[i];
            k[(3 + i, row)] = g[i];
        }
    }
    let mut rhs = DVector::<f64>::zeros(n);
    for i in 0..3 {
        rhs[i] = force[i];
        rhs[3 + i] = moment[i];
    }
    let x = k.lu().solve(&rhs).expect("the bordered system is regular");
    (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    )
}

/// The body's inertia in world axes, R I Rᵀ, by nalgebra's rotation matrix and products.
fn world_inertia(body: &BodyInertia<Spatial>) -> Matrix3<f64> {
    match body.orientation {
        None => body.inertia,
        Some(r) => {
            let r = r.quaternion().to_rotation_matrix();
            r.matrix() * body.inertia * r.matrix().transpose()
        }
    }
}

/// Orthonormal held directions: the first `count` columns of a rotation.
fn held(rotation: &Rotation3<f64>, count: usize) -> Vec<Vector3<f64>> {
    (0..count)
        .map(|i| rotation.matrix().column(i).into_owned())
        .collect()
}

fn vector() -> impl Strategy<Value = [f64; 3]> {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64]
}

fn scaled(x: [f64; 3], s: f64) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2]) * s
}

proptest! {
    #![proptest_config(common::proptest_config(400))]

    /// Every combination of held translations (0–3) and rotations (0–2, at least one axis
    /// free), along tilted directions, for a body whose mass centre is off the reference node,
    /// its inertia given in world axes or in turned body axes with their orientation.
    #[test]
    fn spatial_matches_the_dense_system(
        mass in 0.5..50.0f64,
        centre in vector(),
        principal in [0.1..10.0f64, 0.1..10.0f64, 0.1..10.0f64],
        axes in vector(),
        turned in proptest::option::of(vector()),
        frame_t in vector(),
        frame_r in vector(),
        count_t in 0usize..=3,
        count_r in 0usize..=2,
        force in vector(),
        moment in vector(),
    ) {
        let centre = scaled(centre, 2.0);
        // Inertia about the mass centre (principal moments in tilted axes, positive definite),
        // moved to the reference node: I_O = I_C + m (|c|² 1 − c cᵀ).
        let turn = Rotation3::new(scaled(axes, 3.0));
        let about_centre = turn.matrix()
            * Matrix3::from_diagonal(&Vector3::from(principal))
            * turn.matrix().transpose();
        let inertia = about_centre
            + (Matrix3::identity() * centre.norm_squared() - centre * centre.transpose()) * mass;
        // The centre and the inertia above are in the body's axes; the centre is kept in
        // the world's.
        let orientation = turned.map(|t| Orientation::new(UnitQuaternion::new(scaled(t, 3.0))));
        let body = BodyInertia::<Spatial> {
            mass,
            centre: orientation.map_or(centre, |r| r.quaternion() * centre),
            inertia,
            orientation,
        };
        // The inertia applied in world axes, and its value on an axis.
        let (world, w) = (world_inertia(&body), scaled(moment, 1.0));
        prop_assert!((body.apply(&w) - world * w).norm() <= TOLERANCE * (world * w).norm().max(1.0));
        // The axial value reaches about 600 (m ≤ 50, lever arms ≤ 2√3): its round-off is
        // near 1e-13, so 1e-10 of the largest entry bounds it with a wide margin.
        if let Some(axis) = w.try_normalize(1e-3) {
            let expected = axis.dot(&(world * axis));
            prop_assert!((body.axial(&axis) - expected).abs() <= TOLERANCE * world.amax());
        }
        let held_t = held(&Rotation3::new(scaled(frame_t, 3.0)), count_t);
        let held_r = held(&Rotation3::new(scaled(frame_r, 3.0)), count_r);
        let free_r = Spatial::free_rotations(&held_r);
        let (force, moment) = (scaled(force, 100.0), scaled(moment, 100.0));

        let (a, alpha) = BodySolve::new(&body, &held_t, &free_r).solve(&force, &moment);
        let (a_dense, alpha_dense) = dense_3d(&body, &held_t, &held_r, &force, &moment);
        let scale = a_dense.norm().max(alpha_dense.norm()).max(1.0);
        prop_assert!((a - a_dense).norm() <= TOLERANCE * scale, "a {a} against {a_dense}");
        prop_assert!(
            (alpha - alpha_dense).norm() <= TOLERANCE * scale,
            "alpha {alpha} against {alpha_dense}"
        );
        // Held directions are held exactly where the node is pinned, to round-off otherwise.
        if count_t == 3 {
            prop_assert_eq!(a, Vector3::zeros());
        }
        for d in &held_t {
            prop_assert!(d.dot(&a).abs() <= TOLERANCE * scale);
        }
    }

    /// The planar body: rotation about z always free, 0–2 translations held along tilted
    /// directions.
    #[test]
    fn planar_matches_the_dense_system(
        mass in 0.5..50.0f64,
        centre in vector(),
        polar in 0.1..10.0f64,
        angle in -3.2..3.2f64,
        count_t in 0usize..=2,
        force in vector(),
        moment in -1.0..1.0f64,
    ) {
        let centre = Vector2::new(centre[0], centre[1]) * 2.0;
        let inertia = polar + mass * centre.norm_squared();
        let body = BodyInertia::<Planar> {
            mass,
            centre,
            inertia,
            orientation: None,
        };
        let axes = [Vector2::new(angle.cos(), angle.sin()), Vector2::new(-angle.sin(), angle.cos())];
        let held_t = &axes[..count_t];
        let free_r = Planar::free_rotations(&[]);
        let force = Vector2::new(force[0], force[1]) * 100.0;
        let moment = moment * 100.0;

        let (a, alpha) = BodySolve::new(&body, held_t, &free_r).solve(&force, &moment);
        // The planar body as the spatial one at z = 0 with the out-of-plane motion held.
        let lifted = BodyInertia::<Spatial> {
            mass,
            centre: Vector3::new(centre.x, centre.y, 0.0),
            inertia: Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, inertia)),
            orientation: None,
        };
        let mut held_3d: Vec<Vector3<f64>> =
            held_t.iter().map(|d| Vector3::new(d.x, d.y, 0.0)).collect();
        held_3d.push(Vector3::z());
        let (a_dense, alpha_dense) = dense_3d(
            &lifted,
            &held_3d,
            &[Vector3::x(), Vector3::y()],
            &Vector3::new(force.x, force.y, 0.0),
            &Vector3::new(0.0, 0.0, moment),
        );
        let scale = a_dense.norm().max(alpha_dense.norm()).max(1.0);
        prop_assert!((Vector3::new(a.x, a.y, 0.0) - a_dense).norm() <= TOLERANCE * scale);
        prop_assert!((alpha - alpha_dense.z).abs() <= TOLERANCE * scale);
    }

    /// A 3D body that turns about one free axis g, pinned at its reference node or with its
    /// mass centre there (0–2 translations held), with an anisotropic inertia in tilted axes:
    /// its solve with the operator formed at the orientation R₀ where a step starts gives,
    /// after any turn φ about g (R = Rot(g, φ)·R₀), the turned body's accelerations, as the
    /// dense system at R solves them: the operator is g·R I Rᵀg, and Rᵀg = R₀ᵀg. Checked below so that the test can fail: a turn about a
    /// held axis instead changes it, and so does the same turn about g of a body whose mass
    /// centre is off the node with a translation free (its drag direction Q(g × c) turns).
    #[test]
    fn spatial_operator_at_the_start_serves_every_turn_about_its_axis(
        mass in 0.5..50.0f64,
        centre in vector(),
        principal in [0.1..10.0f64, 0.1..10.0f64, 0.1..10.0f64],
        axes in vector(),
        start in vector(),
        frame_r in vector(),
        frame_t in vector(),
        turn in -3.2..3.2f64,
        pinned in any::<bool>(),
        count_t in 0usize..=2,
        force in vector(),
        moment in vector(),
        centre_off in [0.2..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
    ) {
        let principal = Matrix3::from_diagonal(&Vector3::from(principal));
        let tilt = Rotation3::new(scaled(axes, 3.0));
        let centre = if pinned { scaled(centre, 2.0) } else { Vector3::zeros() };
        let inertia = tilt.matrix() * principal * tilt.matrix().transpose()
            + (Matrix3::identity() * centre.norm_squared() - centre * centre.transpose()) * mass;
        let held_r = held(&Rotation3::new(scaled(frame_r, 3.0)), 2);
        let free_r = Spatial::free_rotations(&held_r);
        let g = free_r[0];
        let held_t = held(&Rotation3::new(scaled(frame_t, 3.0)), if pinned { 3 } else { count_t });
        let oriented = |q: UnitQuaternion<f64>| BodyInertia::<Spatial> {
            mass,
            centre: q * centre,
            inertia,
            orientation: Some(Orientation::new(q)),
        };
        let q0 = UnitQuaternion::new(scaled(start, 3.0));
        let at_start = BodyOperator::of(&oriented(q0), &held_t, &free_r);
        let (force, moment) = (scaled(force, 100.0), scaled(moment, 100.0));

        let turned = oriented(UnitQuaternion::from_scaled_axis(g * turn) * q0);
        let (a, alpha) = BodySolve::with(&turned, &held_t, &free_r, at_start).solve(&force, &moment);
        let (a_dense, alpha_dense) = dense_3d(&turned, &held_t, &held_r, &force, &moment);
        let scale = a_dense.norm().max(alpha_dense.norm()).max(1.0);
        prop_assert!((a - a_dense).norm() <= TOLERANCE * scale, "a {a} against {a_dense}");
        prop_assert!(
            (alpha - alpha_dense).norm() <= TOLERANCE * scale,
            "alpha {alpha} against {alpha_dense}"
        );

        // Turned as far about a held axis instead, the body's inertia about g changes (unless
        // the turn or the anisotropy is small), and the operator at the start no longer serves.
        let wrong = oriented(UnitQuaternion::from_scaled_axis(held_r[0] * turn) * q0);
        let axial_change = (wrong.axial(&g) - turned.axial(&g)).abs();
        if axial_change > 1e-3 * turned.axial(&g) {
            let (_, alpha_wrong) =
                BodySolve::with(&wrong, &held_t, &free_r, at_start).solve(&force, &moment);
            let (_, alpha_wrong_dense) = dense_3d(&wrong, &held_t, &held_r, &force, &moment);
            // With the drag zero the relative error is the change of g·I g over its value:
            // above 1e-3 here, whatever the load (unless the load gives no α at all).
            let relative = (alpha_wrong - alpha_wrong_dense).norm() / alpha_wrong_dense.norm();
            prop_assert!(
                relative > 1e-6 || alpha_wrong_dense == Vector3::zeros(),
                "a turn about a held axis left the operator serving: {relative:e}"
            );
        }

        // The mass centre off the node with a translation free: the operator needs the drag
        // w = Q(g × c), which turns with the body, so the one formed at the start no longer
        // serves once w has moved.
        if !pinned {
            let c = scaled(centre_off, 1.0);
            let offset = |q: UnitQuaternion<f64>| BodyInertia::<Spatial> {
                mass,
                centre: q * c,
                inertia: inertia + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * mass,
                orientation: Some(Orientation::new(q)),
            };
            let q = UnitQuaternion::from_scaled_axis(g * turn) * q0;
            let drag = |q: UnitQuaternion<f64>| {
                let mut w = g.cross(&(q * c));
                for d in &held_t {
                    w -= d * d.dot(&w);
                }
                w
            };
            if (drag(q) - drag(q0)).norm() > 1e-2 * c.norm() {
                let start_operator = BodyOperator::of(&offset(q0), &held_t, &free_r);
                let (a, alpha) =
                    BodySolve::with(&offset(q), &held_t, &free_r, start_operator).solve(&force, &moment);
                let (a_dense, alpha_dense) = dense_3d(&offset(q), &held_t, &held_r, &force, &moment);
                let miss = (a - a_dense).norm() + (alpha - alpha_dense).norm();
                let scale = a_dense.norm().max(alpha_dense.norm());
                prop_assert!(
                    miss > 1e-9 * scale || scale == 0.0,
                    "an off-centre body's operator served after its drag turned: {miss:e}"
                );
            }
        }
    }

    /// A planar body pinned at its reference node, or with its mass centre there, turned to
    /// any orientation: its solve with the operator formed at rest gives the turned body's
    /// accelerations bit for bit. The explicit engine forms such a body's operator once per
    /// step under finite rotation (`Constraints::body_operators`) on this ground: the
    /// operator reads the inertia about the one axis, which turning leaves as it is, and,
    /// unless pinned, the centre, which stays at the node.
    #[test]
    fn planar_operator_at_rest_serves_every_orientation(
        mass in 0.5..50.0f64,
        centre in vector(),
        polar in 0.1..10.0f64,
        angle in -3.2..3.2f64,
        turn in -3.2..3.2f64,
        pinned in any::<bool>(),
        count_t in 0usize..=1,
        force in vector(),
        moment in -1.0..1.0f64,
    ) {
        // Pinned: both translations held, the centre anywhere; otherwise the centre at the
        // node and 0 or 1 translation held.
        let centre = if pinned { Vector2::new(centre[0], centre[1]) * 2.0 } else { Vector2::zeros() };
        let rest = BodyInertia::<Planar> {
            mass,
            centre,
            inertia: polar + mass * centre.norm_squared(),
            orientation: None,
        };
        let r = Heading::new(turn);
        // As the engine turns a body's mass properties: a centre at the node stays there.
        let turned = BodyInertia::<Planar> {
            centre: if centre == Vector2::zeros() { centre } else { Planar::rotate(&r, &centre) },
            orientation: Some(r),
            ..rest
        };
        let axes = [Vector2::new(angle.cos(), angle.sin()), Vector2::new(-angle.sin(), angle.cos())];
        let held_t = if pinned { &axes[..] } else { &axes[..count_t] };
        let free_r = Planar::free_rotations(&[]);
        let force = Vector2::new(force[0], force[1]) * 100.0;
        let moment = moment * 100.0;

        let at_rest = BodyOperator::of(&rest, held_t, &free_r);
        let bits = |(a, alpha): (Vector2<f64>, f64)| (a.x.to_bits(), a.y.to_bits(), alpha.to_bits());
        let cached = BodySolve::with(&turned, held_t, &free_r, at_rest).solve(&force, &moment);
        let formed = BodySolve::new(&turned, held_t, &free_r).solve(&force, &moment);
        prop_assert_eq!(bits(cached), bits(formed));
    }
}

proptest! {
    #![proptest_config(common::proptest_config(2000))]

    /// The free rotation axes complete any held frame to an orthonormal basis to round-off,
    /// also a frame tilted by as little as 1e-9 off the coordinate axes, whose completion from
    /// an axis nearly in the held plane cancels: each completing axis is unit and orthogonal
    /// to every held one and every other free one within 8 ulps (a few roundings per entry of
    /// a projection of a vector at least 1/√3 long, then its normalisation).
    #[test]
    fn free_rotations_complete_any_held_frame_to_round_off(
        exponent in -9.0..-1.0f64,
        direction in vector(),
        permutation in 0usize..6,
        count in 0usize..=2,
    ) {
        let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
        let order = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]][permutation];
        let tilt = Rotation3::new(scaled(direction, 10f64.powf(exponent)));
        let held_r: Vec<Vector3<f64>> = order[..count].iter().map(|&i| tilt * axes[i]).collect();
        let free_r = Spatial::free_rotations(&held_r);
        prop_assert_eq!(free_r.len(), 3 - count);
        let bound = 8.0 * f64::EPSILON;
        for (i, g) in free_r.iter().enumerate() {
            prop_assert!((g.norm() - 1.0).abs() <= bound, "|g| − 1 = {:e}", g.norm() - 1.0);
            for d in held_r.iter().chain(&free_r[..i]) {
                prop_assert!(g.dot(d).abs() <= bound, "g·d = {:e}", g.dot(d));
            }
        }
    }
}

/// The input on which CI first found the completion's loss of precision (proptest's shrunk
/// case of `spatial_operator_at_the_start_serves_every_turn_about_its_axis`): two held
/// rotations whose free axis lies 2.2e-5 off the y–z plane, a body unturned with its centre at
/// the node and an inertia of ratio 100. The free axis, completed from the x axis then, was
/// off by about 1e-11, and α by 2.4e-10 of its size. Against the closed form
/// α = g (g·M)/(g·I g) on the exact free axis g = h₀ × h₁, within 1e-14 relative (a dozen
/// roundings).
#[test]
fn a_free_axis_near_a_coordinate_plane_keeps_the_solve_exact() {
    let frame = Rotation3::new(scaled(
        [0.88427655344461, 0.46300942698768505, -0.03798372741644154],
        3.0,
    ));
    let held_r = held(&frame, 2);
    let free_r = Spatial::free_rotations(&held_r);
    let body = BodyInertia::<Spatial> {
        mass: 0.5,
        centre: Vector3::zeros(),
        inertia: Matrix3::from_diagonal(&Vector3::new(0.1, 9.960322546864811, 0.1)),
        orientation: Some(Orientation::new(UnitQuaternion::identity())),
    };
    let moment = Vector3::new(0.0, 0.0, -0.35164186728534247) * 100.0;
    let (_, alpha) = BodySolve::new(&body, &[], &free_r).solve(&Vector3::zeros(), &moment);
    let g = held_r[0].cross(&held_r[1]);
    assert!(
        g.x.abs() < 3e-5 && g.x.abs() > 1e-5,
        "the free axis's x component {:e}",
        g.x
    );
    let expected = g * (g.dot(&moment) / g.dot(&(body.inertia * g)));
    let miss = (alpha - expected).norm() / expected.norm();
    assert!(
        miss <= 1e-14,
        "α off by {miss:e} of its size: {alpha} against {expected}"
    );
}

/// A body without mass has no positive pivot: the solve gives non-finite accelerations (which
/// the time loop reports as a failed run) instead of finite nonsense.
#[test]
fn a_singular_body_gives_non_finite_accelerations() {
    let body = BodyInertia::<Spatial> {
        mass: 1.0,
        centre: Vector3::zeros(),
        inertia: Matrix3::zeros(),
        orientation: None,
    };
    let free_r = Spatial::free_rotations(&[]);
    let (a, alpha) = BodySolve::new(&body, &[], &free_r).solve(&Vector3::x(), &Vector3::z());
    assert!(alpha.iter().all(|x| x.is_nan()), "{alpha}");
    assert!(a.iter().any(|x| x.is_nan()), "{a}");
    let one_axis = [Vector3::z()];
    let (_, alpha) = BodySolve::new(&body, &[], &one_axis).solve(&Vector3::x(), &Vector3::z());
    assert!(alpha.z.is_nan(), "{alpha}");
}
