//! `reference`, the converged finite-rotation solution: it converges, it is exact where an
//! exact solution is known, it reduces to the small-rotation closed form as the motion shrinks,
//! and the explicit engine converges to it.
use crosscheck::case;
use crosscheck::comparison;
use crosscheck::engines::analytic::{self, AnalyticEngine};
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::reference::ReferenceEngine;
use crosscheck::engines::{Engine, RunOutput, RunSettings};
use crosscheck::scene::{Family, Scene};

fn seed_cases() -> Vec<Scene> {
    case::discover(&case::cases_dir())
        .unwrap()
        .iter()
        .map(|p| case::load(p).unwrap())
        .collect()
}

fn reference(scene: &Scene) -> RunOutput {
    ReferenceEngine
        .run(scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id))
}

/// Halving the tolerance (with at most half the step) moves no column by more than 1e-10 of
/// its peak: the integration error at 1e-12 is far below anything the report resolves. The
/// contact gap stays at its initial value to 1e-12 (length units; the geometry is ~1): the
/// constraint is solved at acceleration level, so it drifts only by the integration error.
#[test]
fn the_reference_converges_on_every_seed_case() {
    for scene in seed_cases() {
        let out = reference(&scene);
        let change = out.info.measures["tolerance_halving_change"];
        assert!(change <= 1e-10, "{}: {change:e}", scene.id);
        if let Some(drift) = out.info.measures.get("constraint_drift") {
            assert!(*drift <= 1e-12, "{}: drift {drift:e}", scene.id);
        }
    }
}

/// On the spring cases (linear, no contact) the reference is the exact linear solution: it
/// equals the general exact solver (matrix exponential) to 1e-10 of each column's peak
/// (1e-12 integration tolerance over ~34 periods, with margin).
#[test]
fn the_reference_equals_the_exact_linear_solution_on_the_spring_cases() {
    for scene in seed_cases()
        .into_iter()
        .filter(|s| s.family == Family::Springs)
    {
        let exact = analytic::linear::solve(&scene).unwrap();
        let c = comparison::compare(&scene, &exact, &reference(&scene).history);
        assert!(c.rows == scene.output_rows, "{}", scene.id);
        assert!(
            c.worst_max.expect("a compared column") <= 1e-10,
            "{}: {:e}",
            scene.id,
            c.worst_max.expect("a compared column")
        );
    }
}

/// The 3D rigid cases hold every DOF but the planar ones, so their reference equals the 2D one
/// (to 1e-12 of the peak: the same equations, integrated with another state layout).
#[test]
fn the_3d_reference_equals_the_2d_one() {
    let cases = seed_cases();
    for s3 in cases.iter().filter(|s| s.id.starts_with("rigid3d")) {
        let s2 = cases
            .iter()
            .find(|s| s.id == s3.id.replace("rigid3d", "rigid2d"))
            .unwrap();
        let a = reference(s2).history;
        let b = reference(s3).history;
        let c = comparison::compare(s2, &a, &b);
        assert!(
            c.worst_max.expect("a compared column") <= 1e-12,
            "{}: {:e}",
            s3.id,
            c.worst_max.expect("a compared column")
        );
    }
}

/// The finite-rotation model tends to the small-rotation one as the motion shrinks: with the
/// load and the initial velocities scaled by s, the difference between `reference` and the
/// closed form (relative to the peak) is model form, of the order of the rotation, so it falls
/// in proportion to s. Measured at s = 1 and s = 1e-3: the ratio must be under 2e-3 (linear
/// with a factor 2 of margin), and the s = 1 gap must be real (over 1e-3). This checks the
/// reference's mechanics against the independently derived closed form.
#[test]
fn the_reference_tends_to_the_closed_form_as_the_motion_shrinks() {
    for scene in seed_cases()
        .into_iter()
        .filter(|s| s.family == Family::RigidBody && s.id.starts_with("rigid2d"))
    {
        let gap = |s: f64| {
            let mut scaled = scene.clone();
            for l in &mut scaled.loads {
                l.force *= s;
            }
            for v in &mut scaled.initial_velocities {
                v.velocity *= s;
                v.angular *= s;
            }
            let closed = AnalyticEngine
                .run(&scaled, &RunSettings::default())
                .unwrap()
                .history;
            comparison::compare(&scaled, &closed, &reference(&scaled).history)
                .worst_max
                .expect("a compared column")
        };
        let (large, small) = (gap(1.0), gap(1e-3));
        assert!(large > 1e-3, "{}: {large:e}", scene.id);
        assert!(
            small <= 2e-3 * large,
            "{}: {small:e} at s = 1e-3 against {large:e} at s = 1",
            scene.id
        );
    }
}

/// `explicit` (finite rotation, penalty contact) at the shipped settings is within 1e-3 of the
/// peak of the reference on every seed case: its own model's exact solution, so what remains is
/// its discretisation (O(h²)) and penalty compliance (O(k/k_p) = 1e-4).
#[test]
fn explicit_is_within_1e_3_of_the_reference_on_every_seed_case() {
    for scene in seed_cases() {
        let exact = reference(&scene).history;
        let out = ExplicitEngine::finite()
            .run(&scene, &RunSettings::default())
            .unwrap();
        let c = comparison::compare(&scene, &exact, &out.history);
        assert!(
            c.worst_max.expect("a compared column") <= 1e-3,
            "{}: {:e}",
            scene.id,
            c.worst_max.expect("a compared column")
        );
    }
}
