//! The engine simulates only the effects a scene calls for: its work counters prove it.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};

fn counters(id: &str, engine: ExplicitEngine) -> std::collections::BTreeMap<String, u64> {
    engine
        .run(&scene(id), &RunSettings::default())
        .unwrap()
        .info
        .counters
}

#[test]
fn spring_only_scene_never_evaluates_contact() {
    for id in [
        "springs_grounded_a",
        "springs_grounded_b",
        "springs_grounded_c",
        "springs_n2n_b",
        "springs_n2n_c",
    ] {
        for engine in [ExplicitEngine::finite(), ExplicitEngine::small()] {
            let c = counters(id, engine);
            assert!(
                c["force_evaluations"] > 10_000,
                "{id}: the run did evaluate forces"
            );
            assert_eq!(c["contact_evaluations"], 0, "{id}: contact code entered");
            assert_eq!(
                c["rotation_updates"], 0,
                "{id}: no body, no rotation update"
            );
            assert_eq!(c["body_solves"], 0, "{id}: no body solve");
        }
    }
}

#[test]
fn contact_scene_evaluates_contact_every_increment_and_no_damping() {
    let c = counters("rigid2d_pin_lumped", ExplicitEngine::finite());
    // One pair, evaluated once per increment (10 000) plus the linearisation and start.
    assert!(c["contact_evaluations"] >= 10_000, "{c:?}");
    assert!(c["contact_evaluations"] <= 10_100, "{c:?}");
    // No dashpots and, with the pin, no centripetal term on a free DOF: no velocity pass.
    assert_eq!(c["damping_evaluations"], 0, "{c:?}");
    assert_eq!(c["rotation_updates"], 10_000, "{c:?}");
}

#[test]
fn damped_scene_has_a_velocity_pass() {
    let c = counters("springs_grounded_a", ExplicitEngine::finite());
    // The centred iteration converges in a few passes at ωh ≈ 0.002.
    let per_step = c["damping_evaluations"] as f64 / 20_000.0;
    println!("damping passes per increment: {per_step:.2}");
    assert!((1.0..=6.0).contains(&per_step), "{c:?}");
}
