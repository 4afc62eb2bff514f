//! Coulomb friction in rapier, held to the exact answers of `cases/friction/`.
//!
//! - The slide-stop case (2D): rapier_f64 (matched) decelerates at exactly μg, so the pair's μ
//!   is the case's (both colliders carry it, combined by their average), and stops short of the
//!   exact distance by the first-order lag of its integrator, which the test predicts.
//! - Isotropy (dimforge/rapier#137): launched at 0°, 30° and 45° in the face's plane, the node
//!   stops at the same distance and never leaves its launch line: rapier projects the tangent
//!   impulse on a cone (since dimforge/rapier#146), not on a pyramid. The control is f32, whose
//!   sideways drift at 30° is round-off: it shrinks with fewer increments and is absent at 45°.
#![cfg(feature = "rapier")]

use crosscheck::contract::History;
use crosscheck::engines::rapier::{MatchedSettings, Precision, RapierEngine};
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::scene::{IncrementRule, Scene};
use std::path::Path;

/// g, μ and v0 of every slide-stop case.
const G: f64 = 9.81;
const MU: f64 = 0.5;
const V0: f64 = 2.0;

fn case(id: &str) -> Scene {
    crosscheck::case::load(Path::new(&format!("cases/friction/{id}.toml")))
        .unwrap_or_else(|e| panic!("{id}: {e}"))
}

/// The history and the substep h/n of a run (h the run's increment).
fn run(scene: &Scene, precision: Precision, increment: Option<f64>) -> (History, f64) {
    let settings = RunSettings {
        increment: increment.map(IncrementRule::Given),
        ..RunSettings::default()
    };
    let out = RapierEngine::matched(precision)
        .run(scene, &settings)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id));
    let substeps = MatchedSettings::chosen(precision).solver_iterations as f64;
    (out.history, out.info.increment / substeps)
}

