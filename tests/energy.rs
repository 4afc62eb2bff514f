//! Energy bookkeeping of the explicit engine (kinetic, elastic, viscous, external work, balance).
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::scene::IncrementRule;

/// On the undamped (rigid-body) cases the balance KE + SE − W − E0 is not exactly zero: central
/// differences conserve a modified energy. For a mode of frequency ω, the energy evaluated with
/// v(n) = (v(n−½) + v(n+½))/2 exceeds the exactly conserved leapfrog invariant
/// ½m·v(n−½)·v(n+½) + ½k·x(n)² by (ωh)²/4 × its elastic energy, so
/// |balance| ≤ (ω h)²/4 × max(KE + SE). We take ω as the highest frequency of the structure
/// without the penalty spring (the consistent contact start leaves the penalty mode nearly
/// unexcited), and also check the error is O(h²): halving h divides it by 4 ± 12 %.
#[test]
fn undamped_energy_balance_is_within_the_schemes_bound() {
    for scene in all_scenes().into_iter().filter(|s| s.dashpots.is_empty()) {
        let h = match scene.settings.increment {
            IncrementRule::Given(h) => h,
            _ => unreachable!(),
        };
        for engine in [ExplicitEngine::finite(), ExplicitEngine::small()] {
            let stable = engine
                .stable_increment(&scene, &RunSettings::default())
                .unwrap();
            let worst = |h: f64| {
                let out = run(
                    &engine,
                    &scene,
                    RunSettings {
                        increment: Some(IncrementRule::Given(h)),
                        ..Default::default()
                    },
                );
                let ke = col(&out, "e_kinetic");
                let se = col(&out, "e_elastic");
                let scale = ke.iter().zip(&se).fold(0.0f64, |m, (k, s)| m.max(k + s));
                (peak(&col(&out, "e_balance")), scale)
            };
            let (e1, scale) = worst(h);
            let (e2, _) = worst(h / 2.0);
            let bound = (stable.omega_structure * h).powi(2) / 4.0 * scale;
            println!(
                "{} {}: |balance| {e1:.3e} = {:.3e} of the energy, bound {bound:.3e}, halving h divides it by {:.2}",
                scene.id,
                engine.name(),
                e1 / scale,
                e1 / e2
            );
            assert!(
                e1 <= bound,
                "{} {}: balance {e1:e} above the O(h²) bound {bound:e}",
                scene.id,
                engine.name()
            );
            assert!(
                (3.5..=4.5).contains(&(e1 / e2)),
                "{} {}: balance error is not O(h²): ratio {}",
                scene.id,
                engine.name(),
                e1 / e2
            );
        }
    }
}

/// On the damped cases the viscous dissipation closes the balance to the same order.
#[test]
fn damped_energy_balance_closes_with_the_dissipation() {
    for id in ["springs_grounded_a", "springs_n2n_b", "springs_n2n_c"] {
        let scene = scene(id);
        let out = run(&ExplicitEngine::finite(), &scene, RunSettings::default());
        let dissipated = *col(&out, "e_viscous").last().unwrap();
        let initial = col(&out, "e_elastic")[0];
        let balance = peak(&col(&out, "e_balance"));
        println!("{id}: dissipated {dissipated:.4} of {initial:.4}; |balance| {balance:.3e}");
        // Most of the initial 15 J is gone after 1 s at zeta ~0.07 (e^{-2·0.068·34·1} ~ 1 %).
        assert!(dissipated > 0.5 * initial, "{id}: dissipation {dissipated}");
        // ω h = 55 × 5e-5: (ωh)²/4 ≈ 2e-6 of the energy.
        assert!(balance <= 2e-6 * initial, "{id}: balance {balance:e}");
    }
}
