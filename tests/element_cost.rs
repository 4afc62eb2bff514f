//! The generated family of the element-cost study: every scene is a valid case with the
//! elements it was asked for, steps stably near its stable increment, and the cost model's fit
//! recovers known coefficients.

use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::run::element_cost::{self, Elements, Model, Origin, Point, TERMS};
use crosscheck::scene::{Dimension, IncrementRule, StepKind};

#[test]
fn every_generated_scene_has_the_elements_it_was_asked_for() {
    for size in element_cost::family() {
        let scene = size.scene().unwrap_or_else(|e| panic!("{e}"));
        let e = Elements::of(&scene);
        assert_eq!(e.bodies, size.bodies, "{}", scene.id);
        assert_eq!(e.particles, size.particles, "{}", scene.id);
        assert_eq!(e.contacts, size.contacts, "{}", scene.id);
        assert_eq!(e.loads, size.contacts, "{}", scene.id);
        // Three springs per body (two axial, one rotational), two per particle.
        assert_eq!(
            e.springs,
            3 * size.bodies + 2 * size.particles,
            "{}",
            scene.id
        );
        let body_dashpots = if size.body_velocity {
            2 * size.bodies
        } else {
            0
        };
        // A dashpot on particles 0, 2, 4 of every six.
        let particle_dashpots = (0..size.particles).filter(|p| p % 6 % 2 == 0).count();
        assert_eq!(
            e.dashpots,
            body_dashpots + particle_dashpots,
            "{}",
            scene.id
        );
    }
}

/// Every scene of the family steps 2,000 increments at 0.98 of the stable increment the engine
/// states, without its energy guard stopping the run: the stated increment holds on scenes
/// nobody tuned it for (their motion stays small, so the linearisation of the start holds).
#[test]
fn every_generated_scene_is_stable_at_098_of_its_stated_increment() {
    let engine = ExplicitEngine::finite();
    for size in element_cost::family() {
        let mut scene = size.scene().unwrap();
        let stable = engine
            .stable_increment(&scene, &RunSettings::default())
            .unwrap_or_else(|| panic!("{}: no stable increment", scene.id))
            .increment;
        let h = 0.98 * stable;
        for step in &mut scene.steps {
            step.kind = StepKind::Dynamic {
                duration: 2000.0 * h,
            };
        }
        let settings = RunSettings {
            increment: Some(IncrementRule::Exact(h)),
            ..RunSettings::default()
        };
        let run = engine
            .run(&scene, &settings)
            .unwrap_or_else(|e| panic!("{} at 0.98 × {stable:e}: {e}", scene.id));
        assert!(
            run.info.steps >= 2000,
            "{}: {} increments",
            scene.id,
            run.info.steps
        );
    }
}

fn point(
    dimension: Dimension,
    particles: usize,
    bodies: usize,
    forces: usize,
    passes: f64,
) -> Point {
    Point {
        case: String::new(),
        origin: Origin::Generated,
        dimension,
        elements: Elements {
            particles,
            bodies,
            springs: forces,
            ..Elements::default()
        },
        increment: 1e-3,
        steps: 1,
        passes,
        ns_per_increment: 0.0,
    }
}

#[test]
fn the_fit_recovers_the_coefficients_of_an_exact_model() {
    // Points generated from known coefficients, with independent counts: the fit must return
    // them to round-off (a relative 1e-9 leaves room for the SVD's conditioning).
    let truth = [100.0, 20.0, 5.0, 15.0, 2.0];
    assert_eq!(truth.len(), TERMS.len());
    let exact = Model {
        dimension: Dimension::Two,
        coefficients: truth,
    };
    let mut points = Vec::new();
    for (particles, bodies, forces, passes) in [
        (1, 1, 3, 1.0),
        (16, 1, 40, 1.0),
        (64, 4, 100, 2.0),
        (1, 16, 60, 3.0),
        (16, 16, 90, 4.5),
        (64, 16, 200, 1.0),
        (4, 4, 10, 5.0),
        (32, 8, 70, 2.5),
    ] {
        let mut p = point(Dimension::Two, particles, bodies, forces, passes);
        p.ns_per_increment = exact.predict(&p);
        points.push(p);
    }
    let refs: Vec<&Point> = points.iter().collect();
    let fitted = Model::fit(&refs, Dimension::Two).expect("a full-rank system");
    for (f, t) in fitted.coefficients.iter().zip(truth) {
        assert!((f - t).abs() <= 1e-9 * t.abs().max(1.0), "{fitted:?}");
    }
    assert!(
        Model::fit(&refs, Dimension::Three).is_none(),
        "no 3D points"
    );
}
