//! The affine step (`engines::explicit::affine`): a small step whose forces are affine in the
//! displacements runs its increments between output rows as a recurrence in its free DOFs, and
//! must give what the general path gives, increment by increment, to round-off.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunOutput, RunSettings};
use crosscheck::scene::{DampingTreatment, Scene};

fn run(engine: ExplicitEngine, scene: &Scene, settings: &RunSettings) -> RunOutput {
    engine
        .run(scene, settings)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id))
}

/// `scene` run by `engine` with and without the affine step, each checked: `steps` increments
/// in all, of which the affine run took every one it may take and the general run none.
fn both_paths(engine: ExplicitEngine, scene: &Scene, steps: u64) -> (RunOutput, RunOutput) {
    let settings = RunSettings::default();
    let affine = run(engine, scene, &settings);
    let general = run(engine.general(), scene, &settings);
    let rows = scene.output_rows as u64 - 1;
    assert_eq!(affine.info.steps, steps, "{}", scene.id);
    let all = eligible(steps, steps / rows);
    assert_eq!(counter(&affine, "affine_increments"), all, "{}", scene.id);
    assert_eq!(counter(&general, "affine_increments"), 0, "{}", scene.id);
    (affine, general)
}

// Each increment sums the forces in another order, so the two runs differ by a few ulps per
// increment; over the 2·10^4 increments of a springs case, summed with random signs, that is
// about √(2·10^4)·4ε ≈ 1e-13 of the peak. The bound allows ten times that.
const ROUND_OFF: f64 = 1e-12;

#[test]
fn the_springs_cases_step_as_the_general_path_to_round_off() {
    for id in SPRINGS_CASES {
        let scene = scene(id);
        for engine in [ExplicitEngine::finite(), ExplicitEngine::small()] {
            // Every increment it may take, and none in the general run.
            let (affine, general) = both_paths(engine, &scene, 20_000);
            // Measured: at most 6.2e-15 (springs_n2n_c, e_kinetic).
            let (d, name) = largest_difference(&affine, &general);
            println!("{id} {}: {d:.1e} ({name})", engine.name());
            assert!(d <= ROUND_OFF, "{id} {}: {name} {d:e}", engine.name());
            // The counters tell the same work: a force pass and a dashpot solve per increment.
            for counter in ["force_evaluations", "damping_evaluations"] {
                assert_eq!(
                    affine.info.counters[counter], general.info.counters[counter],
                    "{id} {counter}"
                );
            }
        }
    }
}

#[test]
fn without_dashpots_the_step_is_the_one_pass_increment_to_round_off() {
    // System B's node-to-node test without its dashpot: no velocity pass, so the general path
    // takes the one-pass increments on the one-dimensional store.
    let dashpot = "[[dashpots]]\nid = \"dashpot-12-13\"\nkind = \"fixed_direction\"\nnodes = [\"12\", \"13\"]\ndirection = [1.0, 0.0]\ndamping = 0.12\n";
    let scene = variant("springs_n2n_b", &[(dashpot, "")]);
    let settings = RunSettings::default();
    let affine = run(ExplicitEngine::finite(), &scene, &settings);
    let general = run(ExplicitEngine::finite().general(), &scene, &settings);
    let rows = scene.output_rows as u64 - 1;
    assert_eq!(
        counter(&affine, "affine_increments"),
        eligible(affine.info.steps, affine.info.steps / rows)
    );
    assert!(general.info.counters["axial_increments"] > 0);
    assert_eq!(affine.info.counters["damping_evaluations"], 0);
    // Measured: 3.2e-15 (e_elastic).
    let (d, name) = largest_difference(&affine, &general);
    println!("without the dashpot: {d:.1e} ({name})");
    assert!(d <= ROUND_OFF, "{name} {d:e}");
    // Without a dashpot nothing is dissipated in either run.
    assert!(col(&affine.history, "e_viscous").iter().all(|e| *e == 0.0));
}

