//! The judging rules on histories whose right answer is known without trusting any engine under
//! test: an orientation compared as a rotation (a spin's exact history, turned by a known
//! angle or unwrapped onto another branch), a transient that decays (rapier's default
//! configuration on the stiff damped pair, over ten times the case's horizon), the stability
//! map reaching past an engine's own step, and a parameter the exact solution ignores.

mod common;

use crosscheck::comparison::compare;
use crosscheck::comparison::invariance;
use crosscheck::comparison::verdict;
use crosscheck::engines::{History, RunSettings};
use crosscheck::run::{self, Plan};
use nalgebra::{Rotation3, Vector3};
use std::f64::consts::PI;

/// `h` with every body point of the spin case turned by `angle` about the world z axis (the
/// body's centre stays at the origin) and its `rz` column shifted by `angle` plus `turns`
/// whole turns.
fn turned(h: &History, angle: f64, turns: f64) -> History {
    let col = |name: &str| h.columns.iter().position(|c| c == name).unwrap();
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), angle);
    let mut out = h.clone();
    for row in &mut out.rows {
        row[col("rz")] += angle + turns * 2.0 * PI;
    }
    for (i, p) in ["P1", "P2", "P3"].iter().enumerate() {
        let c = ["x", "y", "z"].map(|q| col(&format!("u{q}_{p}")));
        for (row, new) in h.rows.iter().zip(&mut out.rows) {
            let start = Vector3::ith(i, 1.0);
            let now = start + Vector3::new(row[c[0]], row[c[1]], row[c[2]]);
            let moved = r * now - start;
            for k in 0..3 {
                new[c[k]] = moved[k];
            }
        }
    }
    out
}

/// The spin near the major axis turns through 50 rad in 0.05 s. Its exact history turned by
/// 0.75 rad about z is 0.75 rad away at every row: 0.75 rad over the farthest the exact
/// orientation gets from its start, π sampled at the rows (to 1 %: a turn is 63 rows),
/// whatever the number of turns (divided by the 50 rad the angle accumulates it would pass a
/// 5e-2 tolerance). The same history with its angle on another branch (three turns on) is the
/// same orientation.
#[test]
fn an_orientation_is_compared_as_a_rotation() {
    let scene = common::stress_scene("stress_spin_major");
    let exact = common::run(
        crosscheck::run::registry::named("reference")
            .unwrap()
            .as_ref(),
        &scene,
        RunSettings::default(),
    );
    let lagging = compare(&scene, &exact, &turned(&exact, 0.75, 0.0));
    let worst = lagging.worst_max.unwrap();
    let over = worst / (0.75 / PI);
    assert!((1.0..1.01).contains(&over), "{worst}");
    assert_eq!(
        verdict::meets(run::Status::Ok, Some(worst), Some(5e-2)),
        Some(false)
    );
    let peak = lagging
        .columns
        .iter()
        .find(|c| c.column == "rz")
        .unwrap()
        .peak;
    assert!(0.75 / peak < 5e-2, "{peak}");
    let branch = compare(&scene, &exact, &turned(&exact, 0.0, 3.0));
    assert!(branch.worst_max.unwrap() < 1e-12, "{branch:?}");
    // In 2D the angle is the orientation: a whole turn apart is no error.
    let pinned = common::scene("rigid2d_pin_lumped");
    let exact = common::run(
        crosscheck::run::registry::named("analytic")
            .unwrap()
            .as_ref(),
        &pinned,
        RunSettings::default(),
    );
    let mut wound = exact.clone();
    let rz = wound.columns.iter().position(|c| c == "rz").unwrap();
    for row in &mut wound.rows {
        row[rz] += 2.0 * PI;
    }
    let c = compare(&pinned, &exact, &wound);
    let col = c.columns.iter().find(|c| c.column == "rz").unwrap();
    assert!(col.max < 1e-12, "{col:?}");
}

