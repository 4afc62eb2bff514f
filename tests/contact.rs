//! Contact that opens and closes, on parry's shapes (`cases/stress/contact_*.toml`): the
//! geometry parry gives against closed-form geometry, the event-driven `reference` against
//! closed forms, penalty contact against the reference as k_p grows, energy through elastic
//! impacts, rebound ratios against e², and a node that would go through a thin solid (rapier's
//! rebounds, with their controls: `tests/fair.rs`).
use crosscheck::case;
use crosscheck::engines::explicit::space::{Planar, Space, Spatial};
use crosscheck::engines::{History, RunOutput, RunSettings};
use crosscheck::scene::{Dimension, IncrementRule, PenaltyRule, Scene, Solid, solid_distance};
use nalgebra::{Vector2, Vector3};

fn stress(id: &str) -> Scene {
    case::load(&case::stress_dir(&case::cases_dir()).join(format!("{id}.toml")))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene, engine: &str, settings: &RunSettings) -> RunOutput {
    crosscheck::run::registry::named(engine)
        .unwrap()
        .run(scene, settings)
        .unwrap_or_else(|e| panic!("{} / {engine}: {e}", scene.id))
}

/// Points where parry's geometry is checked against the closed form: outside (faces, edges,
/// corners, caps) and inside (nearest face), off the medial axes where the nearest feature is
/// not unique.
fn probe_points() -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(1.3, 0.05, 0.02),
        Vector3::new(-0.9, 0.6, 0.1),
        Vector3::new(0.8, -0.5, 0.45),
        Vector3::new(0.1, 1.1, -0.05),
        Vector3::new(0.3, 0.02, 0.01),
        Vector3::new(-0.05, -0.12, 0.07),
        Vector3::new(0.0, -0.9, 0.2),
    ]
}

fn column(h: &History, name: &str) -> Vec<f64> {
    h.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

/// Rebound height ratio of the first impact, from the node's height change `ux_node`: the
/// highest point after the first minimum, over the drop (both from the surface, `drop` below
/// the start).
fn rebound_ratio(h: &History, drop: f64) -> f64 {
    let x = column(h, "ux_node");
    let low = (1..x.len())
        .find(|&i| x[i] > x[i - 1])
        .map_or(x.len() - 1, |i| i - 1);
    let apex = x[low..].iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v));
    (apex + drop) / drop
}

#[test]
fn parry_gap_and_normal_equal_closed_form_geometry() {
    let solids = [
        Solid::Ball { radius: 0.7 },
        Solid::Cuboid {
            half_extents: Vector3::new(0.5, 0.2, 0.3),
        },
        Solid::Capsule {
            half_height: 0.4,
            radius: 0.25,
        },
    ];
    let points = probe_points();
    let mut checked = 0;
    for solid in &solids {
        let spatial = Spatial::solid(solid);
        let planar_solid = match solid {
            Solid::Cuboid { half_extents } => Solid::Cuboid {
                half_extents: Vector3::new(half_extents.x, half_extents.y, 0.0),
            },
            s => s.clone(),
        };
        let planar = Planar::solid(&planar_solid);
        for p in &points {
            // Round-off of a projection on shapes of unit size: 1e-12.
            let (d, n) = Spatial::solid_gap(&spatial, p);
            let (d0, n0) = solid_distance(solid, p);
            assert!((d - d0).abs() < 1e-12, "{solid:?} at {p}: {d} vs {d0}");
            assert!((n - n0).norm() < 1e-12, "{solid:?} at {p}: {n} vs {n0}");
            let q = Vector3::new(p.x, p.y, 0.0);
            let (d, n) = Planar::solid_gap(&planar, &Vector2::new(q.x, q.y));
            let (d0, n0) = solid_distance(&planar_solid, &q);
            assert!((d - d0).abs() < 1e-12, "2D {solid:?} at {q}: {d} vs {d0}");
            assert!((Vector2::new(n0.x, n0.y) - n).norm() < 1e-12);
            checked += 2;
        }
    }
    assert_eq!(checked, 42);
    // A cuboid corner: the normal points along the diagonal from it.
    let cuboid = Spatial::solid(&solids[1]);
    let (d, n) = Spatial::solid_gap(&cuboid, &Vector3::new(0.6, 0.3, 0.4));
    assert!((d - 0.03f64.sqrt()).abs() < 1e-12);
    assert!((n - Vector3::new(1.0, 1.0, 1.0) / 3f64.sqrt()).norm() < 1e-12);
}

