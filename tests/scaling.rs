//! The scaling study's chain family: the explicit engine's error against the exact solution
//! is the one central differences must give, at N = 10, 1000 and 100 000 along x, and at 1000
//! and 300 000 turned off the axes (the same increment whatever the scene's size or direction).
//!
//! Central differences started from rest reproduce a discrete mode's shape exactly and shift
//! only its frequency, from ω to (2/h) asin(ωh/2) (`Chain::predicted_error`), so the measured
//! error must equal the prediction to round-off; any other error (a wrong spring, a wrong
//! start, a lost DOF, a wrong mode shape) would show at once.
use crosscheck::case::chain::Chain;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::run::scaling::{self, STEPS};
use crosscheck::scene::{Connection, Probe, Scene};
use nalgebra::{Rotation3, Vector3};

/// The chain turned by `angle` about z: nodes, springs, the nodes' frames (so the held DOF
/// stays across the chain) and the probes; the motion is the same, along the turned line.
fn turned(mut scene: Scene, angle: f64) -> Scene {
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), angle);
    for node in &mut scene.nodes {
        node.position = r * node.position;
        node.frame = *r.matrix();
    }
    for spring in &mut scene.springs {
        if let Connection::FixedDirection { direction, .. } = &mut spring.connection {
            *direction = r * *direction;
        }
    }
    for column in &mut scene.columns {
        if let Probe::Displacement { direction, .. } | Probe::Velocity { direction, .. } =
            &mut column.probe
        {
            *direction = r * *direction;
        }
    }
    scene
}

/// The largest error over the probes and rows of the chain of `n` masses turned by `angle`,
/// and its prediction.
fn measured_error(n: usize, angle: f64) -> (f64, f64) {
    let chain = Chain::new(n, STEPS);
    let scene = turned(chain.scene(), angle);
    let out = ExplicitEngine::finite()
        .run(&scene, &RunSettings::default())
        .expect("the chain runs");
    assert_eq!(out.info.steps, chain.steps);
    let t = out.history.column("t").unwrap();
    let mut worst: f64 = 0.0;
    for (name, node) in chain.probes() {
        let u = out.history.column(&format!("u_{name}")).unwrap();
        for (t, u) in t.iter().zip(&u) {
            worst = worst.max((u - chain.displacement(node, *t)).abs() / chain.amplitude);
        }
    }
    (worst, chain.predicted_error(chain.increment))
}

/// The error model holds to round-off: positions of size A are summed over 400 increments with
/// compensation, so the history carries a few ulps of A; 1e-9 of the prediction (itself
/// ~1e-2 of A) is far above that and far below any modelling mistake (a wrong ω alone would
/// change the error at first order). Turned off the axes, the springs' directions and the
/// probes add a few ulps more.
fn assert_matches_prediction(n: usize, angle: f64) {
    let (error, predicted) = measured_error(n, angle);
    assert!(
        predicted > 1e-3,
        "the run must be long enough for the phase error to show: {predicted:e}"
    );
    assert!(
        (error - predicted).abs() <= 1e-9 * predicted,
        "N = {n}: error {error:e} against predicted {predicted:e}"
    );
}

#[test]
fn chain_of_10_matches_the_error_model() {
    assert_matches_prediction(10, 0.0);
}

#[test]
fn chain_of_1000_matches_the_error_model() {
    assert_matches_prediction(1000, 0.0);
}

#[test]
fn chain_of_100_000_matches_the_error_model() {
    assert_matches_prediction(100_000, 0.0);
}

#[test]
fn chains_turned_off_the_axes_match_the_error_model() {
    assert_matches_prediction(1000, 0.5);
    assert_matches_prediction(300_000, 0.5);
}

#[test]
fn the_element_bound_on_the_stable_increment_is_safe_and_tight_for_the_chain() {
    // A uniform chain's highest frequency is 2√(k/m) sin(Nπ/(2(N+1))) < 2√(k/m); the row-sum
    // bound gives exactly 2√(k/m) (4k/m per row), so the limit is √(m/k) and lies within
    // (1 − sin(Nπ/(2(N+1)))) of the exact one: 1.2e-7 relative at N = 1000 (above the dense
    // limit, so the bound is what the engine uses).
    let chain = Chain::new(1000, STEPS);
    let scene = chain.scene();
    let stable = ExplicitEngine::finite()
        .stable_increment(&scene, &RunSettings::default())
        .expect("a stable increment");
    let bound = (chain.mass / chain.stiffness).sqrt();
    assert!(
        (stable.increment - bound).abs() <= 1e-12 * bound,
        "{stable:?}"
    );
    let exact = 2.0
        / (2.0
            * (chain.stiffness / chain.mass).sqrt()
            * (1000.0 * std::f64::consts::PI / (2.0 * 1001.0)).sin());
    assert!(stable.increment <= exact && stable.increment >= exact * (1.0 - 2e-6));
}

#[test]
fn the_streaming_limit_is_a_positive_finite_time_per_dof() {
    // The limit loop's ns per DOF and increment is a measured time: positive and finite, and
    // not zero (a loop the compiler removed would take no time).
    let ns = scaling::streaming_limit(10_000, 100, 3);
    assert!(ns.is_finite() && ns > 0.0, "{ns}");
}

#[test]
fn sizes_are_powers_of_ten_up_to_the_maximum() {
    assert_eq!(scaling::sizes(1_000_000).len(), 6);
    assert_eq!(scaling::sizes(999), vec![10, 100]);
}
