//! Long horizon: 10^7 increments of the undamped grounded oscillator and of the pinned rigid
//! case. The energy error stays bounded with no secular drift, and the oscillator's phase error
//! is the scheme's known ω³h²t/24 while its amplitude error stays at round-off.
//!
//! About 3 s in all (10^7 increments take ~1 s), so they run with the rest of the suite.
mod common;

use crosscheck::engines::History;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};

fn column(h: &History, name: &str) -> Vec<f64> {
    let i = h.columns.iter().position(|c| c == name).unwrap();
    h.rows.iter().map(|r| r[i]).collect()
}

fn sci(x: &[f64]) -> String {
    x.iter()
        .map(|v| format!("{v:.3e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Largest |x| over each tenth of the run.
fn envelope(x: &[f64]) -> Vec<f64> {
    let n = x.len() / 10;
    (0..10)
        .map(|d| {
            x[d * n..(d + 1) * n]
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()))
        })
        .collect()
}

#[test]
fn ten_million_increments_of_the_undamped_oscillator() {
    // springs_grounded_a without its dashpot: m = 0.02588, k = 30, released from 1 at rest;
    // h = 1e-4 (ω·h = 3.4e-3) for 1000 s = 10^7 increments.
    let scene = common::variant(
        "springs_grounded_a",
        &[
            ("damping = 0.12", "damping = 0.0"),
            ("increment = 5.0e-5", "increment = 1.0e-4"),
            ("rows = 501", "rows = 100001"),
            ("duration = 1.0", "duration = 1000.0"),
        ],
    );
    let out = ExplicitEngine::finite()
        .run(&scene, &RunSettings::default())
        .unwrap();
    assert_eq!(out.info.steps, 10_000_000);
    let h = out.info.increment;
    let omega = (30.0f64 / 0.02588).sqrt();
    let t = column(&out.history, "t");
    let u = column(&out.history, "u_end");
    let balance = column(&out.history, "e_balance");
    let e0 = 0.5 * 30.0;

    // Energy: the scheme conserves a shadow energy; the energy measured at v(n) oscillates
    // about it by about (ω·h)²/4 of E0 (2.9e-6 here), with no drift: the last tenth's envelope
    // equals the first's to round-off.
    let env: Vec<f64> = envelope(&balance).iter().map(|e| e / e0).collect();
    println!(
        "energy error envelope per tenth of 1000 s (over E0): {}",
        sci(&env)
    );
    let bound = (omega * h).powi(2) / 4.0;
    for e in &env {
        assert!(
            *e <= 1.05 * bound,
            "envelope {e:e} above (ωh)²/4 = {bound:e}"
        );
    }
    assert!(
        (env[9] - env[0]).abs() <= 1e-3 * env[0],
        "secular drift: first tenth {:e}, last {:e}",
        env[0],
        env[9]
    );

    // Phase: central difference oscillates at Ω = (2/h)·asin(ω·h/2) ≈ ω(1 + (ω·h)²/24), so
    // it leads the exact solution by ω³h²t/24. Measured at the last row from u and v: the
    // released scheme is u = cos(Ωt), v(n) = −sin(Ωt)·sin(Ωh)/h, so atan2(−v/ω, u) is Ωt to
    // within (Ω − ω)/ω + (Ωh)²/6 ≈ 3e-6 rad.
    let v = column(&out.history, "v_end");
    let last = t.len() - 1;
    let tau = std::f64::consts::TAU;
    let angle = (-v[last] / omega).atan2(u[last]);
    let lag = angle - omega * t[last];
    let measured = lag - tau * (lag / tau).round();
    let predicted = omega.powi(3) * h * h * t[last] / 24.0;
    println!(
        "phase error at t = {:.1} s: measured {measured:.6e} rad, ω³h²t/24 = {predicted:.6e} rad",
        t[last]
    );
    // The next term of the series is (3/640)(ω·h)⁴ ωt (1e-6 of the first here); the
    // measurement is good to 3e-6 rad of 1.6e-2 (measured: 6e-7 apart): 1e-4 allowed.
    assert!(
        (measured / predicted - 1.0).abs() < 1e-4,
        "measured {measured:e}, predicted {predicted:e}"
    );
    // Amplitude: the scheme keeps it (the released oscillator is cos(Ωt) exactly, to
    // round-off): the largest |u| over the last tenth is 1 within the rows' sampling of the
    // peak (a row every 0.01 s, 1 − cos(Ω·0.005) ≤ 1.5e-2).
    let last_peak = envelope(&u)[9];
    println!("amplitude over the last tenth: {last_peak:.9}");
    assert!((1.0 - 1.5e-2..=1.0 + 1e-9).contains(&last_peak));
}

#[test]
fn ten_million_increments_of_the_pinned_rigid_case() {
    // rigid2d_pin_lumped at its own increment (1e-5 s) for 100 s = 10^7 increments.
    let scene = common::variant(
        "rigid2d_pin_lumped",
        &[
            ("rows = 501", "rows = 10001"),
            ("duration = 0.1", "duration = 100.0"),
        ],
    );
    let out = ExplicitEngine::finite()
        .run(&scene, &RunSettings::default())
        .unwrap();
    assert_eq!(out.info.steps, 10_000_000);
    let balance = column(&out.history, "e_balance");
    let kinetic = column(&out.history, "e_kinetic");
    let elastic = column(&out.history, "e_elastic");
    let scale = kinetic
        .iter()
        .zip(&elastic)
        .map(|(k, e)| k + e)
        .fold(0.0f64, f64::max);
    let env: Vec<f64> = envelope(&balance).iter().map(|e| e / scale).collect();
    println!(
        "energy balance envelope per tenth of 100 s (over the largest energy): {}",
        sci(&env)
    );
    // Bounded: as for the oscillator, the energy measured at v(n) departs from the conserved
    // shadow energy by at most (ω·h)²/4 of the energy in motion, with ω = 373.7 rad/s the
    // pinned mode (spec: PROBLEMS.md) and h = 1e-5: 3.5e-6 (measured 1.6e-6; the motion holds
    // part of the largest energy, the rest is the load's static work).
    let bound = (373.7f64 * 1e-5).powi(2) / 4.0;
    for e in &env {
        assert!(*e <= bound, "envelope {e:e} above {bound:e}");
    }
    // No secular drift: the last tenth's envelope within 10 % of the first's.
    assert!(
        env[9] <= 1.1 * env[0],
        "drift: first tenth {:e}, last {:e}",
        env[0],
        env[9]
    );
}
