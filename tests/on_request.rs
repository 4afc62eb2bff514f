//! Accuracy on request (`--tolerance EPS`, `[time] tolerance`): each engine chooses its own
//! increment (and penalty stiffness), and its error against the exact solution of its own model
//! must land in [EPS/10, EPS]: within the tolerance, and not wastefully more accurate. Measured
//! on every seed case and on scenes no engine was tuned on (other masses, stiffnesses, damping,
//! load geometry).

mod common;

use crosscheck::comparison::{baseline, compare};
use crosscheck::engines::{Engine, EngineError, RunSettings};
use crosscheck::scene::{IncrementRule, Scene};

const TOLERANCES: [f64; 4] = [1e-3, 1e-4, 1e-5, 1e-6];

/// Scenes not among the seed cases.
fn unseen() -> Vec<Scene> {
    vec![
        // Node-to-node springs: heavier masses, stiffer springs.
        common::variant(
            "springs_n2n_b",
            &[
                ("mass = 0.02588", "mass = 0.05"),
                ("stiffness = 30.0", "stiffness = 80.0"),
            ],
        ),
        // The grounded oscillator, lighter and more damped (ζ ≈ 0.6).
        common::variant(
            "springs_grounded_a",
            &[
                ("mass = 0.02588", "mass = 0.015"),
                ("damping = 0.12", "damping = 0.8"),
            ],
        ),
        // The sliding rigid body: heavier, more inertia, the load applied elsewhere.
        common::variant(
            "rigid2d_slide_lumped",
            &[
                ("mass = 20.0", "mass = 35.0"),
                ("inertia = 65.0", "inertia = 90.0"),
                ("at = [-1.0, 1.0]", "at = [-1.5, 1.2]"),
            ],
        ),
    ]
}

/// The error of `engine` run at tolerance `eps`, against its own model's exact solution.
fn achieved(
    scene: &Scene,
    engine: &dyn Engine,
    exact: &crosscheck::engines::History,
    eps: f64,
) -> Result<f64, EngineError> {
    let out = engine.run(
        scene,
        &RunSettings {
            increment: Some(IncrementRule::Tolerance(eps)),
            ..Default::default()
        },
    )?;
    assert_eq!(out.info.measures.get("requested_tolerance"), Some(&eps));
    Ok(compare(scene, exact, &out.history)
        .worst_max
        .expect("a compared column"))
}

fn exact_for(scene: &Scene, engine: &str) -> crosscheck::engines::History {
    let name = baseline(engine).unwrap();
    common::run(
        crosscheck::run::registry::named(name).unwrap().as_ref(),
        scene,
        Default::default(),
    )
}

/// `explicit_small` (its model is linear: the a h² + b/k_p error model holds) meets the band
/// on every seed case and every unseen scene, at every tolerance.
#[test]
fn explicit_small_meets_every_tolerance_within_a_decade() {
    let engine = crosscheck::run::registry::named("explicit_small").unwrap();
    for scene in common::all_scenes().iter().chain(&unseen()) {
        let exact = exact_for(scene, "explicit_small");
        for eps in TOLERANCES {
            let e = achieved(scene, engine.as_ref(), &exact, eps)
                .unwrap_or_else(|err| panic!("{} at {eps:e}: {err}", scene.id));
            println!("{:24} explicit_small {eps:.0e}: {:.3}", scene.id, e / eps);
            assert!(
                e <= eps && e >= eps / 10.0,
                "{} at {eps:e}: {e:e}",
                scene.id
            );
        }
    }
}

/// `explicit` (finite rotation) meets the band at every tolerance, contact cases included
/// (measured at 1e-6: 3.9e-7 pinned, 3.0–3.2e-7 sliding surface). Before its contact start led
/// the gap rate by the increment's lag, a penalty-frequency ringing held its contact force at
/// about 3e-5 of the peak on those cases, and it refused 1e-6 there.
#[test]
fn explicit_meets_every_tolerance() {
    let engine = crosscheck::run::registry::named("explicit").unwrap();
    for scene in common::all_scenes().iter().chain(&unseen()) {
        let exact = exact_for(scene, "explicit");
        for eps in TOLERANCES {
            let e = achieved(scene, engine.as_ref(), &exact, eps)
                .unwrap_or_else(|err| panic!("{} at {eps:e}: {err}", scene.id));
            println!("{:24} explicit {eps:.0e}: {:.3}", scene.id, e / eps);
            assert!(
                e <= eps && e >= eps / 10.0,
                "{} at {eps:e}: {e:e}",
                scene.id
            );
        }
    }
}

