//! The turning step (`engines::explicit::turning`): under finite rotation, a small step with one
//! body turning about one axis runs its increments between output rows with the state in
//! registers, by the general path's own arithmetic in the general path's order. So it must give
//! what the general path gives bit for bit: every output value, every work counter, every
//! impact.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunOutput, RunSettings};
use crosscheck::scene::Scene;

fn run(engine: ExplicitEngine, scene: &Scene) -> RunOutput {
    engine
        .run(scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id))
}

fn turning_increments(out: &RunOutput) -> u64 {
    out.info
        .counters
        .get("turning_increments")
        .copied()
        .unwrap_or(0)
}

/// The increments of a single dynamic step of `steps` increments, with a row every `stride`,
/// that the turning step may take: every one but the first (which starts the half-step
/// velocity), the rows and the step's last two (the last one's acceleration would start a
/// next step).
fn eligible(steps: u64, stride: u64) -> u64 {
    (1..=steps - 2).filter(|n| n % stride != 0).count() as u64
}

/// `scene` run by `explicit` with and without the turning step: the first took every increment
/// it may take (of `steps`), the second none, and the two agree bit for bit in every output
/// value, every work counter and every impact. Returns the run with the turning step.
fn same_as_general_path(scene: &Scene, steps: u64) -> RunOutput {
    let turning = run(ExplicitEngine::finite(), scene);
    let general = run(ExplicitEngine::finite().general(), scene);
    let id = &scene.id;
    assert_eq!(turning.info.steps, steps, "{id}");
    let rows = scene.output_rows as u64 - 1;
    assert_eq!(
        turning_increments(&turning),
        eligible(steps, steps / rows),
        "{id}"
    );
    assert_eq!(turning_increments(&general), 0, "{id}");
    assert_eq!(turning.history.columns, general.history.columns, "{id}");
    assert_eq!(
        turning.history.rows.len(),
        general.history.rows.len(),
        "{id}"
    );
    for (i, (a, b)) in turning
        .history
        .rows
        .iter()
        .zip(&general.history.rows)
        .enumerate()
    {
        for (name, (x, y)) in turning.history.columns.iter().zip(a.iter().zip(b)) {
            assert_eq!(
                x.to_bits(),
                y.to_bits(),
                "{id}: row {i}, {name}: {x:e} vs {y:e}"
            );
        }
    }
    let mut counters = turning.info.counters.clone();
    counters.remove("turning_increments");
    assert_eq!(counters, general.info.counters, "{id}");
    let impacts = |out: &RunOutput| {
        out.info
            .measures
            .iter()
            .filter(|(k, _)| k.starts_with("impact"))
            .map(|(k, v)| (k.clone(), v.to_bits()))
            .collect::<Vec<_>>()
    };
    assert_eq!(impacts(&turning), impacts(&general), "{id}");
    turning
}

#[test]
fn every_rigid_seed_case_is_the_general_path_bit_for_bit() {
    // 0.1 s at the seed cases' increment of 1e-5 s; the pinned and sliding, lumped and
    // surface-mass variants in 2D and 3D: with and without the centripetal terms (an
    // off-centre mass centre on a body that can translate), a fixed body operator and one
    // formed at every increment.
    for id in RIGID_CASES {
        same_as_general_path(&scene(id), 10_000);
    }
}

#[test]
fn a_contact_that_opens_and_closes_is_the_general_path_bit_for_bit() {
    let out = same_as_general_path(&stress_scene("contact_reopen"), 100_000);
    // The pair reopens and closes again: at least one impact after t = 0, noted at the same
    // increment by both paths (checked above).
    assert!(
        out.info.measures["impacts"] >= 1.0,
        "{:?}",
        out.info.measures
    );
}

#[test]
fn scenes_it_has_never_seen_are_the_general_path_bit_for_bit() {
    // Other masses and lever arms, a tilted face, and a body turning about x instead of z
    // (the 3D sliding case with rx free and rz held).
    let variants = [
        variant(
            "rigid2d_slide_surface",
            &[
                ("node = \"M1\"\nmass = 10.0", "node = \"M1\"\nmass = 3.5"),
                ("at = [-1.0, 1.0]", "at = [-0.4, 2.5]"),
            ],
        ),
        variant(
            "rigid2d_pin_lumped",
            &[("face_normal = [1.0, 0.0]", "face_normal = [0.8, 0.6]")],
        ),
        variant(
            "rigid3d_slide_surface",
            &[
                (
                    "dofs = [\"uy\", \"uz\", \"rx\", \"ry\"]",
                    "dofs = [\"uy\", \"uz\", \"rz\", \"ry\"]",
                ),
                ("angular = [0.0, 0.0, 10.0]", "angular = [10.0, 0.0, 0.0]"),
            ],
        ),
    ];
    for scene in &variants {
        same_as_general_path(scene, 10_000);
    }
}

#[test]
fn steps_it_does_not_qualify_for_take_the_general_path() {
    // Small rotation (the affine step's), and a body free to turn about three axes.
    let small = run(ExplicitEngine::small(), &scene("rigid2d_pin_lumped"));
    assert_eq!(turning_increments(&small), 0);
    let spin = run(ExplicitEngine::finite(), &stress_scene("stress_spin_major"));
    assert_eq!(turning_increments(&spin), 0);
    assert!(spin.info.steps > 0);
}
