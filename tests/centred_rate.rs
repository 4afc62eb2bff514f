//! The closed-form centred rate of a body turning about one axis (`centred_rate`): the root of
//! `β s² − s + γ = 0` that tends to γ as β → 0, from the Catalan series at small z = βγ and
//! from the quadratic formula beyond. Checked against the equation it solves, on both sides of
//! each switch of the series, at 8 values of z per decade from 1e-12 to 0.2, of either sign.
//! Its square γ²·C(z)², from the series of C(z)² (`centred_square_factor`), likewise.

use crosscheck::engines::explicit::model::{centred_rate, centred_square_factor};

/// The residual of the computed root, relative to |s|: the terms β s², s and γ each carry
/// round-off of about ε|s| (|β s²| ≤ 0.3|s| and |γ| ≤ 2|s| on this branch for |z| ≤ 0.2), so
/// 4ε bounds a
/// correct root's residual, and a series that leaves out only terms under round-off (14 z⁴ at
/// z = 3.5e-5 is 2e-17 of s, 132 z⁶ at the next switch 1.6e-17) stays under it. Tried: a wrong
/// z³ coefficient (4 for 5) and either switch raised tenfold each fail it (residuals of
/// 1.1e-15 to 1.3e-15 of s at the first z past the change, growing with z).
const RESIDUAL: f64 = 4.0 * f64::EPSILON;

fn zs() -> Vec<f64> {
    let mut z: Vec<f64> = (0..=90)
        .map(|k| 1e-12 * 10f64.powf(k as f64 / 8.0))
        .take_while(|z| *z <= 0.2)
        .collect();
    // Either side of the switches (the root's, then its square's).
    for switch in [3.5e-5, 7e-4, 2.5e-5, 6e-4] {
        z.extend([switch * (1.0 - 1e-9), switch * (1.0 + 1e-9)]);
    }
    z
}

/// The inputs (z, β, γ) the tests run: each z of [`zs`] of either sign, at four values of γ,
/// with β = z/γ.
fn inputs() -> Vec<(f64, f64, f64)> {
    let mut inputs = Vec::new();
    for z in zs() {
        for z in [z, -z] {
            for gamma in [1e-3, 0.7, 12.0, -5.0] {
                inputs.push((z, z / gamma, gamma));
            }
        }
    }
    inputs
}

#[test]
fn the_root_solves_the_quadratic() {
    for (z, beta, gamma) in inputs() {
        let s = centred_rate(beta, gamma).expect("a real root for 4βγ < 1");
        let residual = beta * s * s - s + gamma;
        assert!(
            residual.abs() <= RESIDUAL * s.abs(),
            "z = {z:e}, γ = {gamma}: residual {:e} of s = {s}",
            residual.abs() / s.abs()
        );
        // The branch that tends to γ: s/γ = C(z) lies between 1 and 2 for z ≥ 0 and between
        // 1/2 and 1 below.
        let ratio = s / gamma;
        assert!((0.5..=2.0).contains(&ratio), "z = {z:e}: s/γ = {ratio}");
    }
}

#[test]
fn no_real_root_is_none() {
    assert_eq!(centred_rate(1.0, 0.26), None);
    assert_eq!(centred_rate(-2.0, -0.2), None);
    assert_eq!(centred_rate(f64::NAN, 1.0), None);
    assert_eq!(centred_rate(1.0, f64::INFINITY), None);
    assert_eq!(centred_rate(-1.0, f64::INFINITY), None);
    assert_eq!(centred_rate(f64::NEG_INFINITY, 1.0), None);
    // At 4βγ = 1 the two roots meet at 2γ.
    assert_eq!(centred_rate(0.5, 0.5), Some(1.0));
}

/// The square's residual, relative to it: t = s² gives the root s = β t + γ of the quadratic
/// (exact for the true s²), whose square returns t. A relative error δ in t comes back as
/// δ·|1 − 2βs| = δ·√(1 − 4z), at least 0.44 δ for |z| ≤ 0.2; the check's own rounding (β t,
/// the sum, the square, γ² and its product with the factor) is a few ε of t, so 8ε bounds a
/// correct square and a series that leaves out only terms under round-off (42 z⁴ at
/// z = 2.5e-5 is 1.6e-17 of t, 429 z⁶ at the next switch 2e-17) stays under it. Tried: a
/// wrong z² or z³ coefficient (4 for 5, 13 for 14) and either switch raised tenfold each fail
/// it (residuals of 1.9e-15 to 4.2e-15 of t). One z⁵ too few (131 for 132) moves t by under
/// 8e-17 of itself, under round-off: it passes.
const SQUARE_RESIDUAL: f64 = 8.0 * f64::EPSILON;

#[test]
fn the_square_is_the_roots() {
    for (z, beta, gamma) in inputs() {
        let t =
            gamma * gamma * centred_square_factor(beta, gamma).expect("a real root for 4βγ < 1");
        let s = beta * t + gamma;
        let residual = s * s - t;
        assert!(
            residual.abs() <= SQUARE_RESIDUAL * t,
            "z = {z:e}, γ = {gamma}: residual {:e} of s² = {t}",
            residual.abs() / t
        );
        // The same root as `centred_rate`'s (tested above), to the rounding of either.
        let root = centred_rate(beta, gamma).expect("a real root");
        assert!(
            (t - root * root).abs() <= SQUARE_RESIDUAL * t,
            "z = {z:e}: s² = {t}, the root squared {}",
            root * root
        );
    }
    for (beta, gamma) in [
        (1.0, 0.26),
        (-2.0, -0.2),
        (f64::NAN, 1.0),
        (1.0, f64::INFINITY),
        (-1.0, f64::INFINITY),
        (f64::NEG_INFINITY, 1.0),
    ] {
        assert_eq!(
            centred_square_factor(beta, gamma),
            None,
            "β = {beta}, γ = {gamma}"
        );
    }
}
