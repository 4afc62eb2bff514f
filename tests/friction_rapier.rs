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

/// A run of rapier in its default configuration: the history and its substep h/4.
fn run_default(scene: &Scene) -> (History, f64) {
    let out = RapierEngine::default_configuration(Precision::F64)
        .run(scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id));
    let substeps = crosscheck::engines::rapier::backend::DEFAULT_SOLVER_ITERATIONS as f64;
    (out.history, out.info.increment / substeps)
}

/// The slide stop's frictional dissipation, read from rapier's friction impulses, is μ m g
/// times rapier's own slide distance; the balance's residual is what rapier lost besides:
/// semi-implicit Euler's lag, μ m g · v0 h'/2, first order in the substep h'.
#[test]
fn rapier_f64s_friction_dissipates_mu_m_g_along_its_own_path_and_its_balance_is_its_lag() {
    let scene = case("friction_slide_stop_2d");
    let (h, substep) = run(&scene, Precision::F64, None);
    let friction = MU * G; // μ m g with m = 1
    let (dissipated, distance) = (last(&h, "e_frictional"), last(&h, "ux_node"));
    // Each step's friction impulse (μ N h, 4 equal substeps) times the step's slip over h is
    // μ N times the slip: the sum is μ m g · distance but for the step where the node stops,
    // whose friction is below μ N over a slip of at most μ g h² = 4.9e-10 m (≤ 2.4e-9 J), and
    // round-off (measured 7.4e-11 J in all).
    assert!(
        (dissipated - friction * distance).abs() < 2.5e-9,
        "e_frictional {dissipated:e} against mu m g d = {:e}",
        friction * distance
    );
    // The kinetic energy friction took, ½ m v0² − e_kinetic, is more by the lag: rapier's
    // velocity falls at exactly μ g but it covers d − v0 h'/2 (measured 1.2263e-5 J against
    // μ m g v0 h'/2 = 1.22625e-5; what is left is O(μ g h'), 1e-5 of it).
    let lag = friction * V0 * substep / 2.0;
    let taken = 0.5 * V0 * V0 - last(&h, "e_kinetic");
    assert!(
        ((taken - dissipated) - lag).abs() < 1e-3 * lag,
        "kinetic energy taken {taken:e}, dissipated {dissipated:e}, lag {lag:e}"
    );
    // The balance is the lag and the load's work through the node's sinking into the face
    // (2.4e-8 J: rapier's contact stores no energy), both lost by rapier's integration.
    let balance = last(&h, "e_balance");
    let sinking = last(&h, "w_external");
    assert!(
        (balance + sinking + lag).abs() < 1e-3 * lag,
        "e_balance {balance:e} against -(lag {lag:e} + sinking {sinking:e})"
    );
    // First order: at half the increment (2 h', h = 4 h') the lag, and the balance less the
    // sinking, halve.
    let (half, _) = run(&scene, Precision::F64, Some(2.0 * substep));
    let ratio = (last(&half, "e_balance") + last(&half, "w_external")) / (balance + sinking);
    assert!((ratio - 0.5).abs() < 1e-3, "balance ratio at h/2: {ratio}");
}

/// On the incline the node sticks after the first substep, which advances it by g sinθ h'²
/// before friction acts; the friction that then holds it dissipates the tangential weight's
/// work through that slip, m g sinθ · g sinθ h'², and nothing after.
#[test]
fn rapier_f64s_friction_dissipates_only_the_first_substeps_slip_on_the_incline() {
    let scene = case("friction_incline_stick");
    let tangential = G * 20f64.to_radians().sin(); // m = 1
    for (name, (h, substep)) in [
        ("matched", run(&scene, Precision::F64, None)),
        ("default", run_default(&scene)),
    ] {
        let expected = tangential * tangential * substep * substep;
        let dissipated = last(&h, "e_frictional");
        // The slip is g sinθ h'² to 5 digits (docs/rapier.md: 2.0970e-11 and 5.8250e-5 m).
        assert!(
            (dissipated - expected).abs() < 1e-3 * expected,
            "{name}: e_frictional {dissipated:e} against {expected:e}"
        );
        // Nothing more once it holds: the column is flat over the last half of the run.
        let e = column(&h, "e_frictional");
        let drift = e.last().unwrap() - e[e.len() / 2];
        assert!(drift.abs() < 1e-3 * expected, "{name}: drift {drift:e}");
    }
}

/// The stick-slip oscillator: friction dissipates μ N times the path rapier's node covers;
/// the balance's residual is the spring's implicit motor (backward Euler, which loses energy
/// at the rate ω² h' E), so it is first order and at most ω² h' E0 t_stop.
#[test]
fn rapier_f64s_friction_dissipates_mu_n_along_the_stick_slip_path() {
    let scene = case("friction_spring_stickslip");
    let (mu, v0, k) = (0.3, 3.0, 100.0);
    let (h, substep) = run(&scene, Precision::F64, None);
    let u = column(&h, "ux_node");
    let path: f64 = u.windows(2).map(|w| (w[1] - w[0]).abs()).sum();
    let dissipated = last(&h, "e_frictional");
    // Rows every 2e-3 s: a turning point inside a row interval hides at most its curvature's
    // share, ½ a δt² with a ≤ k |x| + μ g ≤ 30 m/s², 6e-5 m per turning point, 6 of them:
    // 3.6e-4 m of path, 1.1e-3 J at μ N = 2.943 N.
    let along = mu * G * path;
    assert!(
        (dissipated - along).abs() < 1.1e-3,
        "e_frictional {dissipated:e} against mu N path = {along:e}"
    );
    let balance = last(&h, "e_balance") + last(&h, "w_external");
    let bound = k * substep * 0.5 * v0 * v0 * 1.718097;
    assert!(
        balance < 0.0 && -balance < bound,
        "balance {balance:e}, bound {bound:e}"
    );
    let (half, _) = run(&scene, Precision::F64, Some(2.0 * substep));
    let ratio = (last(&half, "e_balance") + last(&half, "w_external")) / balance;
    assert!((ratio - 0.5).abs() < 0.02, "balance ratio at h/2: {ratio}");
}
