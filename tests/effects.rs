//! The engine simulates only the effects a scene calls for: its work counters prove it.
mod common;
use common::*;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, RunSettings};

fn counters(id: &str, engine: ExplicitEngine) -> std::collections::BTreeMap<String, u64> {
    engine
        .run(&scene(id), &RunSettings::default())
        .unwrap()
        .info
        .counters
}

#[test]
fn spring_only_scene_never_evaluates_contact() {
    for id in SPRINGS_CASES {
        for engine in [ExplicitEngine::finite(), ExplicitEngine::small()] {
            let c = counters(id, engine);
            assert!(
                c["force_evaluations"] > 10_000,
                "{id}: the run did evaluate forces"
            );
            assert_eq!(c["contact_evaluations"], 0, "{id}: contact code entered");
            assert_eq!(
                c["rotation_updates"], 0,
                "{id}: no body, no rotation update"
            );
            assert_eq!(c["body_solves"], 0, "{id}: no body solve");
        }
    }
}

#[test]
fn contact_scene_evaluates_contact_every_increment_and_no_damping() {
    let c = counters("rigid2d_pin_lumped", ExplicitEngine::finite());
    // One pair, evaluated once per increment (10 000) plus the linearisation and start.
    assert!(c["contact_evaluations"] >= 10_000, "{c:?}");
    assert!(c["contact_evaluations"] <= 10_100, "{c:?}");
    // No dashpots and, with the pin, no centripetal term on a free DOF: no velocity pass.
    assert_eq!(c["damping_evaluations"], 0, "{c:?}");
    assert_eq!(c["rotation_updates"], 10_000, "{c:?}");
}

#[test]
fn damped_scene_has_one_velocity_pass() {
    // Dashpots between particles: the centred velocity is solved directly, one pass per
    // increment (the fixed-point iteration took two or three).
    for id in ["springs_grounded_a", "springs_n2n_c"] {
        let c = counters(id, ExplicitEngine::finite());
        let per_step = c["damping_evaluations"] as f64 / 20_000.0;
        println!("{id}: damping passes per increment: {per_step:.5}");
        assert!((1.0..=1.001).contains(&per_step), "{id}: {c:?}");
    }
}

#[test]
fn centred_damping_follows_the_schemes_own_recurrence() {
    // The damped oscillator m ẍ + c ẋ + k x = 0 under central differences with the centred
    // dashpot velocity v(n) = (x(n+1) − x(n−1))/(2h) is the recurrence
    // (1 + a) x(n+1) = (2 − b) x(n) − (1 − a) x(n−1), a = ζωh = ch/(2m), b = ω²h², started
    // from x(0) = 1 at rest by x(1) = 1 − b/2 (the half-step start v(½) = (h/2)·a(0)). Its
    // exact solution is x(n) = ρⁿ (cos nθ + D sin nθ) with ρ² = (1 − a)/(1 + a) and
    // θ = atan2(√(b(4 − b) − 4a²), 2 − b), evaluated here in closed form (phase accurate to
    // n·θ·ε ≈ 4e-15). The engine must follow it to its own round-off: 2·10^4 increments,
    // each rounding at ε ≈ 1e-16, with the oscillation carrying a local error forward at up to
    // 1/sin θ ≈ 600 times its size: a few 1e-13 (measured 2.4e-13 with the direct solve,
    // 4.5e-13 with the fixed-point iteration it replaced). 2e-12 bounds it.
    let (m, k, c, h) = (0.02588_f64, 30.0_f64, 0.12_f64, 5.0e-5_f64);
    let omega = (k / m).sqrt();
    let (a, b) = (0.5 * c / m * h, omega * omega * h * h);
    let theta = (b * (4.0 - b) - 4.0 * a * a).sqrt().atan2(2.0 - b);
    let log_rho = 0.5 * ((-a).ln_1p() - a.ln_1p());
    let rho = log_rho.exp();
    let d = ((1.0 - 0.5 * b) / rho - theta.cos()) / theta.sin();
    let x = |n: usize| {
        let n = n as f64;
        (n * log_rho).exp() * ((n * theta).cos() + d * (n * theta).sin())
    };
    let steps = 20_000;
    let out = ExplicitEngine::finite()
        .run(&scene("springs_grounded_a"), &RunSettings::default())
        .unwrap();
    assert_eq!(out.info.steps, steps as u64);
    let (u, v) = (col(&out.history, "u_end"), col(&out.history, "v_end"));
    let mut worst: f64 = 0.0;
    for (row, (u, v)) in u.iter().zip(&v).enumerate().skip(1) {
        let n = row * 40; // 501 rows over 2·10^4 increments
        let expected_v = (x(n + 1) - x(n - 1)) / (2.0 * h);
        worst = worst
            .max((u - x(n)).abs())
            .max((v - expected_v).abs() / omega);
    }
    println!("largest departure from the recurrence: {worst:.3e} of the peak");
    assert!(worst < 2e-12, "{worst:e}");
}