#[test]
fn the_event_driven_reference_is_exact_through_impacts() {
    let g = 9.81f64;
    for (id, e) in [
        ("contact_drop_e0", 0.0),
        ("contact_drop_e03", 0.3),
        ("contact_drop_e06", 0.6),
        ("contact_drop_e09", 0.9),
        ("contact_drop_e1", 1.0),
    ] {
        let out = run(&stress(id), "reference", &RunSettings::default());
        let m = &out.info.measures;
        // Free fall from 1 m: t1 = sqrt(2/g), v1 = sqrt(2 g); the event is located to the
        // integration tolerance (1e-12 relative).
        let (t1, v1) = ((2.0 / g).sqrt(), (2.0 * g).sqrt());
        assert!((m["impact_1_time"] - t1).abs() < 1e-10, "{id}");
        assert!((m["impact_1_speed"] - v1).abs() < 1e-9, "{id}");
        assert!((m["impact_1_rebound"] - e * v1).abs() < 1e-9, "{id}");
        let ratio = rebound_ratio(&out.history, 1.0);
        // The apex between rows: a row every 5e-4 s misses it by at most g (2.5e-4)²/2.
        assert!((ratio - e * e).abs() < 1e-6, "{id}: {ratio} vs {}", e * e);
    }
}

#[test]
fn the_node_leaves_the_ball_where_its_normal_force_vanishes() {
    let scene = stress("contact_slide_ball");
    let out = run(&scene, "reference", &RunSettings::default());
    let (g, r, v0) = (9.81f64, 1.0f64, 1.0f64);
    let leaving = (2.0 + v0 * v0 / (g * r)) / 3.0;
    let x = column(&out.history, "ux_node");
    let force = column(&out.history, "contact_force");
    let opening = out.info.measures["opening_1_time"];
    let t = column(&out.history, "t");
    let mut closed_rows = 0;
    for i in 0..t.len() {
        let cos = 1.0 + x[i] / r;
        if t[i] < opening {
            // On the ball: N = m (g cos θ − v²/R), v² = v0² + 2 g R (1 − cos θ).
            let v2 = v0 * v0 + 2.0 * g * r * (1.0 - cos);
            let expected = g * cos - v2 / r;
            assert!((force[i] - expected).abs() < 1e-9 * g, "row {i}");
            assert!(cos > leaving - 1e-9);
            closed_rows += 1;
        } else {
            assert_eq!(force[i], 0.0, "row {i}: the contact is open");
        }
    }
    // The last closed row is within one row of the leaving angle (5.9e-4 s at ~2.5 rad/s).
    let last = 1.0 + x[closed_rows - 1] / r;
    assert!(last - leaving < 2e-3, "{last} vs {leaving}");
    assert!(closed_rows > 100 && closed_rows < t.len() - 100);
}

