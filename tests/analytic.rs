//! The `analytic` engine against closed forms evaluated independently here, by hand.
mod common;
use common::*;
use crosscheck::engines::RunSettings;
use crosscheck::engines::analytic::AnalyticEngine;

/// Value of a column at time t (t must be an output time).
fn at(h: &crosscheck::engines::History, name: &str, t: f64) -> f64 {
    let times = col(h, "t");
    let i = times
        .iter()
        .position(|x| (x - t).abs() < 1e-12)
        .expect("an output time");
    col(h, name)[i]
}

/// Grounded test: m ü + c u̇ + k u = 0 from u(0) = 1 at rest, with m = 0.02588, k = 30,
/// c = 0.12: ωn = √(k/m), ζ = c/(2mωn), ωd = ωn√(1−ζ²),
/// u = e^(−ζωn t)(cos ωd t + ζωn/ωd sin ωd t), u̇ = −(ωn²/ωd) e^(−ζωn t) sin ωd t.
/// Both exact: 1e-12 allows the round-off of the trigonometric and exponential functions.
#[test]
fn grounded_oscillator_matches_the_damped_closed_form() {
    let (m, k, c): (f64, f64, f64) = (0.02588, 30.0, 0.12);
    let wn = (k / m).sqrt(); // 34.04697...
    let zeta = c / (2.0 * m * wn); // 0.068094...
    let wd = wn * (1.0 - zeta * zeta).sqrt(); // 33.96795...
    for id in [
        "springs_grounded_a",
        "springs_grounded_b",
        "springs_grounded_c",
    ] {
        let h = run(&AnalyticEngine, &scene(id), RunSettings::default());
        for t in [0.25, 0.5, 1.0] {
            let decay = (-zeta * wn * t).exp();
            let u = decay * ((wd * t).cos() + zeta * wn / wd * (wd * t).sin());
            let v = -wn * wn / wd * decay * (wd * t).sin();
            assert!((at(&h, "u_end", t) - u).abs() <= 1e-12, "{id} u({t})");
            assert!((at(&h, "v_end", t) - v).abs() <= 1e-12 * wn, "{id} v({t})");
        }
        // A value computed once by hand (Python, same formula): u(1) = −0.0780788860170107.
        assert!((at(&h, "u_end", 1.0) + 0.07807888601701071).abs() <= 1e-12);
    }
}