fn column(h: &History, name: &str) -> Vec<f64> {
    h.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

fn last(h: &History, name: &str) -> f64 {
    *column(h, name).last().unwrap()
}

fn largest(h: &History, name: &str) -> f64 {
    column(h, name).iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

#[test]
fn rapier_f64_stops_the_sliding_node_at_the_exact_distance_less_its_integrators_lag() {
    let (h, substep) = run(&case("friction_slide_stop_2d"), Precision::F64, None);
    let (t, u, v) = (
        column(&h, "t"),
        column(&h, "ux_node"),
        column(&h, "vx_node"),
    );
    let stop_time = V0 / (MU * G);
    let distance = V0 * V0 / (2.0 * MU * G);
    // While it slides the velocity is v0 − μ g t: rapier's velocity update under a constant
    // force is exact, so what is left is round-off over 1.6e5 substeps (~1e-11). A pair's μ
    // combined otherwise than to the case's (a product: 0.25) would miss by 0.5 μ g t.
    for k in (0..t.len()).filter(|&k| t[k] < stop_time) {
        let exact = V0 - MU * G * t[k];
        assert!(
            (v[k] - exact).abs() < 1e-9,
            "t = {}: vx {} against {exact}",
            t[k],
            v[k]
        );
    }
    // It stops in the row interval that holds t* = 0.407747 s (rows every 1e-3 s) and stays.
    let first_stopped = t.iter().position(|&s| s > stop_time).unwrap();
    assert!(v[first_stopped - 1] > 0.0 && v[first_stopped..].iter().all(|x| x.abs() < 1e-12));
    assert_eq!(u[first_stopped], *u.last().unwrap());
    // rapier advances the position with each substep's new velocity (semi-implicit Euler):
    // under the constant deceleration the node covers h'·Σ(v0 − k a h') = d − v0 h'/2 + O(a h'²)
    // with h' = h/4 = 2.5e-6 s, i.e. it stops v0 h'/2 = 2.5e-6 m (6.1e-6 of d) short. Measured:
    // 2.499998e-6 m short (the default configuration's 1/240 s substep: 4.16e-3 m, the same
    // law). 1 % of the lag bounds what is left (the O(a h'²) term is 1e-6 of it).
    let lag = V0 * substep / 2.0;
    let short = distance - last(&h, "ux_node");
    assert!(
        (short - lag).abs() < 0.01 * lag,
        "stopped {short:e} m short of {distance}, the integrator's lag {lag:e}"
    );
}

#[test]
fn rapier_friction_is_isotropic_and_f32s_sideways_drift_is_round_off() {
    let distance = V0 * V0 / (2.0 * MU * G);
    let f64_runs: Vec<(f64, History, f64)> = [
        ("friction_slide_stop_3d", 0.0),
        ("friction_isotropy_30", 30.0),
        ("friction_isotropy_45", 45.0),
    ]
    .into_iter()
    .map(|(id, angle)| {
        let (h, substep) = run(&case(id), Precision::F64, None);
        (angle, h, substep)
    })
    .collect();
    // A pyramid (each tangent impulse clamped at μλ on its own, rapier before #146) in the
    // face's tangent basis, which for the normal +y lies along z and x, would stop the node at
    // 45° after d/√2 = 0.288 m and turn its path at 30° (0.316 m along, 0.065 m across). The
    // cone stops it at d less the integrator's lag v0 h'/2 (2.5e-6 m) whatever the angle;
    // measured: the three distances within 3.4e-12 m of each other, the drift across at most
    // 2.4e-13 m (30°), both round-off. 1e-9 m is round-off's bound with a thousandfold margin
    // and a millionth of what a pyramid would do.
    let stops: Vec<f64> = f64_runs
        .iter()
        .map(|(_, h, _)| last(h, "us_node"))
        .collect();
    let spread = stops.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
        - stops.iter().fold(f64::INFINITY, |m, &x| m.min(x));
    assert!(spread < 1e-9, "stop distances {stops:?}");
    for (angle, h, substep) in &f64_runs {
        let short = distance - last(h, "us_node");
        let lag = V0 * substep / 2.0;
        assert!(
            (short - lag).abs() < 0.01 * lag,
            "{angle}°: {short:e} short"
        );
        assert!(largest(h, "us_side") < 1e-9, "{angle}°: drifts across");
    }
    // The control: f32, where the same cone drifts across at 30° by 1.9e-4 m at h = 1e-5 s
    // and by 1.1e-5 m at 1e-4 s (ten times fewer increments, 18 times less drift), and not at
    // all at 45°, where the two components round alike. Each substep adds μ g h/4 = 1.2e-5 m/s
    // to a velocity whose f32 quantum is 1.2e-7 (and 5e-6 m to a position whose quantum is
    // 3e-8): the increments are rounded by up to 1 %, with a bias that differs between the
    // components unless they are equal. Bounds: the drift between 1e-5 and 1e-3 m at 1e-5 s,
    // under a tenth of that at 1e-4 s, and under 1e-12 m at 45°.
    let scene = case("friction_isotropy_30");
    let fine = largest(&run(&scene, Precision::F32, Some(1e-5)).0, "us_side");
    let coarse = largest(&run(&scene, Precision::F32, Some(1e-4)).0, "us_side");
    assert!(
        (1e-5..1e-3).contains(&fine),
        "f32 at 30°, h = 1e-5: {fine:e}"
    );
    assert!(
        coarse < 0.1 * fine,
        "f32 at 30°, h = 1e-4: {coarse:e} against {fine:e}"
    );
    let diagonal = run(&case("friction_isotropy_45"), Precision::F32, None).0;
    assert!(largest(&diagonal, "us_side") < 1e-12);
}

/// rapier has one friction coefficient: a pair whose static coefficient is above its kinetic
/// one (the ramp case's μ_s = 0.5, μ_k = 0.3) is refused, naming the pair, rather than run at
/// μ_k, where it would break away at μ_k N (0.294 s) instead of μ_s N (0.4905 s). The same
/// scene with μ_s lowered to μ_k runs.
#[test]
fn rapier_refuses_a_static_coefficient_above_the_kinetic_one() {
    let scene = case("friction_ramp_breakaway");
    for precision in [Precision::F64, Precision::F32] {
        match RapierEngine::matched(precision).run(&scene, &RunSettings::default()) {
            Err(crosscheck::engines::EngineError::Unsupported(m)) => {
                assert!(
                    m.contains("contact `face`") && m.contains("static friction 0.5"),
                    "{m}"
                )
            }
            other => panic!("{precision:?}: {:?}", other.map(|o| o.info.increment)),
        }
    }
    let mut single = scene.clone();
    for pair in &mut single.contacts {
        let f = pair.friction.as_mut().unwrap();
        f.static_coefficient = f.kinetic_coefficient;
    }
    let (h, _) = run(&single, Precision::F64, None);
    // With one coefficient μ_k = 0.3 the pull r·t reaches μ_k N = 2.943 N at 0.2943 s: the
    // node has moved by then (the exact μ_s answer has it at rest until 0.4905 s).
    let moved_at = |u: &[f64], t: &[f64]| t[u.iter().position(|x| x.abs() > 1e-6).unwrap()];
    let at = moved_at(&column(&h, "ux_node"), &column(&h, "t"));
    assert!((0.294..0.31).contains(&at), "moves at {at} s");
}