#[test]
fn penalty_impacts_approach_the_reference_as_one_over_root_kp() {
    // An elastic penalty impact lasts π√(m/k_p); the rigid impact none, so after it the
    // penalty run lags by v·π√(m/k_p): the difference falls like k_p^(-1/2), not 1/k_p.
    let scene = stress("contact_drop_e1");
    let reference = run(&scene, "reference", &RunSettings::default());
    let exact = column(&reference.history, "ux_node");
    let v = (2.0f64 * 9.81).sqrt();
    let mut errors = Vec::new();
    for kp in [1e6, 1e7, 1e8] {
        let settings = RunSettings {
            penalty: Some(PenaltyRule::Stiffness(kp)),
            increment: Some(IncrementRule::Given(1e-6)),
            ..Default::default()
        };
        let out = run(&scene, "explicit", &settings);
        let got = column(&out.history, "ux_node");
        let error = exact
            .iter()
            .zip(&got)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let lag = v * std::f64::consts::PI * (1.0 / kp).sqrt();
        // The lag model to 10 %: the integration (h = 1e-6, ω_p h ≤ 0.01) adds below 1e-4 of it.
        assert!(
            (error / lag - 1.0).abs() < 0.1,
            "k_p {kp:e}: {error:e} vs {lag:e}"
        );
        errors.push(error);
    }
    let slope = (errors[2] / errors[0]).log10() / 2.0;
    assert!((slope + 0.5).abs() < 0.05, "slope {slope}");
}

#[test]
fn explicit_keeps_the_energy_of_elastic_impacts_and_rebounds_by_e_squared() {
    for (id, e) in [
        ("contact_drop_e0", 0.0),
        ("contact_drop_e03", 0.3),
        ("contact_drop_e06", 0.6),
        ("contact_drop_e09", 0.9),
        ("contact_drop_e1", 1.0),
    ] {
        let out = run(&stress(id), "explicit", &RunSettings::default());
        let ratio = rebound_ratio(&out.history, 1.0);
        // The linear spring–dashpot law rebounds by exactly e; gravity during the 1e-3 s
        // contact and the penalty's compliance move the height ratio by under 0.02.
        assert!((ratio - e * e).abs() < 0.02, "{id}: {ratio} vs {}", e * e);
    }
    // Elastic: the energy after every impact within 1e-3 of what the run holds (its largest
    // kinetic energy: 9.81 J in the drop).
    for id in ["contact_drop_e1", "contact_rattle", "contact_reopen"] {
        let out = run(&stress(id), "explicit", &RunSettings::default());
        let kinetic = column(&out.history, "e_kinetic");
        let balance = column(&out.history, "e_balance");
        let initial = kinetic.iter().fold(0.0f64, |m, k| m.max(*k));
        let worst = balance.iter().fold(0.0f64, |m, b| m.max(b.abs()));
        assert!(worst < 1e-3 * initial, "{id}: {worst:e} of {initial:e}");
    }
}

