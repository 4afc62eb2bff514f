//! Problems that must give the same answer whatever way the scene is built.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::scene::{Scene, Step, StepKind};

fn engines() -> [ExplicitEngine; 2] {
    [ExplicitEngine::finite(), ExplicitEngine::small()]
}

/// Grounded A (SPRING1), B (SPRING2 with the middle mass held) and C (SPRINGA at 45°) are the
/// same oscillator: equal to round-off. 1e-12 of the peak allows ~10⁴ roundings of 1e-16.
#[test]
fn grounded_a_b_c_agree() {
    for e in engines() {
        let a = run(&e, &scene("springs_grounded_a"), RunSettings::default());
        let ua = col(&a, "u_end");
        for other in ["springs_grounded_b", "springs_grounded_c"] {
            let h = run(&e, &scene(other), RunSettings::default());
            let d = max_diff(&ua, &col(&h, "u_end")) / peak(&ua);
            println!("{} A vs {other}: {d:.2e}", e.name());
            assert!(
                d <= 1e-12,
                "{} {other}: u_end differs from A by {d:e} of the peak",
                e.name()
            );
        }
    }
}

/// Node-to-node B (fixed-direction elements) and C (axial elements along 45°) agree.
#[test]
fn node_to_node_b_c_agree() {
    for e in engines() {
        let b = run(&e, &scene("springs_n2n_b"), RunSettings::default());
        let c = run(&e, &scene("springs_n2n_c"), RunSettings::default());
        for name in ["u_end", "u_mid"] {
            let (x, y) = (col(&b, name), col(&c, name));
            let d = max_diff(&x, &y) / peak(&x);
            println!("{} n2n {name}: {d:.2e}", e.name());
            assert!(
                d <= 1e-12,
                "{}: {name} differs by {d:e} of the peak",
                e.name()
            );
        }
    }
}

/// Each 3D rigid case equals its 2D twin (the 3D run rotates by quaternions, the 2D one adds
/// angles: the difference is accumulated round-off, far below 1e-9 of the peak).
#[test]
fn three_d_equals_two_d() {
    for variant in ["pin_lumped", "pin_surface", "slide_lumped", "slide_surface"] {
        for e in engines() {
            let two = run(
                &e,
                &scene(&format!("rigid2d_{variant}")),
                RunSettings::default(),
            );
            let three = run(
                &e,
                &scene(&format!("rigid3d_{variant}")),
                RunSettings::default(),
            );
            let rz = col(&two, "rz");
            for name in ["rz", "ux", "ux_node"] {
                let d = max_diff(&col(&two, name), &col(&three, name)) / peak(&rz);
                println!("{variant} {} {name}: {d:.2e}", e.name());
                assert!(
                    d <= 1e-9,
                    "{variant} {}: {name} 3D vs 2D differs by {d:e} of the peak rotation",
                    e.name()
                );
            }
        }
    }
}

/// The pinned lumped and surface-mass variants share one rotational answer (same inertia about
/// the pin; the offset centre of mass only loads the pin).
#[test]
fn pinned_variants_share_the_rotation() {
    for dim in ["2d", "3d"] {
        for e in engines() {
            let lumped = col(
                &run(
                    &e,
                    &scene(&format!("rigid{dim}_pin_lumped")),
                    RunSettings::default(),
                ),
                "rz",
            );
            let surface = col(
                &run(
                    &e,
                    &scene(&format!("rigid{dim}_pin_surface")),
                    RunSettings::default(),
                ),
                "rz",
            );
            let d = max_diff(&lumped, &surface) / peak(&lumped);
            println!("{dim} {}: {d:.2e}", e.name());
            assert!(
                d <= 1e-9,
                "{dim} {}: pinned variants differ by {d:e} of the peak",
                e.name()
            );
        }
    }
}

/// An increment that writes no row takes a shorter path than one that does (the particles
/// stepped in one pass, the dashpots' rates solved directly, the bodies' centred rates in
/// closed form, the bodies' half-step velocities updated in place), which must be the general
/// path's arithmetic bit for bit. A run with a row at every increment takes the general path
/// throughout; at the times both runs write, every column of every seed case but the time is
/// the same bit for bit (energies and dissipation included; a row's time is its index times
/// the row interval, which rounds differently for the two intervals). So on each seed case
/// with its dynamic step split in two halves: the second half restarts from the first half's
/// last accelerations, which the shorter paths keep for it alone.
#[test]
fn rows_at_every_increment_change_no_bit() {
    for id in SPRINGS_CASES.iter().chain(&RIGID_CASES) {
        for sparse in [scene(id), halved(&scene(id))] {
            for e in engines() {
                assert_rows_equal(&e, &sparse);
            }
        }
    }
}

/// `scene` with each dynamic step split into two of half its length under the same
/// conditions.
fn halved(scene: &Scene) -> Scene {
    let mut split = scene.clone();
    split.steps = scene
        .steps
        .iter()
        .flat_map(|step| match step.kind {
            StepKind::Dynamic { duration } => {
                let half = Step {
                    kind: StepKind::Dynamic {
                        duration: duration / 2.0,
                    },
                    ..step.clone()
                };
                vec![half.clone(), half]
            }
            StepKind::Static => vec![step.clone()],
        })
        .collect();
    assert!(split.steps.len() > scene.steps.len(), "{}", scene.id);
    split
}

/// `engine` on `sparse` and on it with a row at every increment: every row of the first equals
/// the second's row at its time, bit for bit, but for the time, and both count the same work
/// (a shorter path that leaves an increment to the general one takes back what it counted).
fn assert_rows_equal(engine: &ExplicitEngine, sparse: &Scene) {
    let (id, settings) = (&sparse.id, RunSettings::default());
    let name = engine.name();
    let few = engine.run(sparse, &settings).expect("a case that runs");
    let increments = few.info.steps as usize;
    let mut dense = sparse.clone();
    dense.output_rows = increments + 1;
    let every = engine.run(&dense, &settings).expect("a case that runs");
    let stride = increments / (sparse.output_rows - 1);
    assert_eq!(stride * (sparse.output_rows - 1), increments, "{id}");
    assert_eq!(few.history.columns, every.history.columns, "{id}");
    for (i, row) in few.history.rows.iter().enumerate() {
        let other = &every.history.rows[i * stride];
        let same = row[1..]
            .iter()
            .zip(&other[1..])
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(
            same,
            "{id} / {name}: row {i} differs: {row:?} against {other:?}"
        );
    }
    assert_eq!(few.info.counters, every.info.counters, "{id} / {name}");
}