#[test]
fn a_dashpot_that_never_acts_is_counted_as_the_general_path_counts_it() {
    // System B's dashpot at zero damping: the direct solve has no dashpot to solve, yet the
    // general path passes through it at every increment, and so counts the affine step.
    let scene = variant("springs_n2n_b", &[("damping = 0.12", "damping = 0.0")]);
    let settings = RunSettings::default();
    let affine = run(ExplicitEngine::finite(), &scene, &settings);
    let general = run(ExplicitEngine::finite().general(), &scene, &settings);
    assert!(counter(&affine, "affine_increments") > 0);
    for counter in ["force_evaluations", "damping_evaluations"] {
        assert_eq!(
            affine.info.counters[counter], general.info.counters[counter],
            "{counter}"
        );
    }
    let (d, name) = largest_difference(&affine, &general);
    assert!(d <= ROUND_OFF, "{name} {d:e}");
}

#[test]
fn ends_that_would_pass_each_other_stop_the_recurrence() {
    // System C's grounded test with 103 thrown at 102 along the line: it passes 102 and the
    // spring between them, held on its line, takes its turning force (tests/held_lines.rs). The
    // recurrence stops before the increment where the ends would meet and resumes after.
    let scene = grounded_c_thrown();
    let settings = RunSettings::default();
    let affine = run(ExplicitEngine::finite(), &scene, &settings);
    let general = run(ExplicitEngine::finite().general(), &scene, &settings);
    let rows = scene.output_rows as u64 - 1;
    let taken = counter(&affine, "affine_increments");
    let all = eligible(affine.info.steps, affine.info.steps / rows);
    println!("affine increments: {taken} of {all}");
    assert!(taken > all / 2 && taken < all, "{taken} of {all}");
    let u = col(&affine.history, "u_end");
    assert!(u.iter().any(|x| *x < -2.0), "103 passes 102");
    // Measured: 2.2e-15.
    let (d, name) = largest_difference(&affine, &general);
    println!("through the crossing: {d:.1e} ({name})");
    assert!(d <= ROUND_OFF, "{name} {d:e}");
    // Where the ends have passed, the general path alone evaluates the forces.
    assert_eq!(
        affine.info.counters["force_evaluations"],
        general.info.counters["force_evaluations"]
    );
}

/// Every counter of the general path's run, the affine step's own aside.
fn work(out: &RunOutput) -> Vec<(String, u64)> {
    let own = ["affine_increments"];
    let counters = out.info.counters.iter();
    counters
        .filter(|(name, _)| !own.contains(&name.as_str()))
        .map(|(name, n)| (name.clone(), *n))
        .collect()
}

#[test]
fn the_rigid_cases_under_small_rotation_step_as_the_general_path_to_round_off() {
    // Under small rotation the rigid seed cases are affine while their contact presses, which
    // it does from start to end: every increment the step may take is taken.
    for id in RIGID_CASES {
        let (affine, general) = both_paths(ExplicitEngine::small(), &scene(id), 10_000);
        // Measured: at most 1.8e-14 (e_kinetic) on the motion and the energies, 4.4e-11 on
        // the contact force against bounds of 1.4e-8 to 2.0e-8.
        let ((d, name), contact) = differences(&affine, &general);
        let bound = contact_bound(&general, &["ux", "ux_node"], ROUND_OFF);
        println!("{id}: {d:.1e} ({name}); contact force {contact:.1e} (bound {bound:.1e})");
        assert!(d <= ROUND_OFF, "{id}: {name} {d:e}");
        assert!(
            contact <= bound,
            "{id}: contact force {contact:e} > {bound:e}"
        );
        // The same work counted: a force pass, a contact pair, a body solve and an
        // orientation update per increment.
        assert_eq!(work(&affine), work(&general), "{id}");
    }
}