#[test]
fn a_node_that_would_go_through_a_thin_solid_is_refused_with_what_it_needs() {
    // The drop onto a cuboid 2 mm thick, from 50 m (31 m/s): at the case's increment the node
    // moves 3.1e-4 per increment, but the penalty (k_p = 1e7) lets it 1e-2 deep, past the
    // half thickness: refused, naming the speed and the increment and stiffness it needs.
    let text =
        std::fs::read_to_string(case::stress_dir(&case::cases_dir()).join("contact_drop_e1.toml"))
            .unwrap()
            .replace("id = \"contact_drop_e1\"", "id = \"thin\"")
            .replace("half_extents = [0.05, 0.5]", "half_extents = [0.001, 0.5]")
            .replace("centre = [-0.05, 0.0]", "centre = [-0.001, 0.0]")
            .replace(
                "at = [1.0, 0.0]\n\n# The block",
                "at = [50.0, 0.0]\n\n# The block",
            )
            .replace("duration = 1.0", "duration = 3.3");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("thin.toml");
    std::fs::write(&path, text).unwrap();
    let scene = case::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let Err(error) = crosscheck::run::registry::named("explicit")
        .unwrap()
        .run(&scene, &RunSettings::default())
    else {
        panic!("a node going through a 2 mm cuboid at 31 m/s was not refused");
    };
    let message = error.to_string();
    assert!(message.contains("went through the cuboid"), "{message}");
    assert!(message.contains("half thickness 1e-3"), "{message}");
    // It names the speed (31.3 m/s) and what would catch it.
    assert!(message.contains("moving 3.1"), "{message}");
    assert!(message.contains("--increment") && message.contains("--penalty"));
    // With what it asks for (the increment a tenth of the bound, to resolve the 2e-5 s
    // impact), the node bounces off the thin cuboid instead of going through.
    let needed = |key: &str| -> f64 {
        let at = message.find(key).unwrap() + key.len();
        message[at..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let settings = RunSettings {
        increment: Some(IncrementRule::Given(
            0.1 * needed("only with an increment below "),
        )),
        penalty: Some(PenaltyRule::Stiffness(
            2.0 * needed("and a penalty stiffness above "),
        )),
        ..Default::default()
    };
    let out = run(&scene, "explicit", &settings);
    // The rebound speed is the impact speed, √(2 g 50) = 31.32 m/s, less what gravity takes
    // until the row after the impact (t = 3.193 s, rows every 1.65e-3 s), within 1 %.
    let rebound = column(&out.history, "vx_node")
        .into_iter()
        .fold(f64::NEG_INFINITY, f64::max);
    let speed = (2.0f64 * 9.81 * 50.0).sqrt();
    assert!((rebound / speed - 1.0).abs() < 0.01, "{rebound} vs {speed}");
}

#[test]
fn explicit_strikes_within_an_increment_of_the_reference() {
    // The penalty starts where the gap reaches zero, as the rigid impact does: the first
    // impact's time differs only by where the increment falls (under one increment). Later
    // impacts inherit what the earlier ones did (the lag v·π√(m/k_p), the rebound within 0.02
    // of e²) and are not held to it.
    for id in [
        "contact_drop_e06",
        "contact_drop_e1",
        "contact_rattle",
        "contact_reopen",
    ] {
        let scene = stress(id);
        let exact = run(&scene, "reference", &RunSettings::default());
        let got = run(&scene, "explicit", &RunSettings::default());
        let h = got.info.increment;
        let a = exact.info.measures["impact_1_time"];
        let b = got.info.measures["impact_1_time"];
        assert!((b - a).abs() <= h, "{id}: {b} vs {a} (h = {h:e})");
    }
}

#[cfg(feature = "rapier")]
#[test]
fn rapier_reports_its_impacts_from_its_steps() {
    // Rapier's impulse acts within one step, and the output rows (50 increments apart on the
    // drops) never see it: the impact is the middle of the first step with a contact impulse.
    // Its soft contact acts from the step that would close the gap, so the first impact comes
    // within one increment of the reference's (measured: 0.9 early on the drop, 0.4 on the
    // rattle). On the rattle, where each pair's ball touches only its own plate, it counts the
    // reference's 12 impacts.
    for id in ["contact_drop_e06", "contact_rattle"] {
        let scene = stress(id);
        let exact = run(&scene, "reference", &RunSettings::default());
        let got = run(&scene, "rapier_f64", &RunSettings::default());
        let h = got.info.increment;
        let a = exact.info.measures["impact_1_time"];
        let b = got.info.measures["impact_1_time"];
        assert!((b - a).abs() <= h, "{id}: {b} vs {a} (h = {h:e})");
        if id == "contact_rattle" {
            assert_eq!(got.info.measures["impacts"], exact.info.measures["impacts"]);
        }
    }
}

#[test]
fn polytopes_refuse_corners_a_hull_library_could_read_two_ways() {
    use crosscheck::scene::polytope::{MIN_TURN, Polytope, PolytopeError};
    let polygon = |c: &[[f64; 2]]| {
        Polytope::new(
            &c.iter()
                .map(|p| Vector3::new(p[0], p[1], 0.0))
                .collect::<Vec<_>>(),
            true,
        )
    };
    // The wedge of contact_bounce_wedge: its inradius is twice its area over its perimeter.
    let (a, b, c) = ([-0.5, 0.866], [0.5, -0.866], [-1.0, -0.866]);
    let wedge = polygon(&[a, b, c]).unwrap();
    let side = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs();
    let perimeter = side(a, b) + side(b, c) + side(c, a);
    // Closed form against closed form: round-off.
    assert!((wedge.inradius - 2.0 * area / perimeter).abs() < 1e-12);
    // A corner given twice, and one a side bends at by 2e-5 rad (1e-5 m off a side's middle),
    // are refused with the corner's index.
    let off = [1e-5 * 0.866, 1e-5 * 0.5];
    for (corners, want) in [
        (vec![a, b, c, a], "repeats"),
        (vec![a, b, c, off], "straight"),
    ] {
        match polygon(&corners) {
            Err(e @ PolytopeError::Repeated { index: 3, .. }) => assert_eq!(want, "repeats", "{e}"),
            Err(
                e @ PolytopeError::Straight {
                    index: 3, angle, ..
                },
            ) => {
                assert_eq!(want, "straight", "{e}");
                // Two sides of length 1 each bent by atan(1e-5): 2e-5 rad.
                assert!((angle - 2e-5).abs() < 1e-8, "{angle}");
            }
            other => panic!("{want}: {other:?}"),
        }
    }
    // Every corner accepted is one parry keeps: bent by twice the least turn, parry's hull of
    // the quadrilateral has its four corners (2D); a cube with a low pyramid on a face (its
    // faces turn by √2·2e-3 at the apex) its nine (3D).
    let bent = [MIN_TURN * 0.866, MIN_TURN * 0.5];
    let kept = polygon(&[a, b, c, bent]).unwrap();
    let hull = parry2d_f64::shape::SharedShape::convex_hull(
        &kept
            .corners
            .iter()
            .map(|p| parry2d_f64::math::Vector::new(p.x, p.y))
            .collect::<Vec<_>>(),
    )
    .unwrap();
    assert_eq!(hull.as_convex_polygon().unwrap().points().len(), 4);
    let mut corners: Vec<Vector3<f64>> = (0..8)
        .map(|i| {
            let s = |k: usize| if i & (1 << k) == 0 { -0.5 } else { 0.5 };
            Vector3::new(s(0), s(1), s(2))
        })
        .collect();
    // A ninth corner MIN_TURN over the middle of the +z face: the pyramid's faces tilt by
    // atan(2 MIN_TURN).
    corners.push(Vector3::new(0.0, 0.0, 0.5 + MIN_TURN));
    let kept = Polytope::new(&corners, false).unwrap();
    let hull = parry3d_f64::shape::SharedShape::convex_hull(
        &kept
            .corners
            .iter()
            .map(|p| parry3d_f64::math::Vector::new(p.x, p.y, p.z))
            .collect::<Vec<_>>(),
    )
    .unwrap();
    assert_eq!(hull.as_convex_polyhedron().unwrap().points().len(), 9);
}

#[test]
fn parry_convex_shapes_equal_the_closed_form_polytope() {
    use crosscheck::scene::Polytope;
    use std::sync::Arc;
    let convex = |corners: &[[f64; 3]], planar: bool| Solid::Convex {
        polytope: Arc::new(
            Polytope::new(
                &corners
                    .iter()
                    .map(|c| Vector3::new(c[0], c[1], c[2]))
                    .collect::<Vec<_>>(),
                planar,
            )
            .unwrap(),
        ),
    };
    // A cube given by its corners is the cuboid: two closed forms written apart agree.
    let h = Vector3::new(0.5, 0.2, 0.3);
    let corners: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            let s = |b: usize| if i & (1 << b) == 0 { -1.0 } else { 1.0 };
            [s(0) * h.x, s(1) * h.y, s(2) * h.z]
        })
        .collect();
    let cube = convex(&corners, false);
    let cuboid = Solid::Cuboid { half_extents: h };
    let spatial = [
        cube.clone(),
        // An irregular polyhedron: a skewed octahedron.
        convex(
            &[
                [0.9, 0.1, 0.0],
                [-0.6, 0.0, 0.1],
                [0.1, 0.7, -0.1],
                [0.0, -0.8, 0.05],
                [0.05, 0.1, 0.6],
                [-0.1, 0.0, -0.5],
            ],
            false,
        ),
    ];
    let planar = [
        convex(
            &[
                [0.6, 0.0, 0.0],
                [0.1, 0.5, 0.0],
                [-0.5, 0.2, 0.0],
                [-0.3, -0.6, 0.0],
                [0.4, -0.4, 0.0],
            ],
            true,
        ),
        convex(
            &[[-0.5, 0.866, 0.0], [0.5, -0.866, 0.0], [-1.0, -0.866, 0.0]],
            true,
        ),
    ];
    let points: Vec<Vector3<f64>> = probe_points()
        .into_iter()
        .chain([Vector3::new(0.6, 0.3, 0.4)])
        .collect();
    let mut checked = 0;
    for p in &points {
        // Round-off of a projection on shapes of unit size: 1e-12.
        let (d, n) = solid_distance(&cube, p);
        let (d0, n0) = solid_distance(&cuboid, p);
        assert!(
            (d - d0).abs() < 1e-12 && (n - n0).norm() < 1e-12,
            "cube at {p}"
        );
        for solid in &spatial {
            let (d, n) = Spatial::solid_gap(&Spatial::solid(solid), p);
            let (d0, n0) = solid_distance(solid, p);
            assert!((d - d0).abs() < 1e-12, "{solid:?} at {p}: {d} vs {d0}");
            assert!((n - n0).norm() < 1e-12, "{solid:?} at {p}: {n} vs {n0}");
            checked += 1;
        }
        for solid in &planar {
            let q = Vector3::new(p.x, p.y, 0.0);
            let (d, n) = Planar::solid_gap(&Planar::solid(solid), &Vector2::new(q.x, q.y));
            let (d0, n0) = solid_distance(solid, &q);
            assert!((d - d0).abs() < 1e-12, "2D {solid:?} at {q}: {d} vs {d0}");
            assert!((Vector2::new(n0.x, n0.y) - n).norm() < 1e-12, "2D at {q}");
            checked += 1;
        }
    }
    assert_eq!(checked, 32);
}