/// Scenes whose pilots at 0.9 of the stable increment lie outside the range where the time
/// error is a h²: a fast mode that carries little of the motion, but whose accumulated phase
/// error (ω³ T h²/24 rad) has saturated at its amplitude by the end, so that the change between
/// the pilots at h₁ and h₁/2 hardly falls and underestimates a. Each with the tolerances it
/// must meet; at the others it may refuse, saying why (the stable increment, or the output
/// interval, already gives less than ε/10).
fn fast_mode_scenes() -> Vec<(Scene, Vec<f64>)> {
    vec![
        // springs_n2n_b with the spring between the masses 100× stiffer and undamped (a mode
        // of about 480 rad/s over 1 s): the pilots' a was 6.0e5 where the error's is 4.4e6, and
        // the choice missed every tolerance by 2.26–2.30×.
        (
            common::variant(
                "springs_n2n_b",
                &[
                    (
                        "stiffness = 30.0\n\n[[dashpots]]",
                        "stiffness = 3000.0\n\n[[dashpots]]",
                    ),
                    ("damping = 0.12", "damping = 0.0"),
                ],
            ),
            TOLERANCES.to_vec(),
        ),
        // A 1e6 mass ratio (100 rad/s over 10 s): 2.0, 4.1 and 4.3 ε at 1e-4 … 1e-6.
        (
            common::stress_scene("stress_mass_ratio"),
            TOLERANCES.to_vec(),
        ),
        // A stiff mode of 141 rad/s over 20 s: 5.0 and 25.8 ε at 1e-5 and 1e-6; at 1e-3 the
        // largest increment gives 0.085 ε.
        (
            common::stress_scene("stress_pair_undamped"),
            vec![1e-4, 1e-5, 1e-6],
        ),
        // A 1e-9 mass (3.2e4 rad/s over 0.1 s): 2.0 and 19.8 ε at 1e-5 and 1e-6.
        (
            common::stress_scene("stress_tiny_mass"),
            vec![1e-4, 1e-5, 1e-6],
        ),
        // 0.9 of the stable increment (0.018 s) shortened to 0.01 s to divide the output
        // interval: 0.043 ε at 1e-3.
        (
            common::stress_scene("stress_inertia_ratio"),
            vec![1e-4, 1e-5, 1e-6],
        ),
        // The stable increment gives 9e-9 of the peak: under ε/10 at every tolerance.
        (common::stress_scene("stress_stiffness_ratio"), vec![]),
    ]
}

/// `explicit_small` meets the band on scenes whose pilots are outside the a h² range, or
/// refuses with the reason; it refuses only where it cannot do otherwise.
#[test]
fn explicit_small_meets_the_band_or_says_why_not_with_a_fast_mode() {
    let engine = crosscheck::run::registry::named("explicit_small").unwrap();
    for (scene, must) in fast_mode_scenes() {
        let exact = exact_for(&scene, "explicit_small");
        for eps in TOLERANCES {
            match achieved(&scene, engine.as_ref(), &exact, eps) {
                Ok(e) => {
                    println!("{:24} explicit_small {eps:.0e}: {:.3}", scene.id, e / eps);
                    assert!(
                        e <= eps && e >= eps / 10.0,
                        "{} at {eps:e}: {e:e}",
                        scene.id
                    );
                }
                Err(EngineError::Unsupported(m)) => {
                    println!("{:24} explicit_small {eps:.0e}: {m}", scene.id);
                    assert!(m.contains("out of reach"), "{m}");
                    assert!(!must.contains(&eps), "{} at {eps:e}: {m}", scene.id);
                }
                Err(err) => panic!("{} at {eps:e}: {err}", scene.id),
            }
        }
    }
}