#[test]
fn numbers_that_round_give_the_general_path_to_round_off_too() {
    // The seed cases' loads, masses and inertia are numbers whose sums round exactly; these
    // are not. The response and the contact's push are differences of force passes that also
    // sum the loads, so they carry the loads' rounding over the probe: with a unit normal
    // force as the probe that is ε·|load| ≈ 1e-11 of the push, with the probe used
    // (2^20 times the largest force at rest) ε/2^20.
    let scene = variant(
        "rigid2d_pin_lumped",
        &[
            ("force = [-1.0e5, 0.0]", "force = [-98765.4321, 0.0]"),
            ("mass = 5.0", "mass = 5.3"),
            ("inertia = 65.0", "inertia = 64.77"),
        ],
    );
    let settings = RunSettings::default();
    let engine = ExplicitEngine::small();
    let affine = run(engine, &scene, &settings);
    let general = run(engine.general(), &scene, &settings);
    assert!(counter(&affine, "affine_increments") > 0);
    let ((d, name), contact) = differences(&affine, &general);
    let bound = contact_bound(&general, &["ux", "ux_node"], ROUND_OFF);
    println!(
        "numbers that round: {d:.1e} ({name}); contact force {contact:.1e} (bound {bound:.1e})"
    );
    // Measured: 7.2e-15 (e_kinetic); the contact force 7.7e-11 (bound 2.2e-8).
    assert!(d <= ROUND_OFF, "{name} {d:e}");
    assert!(contact <= bound, "contact force {contact:e} > {bound:e}");
}

#[test]
fn a_contact_that_opens_and_closes_ends_a_batch_at_each_change() {
    // The pinned seed problem with omega0 reversed: the face runs away from N and strikes it
    // again, six times in 0.1 s under small rotation. A batch keeps each contact on the side
    // it started on: where the motion takes it across, the batch ends and the next starts
    // from the other side, with the engine's own force pass, which notes the impact. So every
    // increment the step may take is taken, and the impacts fall on the same increments as in
    // the general path. (Were a contact kept on its side past the change, it would pull in
    // tension or miss an impact: the runs would differ by far more than round-off.)
    let (affine, general) = both_paths(
        ExplicitEngine::small(),
        &stress_scene("contact_reopen"),
        100_000,
    );
    let impacts = affine.info.measures["impacts"];
    assert!(
        impacts >= 5.0,
        "the contact closes again: {impacts} impacts"
    );
    assert_eq!(affine.info.measures, general.info.measures);
    let force = col(&affine.history, "contact_force");
    assert!(force.contains(&0.0) && force.iter().any(|f| *f > 0.0));
    // Measured: 5.7e-14 (gap), the contact force 7.4e-12 (bound 3.6e-10).
    let ((d, name), contact) = differences(&affine, &general);
    let bound = contact_bound(&general, &["ux_node"], ROUND_OFF);
    println!(
        "opening and closing: {d:.1e} ({name}); contact force {contact:.1e} (bound {bound:.1e})"
    );
    assert!(d <= ROUND_OFF, "{name} {d:e}");
    assert!(contact <= bound, "contact force {contact:e} > {bound:e}");
    assert_eq!(work(&affine), work(&general));
}

#[test]
fn the_recurrence_is_declined_where_the_forces_are_not_affine_or_damping_is_lagged() {
    let lagged = RunSettings {
        damping: Some(DampingTreatment::Lagged),
        ..RunSettings::default()
    };
    let out = run(ExplicitEngine::finite(), &scene("springs_n2n_b"), &lagged);
    assert_eq!(counter(&out, "affine_increments"), 0, "lagged dashpots");
    for id in ["rigid2d_pin_lumped", "rigid3d_slide_surface"] {
        let out = run(
            ExplicitEngine::finite(),
            &scene(id),
            &RunSettings::default(),
        );
        assert_eq!(
            counter(&out, "affine_increments"),
            0,
            "{id}: finite rotation"
        );
    }
    // Under small rotation too where a contact is a solid's (a curved surface) or damped.
    for id in ["contact_drop_e1", "contact_drop_e06"] {
        let out = run(
            ExplicitEngine::small(),
            &stress_scene(id),
            &RunSettings::default(),
        );
        assert_eq!(counter(&out, "affine_increments"), 0, "{id}");
    }
}