#[test]
fn a_node_bounces_off_a_convex_face_by_the_reflection_law() {
    // Dropped 1 m on a face of normal n: it strikes at t1 = sqrt(2/g) with v = -sqrt(2 g) x̂ and
    // leaves, elastic and frictionless, with v - 2 (v·n) n; afterwards only gravity acts.
    let g = 9.81f64;
    let (t1, v1) = ((2.0 / g).sqrt(), (2.0 * g).sqrt());
    for (id, n) in [
        (
            "contact_bounce_wedge",
            Vector3::new(3f64.sqrt() / 2.0, 0.5, 0.0),
        ),
        (
            "contact_bounce_tetrahedron",
            Vector3::new(1.0, 0.4, 0.3).normalize(),
        ),
    ] {
        let v = Vector3::new(-v1, 0.0, 0.0);
        let after = v - n * (2.0 * v.dot(&n));
        let scene = stress(id);
        // Penalty contact (k_p = 1e7, m = 1) lasts τ = π√(m/k_p) and leaves with the normal
        // speed it came in with, where the rigid impact's node has meanwhile lost g n_x τ of it
        // to gravity: the penalty run keeps that much more normal velocity, for good.
        let tau = std::f64::consts::PI * (1.0 / 1e7f64).sqrt();
        for (engine, lag, tol) in [
            // The reference: event located and integrated to 1e-12 relative.
            ("reference", 0.0, 1e-9),
            // What is left: the impact's start within an increment (g h = 1e-4 m/s, 2e-5 of
            // v) and the contact's length changed by the gravity offset: 1e-4 of v (measured
            // 1.7e-5).
            ("explicit", g * n.x * tau, 1e-4),
        ] {
            let out = run(&scene, engine, &RunSettings::default());
            let t = column(&out.history, "t");
            let last = t.len() - 1;
            let expected = after - Vector3::x() * (g * (t[last] - t1)) + n * lag;
            let axes = if scene.dimension == Dimension::Two {
                &["vx_node", "vy_node"][..]
            } else {
                &["vx_node", "vy_node", "vz_node"][..]
            };
            for (k, name) in axes.iter().enumerate() {
                let c = column(&out.history, name);
                assert!(
                    (c[last] - expected[k]).abs() < tol * v1,
                    "{id} / {engine} {name}: {} vs {}",
                    c[last],
                    expected[k]
                );
            }
            assert!(
                (out.info.measures["impact_1_time"] - t1).abs() < 2e-5,
                "{id} / {engine}"
            );
        }
    }
}

