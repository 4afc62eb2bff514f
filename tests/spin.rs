//! Fast spin in 3D: a free body (principal inertias 1, 2, 3) at 1000 rad/s near its major,
//! minor and intermediate axes (`cases/stress/stress_spin_*.toml`). The angular momentum in the
//! world frame and the kinetic energy are recovered from the histories of three body points on
//! the principal axes, and the intermediate axis's flip is timed against `reference`. Then a
//! body that turns about one tilted axis after a free turn, against `reference`.
#![cfg(feature = "rapier")]
use crosscheck::case;
use crosscheck::engines::{History, RunSettings};
use crosscheck::scene::IncrementRule;
use nalgebra::{Matrix3, Vector3};

fn stress(id: &str) -> crosscheck::scene::Scene {
    case::load(&case::stress_dir(&case::cases_dir()).join(format!("{id}.toml")))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Per row: time, orientation R (columns: the body axes in the world), angular velocity ω.
fn motion(h: &History) -> Vec<(f64, Matrix3<f64>, Vector3<f64>)> {
    let col = |name: &str| h.columns.iter().position(|c| c == name).unwrap();
    let points = ["P1", "P2", "P3"];
    h.rows
        .iter()
        .map(|r| {
            let mut p = [Vector3::zeros(); 3];
            let mut v = [Vector3::zeros(); 3];
            for (i, name) in points.iter().enumerate() {
                for (k, q) in ["x", "y", "z"].iter().enumerate() {
                    p[i][k] = r[col(&format!("u{q}_{name}"))] + if i == k { 1.0 } else { 0.0 };
                    v[i][k] = r[col(&format!("v{q}_{name}"))];
                }
            }
            // For orthonormal p_i: Σ p_i × (ω × p_i) = 3ω − ω = 2ω.
            let w = (p[0].cross(&v[0]) + p[1].cross(&v[1]) + p[2].cross(&v[2])) * 0.5;
            (r[0], Matrix3::from_columns(&p), w)
        })
        .collect()
}

/// Angular momentum in the world frame and kinetic energy.
fn momentum_and_energy(r: &Matrix3<f64>, w: &Vector3<f64>) -> (Vector3<f64>, f64) {
    let inertia = r * Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0)) * r.transpose();
    let l = inertia * w;
    (l, 0.5 * w.dot(&l))
}

struct Measured {
    momentum_drift: f64,
    energy_drift: f64,
    /// Smallest alignment of the spin axis (the body axis it started on) with its initial
    /// world direction.
    alignment: f64,
    /// Times at which the spin axis turns over (its alignment changes sign).
    flips: Vec<f64>,
}

fn measure(case: &str, engine: &str, increment: Option<f64>) -> Measured {
    let scene = stress(case);
    let axis = match case {
        "stress_spin_minor" => 0,
        "stress_spin_intermediate" => 1,
        _ => 2,
    };
    let settings = RunSettings {
        increment: increment.map(IncrementRule::Given),
        ..Default::default()
    };
    let out = crosscheck::run::registry::named(engine)
        .unwrap()
        .run(&scene, &settings)
        .unwrap_or_else(|e| panic!("{case} / {engine}: {e}"));
    let m = motion(&out.history);
    let (l0, k0) = momentum_and_energy(&m[0].1, &m[0].2);
    let mut measured = Measured {
        momentum_drift: 0.0,
        energy_drift: 0.0,
        alignment: 1.0,
        flips: Vec::new(),
    };
    for (i, (t, r, w)) in m.iter().enumerate() {
        let (l, k) = momentum_and_energy(r, w);
        measured.momentum_drift = measured.momentum_drift.max((l - l0).norm() / l0.norm());
        measured.energy_drift = measured.energy_drift.max((k - k0).abs() / k0);
        measured.alignment = measured.alignment.min(r[(axis, axis)]);
        if i > 0 {
            let (t0, r0, _) = &m[i - 1];
            let (a, b) = (r0[(axis, axis)], r[(axis, axis)]);
            if a.signum() != b.signum() {
                measured.flips.push(t0 + (t - t0) * a / (a - b));
            }
        }
    }
    println!(
        "{case:26} {engine:18} h = {:.3e}: |ΔL|/|L| = {:.3e}  |ΔK|/K = {:.3e}  alignment ≥ {:.6}  flips at {:?}",
        out.info.increment,
        measured.momentum_drift,
        measured.energy_drift,
        measured.alignment,
        measured
            .flips
            .iter()
            .map(|f| format!("{f:.6}"))
            .collect::<Vec<_>>()
    );
    measured
}

