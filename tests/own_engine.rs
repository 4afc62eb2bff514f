//! A user's engine, written against the public trait only (`examples/own_engine/engine.rs`),
//! goes through the studies as the built-in engines do, and they measure what its scheme is:
//! semi-implicit Euler is first order, and with its dashpots seeing the velocity of the
//! increment before, it is stable up to (2/ω)(√(1 + ζ²) − ζ).
mod common;

#[path = "../examples/own_engine/engine.rs"]
mod engine;

use crosscheck::comparison::stability;
use crosscheck::comparison::{self, work_precision};
use crosscheck::engines::Engine;
use crosscheck::pipeline::exact_solutions;
use crosscheck::run::sweep;

/// Its history meets the output contract on every springs case at the case's own increment
/// (the explicit engine's, as its `Needs` asks), 20,000 increments on the seed cases: every
/// output row, the last at the end of the duration.
#[test]
fn its_history_meets_the_output_contract() {
    use crosscheck::contract;
    use crosscheck::run::{Plan, execute};
    let cases: Vec<_> = common::SPRINGS_CASES
        .iter()
        .map(|c| common::scene(c))
        .collect();
    let plan = Plan {
        cases,
        engines: vec![Box::new(engine::SemiImplicitEuler)],
        settings: Default::default(),
    };
    let outcome = execute(&plan, false);
    assert_eq!(outcome.jobs.len(), common::SPRINGS_CASES.len());
    for job in &outcome.jobs {
        let scene = plan.cases.iter().find(|s| s.id == job.case).unwrap();
        // The harness checks the contract as it runs the job: a breach is an `Err` here.
        let run = job
            .result
            .as_ref()
            .unwrap_or_else(|e| panic!("{}: {e}", job.case));
        contract::check(scene, &run.history).unwrap_or_else(|e| panic!("{}: {e}", job.case));
    }
}

/// A case file may declare a tolerance for a user's engine when the cases are loaded for it
/// (`run::load_cases_for`); loaded for crosscheck's own engines only, the name is refused with
/// the file, line and field. The engine is then held to it: semi-implicit Euler's error on
/// springs_grounded_a at the case's increment is its velocity's half-increment lag, ω·h/2 of
/// the peak (8.51e-4 at ω = 34.05 rad/s, h = 5e-5 s; measured 8.45e-4, within 5 %), within
/// 1e-3 and not within 5e-4.
#[test]
fn a_case_may_declare_its_tolerance() {
    use crosscheck::run::{self, Plan};
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(crosscheck::case::cases_dir().join("springs_grounded_a.toml"))
            .unwrap();
    let lag = (30.0f64 / 0.02588).sqrt() * 5e-5 / 2.0;
    for (tolerance, meets) in [(1e-3, true), (5e-4, false)] {
        let with = format!("{text}semi_implicit_euler = {tolerance:e}\n");
        let path = dir.path().join("springs_grounded_a.toml");
        std::fs::write(&path, with).unwrap();
        let args = [path.display().to_string()];
        let refused = run::load_cases(&args, dir.path()).unwrap_err();
        let message = format!("{}", refused[0]);
        assert!(message.contains("semi_implicit_euler"), "{message}");
        let cases = run::load_cases_for(&args, dir.path(), &["semi_implicit_euler"]).unwrap();
        assert_eq!(cases[0].tolerances["semi_implicit_euler"], tolerance);
        let (plan, outcome) = exact_solutions(cases.clone());
        let own = Plan {
            cases,
            engines: vec![Box::new(engine::SemiImplicitEuler)],
            settings: Default::default(),
        };
        let mine = crosscheck::run::execute(&own, false);
        let history = &mine.jobs[0].result.as_ref().unwrap().history;
        let error =
            comparison::against_own_model(&outcome, &plan.cases[0], "semi_implicit_euler", history)
                .unwrap();
        assert!(
            (error / lag - 1.0).abs() < 0.05,
            "error {error:e} against ω·h/2 = {lag:e}"
        );
        assert_eq!(
            error <= tolerance,
            meets,
            "error {error:e} against {tolerance:e}"
        );
    }
}