#[test]
fn two_balls_collide_obliquely_as_newton_says() {
    // Node A (m 1, at 1 m/s) strikes ball B (m 3, at rest) with the line of centres at 30°:
    // J = 2 m_A m_B (v_rel·n)/(m_A + m_B) along n, so A leaves at (-0.125, 0.6495) and B at
    // (0.375, -0.2165); momentum (1, 0) and energy 0.5 J are kept.
    let scene = stress("contact_balls_oblique");
    let n = Vector2::new(-(3f64.sqrt()) / 2.0, 0.5);
    let (ma, mb) = (1.0, 3.0);
    let j = 2.0 * ma * mb * (Vector2::new(1.0, 0.0).dot(&n)).abs() / (ma + mb);
    let a = Vector2::new(1.0, 0.0) + n * (j / ma);
    let b = -n * (j / mb);
    // Penalty contact lasts τ = π√(μ/k_p) (μ = 0.75, k_p = 1e7) while the balls slide past
    // each other at v_t = 0.5 m/s: the line of centres turns by v_t τ/R, and the impulse,
    // spread over that turn, points on average v_t τ/(2R) off the rigid one: a velocity error
    // of about J v_t τ/(2R)/m_A (9.3e-4 m/s). The reference's is the integration's.
    let tau = std::f64::consts::PI * (0.75 / 1e7f64).sqrt();
    let predicted = j * 0.5 * tau / (2.0 * 0.3) / ma;
    for (engine, tol) in [("reference", 1e-12), ("explicit", 1.5 * predicted)] {
        let out = run(&scene, engine, &RunSettings::default());
        let last = |name: &str| *column(&out.history, name).last().unwrap();
        let va = Vector2::new(last("vx_node"), last("vy_node"));
        let vb = Vector2::new(last("vx"), last("vy"));
        assert!((va - a).amax() < tol, "{engine}: A {va} vs {a}");
        assert!((vb - b).amax() < tol, "{engine}: B {vb} vs {b}");
        if engine == "explicit" {
            assert!(
                (va - a).amax() > 0.5 * predicted,
                "the error model: {va} vs {a}"
            );
        }
        // Only the pair's equal and opposite forces act: momentum to round-off.
        let p = va * ma + vb * mb;
        assert!(
            (p - Vector2::new(1.0, 0.0)).amax() < 1e-12,
            "{engine}: momentum {p}"
        );
        // B is struck through its centre: it never turns.
        assert!(last("rz").abs() < 1e-12, "{engine}");
    }
}