/// contact_slide_ball: the node slides and never strikes, so its restitution enters no exact
/// history (the reference gives the same one at e = 0 and e = 1), and the invariance control
/// names the engine whose verdict depends on it: `explicit`, whose contact dashpot (sized for
/// e < 1) acts on the sliding contact (measured 3.9e-3 at e = 0, 4.8e-6 at e = 1, tolerance
/// 1e-4).
#[test]
fn a_parameter_the_exact_solution_ignores_is_run_at_both_values() {
    let plan = Plan {
        cases: vec![common::stress_scene("contact_slide_ball")],
        engines: ["reference", "explicit"]
            .iter()
            .filter_map(|n| crosscheck::run::registry::named(n))
            .collect(),
        settings: RunSettings::default(),
    };
    let outcome = run::execute(&plan, false);
    let found = invariance::measure(&plan, &outcome, false);
    assert_eq!(found.len(), 1, "{found:?}");
    let i = &found[0];
    assert!(i.exact_change.unwrap() < invariance::ROUND_OFF, "{i:?}");
    let explicit = i.engines.iter().find(|p| p.engine == "explicit").unwrap();
    assert!(explicit.depends(), "{explicit:?}");
    assert_eq!(explicit.met, [Some(false), Some(true)]);
    let tolerance = verdict::tolerance(&plan.cases[0], "explicit").unwrap();
    assert!(explicit.errors[0].unwrap() > 10.0 * tolerance);
    // The cell itself is judged at the value the case states, e = 0.
    let judged = compare(
        &plan.cases[0],
        outcome.history("contact_slide_ball", "reference").unwrap(),
        outcome.history("contact_slide_ball", "explicit").unwrap(),
    );
    assert_eq!(judged.worst_max, explicit.errors[0]);
}

/// Rapier's default configuration: a transient it makes is bounded, and the map reaches past its
/// own step.
#[cfg(feature = "rapier")]
mod rapier {
    use super::common;
    use crosscheck::comparison::stability::{self, Bound, Search};
    use crosscheck::comparison::verdict::growth;
    use crosscheck::engines::RunSettings;
    use crosscheck::pipeline::exact_solutions;
    use crosscheck::run;

    /// rapier's default configuration on the stiff damped pair at 22, 32 and 64 × the explicit
    /// stable increment, run for 300 s (ten times the case): its energy peaks once near 2 s at
    /// 2–31 × its initial value, then decays. A transient, so bounded, with the peak reported;
    /// and the map's run on the case's own 30 s says the same.
    #[test]
    fn a_transient_that_decays_is_bounded_over_a_long_horizon() {
        let scene = common::stress_scene("stress_pair_zeta5");
        let engine = crosscheck::run::registry::named("rapier_f64_default").unwrap();
        let stable = run::stability::explicit_stable(&scene).unwrap();
        for (ratio, least) in [(22.0, 2.0), (32.0, 4.0), (64.0, 25.0)] {
            let long = run::stability::continued(&scene, 10);
            let settings = RunSettings {
                increment: Some(crosscheck::scene::IncrementRule::Exact(ratio * stable)),
                ..RunSettings::default()
            };
            let out = engine.run(&long, &settings).unwrap();
            let g = growth::judge(&out.history, out.info.steps as f64).unwrap();
            println!("{ratio}×: {g:?}");
            assert_eq!(g.verdict, growth::Verdict::Bounded, "{ratio}×");
            assert!(g.peak > least && g.peak_time < 5.0, "{ratio}×: {g:?}");
            assert!(g.end < 1e-3, "{ratio}×: {g:?}");
            let short = run::stability::run_at(&scene, engine.as_ref(), ratio);
            let out = short.output.unwrap();
            let g = growth::judge(&out.history, out.info.steps as f64).unwrap();
            assert_eq!(g.verdict, growth::Verdict::Bounded, "{ratio}× over 30 s");
        }
    }

    /// The map runs rapier's default configuration at its own step (1/60 s) and on to 4 × it on
    /// the pinned seed case, which lasts 0.1 s: the case is continued in time so that every run
    /// takes at least 20 increments, and the bound is at least 4/60 s, not a ceiling below the
    /// engine's own step.
    #[test]
    fn the_map_reaches_past_an_engines_own_step() {
        let (plan, outcome) = exact_solutions(vec![common::scene("rigid2d_pin_lumped")]);
        let default = crosscheck::run::registry::named("rapier_f64_default").unwrap();
        let map = stability::measure(&plan, &outcome, &[default.as_ref()], false);
        let c = &map.critical[0];
        assert_eq!(c.bound, Bound::AtLeast);
        assert!(c.increment >= 4.0 / 60.0 * (1.0 - 1e-9), "{c:?}");
        assert!(c.covers_own_step(), "{c:?}");
        let furthest = map
            .points
            .iter()
            .filter(|p| p.search == Search::Beyond)
            .max_by(|a, b| a.ratio.total_cmp(&b.ratio))
            .unwrap();
        let steps = furthest.continued.unwrap() as f64 * 0.1 / furthest.increment.unwrap();
        assert!(steps >= 20.0 - 1e-9, "{furthest:?}");
    }
}