/// A chain of three masses on a line, ground–1–2–3, with a spring on each link and a dashpot
/// of the kind given on each link that has one (`kinds`, link by link), started from their
/// reference positions with initial velocities. With a dashpot on every link they share
/// nodes and have unequal rates per mass, so the direct solve's k×k system (k = 3) is full
/// and unsymmetric. `on_axis`: the masses are held across the line (their `uy`), so that an
/// axial dashpot's line stays on it; otherwise they are free across it and only nothing
/// pushing them off it keeps them there. Either way an axial dashpot's line is taken as
/// turning.
fn dashpot_chain(kinds: [Option<&str>; 3], on_axis: bool) -> crosscheck::scene::Scene {
    let mut text = String::from(
        "id = \"dashpot_chain\"\ntitle = \"a chain of three masses with dashpots\"\nfamily = \"springs\"\ndimension = 2\n\n[time]\nincrement = 1.0e-3\n\n[output]\nrows = 201\n\n",
    );
    text += &springs_columns("3", "2", "[1.0, 0.0]");
    text += "[[nodes]]\nid = \"0\"\nat = [0.0, 0.0]\nfixed = true\n\n";
    for (i, m) in CHAIN_MASSES.iter().enumerate() {
        text += &format!(
            "[[nodes]]\nid = \"{0}\"\nat = [{0}.0, 0.0]\n\n[[masses]]\nnode = \"{0}\"\nmass = {m:e}\n\n",
            i + 1
        );
    }
    for (i, ((k, c), kind)) in CHAIN_SPRINGS
        .iter()
        .zip(CHAIN_DASHPOTS)
        .zip(kinds)
        .enumerate()
    {
        let nodes = format!("nodes = [\"{i}\", \"{}\"]", i + 1);
        text += &format!(
            "[[springs]]\nid = \"s{i}\"\nkind = \"fixed_direction\"\n{nodes}\ndirection = [1.0, 0.0]\nstiffness = {k:e}\n\n"
        );
        let Some(kind) = kind else {
            continue;
        };
        let direction = if kind == "axial" {
            String::new()
        } else {
            "direction = [1.0, 0.0]\n".to_string()
        };
        text += &format!(
            "[[dashpots]]\nid = \"d{i}\"\nkind = \"{kind}\"\n{nodes}\n{direction}damping = {c:e}\n\n"
        );
    }
    for (i, v) in CHAIN_VELOCITIES.iter().enumerate() {
        text += &format!(
            "[[initial_velocities]]\nnode = \"{}\"\nvelocity = [{v:e}, 0.0]\n\n",
            i + 1
        );
    }
    text += "[[steps]]\nkind = \"dynamic\"\nduration = 2.0\nhold = [\n";
    for i in (1..=3).filter(|_| on_axis) {
        text += &format!("    {{ node = \"{i}\", dofs = [\"uy\"] }},\n");
    }
    text += "]\n";
    crosscheck::case::parse(&text, std::path::Path::new("dashpot_chain.toml"))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

const CHAIN_MASSES: [f64; 3] = [1.0, 2.0, 0.5];
const CHAIN_SPRINGS: [f64; 3] = [100.0, 200.0, 150.0];
const CHAIN_DASHPOTS: [f64; 3] = [0.5, 1.0, 2.0];
const CHAIN_VELOCITIES: [f64; 3] = [1.0, -0.5, 2.0];

/// The chain's positions x(0..=2001) (the last for the centred velocity at 2000) by the scheme's own recurrence, with the dashpot rates
/// `dashpots` per link (0: no dashpot). Central differences with centred dashpots on
/// M ẍ + C ẋ + K x = 0 are the recurrence (M/h² + C/2h) x(n+1) = (2M/h² − K) x(n) −
/// (M/h² − C/2h) x(n−1), started from x(0) = 0 by x(1) = h·(v(0) + (h/2)·a(0)),
/// a(0) = −M⁻¹C v(0) (the half-step start), with the centred velocity (x(n+1) − x(n−1))/2h.
/// It is evaluated here with nalgebra from the chain's M, C and K, in its difference form,
/// d = x(n+1) − x(n): (M/h² + C/2h) d(n+½) = (M/h² − C/2h) d(n−½) − K x(n), which does not
/// lose digits to the second difference.
fn chain_recurrence(h: f64, dashpots: [f64; 3]) -> Vec<nalgebra::Vector3<f64>> {
    use nalgebra::{Matrix3, Vector3};
    let m = Matrix3::from_diagonal(&Vector3::from(CHAIN_MASSES));
    let link = |w: [f64; 3]| {
        Matrix3::new(
            w[0] + w[1],
            -w[1],
            0.0,
            -w[1],
            w[1] + w[2],
            -w[2],
            0.0,
            -w[2],
            w[2],
        )
    };
    let (k, c) = (link(CHAIN_SPRINGS), link(dashpots));
    let v0 = Vector3::from(CHAIN_VELOCITIES);
    let a0 = -m.try_inverse().unwrap() * c * v0;
    let lhs = (m / (h * h) + c / (2.0 * h)).try_inverse().unwrap();
    let mut d = h * (v0 + 0.5 * h * a0);
    let mut x = vec![Vector3::zeros(), d];
    for n in 1..2001 {
        d = lhs * ((m / (h * h) - c / (2.0 * h)) * d - k * x[n]);
        x.push(x[n] + d);
    }
    x
}

/// The largest departure of `engine`'s run of the chain with dashpots `kinds` (`on_axis`,
/// see [`dashpot_chain`]) from the recurrence `x`, over the peak of the contract columns.
fn departure_from_chain(
    engine: ExplicitEngine,
    kinds: [Option<&str>; 3],
    on_axis: bool,
    x: &[nalgebra::Vector3<f64>],
    h: f64,
) -> f64 {
    let out = engine
        .run(&dashpot_chain(kinds, on_axis), &RunSettings::default())
        .unwrap();
    assert_eq!(out.info.steps, 2000);
    let (mut worst, mut scale): (f64, f64) = (0.0, 0.0);
    for (name, node) in [("u_end", 2), ("u_mid", 1), ("v_end", 2), ("v_mid", 1)] {
        for (row, got) in col(&out.history, name).iter().enumerate().skip(1) {
            let n = row * 10; // 201 rows over 2000 increments
            let expected = if name.starts_with('u') {
                x[n][node]
            } else {
                (x[n + 1][node] - x[n - 1][node]) / (2.0 * h)
            };
            worst = worst.max((got - expected).abs());
            scale = scale.max(expected.abs());
        }
    }
    worst / scale
}

#[test]
fn several_dashpots_follow_the_schemes_own_recurrence() {
    // `explicit_small` solves the dashpots' rates with the step's inverse of I + (h/2)·K
    // (formed once: no line turns); `explicit`, with the outer two dashpots axial and the
    // middle one along a fixed direction, the axial lines taken as turning (along their
    // spans, re-formed at every increment) and the system solved by elimination, with the
    // masses free across the line or held on it. All must follow the
    // recurrence (`chain_recurrence`) to round-off: 2000 increments of ε-sized roundings,
    // carried forward by modes with ω·h ≤ 0.03 (measured 1.0e-14 of the peak, every run);
    // 1e-13 bounds it. A wrong entry of the 3×3 solve (its inverse transposed, say) changes
    // the damping force by O(h·c/m) and the answer far above round-off (measured: 6.6e-5 of
    // the peak with the inverse transposed, which only the steady path uses; 9.3e-5 with the
    // coupling between dashpots that share a node dropped; 2.1e-2 with the spans' |l|² left
    // out of the diagonal, turning). The dissipated power is checked by the energy balance
    // (`tests/energy.rs`).
    let h = 1.0e-3;
    let x = chain_recurrence(h, CHAIN_DASHPOTS);
    let axial = [Some("axial"), Some("fixed_direction"), Some("axial")];
    for (engine, kinds, on_axis) in [
        (ExplicitEngine::small(), [Some("fixed_direction"); 3], true),
        (ExplicitEngine::finite(), axial, false),
        (ExplicitEngine::finite(), axial, true),
    ] {
        let kind = kinds[0].unwrap();
        let departure = departure_from_chain(engine, kinds, on_axis, &x, h);
        println!(
            "{kind}, on the axis {on_axis}: largest departure from the recurrence {departure:.3e} of the peak"
        );
        assert!(departure < 1e-13, "{kind}, {on_axis}: {departure:e}");
    }
}

#[test]
fn one_dashpot_follows_the_schemes_own_recurrence() {
    // One dashpot takes its own 1×1 solve, kept in registers, at every increment but the
    // first (`ParticleDashpots::solve`; the first restarts the half-step sequence through
    // `Model::damping`): axial under `explicit` (its line taken as turning: the system is
    // formed at every increment) with the masses free across the line or held on it, and
    // along a fixed line under `explicit_small` (the step's inverse). The chain with a
    // dashpot on one link only: on the first link (one end on the ground) and on the last
    // (both ends particles, of unequal mass). Same recurrence and the same round-off bound as
    // above (measured: 4.2e-14 and 1.1e-14 of the peak, turning; 4.2e-14 and 1.1e-14,
    // steady). A wrong term of either solve changes the damping force by O(h·c/m) or more,
    // far above it. Measured on the first link, turning: 2.7e-5 of the peak with the moving
    // end's coupling to itself dropped from the diagonal; 1.1e-3 with the right-hand side
    // taken from v(n−½) without the half step of the accelerations; 1.6 with |l|² left out
    // of the diagonal. Steady: 2.7e-5 with the step's inverse left out; 1.1e-3 with the same
    // right-hand side from v(n−½); 0.43 on the last link with the force put on its first end
    // only.
    let h = 1.0e-3;
    for link in [0, 2] {
        let mut rates = [0.0; 3];
        rates[link] = CHAIN_DASHPOTS[link];
        let x = chain_recurrence(h, rates);
        for (engine, kind, on_axis) in [
            (ExplicitEngine::finite(), "axial", false),
            (ExplicitEngine::finite(), "axial", true),
            (ExplicitEngine::small(), "fixed_direction", true),
        ] {
            let mut kinds = [None; 3];
            kinds[link] = Some(kind);
            let departure = departure_from_chain(engine, kinds, on_axis, &x, h);
            println!(
                "{kind} dashpot on link {link}, on the axis {on_axis}: departure {departure:.3e} of the peak"
            );
            assert!(
                departure < 1e-13,
                "{kind}, link {link}, {on_axis}: {departure:e}"
            );
        }
    }
}

#[test]
fn turning_body_iterates_its_centred_velocity_to_the_same_fixed_point_with_an_inert_dashpot() {
    // The sliding bodies with off-centre mass: the centripetal term is the only
    // velocity-dependent force, so the centred velocity is iterated: two or three body solves
    // per increment (the iteration stops within 1e-14 of the velocity scale; the predictor
    // v(n−½) + (h/2)·a(n−1) is that close after one or two passes at ω·h ≈ 1e-5).
    for (id, direction) in [
        ("rigid2d_slide_surface", "[1.0, 0.0]"),
        ("rigid3d_slide_surface", "[1.0, 0.0, 0.0]"),
    ] {
        let c = counters(id, ExplicitEngine::finite());
        let per_step = c["body_solves"] as f64 / 10_000.0;
        println!("{id}: body solves per increment: {per_step:.5}");
        // At least the check pass after the first; at most the 100 passes the iteration
        // allows would show as far more than 4 (plus about 20 for the setup).
        assert!((2.0..=4.0).contains(&per_step), "{id}: {c:?}");
        // The same scene with a dashpot far too weak to act (1e-100 N·s/m, the smallest a
        // case accepts, on the body's spring node) iterates with the dashpot's forces too:
        // the same fixed point. Each iteration stops within 1e-14 of the velocity scale per
        // increment; over 10^4 increments the positions then differ by about 1e-12 of their
        // peak and the contact force, through the penalty's 1e10 N/m, by about 1e-10 of its
        // peak; 1e-9 bounds it.
        let iterated = variant(
            id,
            &[(
                "# Frictionless node-to-face",
                &format!(
                    "[[dashpots]]\nid = \"inert\"\nkind = \"fixed_direction\"\nnodes = [\"S1\", \"G1\"]\ndirection = {direction}\ndamping = 1.0e-100\n\n# Frictionless node-to-face"
                ),
            )],
        );
        let closed = run(
            &ExplicitEngine::finite(),
            &scene(id),
            RunSettings::default(),
        );
        let iterated = run(&ExplicitEngine::finite(), &iterated, RunSettings::default());
        for column in live_columns(&scene(id)) {
            let (a, b) = (col(&closed, &column), col(&iterated, &column));
            let change = max_diff(&a, &b) / peak(&a);
            println!("{id} {column}: without and with the inert dashpot {change:.2e} of the peak");
            assert!(change <= 1e-9, "{id} {column}: {change:e}");
        }
    }
}