#[test]
fn simultaneous_impacts_on_one_body_keep_momentum_and_energy() {
    // Two nodes (mass 1 each, at ±1 m/s) strike a free ball (mass 0.3, at rest) from either
    // side at the same instant (the scene is mirror-symmetric to the bit). One pair's impulse
    // throws the light ball at the other node, whose impulse throws it back faster than the
    // first node leaves: the pairs are struck again in turn (three passes) until both separate. Each impulse is elastic along the one line of
    // centres, so whatever the order, momentum (zero) and energy (1 J) are kept and every
    // pair leaves: A no faster right than the ball, C no slower.
    let text = std::fs::read_to_string(
        case::stress_dir(&case::cases_dir()).join("contact_balls_oblique.toml"),
    )
    .unwrap();
    let mut text = text
        .replace(
            "id = \"contact_balls_oblique\"",
            "id = \"contact_simultaneous\"",
        )
        .replace("at = [0.0, 0.15]", "at = [-1.0, 0.0]")
        .replace("at = [1.0, 0.0]", "at = [0.0, 0.0]")
        .replace("centre = [1.0, 0.0]", "centre = [0.0, 0.0]")
        .replace("mass = 3.0", "mass = 0.3")
        .replace("inertia = 0.048", "inertia = 0.0048");
    text.push_str(
        r#"
[[nodes]]
id = "C"
at = [1.0, 0.0]

[[masses]]
node = "C"
mass = 1.0

[[contacts]]
id = "balls_c"
node = "C"
body = "ball"
shape = "ball"
centre = [0.0, 0.0]
radius = 0.3
initially = "open"
restitution = 1.0

[[initial_velocities]]
node = "C"
velocity = [-1.0, 0.0]

[[output.columns]]
name = "vx_c"
velocity = "C"
direction = [1.0, 0.0]
"#,
    );
    let scene = case::parse(&text, std::path::Path::new("contact_simultaneous.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let out = run(&scene, "reference", &RunSettings::default());
    let last = |name: &str| *column(&out.history, name).last().unwrap();
    let (a, b, c) = (last("vx_node"), last("vx"), last("vx_c"));
    // Impulses through exact 3×3 algebra: momentum and energy to round-off.
    assert!(
        (a + 0.3 * b + c).abs() < 1e-12,
        "momentum {}",
        a + 0.3 * b + c
    );
    let energy = 0.5 * (a * a + 0.3 * b * b + c * c);
    assert!((energy - 1.0).abs() < 1e-10, "energy {energy}");
    assert!(a <= b && b <= c, "separating: {a} {b} {c}");
    // Both pairs struck once (one impact each, whatever the number of passes) at t = 0.7.
    assert_eq!(out.info.measures["impacts"], 2.0);
    assert!((out.info.measures["impact_1_time"] - 0.7).abs() < 1e-9);
}

#[test]
fn every_engine_reports_the_gap_it_moves_through() {
    // The drop starts 1 m above a held cuboid's face along +x, `ux_node` measures the node and
    // `ux` the cuboid along that normal: each engine's `gap` column (its own geometry: the
    // reference's closed form, the explicit engine's parry projection, rapier's bodies through
    // the scene's geometry) must be 1 + ux_node − ux, to f64 round-off on values of order 1
    // (the `ux` term keeps the check true of a cuboid that moves; rapier's is a fixed body).
    let mut scene = stress("contact_drop_e1");
    for engine in ["reference", "explicit", "rapier_f64_default", "rapier_f64"]
        .into_iter()
        .filter(|e| crosscheck::run::registry::named(e).is_some())
    {
        let out = run(&scene, engine, &RunSettings::default());
        let (gap, x) = (column(&out.history, "gap"), column(&out.history, "ux_node"));
        let body = column(&out.history, "ux");
        let worst = (0..gap.len()).fold(0.0_f64, |m, i| {
            m.max((gap[i] - (1.0 + x[i] - body[i])).abs())
        });

        assert!(
            worst < 1e-12,
            "{engine}: gap off 1 + ux_node - ux by {worst:e}"
        );
    }
    // The explicit engine's penalty lets the node in by the oscillation of mass m on k_p under
    // gravity: mg/k_p + √((mg/k_p)² + (v/ω_p)²), v = √(2 g h), ω_p = √(k_p/m). With a row per
    // increment (1e-5 s, ω_p h = 0.03) the rows see the deepest point to (ω_p h)²/8 = 1.3e-4,
    // and the scheme's amplitude is exact to O((ω_p h)²) (measured: 7.6e-6 off in all).
    scene.output_rows = 100_001;
    let out = run(&scene, "explicit", &RunSettings::default());
    let (g, kp) = (9.81_f64, 1e7_f64);
    let (offset, amplitude) = (g / kp, (2.0 * g).sqrt() / kp.sqrt());
    let expected = offset + (offset * offset + amplitude * amplitude).sqrt();
    let deepest = column(&out.history, "gap")
        .iter()
        .fold(0.0_f64, |m, g| m.max(-g));
    assert!(
        (deepest / expected - 1.0).abs() < 5e-4,
        "deepest {deepest:e} vs {expected:e}"
    );
}