#[test]
fn near_the_major_and_minor_axes_the_spin_is_stable_and_conserved() {
    for case in ["stress_spin_major", "stress_spin_minor"] {
        let explicit = measure(case, "explicit", None);
        // 1 rad/s off-axis in 1000: the axis wobbles by ~1e-3 rad and never turns over.
        assert!(explicit.flips.is_empty() && explicit.alignment > 0.999);
        // Angular momentum in the world frame to 1e-9 (measured 9.6e-10 major, 1.7e-10
        // minor, at ω·h = 1e-3); kinetic energy to 1e-12 (measured 1.4e-13, 8.4e-14).
        assert!(explicit.momentum_drift <= 1e-9, "{case}");
        assert!(explicit.energy_drift <= 1e-12, "{case}");
        for engine in ["rapier_f64", "rapier_f32"] {
            measure(case, engine, None);
        }
    }
}

#[test]
fn near_the_intermediate_axis_the_body_flips_when_the_reference_says() {
    let case = "stress_spin_intermediate";
    let reference = measure(case, "reference", None);
    let explicit = measure(case, "explicit", None);
    assert_eq!(reference.flips.len(), 2);
    assert_eq!(explicit.flips.len(), reference.flips.len());
    // The flips (at 14.9 ms and 42.4 ms) within 2 increments (2e-6 s) of the reference's.
    for (e, r) in explicit.flips.iter().zip(&reference.flips) {
        assert!((e - r).abs() <= 2e-6, "explicit flip at {e}, reference {r}");
    }
    // Through the flips the angular momentum drifts by the scheme's O(h²) error, not by a
    // conservation defect: halving h quarters it (1.11e-7 at 1e-6 s, 2.78e-8 at 5e-7 s), so
    // 1e-9 takes h ≤ 9.5e-8 s; at 9e-8 s (5.6e5 increments) it is met.
    let half = measure(case, "explicit", Some(5e-7));
    let ratio = explicit.momentum_drift / half.momentum_drift;
    assert!((ratio / 4.0 - 1.0).abs() < 0.02, "ratio {ratio}");
    let fine = measure(case, "explicit", Some(9e-8));
    assert!(fine.momentum_drift <= 1e-9, "{:e}", fine.momentum_drift);
    // Kinetic energy bounded: within 1e-7 through the flips (measured 8.3e-8 at 1e-6 s).
    assert!(explicit.energy_drift <= 1e-7);
    // Rapier on the same, measured: f64 flips within 1e-5 s; f32 does not hold the motion.
    let rapier = measure(case, "rapier_f64", None);
    for (e, r) in rapier.flips.iter().zip(&reference.flips) {
        assert!(
            (e - r).abs() <= 1e-5,
            "rapier_f64 flip at {e}, reference {r}"
        );
    }
    measure(case, "rapier_f32", None);
}