/// The sweep refines its increment from the output interval down and fits the order: 1 for
/// semi-implicit Euler (its velocity lags half an increment), within 0.1 (the fit's spread over
/// the points of a path, measured 1.00), beside `explicit`'s 2.
#[test]
fn the_sweep_measures_first_order() {
    let (plan, outcome) = exact_solutions(vec![common::scene("springs_grounded_a")]);
    let mut engines = common::engines_named(&["explicit"]);
    engines.push(Box::new(engine::SemiImplicitEuler));
    let grid = sweep::Grid {
        repeat: 1,
        ..sweep::Grid::default()
    };
    let swept = work_precision::measure(&plan, &outcome, &common::refs(&engines), &grid, false);
    let order = |name: &str| {
        let fit = swept[0].fits.iter().find(|f| f.engine == name).unwrap();
        fit.observed_order
            .as_ref()
            .expect("an observed order")
            .value
    };
    let (own, explicit) = (order("semi_implicit_euler"), order("explicit"));
    assert!(
        (0.9..=1.1).contains(&own),
        "semi_implicit_euler: order {own}"
    );
    assert!(
        (1.8..=2.2).contains(&explicit),
        "explicit: order {explicit}"
    );
}

/// The stability map bisects its critical increment to the lagged-damping limit
/// √(1 + ζ²) − ζ of the explicit engine's (whose centred damping keeps 2/ω), within the
/// bisection's 1 %: ζ = 0.5, 1 and 5 on the stiff mode of the stress pairs, and
/// ζ = c/(2√(km)) on the grounded seed case. Its energy reading ((1 + r)/(1 − r), the
/// engine's own) keeps a stable run from being called unstable.
#[test]
fn the_stability_map_finds_the_lagged_damping_limit() {
    let k_grounded: f64 = 30.0;
    let (c, m) = (0.12, 0.02588);
    let cases = [
        (
            common::scene("springs_grounded_a"),
            c / (2.0 * (k_grounded * m).sqrt()),
        ),
        (common::stress_scene("stress_pair_zeta05"), 0.5),
        (common::stress_scene("stress_pair_zeta1"), 1.0),
        (common::stress_scene("stress_pair_zeta5"), 5.0),
    ];
    let scenes = cases.iter().map(|(s, _)| s.clone()).collect();
    let (plan, outcome) = exact_solutions(scenes);
    let own: Vec<Box<dyn Engine>> = vec![Box::new(engine::SemiImplicitEuler)];
    let map = comparison::stability::measure(&plan, &outcome, &common::refs(&own), false);
    for (scene, zeta) in &cases {
        let limit = (1.0 + zeta * zeta).sqrt() - zeta;
        let critical = map
            .critical
            .iter()
            .find(|c| c.case == scene.id)
            .unwrap_or_else(|| panic!("{}: no critical increment", scene.id));
        let ratio = critical.explicit_ratio();
        let off = ratio / limit;
        assert!(
            (1.0 / stability::BISECTION_WIDTH..=stability::BISECTION_WIDTH).contains(&off),
            "{}: critical {ratio:.4} against √(1 + ζ²) − ζ = {limit:.4}",
            scene.id
        );
    }
}

/// What it does not model it refuses as unsupported (the report then says "not applicable"):
/// a rigid body, and an increment it would have to choose itself.
#[test]
fn it_refuses_what_it_does_not_model() {
    use crosscheck::engines::{EngineError, RunSettings};
    use crosscheck::scene::IncrementRule;
    let scene = common::scene("rigid2d_pin_lumped");
    let given = RunSettings {
        increment: Some(IncrementRule::Forced(1e-4)),
        ..RunSettings::default()
    };
    let refused = engine::SemiImplicitEuler.run(&scene, &given);
    assert!(matches!(refused, Err(EngineError::Unsupported(_))));
    let scene = common::scene("springs_grounded_a");
    let own_choice = RunSettings {
        increment: Some(IncrementRule::Tolerance(1e-3)),
        ..RunSettings::default()
    };
    let refused = engine::SemiImplicitEuler.run(&scene, &own_choice);
    assert!(matches!(refused, Err(EngineError::Unsupported(_))));
}
