//! Accuracy on request (`--tolerance EPS`, `[time] tolerance`): each engine chooses its own
//! increment (and penalty stiffness), and its error against the exact solution of its own model
//! must land in [EPS/10, EPS]: within the tolerance, and not wastefully more accurate. Measured
//! on every seed case and on scenes no engine was tuned on (other masses, stiffnesses, damping,
//! load geometry).

mod common;

use crosscheck::comparison::{baseline, compare};
use crosscheck::engines::{self, Engine, EngineError, RunSettings};
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
        engines::named(name).unwrap().as_ref(),
        scene,
        Default::default(),
    )
}

/// `explicit_small` (its model is linear: the a h² + b/k_p error model holds) meets the band
/// on every seed case and every unseen scene, at every tolerance.
#[test]
fn explicit_small_meets_every_tolerance_within_a_decade() {
    let engine = engines::named("explicit_small").unwrap();
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
    let engine = engines::named("explicit").unwrap();
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

/// Rapier picks its increment from its observed first-order error, or says the tolerance is out
/// of reach and why; what it returns is within the tolerance. On the spring cases 1e-3 is
/// within its reach (measured 0.34–0.50 of it).
#[cfg(feature = "rapier")]
#[test]
fn rapier_meets_a_tolerance_or_says_why_not() {
    for name in ["rapier_f64", "rapier_f64_default"] {
        let engine = engines::named(name).unwrap();
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
    let engine = engines::named("explicit").unwrap();
    let exact = exact_for(&scene, "explicit");
    let out = engine.run(&scene, &RunSettings::default()).unwrap();
    let e = compare(&scene, &exact, &out.history)
        .worst_max
        .expect("a compared column");
    assert!((1e-5..=1e-4).contains(&e), "{e:e}");
    assert!(out.info.counters["pilot_increments"] > 0);
}