/// A body that turns freely in a first step (`first_hold`, for `first` seconds of 1.2), then
/// about one tilted axis g (`frames.tilted`'s y axis, (1, −1, 0)/√2) with the other two
/// rotations held (`second_hold`): pinned at its reference node O, or sliding along the frame's
/// x axis, with its mass centre off O (three point masses, an anisotropic inertia); `extra`
/// adds elements. In the second step `explicit` iterates the centred angular rate of each;
/// rapier fits its joints to the pose the step starts from (`JointSpec::fitted`).
/// `reference` integrates the same scene with its own equations and error control. A spring
/// from a body point to the ground gives the moment. (The test found `reference` ending a
/// dynamic step that another follows at its last output row, one interval short of the step's
/// end: 1.4e-3 of the peak at the boundary.)
fn tilted_turn(
    first_hold: &str,
    first: f64,
    second_hold: &str,
    extra: &str,
) -> crosscheck::scene::Scene {
    let second = 1.2 - first;
    let text = format!(
        r#"
id = "tilted_turn"
title = "a turn about a tilted axis after a free one"
family = "rigid_body"
dimension = 3
[time]
increment = 1.0e-4
[output]
rows = 241
[[output.columns]]
name = "rz"
rotation = "body"
[[output.columns]]
name = "ux"
displacement = "O"
direction = [1.0, 0.0, 0.0]
[[output.columns]]
name = "ux_node"
zero = "no contact node"
[[output.columns]]
name = "contact_force"
zero = "no contact"
[[output.columns]]
name = "ux_P"
displacement = "P"
direction = [1.0, 0.0, 0.0]
[[output.columns]]
name = "uy_P"
displacement = "P"
direction = [0.0, 1.0, 0.0]
[[output.columns]]
name = "uz_P"
displacement = "P"
direction = [0.0, 0.0, 1.0]
[[frames]]
id = "tilted"
x_axis = [1.0, 1.0, 1.0]
y_axis = [1.0, -1.0, 0.0]
[[nodes]]
id = "O"
at = [0.0, 0.0, 0.0]
frame = "tilted"
[[nodes]]
id = "P"
at = [0.8, -0.4, 0.6]
body = "body"
[[nodes]]
id = "G"
at = [1.0, 0.6, 0.2]
fixed = true
[[nodes]]
id = "M1"
at = [1.0, 0.0, 0.0]
body = "body"
[[nodes]]
id = "M2"
at = [0.0, 1.2, 0.3]
body = "body"
[[nodes]]
id = "M3"
at = [-0.4, 0.2, 0.9]
body = "body"
[[bodies]]
id = "body"
reference = "O"
[[masses]]
node = "M1"
mass = 1.0
[[masses]]
node = "M2"
mass = 2.0
[[masses]]
node = "M3"
mass = 1.5
[[springs]]
id = "spring"
kind = "fixed_direction"
nodes = ["P", "G"]
direction = [0.2, 1.0, -0.4]
stiffness = 40.0
{extra}
[[initial_velocities]]
node = "O"
angular = [1.5, -1.0, 2.0]
[[steps]]
kind = "dynamic"
duration = {first}
hold = [{{ node = "O", dofs = {first_hold} }}]
[[steps]]
kind = "dynamic"
duration = {second}
hold = [{{ node = "O", dofs = {second_hold} }}]
"#
    );
    crosscheck::case::parse(&text, std::path::Path::new("tilted_turn.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_turn_about_a_tilted_axis_after_a_free_one_follows_the_reference() {
    const PINNED: &str = r#"["ux", "uy", "uz"]"#;
    const TURNING: &str = r#"["ux", "uy", "uz", "rx", "rz"]"#;
    let spring = "[[springs]]\nid = \"twist\"\nkind = \"grounded\"\nnodes = [\"O\"]\ndof = \"ry\"\nstiffness = 5.0";
    for (what, first_hold, first, hold, extra) in [
        ("pinned", PINNED, 0.3, TURNING, ""),
        ("sliding", PINNED, 0.3, r#"["uy", "uz", "rx", "rz"]"#, ""),
        // A grounded spring on the free axis reads the body's total twist since t = 0.
        (
            "pinned, a spring on the free axis",
            PINNED,
            0.3,
            TURNING,
            spring,
        ),
        // O slides along the frame's x axis first, then is held again where it got to.
        (
            "held again where it slid",
            r#"["uy", "uz"]"#,
            0.3,
            TURNING,
            "",
        ),
        // The first step ends between two rows.
        ("a step ending between rows", PINNED, 0.3021, TURNING, ""),
    ] {
        let scene = tilted_turn(first_hold, first, hold, extra);
        let run = |engine: &str| {
            crosscheck::run::registry::named(engine)
                .unwrap()
                .run(&scene, &RunSettings::default())
                .unwrap_or_else(|e| panic!("{what} / {engine}: {e}"))
                .history
        };
        let reference = run("reference");
        // explicit: central differences' phase error, ω³h²T/24 with ω ≈ 4 rad/s (the spin
        // and the spring's mode), h = 1e-4 s and T = 1.2 s: about 3e-8 of the peak (measured
        // 1.2e-9 to 1.5e-7 over the five variants). 1e-6 bounds it. A slip fails it by far
        // more: the pinned body's
        // operator formed from its unturned inertia, 3.0e-3; the sliding body's centripetal
        // term left out of α, 6.1e-2 (both tried).
        // rapier_f64 (matched): measured 3.2e-5 to 3.7e-4 of the peak (its joints and the
        // spring's motor, first order in its substep); 1e-3 bounds it. Before its second
        // step's joints were fitted to the pose the step starts from, the held rotations
        // snapped the pinned body back towards its orientation at t = 0 (1.4 of the peak);
        // before the held rotations were taken out with the node's velocity kept (not the
        // centre of mass's), the sliding body's node started the step moving (2.0). Without
        // the translation's fit, O held again is pulled back to where it started (1.3, tried).
        // With a grounded spring on the tilted axis, rapier's motor reads the angle as
        // 2·asin of the relative rotation's component on its axis, not the twist the scene
        // defines; the two part while the body also swings (the first step, every rotation
        // free): 1.6e-4 of the peak by the first step's end, 3.0e-3 at worst after, with no
        // jump at the boundary. 1e-2 bounds it; a motor that read 0 instead of the twist since
        // t = 0 when the second step starts fails it (tried: 0.37).
        // rapier_f32, the same plan in single precision: measured 3.3e-3 to 2.6e-2 of the
        // peak (its f32 solver and integration, as on the seed cases); 5e-2 bounds it, far
        // below a snap at the step's start.
        let rapier = if extra.is_empty() { 1e-3 } else { 1e-2 };
        for (engine, bound) in [
            ("explicit", 1e-6),
            ("rapier_f64", rapier),
            ("rapier_f32", 5e-2),
        ] {
            let history = run(engine);
            for name in ["ux_P", "uy_P", "uz_P", "ux"] {
                let column = |h: &History| -> Vec<f64> {
                    let i = h.columns.iter().position(|c| c == name).unwrap();
                    h.rows.iter().map(|r| r[i]).collect()
                };
                let (e, r) = (column(&history), column(&reference));
                assert_eq!(e.len(), r.len(), "{what}: {engine}: rows");
                let peak = r.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                let worst = e
                    .iter()
                    .zip(&r)
                    .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
                println!(
                    "{what}: {engine}: {name}: peak {peak:.3e}, − reference {worst:.3e} ({:.1e})",
                    worst / peak
                );
                if name == "ux" && first_hold == PINNED && hold == TURNING {
                    // O is pinned: exactly under explicit; rapier's joint holds it to its
                    // solver's residual (measured 8.9e-10 m in f64, 3.0e-7 m in f32).
                    let held = match engine {
                        "explicit" => 0.0,
                        "rapier_f64" => 1e-8,
                        _ => 1e-6,
                    };
                    assert!(worst <= held, "{what}: {engine}: O is pinned: {worst:e}");
                    continue;
                }
                assert!(
                    worst <= bound * peak,
                    "{what}: {engine}: {name}: {worst:e} of {peak:e}"
                );
            }
        }
    }
}

/// A rotation held again after a free turn while two rotations stay free, one of them with a
/// grounded rotational spring: rapier's joint cannot hold the first where it is and measure the
/// spring's total twist on the second, so the rapier engines refuse the scene (explicit and
/// reference run it).
#[test]
fn rapier_refuses_a_rotation_held_again_beside_a_turning_spring() {
    let spring = r#"
[[springs]]
id = "twist"
kind = "grounded"
nodes = ["O"]
dof = "ry"
stiffness = 5.0"#;
    let scene = tilted_turn(
        r#"["ux", "uy", "uz"]"#,
        0.3,
        r#"["ux", "uy", "uz", "rx"]"#,
        spring,
    );
    for engine in ["rapier_f64", "rapier_f32"] {
        match crosscheck::run::registry::named(engine)
            .unwrap()
            .run(&scene, &RunSettings::default())
        {
            Err(crosscheck::engines::EngineError::Unsupported(why)) => {
                assert!(why.contains("held again"), "{engine}: {why}")
            }
            other => panic!("{engine}: {:?}", other.map(|o| o.info.increment)),
        }
    }
    for engine in ["explicit", "reference"] {
        let run = crosscheck::run::registry::named(engine)
            .unwrap()
            .run(&scene, &RunSettings::default());
        assert!(run.is_ok(), "{engine}: {:?}", run.err());
    }
}