/// Node-to-node test: masses m (middle, end), springs k ground–middle and middle–end, dashpot c
/// between the masses only. Integrated here independently by classical RK4 with h = 1e-5
/// (error ~ (ωh)⁴ ≈ 1e-13 at ω = 55), not by a matrix exponential.
#[test]
fn node_to_node_matches_an_independent_integration() {
    let (m, k, c): (f64, f64, f64) = (0.02588, 30.0, 0.12);
    let f = |z: [f64; 4]| {
        let [u1, u2, v1, v2] = z;
        let a1 = (-2.0 * k * u1 + k * u2 - c * (v1 - v2)) / m;
        let a2 = (k * (u1 - u2) - c * (v2 - v1)) / m;
        [v1, v2, a1, a2]
    };
    let add = |z: [f64; 4], d: [f64; 4], s: f64| {
        [
            z[0] + s * d[0],
            z[1] + s * d[1],
            z[2] + s * d[2],
            z[3] + s * d[3],
        ]
    };
    let mut z = [0.0, 1.0, 0.0, 0.0];
    let h = 1e-5;
    let mut samples = Vec::new();
    for n in 0..=100_000 {
        if n % 25_000 == 0 {
            samples.push((n as f64 * h, z));
        }
        let k1 = f(z);
        let k2 = f(add(z, k1, h / 2.0));
        let k3 = f(add(z, k2, h / 2.0));
        let k4 = f(add(z, k3, h));
        z = [0, 1, 2, 3].map(|i| z[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    }
    for id in ["springs_n2n_b", "springs_n2n_c"] {
        let a = run(&AnalyticEngine, &scene(id), RunSettings::default());
        for (t, z) in &samples {
            for (name, want) in [("u_mid", z[0]), ("u_end", z[1])] {
                let got = at(&a, name, *t);
                assert!(
                    (got - want).abs() <= 1e-11,
                    "{id} {name}({t}): {got} vs {want}"
                );
            }
        }
    }
}

/// Pinned variants: one DOF θ. Slaving the contact node (mass 5 at r = (1, −0.5)) adds
/// m r_y² to the inertia: M = 65 + 5·0.25 = 66.25; springs at body point (1, −3) (elongation
/// 3θ) and on the node (0.5θ): K = 1e6·(9 + 0.25) = 9.25e6; the load 1e5 along −x at (−1, 1)
/// gives the moment Q = 1e5. θ(0) = 0, θ̇(0) = 10:
/// θ = Q/K (1 − cos ωt) + (10/ω) sin ωt, ω = √(K/M) ≈ 373.66 (the spec's sanity figure).
/// Node: u_N = 0.5θ; its equation m ü_N = −k u_N + λ gives the contact force λ.
#[test]
fn pinned_rigid_body_matches_the_one_dof_closed_form() {
    let (m_bar, k_bar, q): (f64, f64, f64) = (66.25, 9.25e6, 1.0e5);
    let w: f64 = (k_bar / m_bar).sqrt();
    assert!((w - 373.7).abs() < 0.05, "spec sanity figure");
    for id in [
        "rigid2d_pin_lumped",
        "rigid2d_pin_surface",
        "rigid3d_pin_lumped",
        "rigid3d_pin_surface",
    ] {
        let h = run(&AnalyticEngine, &scene(id), RunSettings::default());
        for t in [0.02, 0.05, 0.1] {
            let theta = q / k_bar * (1.0 - (w * t).cos()) + 10.0 / w * (w * t).sin();
            let theta_dd = (q - k_bar * theta) / m_bar;
            let lambda = 5.0 * 0.5 * theta_dd + 1.0e6 * 0.5 * theta;
            assert!(
                (at(&h, "rz", t) - theta).abs() <= 1e-12 * 0.04,
                "{id} θ({t})"
            );
            assert!(
                (at(&h, "ux_node", t) - 0.5 * theta).abs() <= 1e-12 * 0.02,
                "{id} u_N({t})"
            );
            assert!(
                (at(&h, "contact_force", t) - lambda).abs() <= 1e-12 * 1e4,
                "{id} λ({t})"
            );
        }
        // λ(0) = 5·0.5·Q/M: the spec's 3.77e3.
        assert!((at(&h, "contact_force", 0.0) - 2.5 * q / m_bar).abs() <= 1e-9);
    }
}

/// Sliding, lumped: q = (u, θ). Body [[20, 0], [0, 65]] plus the slaved node 5·a aᵀ,
/// a = (1, 0.5): M = [[25, 2.5], [2.5, 66.25]]. Spring 1 elongation u + 3θ, spring 2 u + 0.5θ:
/// K = 1e6·[[2, 3.5], [3.5, 9.25]]. Load +1e5 along x at (−1, 1): x-displacement u − θ, so
/// Q = 1e5·(1, −1). q(0) = 0, q̇(0) = (15, 10). Modal superposition about the static
/// q_s = K⁻¹Q with M-normalised modes from det(K − ω²M) = 0 (a quadratic in ω²).
#[test]
fn sliding_lumped_matches_modal_superposition() {
    let (m11, m12, m22): (f64, f64, f64) = (25.0, 2.5, 66.25);
    let (k11, k12, k22): (f64, f64, f64) = (2.0e6, 3.5e6, 9.25e6);
    let (q1, q2) = (1.0e5, -1.0e5);
    let det_k = k11 * k22 - k12 * k12;
    let qs = [(k22 * q1 - k12 * q2) / det_k, (k11 * q2 - k12 * q1) / det_k];
    // (K − λM)φ = 0: a λ² + b λ + c = 0.
    let a = m11 * m22 - m12 * m12;
    let b = -(k11 * m22 + k22 * m11 - 2.0 * k12 * m12);
    let c = det_k;
    let disc = (b * b - 4.0 * a * c).sqrt();
    let lambdas = [(-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a)];
    let omegas = lambdas.map(f64::sqrt);
    assert!(
        (omegas[0] - 141.2).abs() < 0.1 && (omegas[1] - 435.8).abs() < 1.0,
        "spec sanity figures {omegas:?}"
    );
    let modes = lambdas.map(|l| {
        let phi = [-(k12 - l * m12), k11 - l * m11];
        let norm =
            (phi[0] * phi[0] * m11 + 2.0 * phi[0] * phi[1] * m12 + phi[1] * phi[1] * m22).sqrt();
        [phi[0] / norm, phi[1] / norm]
    });
    let m_dot = |phi: [f64; 2], x: [f64; 2]| {
        phi[0] * (m11 * x[0] + m12 * x[1]) + phi[1] * (m12 * x[0] + m22 * x[1])
    };
    let v0 = [15.0, 10.0];
    let h = run(
        &AnalyticEngine,
        &scene("rigid2d_slide_lumped"),
        RunSettings::default(),
    );
    let h3 = run(
        &AnalyticEngine,
        &scene("rigid3d_slide_lumped"),
        RunSettings::default(),
    );
    for t in [0.03, 0.07, 0.1] {
        let mut q = qs;
        for (phi, w) in modes.iter().zip(omegas) {
            let amp_c = -m_dot(*phi, qs);
            let amp_s = m_dot(*phi, v0) / w;
            let s = amp_c * (w * t).cos() + amp_s * (w * t).sin();
            q[0] += phi[0] * s;
            q[1] += phi[1] * s;
        }
        for hist in [&h, &h3] {
            assert!((at(hist, "ux", t) - q[0]).abs() <= 1e-12 * 0.4, "u({t})");
            assert!((at(hist, "rz", t) - q[1]).abs() <= 1e-12 * 0.2, "θ({t})");
            assert!(
                (at(hist, "ux_node", t) - (q[0] + 0.5 * q[1])).abs() <= 1e-12 * 0.4,
                "u_N({t})"
            );
        }
    }
}

/// The closed form reports its own validity: the contact stays compressive in every variant,
/// with the smallest margin (about 5 % of the peak) in the sliding lumped one (spec).
#[test]
fn contact_margins_are_reported() {
    use crosscheck::engines::analytic::rigid;
    let margin = |id: &str| rigid::solve(&scene(id)).unwrap();
    let sliding = margin("rigid2d_slide_lumped");
    assert!(sliding.valid_until.is_none());
    assert!(
        (sliding.contact_margin - 0.054).abs() < 0.005,
        "{}",
        sliding.contact_margin
    );
    for id in ["rigid2d_pin_lumped", "rigid2d_slide_surface"] {
        let m = margin(id);
        assert!(
            m.valid_until.is_none() && m.contact_margin > sliding.contact_margin,
            "{id}"
        );
    }
    // Initial contact forces (spec): 3.77e3 pinned, 1.67e4 sliding lumped, 5.83e4 sliding surface.
    for (id, f0) in [
        ("rigid2d_pin_lumped", 3.77e3),
        ("rigid2d_slide_lumped", 1.67e4),
        ("rigid2d_slide_surface", 5.83e4),
    ] {
        let got = margin(id).initial_contact_force;
        assert!((got / f0 - 1.0).abs() < 0.005, "{id}: {got}");
    }
}

/// The grounded oscillator at ζ = 0.5, 1 and 3 (and a hair either side of critical, where the
/// under- and over-damped forms divide by ωd → 0 and r₁ − r₂ → 0): the hand-derived forms
/// against the reference, an ODE solution (Dop853 at rtol 1e-12) that shares no formula with
/// them, and against the general exact linear solver (matrix exponential). Both bounds are
/// 1e-10 of the column's peak: 1e-12 integration tolerance over the 1 s run, with margin.
#[test]
fn every_damping_ratio_matches_an_independent_ode_solution() {
    use crosscheck::comparison::compare;
    use crosscheck::engines::Engine;
    use crosscheck::engines::analytic::{linear, springs};
    use crosscheck::engines::reference::ReferenceEngine;
    let (m, k): (f64, f64) = (0.02588, 30.0);
    for zeta in [0.5, 1.0 - 1e-9, 1.0, 1.0 + 1e-9, 3.0] {
        let c = 2.0 * zeta * (k * m).sqrt();
        let scene = common::variant(
            "springs_grounded_a",
            &[("damping = 0.12", &format!("damping = {c:e}"))],
        );
        let hand = springs::solve(&scene).unwrap();
        let reference = ReferenceEngine
            .run(&scene, &RunSettings::default())
            .unwrap()
            .history;
        let against_ode = compare(&scene, &reference, &hand);
        assert!(
            against_ode.worst_max.expect("a compared column") <= 1e-10,
            "ζ = {zeta}: {:e}",
            against_ode.worst_max.expect("a compared column")
        );
        let against_linear = compare(&scene, &linear::solve(&scene).unwrap(), &hand);
        assert!(
            against_linear.worst_max.expect("a compared column") <= 1e-10,
            "ζ = {zeta}: {:e}",
            against_linear.worst_max.expect("a compared column")
        );
    }
    // Critical damping by hand at t = 0.1 s: u = e^(−ωn t)(1 + ωn t), u̇ = −ωn² t e^(−ωn t).
    let wn = (k / m).sqrt();
    let c = 2.0 * (k * m).sqrt();
    let scene = common::variant(
        "springs_grounded_a",
        &[("damping = 0.12", &format!("damping = {c:e}"))],
    );
    let h = run(&AnalyticEngine, &scene, RunSettings::default());
    let t = 0.1;
    let decay = (-wn * t).exp();
    assert!((at(&h, "u_end", t) - decay * (1.0 + wn * t)).abs() <= 1e-12);
    assert!((at(&h, "v_end", t) + wn * wn * t * decay).abs() <= 1e-12 * wn);
}

/// System C turned to 30°, exactly, but with the probes' line of action given to 4 digits,
/// (0.866, 0.5): 1.3e-5 rad off the elements, so no hand-derived form applies (they assume one
/// line; 1 − cos θ = 8e-11 is far above round-off). `check` accepts the case, and the run
/// does not refuse it either: `analytic` solves it with the exact linear solver, which equals
/// the independent ODE solution (`reference`) to 1e-10 of the peak. (The elements themselves
/// lie on the motion's line, so the reference's finite geometry adds nothing here.)
#[test]
fn a_line_given_to_four_digits_passes_check_and_is_solved() {
    use crosscheck::comparison::compare;
    use crosscheck::engines::Engine;
    use crosscheck::engines::analytic::springs;
    use crosscheck::engines::reference::ReferenceEngine;
    let scene = common::variant(
        "springs_grounded_c",
        &[
            ("direction = [1.0, 1.0]", "direction = [0.866, 0.5]"),
            ("x_axis = [1.0, 1.0]", "x_axis = [0.8660254037844387, 0.5]"),
            (
                "[0.7071067811865476, 0.7071067811865476]",
                "[0.8660254037844387, 0.5]",
            ),
            (
                "[1.4142135623730951, 1.4142135623730951]",
                "[1.7320508075688772, 1.0]",
            ),
        ],
    );
    crosscheck::run::check_scene(&scene).unwrap();
    assert!(
        springs::solve(&scene).is_err(),
        "the hand form assumes one line"
    );
    let out = AnalyticEngine
        .run(&scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("refused at run time: {e}"));
    let reference = ReferenceEngine
        .run(&scene, &RunSettings::default())
        .unwrap()
        .history;
    let c = compare(&scene, &reference, &out.history);
    assert!(
        c.worst_max.expect("a compared column") <= 1e-10,
        "{:e}",
        c.worst_max.expect("a compared column")
    );
}
