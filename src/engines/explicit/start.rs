//! The consistent start of penalty contacts: every pair that starts closed starts where the
//! rigid model is, so the penalty mode starts nearly unexcited.

use super::model::{Config, Constraints, ContactMode, Counters, Model, Rates};
use super::space::Space;
use nalgebra::{DMatrix, DVector};

/// Contact forces that make every gap's second derivative vanish (the rigid model's forces at
/// this state), the accelerations they give, and B = ∂(gap accelerations)/∂(forces).
/// `tau` (the increment) bounds the finite-difference interval of a solid's gap acceleration.
fn consistent_forces<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &Config<S>,
    vel: &Rates<S>,
    held: &Constraints<S>,
    tau: f64,
    counters: &mut Counters,
) -> Option<(DVector<f64>, Rates<S>, DMatrix<f64>)> {
    let n = model.contacts.len();
    let response = |given: &[f64], counters: &mut Counters| -> (DVector<f64>, Rates<S>) {
        let mut f = model.zero_forces();
        model.forces(cfg, ContactMode::Given(given), &mut f, counters);
        if model.has_dashpots() {
            model.damping(cfg, vel, &mut f, counters);
        }
        let mut acc = model.zero_rates();
        model.accelerations(cfg, &f, vel, held, &mut acc, counters);
        (
            DVector::from_fn(n, |k, _| model.gap_acceleration(cfg, vel, &acc, k, tau)),
            acc,
        )
    };
    let zero = vec![0.0; n];
    let (a0, _) = response(&zero, counters);
    let mut b = DMatrix::zeros(n, n);
    for j in 0..n {
        let mut unit = zero.clone();
        unit[j] = 1.0;
        b.set_column(j, &(response(&unit, counters).0 - &a0));
    }
    let f = b.clone().lu().solve(&(-a0))?.map(|x| x.max(0.0));
    let (_, acc) = response(f.as_slice(), counters);
    Some((f, acc, b))
}

/// Start penalty contacts where the rigid model is, so the penalty mode starts nearly
/// unexcited instead of ringing with amplitudes λ0, λ̇0/ω_p and λ̈0/ω_p².
///
/// With the penalty, λ = −k_p d, and the gap obeys d̈ = A + B λ; the rigid model's force
/// λ_r = −B⁻¹A. Expanding the penalty solution about it gives λ = λ_r − (k_p B)⁻¹ λ̈_r + …, so
/// the start sets the penetration to carry λ_r(0) − (k_p B)⁻¹ λ̈_r(0) and the gap rate to
/// −λ̇_r(0)/k_p, led by the increment's own lag (below). λ̇_r and λ̈_r are central differences
/// of the rigid force along the trajectory extrapolated ±τ (τ = the increment).
pub(super) fn consistent_start<S: Space, const FINITE: bool>(
    model: &Model<S, FINITE>,
    cfg: &mut Config<S>,
    vel: &mut Rates<S>,
    held: &Constraints<S>,
    tau: f64,
    counters: &mut Counters,
) {
    // Two passes: moving the node changes the springs attached to it slightly.
    for _ in 0..2 {
        let Some((f, _, _)) = consistent_forces(model, cfg, vel, held, tau, counters) else {
            return;
        };
        for (k, fk) in f.iter().enumerate() {
            model.set_penetration(cfg, k, fk / model.penalty);
        }
    }
    let Some((f0, acc, b)) = consistent_forces(model, cfg, vel, held, tau, counters) else {
        return;
    };
    // Along the rigid trajectory, extrapolated ±τ. The rigid force depends on velocities
    // (centripetal and Coriolis terms of the gap under finite rotation), so the velocity must be
    // extrapolated to second order: the jerk comes from a first pass.
    let mut at = |s: f64, jerk: &Rates<S>| {
        let (c, v) = model.extrapolate(cfg, vel, &acc, jerk, s);
        consistent_forces(model, &c, &v, held, tau, counters)
    };
    let zero = model.zero_rates();
    let (Some((_, acc_ahead, _)), Some((_, acc_behind, _))) = (at(tau, &zero), at(-tau, &zero))
    else {
        return;
    };
    let jerk = zero.plus(0.5 / tau, &acc_ahead.plus(-1.0, &acc_behind));
    let (Some((ahead, _, _)), Some((behind, _, _))) = (at(tau, &jerk), at(-tau, &jerk)) else {
        return;
    };
    let rate = (&ahead - &behind) / (2.0 * tau);
    let curvature = (&ahead - &f0 * 2.0 + &behind) / (tau * tau);
    let correction = (b * model.penalty)
        .lu()
        .solve(&curvature)
        .unwrap_or_else(|| DVector::zeros(f0.len()));
    for k in 0..model.contacts.len() {
        if f0[k] > 0.0 {
            model.set_penetration(cfg, k, (f0[k] - correction[k]) / model.penalty);
            // The leapfrog's smooth solution through (q₀, v₀) moves at q̇(0) = v₀ − (h²/6)·q⃛
            // (its first increment is q₀ + h v₀ + (h²/2) a₀, without the cubic term), so its
            // gap rate is ∂g·v₀ − (h²/6)·∂g·q⃛. Where the gap is linear in the coordinates
            // ∂g·q⃛ is the rigid gap's third derivative, ≈ 0; under finite rotation it is not
            // (the gap's curvature terms), and without this lead the penalty mode rings with
            // a force amplitude ≈ ω_p m h²·∂g·q⃛/6, which grows like √k_p at a fixed h.
            let lead = tau * tau / 6.0 * model.gap_rate(cfg, &jerk, k);
            model.set_gap_rate(cfg, vel, k, -rate[k] / model.penalty + lead);
        }
    }
    model.enforce(vel, held);
}