/// Contact that strikes: the penalty error falls as 1/√k_p (a penalty impact lasts
/// π√(m/k_p)), not as 1/k_p, and the contact force after an impact is a pulse the comparison
/// does not judge. `explicit` meets the band or refuses with the reason. Before: 4.1 ε
/// (`contact_drop_e1`) and 2.4 ε (`contact_bounce_wedge`) at 1e-6, 6.4–74 ε on
/// `contact_reopen`, 0.015 and 0.064 ε on `contact_balls_oblique` at 1e-3 and 1e-4.
#[test]
fn explicit_meets_the_band_or_says_why_not_where_contact_strikes() {
    let engine = crosscheck::run::registry::named("explicit").unwrap();
    let cases: [(&str, &[f64]); 4] = [
        ("contact_drop_e1", &[1e-3, 1e-4]),
        ("contact_bounce_wedge", &[1e-3, 1e-4, 1e-5]),
        ("contact_balls_oblique", &[1e-3, 1e-4, 1e-5]),
        ("contact_reopen", &[]),
    ];
    for (id, must) in cases {
        let scene = common::stress_scene(id);
        let exact = exact_for(&scene, "explicit");
        for eps in TOLERANCES {
            match achieved(&scene, engine.as_ref(), &exact, eps) {
                Ok(e) => {
                    println!("{id:24} explicit {eps:.0e}: {:.3}", e / eps);
                    assert!(e <= eps && e >= eps / 10.0, "{id} at {eps:e}: {e:e}");
                }
                Err(EngineError::Unsupported(m)) => {
                    println!("{id:24} explicit {eps:.0e}: {m}");
                    assert!(m.contains("out of reach"), "{m}");
                    assert!(!must.contains(&eps), "{id} at {eps:e}: {m}");
                }
                Err(err) => panic!("{id} at {eps:e}: {err}"),
            }
        }
    }
}

/// Rapier picks its increment from its observed first-order error, or says the tolerance is out
/// of reach and why; what it returns is within the tolerance. On the spring cases 1e-3 is
/// within its reach (measured 0.34–0.50 of it).
#[cfg(feature = "rapier")]
#[test]
fn rapier_meets_a_tolerance_or_says_why_not() {
    for name in ["rapier_f64", "rapier_f64_default"] {
        let engine = crosscheck::run::registry::named(name).unwrap();
        for scene in common::all_scenes() {
            let exact = exact_for(&scene, name);
            for eps in [1e-3, 1e-4] {
                match achieved(&scene, engine.as_ref(), &exact, eps) {
                    Ok(e) => {
                        println!("{:24} {name} {eps:.0e}: {:.3}", scene.id, e / eps);
                        assert!(
                            e <= eps && e >= eps / 10.0,
                            "{} {name} at {eps:e}: {e:e}",
                            scene.id
                        );
                    }
                    Err(EngineError::Unsupported(m)) => {
                        println!("{:24} {name} {eps:.0e}: {m}", scene.id);
                        assert!(m.contains("out of reach"), "{m}");
                        assert!(
                            !(eps == 1e-3 && scene.id.starts_with("springs")),
                            "{}: {m}",
                            scene.id
                        );
                    }
                    Err(err) => panic!("{} {name} at {eps:e}: {err}", scene.id),
                }
            }
        }
    }
}

/// `[time] tolerance` in a case file is the same request as `--tolerance`.
#[test]
fn a_case_file_can_ask_for_a_tolerance() {
    let scene = common::variant(
        "springs_n2n_c",
        &[("increment = 5.0e-5", "tolerance = 1.0e-4")],
    );
    assert_eq!(scene.settings.increment, IncrementRule::Tolerance(1e-4));
    let engine = crosscheck::run::registry::named("explicit").unwrap();
    let exact = exact_for(&scene, "explicit");
    let out = engine.run(&scene, &RunSettings::default()).unwrap();
    let e = compare(&scene, &exact, &out.history)
        .worst_max
        .expect("a compared column");
    assert!((1e-5..=1e-4).contains(&e), "{e:e}");
    assert!(out.info.counters["pilot_increments"] > 0);
}
