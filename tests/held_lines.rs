//! An axial element whose line cannot turn in a step acts along that fixed line
//! (`Model::with_lines_held`): its force is the turning force to round-off while its ends keep
//! their order along the line, and exactly the turning force once they pass each other.
mod common;
use common::*;
use crosscheck::case;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::explicit::model::{ContactMode, Counters, Model};
use crosscheck::engines::explicit::space::Planar;
use crosscheck::engines::{Engine, History, RunSettings};
use crosscheck::scene::Scene;
use nalgebra::Vector2;

const STIFFNESS: f64 = 30.0; // every spring of system C
const LENGTH: f64 = 1.0; // each element's length at t = 0

/// The dynamic step of the node-to-node test of system C with only its end moves: 102 held,
/// 103 on the 45° line, its spring and dashpot to 102 axial and of unit length at t = 0.
fn grounded_c() -> (Scene, Model<Planar, true>) {
    let scene = scene("springs_grounded_c");
    let model = Model::compile(&scene, 0.0);
    (scene, model)
}

#[test]
fn a_held_line_takes_the_turning_force_to_round_off() {
    let (scene, model) = grounded_c();
    let held = model.constraints(&scene, &scene.steps[1]);
    let line = Vector2::new(1.0, 1.0).normalize();
    let mut cfg = model.initial_config();
    let lines = model
        .with_lines_held(&cfg, &held)
        .expect("both springs and the dashpot of system C stay on their line");
    let (mut turning, mut fixed) = (model.zero_forces(), model.zero_forces());
    let mut counters = Counters::default();
    // 103 (the second particle) anywhere on the line while it stays beyond 102: stretched,
    // compressed, down to a hundredth of its length.
    for x in [1.0, 0.5, 1e-3, 1e-9, 0.0, -1e-9, -0.3, -0.99, 3.0] {
        cfg.u[1] = line * x;
        model.forces(&cfg, ContactMode::Unilateral, &mut turning, &mut counters);
        lines.forces(&cfg, ContactMode::Unilateral, &mut fixed, &mut counters);
        // The turning force forms the span l = L0 + x rounded to an ulp of L0 + |x|, the
        // stretch |l| − L0 from it, and its direction l/|l| to that ulp over |l|; the fixed
        // line's stretch is exact to an ulp of x. So the two differ by a few ulps of
        // k (L0 + |x|) (1 + |x|/|l|). (On this 45° line the span's components stay equal and
        // its direction is exact, but the bound holds at any angle.)
        let span = LENGTH + x;
        let bound = 8.0 * f64::EPSILON * STIFFNESS * (LENGTH + x.abs()) * (1.0 + x.abs() / span);
        for (a, b) in turning.p.iter().zip(&fixed.p) {
            assert!(
                (a - b).norm() <= bound,
                "x = {x}: {a} against {b} (bound {bound:e})"
            );
        }
        // The fixed line's force is k x along the line, to round-off.
        let on_end = fixed.p[1];
        assert!((on_end + line * (STIFFNESS * x)).norm() <= bound, "x = {x}");
        // ½ k e²: the stretches differ by a few ulps of L0 + |x| (above), so the energies by
        // k |x| times that.
        assert!(
            (turning.elastic - fixed.elastic).abs() <= bound * x.abs(),
            "x = {x}: energy {} against {}",
            turning.elastic,
            fixed.elastic
        );
    }
    // Past 102 the span reverses: the turning spring acts along the reversed line, with
    // force k (|l| − L0) on 103 along +line (compressed at |l| = 0.5 it pushes 103 on, away
    // from 102; stretched at |l| = 2 it pulls it back), where the fixed line's −k x would
    // differ by 2 k L0. The held line takes the turning force there, bit for bit.
    for x in [-1.5, -3.0] {
        cfg.u[1] = line * x;
        model.forces(&cfg, ContactMode::Unilateral, &mut turning, &mut counters);
        lines.forces(&cfg, ContactMode::Unilateral, &mut fixed, &mut counters);
        assert_eq!(turning.p, fixed.p, "x = {x}");
        let reversed = line * (STIFFNESS * ((-x - LENGTH) - LENGTH));
        assert!((turning.p[1] - reversed).norm() <= 1e-13, "x = {x}");
        assert!((turning.p[1] + line * (STIFFNESS * x)).norm() > STIFFNESS * LENGTH);
    }
}

#[test]
fn only_a_line_that_cannot_turn_is_held() {
    let (scene, model) = grounded_c();
    let held = model.constraints(&scene, &scene.steps[1]);
    let cfg = model.initial_config();
    let lines = |model: &Model<Planar, true>, cfg: &_, held: &_| {
        model
            .with_lines_held(cfg, held)
            .map_or(0, |m| m.held_lines())
    };
    // 101–102 (102 held) and the spring and dashpot 102–103 (103 free only along the line).
    assert_eq!(lines(&model, &cfg, &held), 3);
    // Started a micrometre off its line (103 moved across it), the span 102–103 would turn.
    let mut off = cfg.clone();
    off.u[1] = Vector2::new(-1.0, 1.0) * 1e-6;
    assert_eq!(lines(&model, &off, &held), 1);
    // And where 103 is free across the line, it could leave it.
    let released = released_end("springs_grounded_c", &["103"]);
    let free = model.constraints(&released, &released.steps[1]);
    assert_eq!(lines(&model, &cfg, &free), 1);
    // Under small rotations no element turns: nothing to hold.
    let small = Model::<Planar, false>::compile(&scene, 0.0);
    assert!(small.with_lines_held(&cfg, &held).is_none());
}

/// `id` with `nodes` free across the line in the dynamic step (where each is held in `uy`).
fn released_end(id: &str, nodes: &[&str]) -> Scene {
    let path = case::cases_dir().join(format!("{id}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    let at = text.find("kind = \"dynamic\"").expect("a dynamic step");
    let mut step = text[at..].to_string();
    for node in nodes {
        let line = format!("    {{ node = \"{node}\", dofs = [\"uy\"] }},\n");
        assert!(step.contains(&line), "{id}: {node} is not held in uy");
        step = step.replacen(&line, "", 1);
    }
    case::parse(&format!("{}{step}", &text[..at]), &path).unwrap_or_else(|e| panic!("{e}"))
}

fn explicit(scene: &Scene) -> (History, std::collections::BTreeMap<String, u64>) {
    let out = ExplicitEngine::finite()
        .run(scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id));
    (out.history, out.info.counters)
}

/// Largest difference of column `name` between two histories, over its peak in `a`.
fn relative_difference(a: &History, b: &History, name: &str) -> f64 {
    let (x, y) = (a.column(name).unwrap(), b.column(name).unwrap());
    let peak = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let largest = x
        .iter()
        .zip(&y)
        .fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()));
    // A column that never moves (102 in the grounded test) must not move in either run.
    if peak == 0.0 { largest } else { largest / peak }
}

#[test]
fn the_seed_cases_step_on_held_lines_as_they_would_turning() {
    // With the moving masses free across the line, the same motion is stepped with the
    // turning elements (nothing pushes a mass off the 45° line, whose components stay
    // equal): the two runs differ by the rounding of the turning force's stretch and
    // direction, an ulp or so per increment. Summed with random signs over the 20 000
    // increments that is √(2·10^4)·ε ≈ 3e-14 of the peak; the bound allows 30 times that
    // (measured: at most 1.3e-15).
    for (id, moving, held_lines, turning_lines) in [
        ("springs_grounded_c", &["103"][..], 3, Some(&1)),
        ("springs_n2n_c", &["102", "103"][..], 3, None),
    ] {
        let (held, counters) = explicit(&scene(id));
        assert_eq!(counters.get("held_lines"), Some(&held_lines), "{id}");
        let (turning, counters) = explicit(&released_end(id, moving));
        // In the grounded test 101–102 stays held: 102 does not move.
        assert_eq!(counters.get("held_lines"), turning_lines, "{id}");
        for name in ["u_end", "u_mid", "v_end", "v_mid"] {
            let d = relative_difference(&turning, &held, name);
            assert!(d <= 1e-12, "{id} {name}: {d:e}");
        }
    }
    // Small rotations never hold a line: none turns.
    let out = ExplicitEngine::small()
        .run(&scene("springs_n2n_c"), &RunSettings::default())
        .unwrap();
    assert_eq!(out.info.counters.get("held_lines"), None);
}

#[test]
fn ends_that_pass_each_other_take_the_turning_force() {
    // 103 thrown at 102 along the line: it passes 102, the span reverses, and the spring,
    // turning with it, pushes it on. The held-line run must follow it through as the run with
    // 103 free across the line does.
    let held_scene = grounded_c_thrown();
    let (held, counters) = explicit(&held_scene);
    assert_eq!(counters.get("held_lines"), Some(&3));
    // The same bound as for the seed cases (measured: 3.3e-16), through the crossing.
    let mut turning_scene = released_end("springs_grounded_c", &["103"]);
    turning_scene.initial_velocities = held_scene.initial_velocities.clone();
    let (turning, counters) = explicit(&turning_scene);
    assert_eq!(counters.get("held_lines"), Some(&1));
    let u = held.column("u_end").unwrap();
    let least = u.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    assert!(least < -2.0 * LENGTH, "103 passes 102: least u_end {least}");
    for name in ["u_end", "v_end"] {
        let d = relative_difference(&turning, &held, name);
        assert!(d <= 1e-12, "{name}: {d:e}");
    }
}

/// A 3D chain ground 0 – 1 – 2 along x with axial springs on both links and an axial dashpot
/// on the second, its particles held as `holds` says in its one dynamic step (node, dofs),
/// particle 1 in frame `frame_x` (its x axis; y_axis [0, 1, 0]); particle 2 starts at 1 m/s
/// along x unless a particle is held in every DOF.
fn chain_3d(holds: &[(&str, &str)], frame_x: [f64; 3]) -> Scene {
    let mut text = String::from(
        "id = \"line3d\"\ntitle = \"a 3D chain on x\"\nfamily = \"springs\"\ndimension = 3\n\n[time]\nincrement = 1.0e-3\n\n[output]\nrows = 201\n\n",
    );
    text += &springs_columns("2", "1", "[1.0, 0.0, 0.0]");
    text += &format!(
        "[[frames]]\nid = \"f\"\nx_axis = [{:e}, {:e}, {:e}]\ny_axis = [0.0, 1.0, 0.0]\n\n",
        frame_x[0], frame_x[1], frame_x[2]
    );
    text += "[[nodes]]\nid = \"0\"\nat = [0.0, 0.0, 0.0]\nfixed = true\n\n";
    text += "[[nodes]]\nid = \"1\"\nat = [1.0, 0.0, 0.0]\nframe = \"f\"\n\n";
    text += "[[nodes]]\nid = \"2\"\nat = [2.0, 0.0, 0.0]\n\n";
    for node in ["1", "2"] {
        text += &format!("[[masses]]\nnode = \"{node}\"\nmass = 1.0\n\n");
    }
    for (id, nodes) in [("s01", "[\"0\", \"1\"]"), ("s12", "[\"1\", \"2\"]")] {
        text += &format!(
            "[[springs]]\nid = \"{id}\"\nkind = \"axial\"\nnodes = {nodes}\nstiffness = 100.0\n\n"
        );
    }
    text +=
        "[[dashpots]]\nid = \"d12\"\nkind = \"axial\"\nnodes = [\"1\", \"2\"]\ndamping = 0.5\n\n";
    if !holds.iter().any(|(_, dofs)| dofs.contains("all")) {
        text += "[[initial_velocities]]\nnode = \"2\"\nvelocity = [1.0, 0.0, 0.0]\n\n";
    }
    text += "[[steps]]\nkind = \"dynamic\"\nduration = 0.2\nhold = [\n";
    for (node, dofs) in holds {
        text += &format!("    {{ node = \"{node}\", dofs = [{dofs}] }},\n");
    }
    text += "]\n";
    case::parse(&text, std::path::Path::new("line3d.toml"))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn in_space_a_line_is_held_only_where_both_ends_keep_to_it() {
    use crosscheck::engines::explicit::space::Spatial;
    let held_lines = |scene: &Scene| {
        let model = Model::<Spatial, true>::compile(scene, 0.0);
        let held = model.constraints(scene, &scene.steps[0]);
        model
            .with_lines_held(&model.initial_config(), &held)
            .map_or(0, |m| m.held_lines())
    };
    let across = "\"uy\", \"uz\"";
    let x = [1.0, 0.0, 0.0];
    // Both particles held across the line in y and z: all three elements.
    assert_eq!(held_lines(&chain_3d(&[("1", across), ("2", across)], x)), 3);
    // Particle 2 held in y only: in space it moves in a plane, so 1–2 (spring and dashpot)
    // can turn; 0–1 cannot.
    assert_eq!(
        held_lines(&chain_3d(&[("1", across), ("2", "\"uy\"")], x)),
        1
    );
    // Particle 1's frame tilted by 1e-12 rad off the line: it moves along the tilted axis,
    // off every element's line by far more than round-off.
    let tilted = [1.0, 1e-12, 0.0];
    assert_eq!(
        held_lines(&chain_3d(&[("1", across), ("2", across)], tilted)),
        0
    );
    // Both held in every DOF: nothing moves, and no line can turn.
    let all = "\"all\"";
    assert_eq!(held_lines(&chain_3d(&[("1", all), ("2", all)], x)), 3);
    // The engine runs it stepped on the held lines, and counts them.
    let out = ExplicitEngine::finite()
        .run(
            &chain_3d(&[("1", across), ("2", across)], x),
            &RunSettings::default(),
        )
        .unwrap();
    assert_eq!(out.info.counters.get("held_lines"), Some(&3));
}

#[test]
fn a_line_to_a_body_is_never_held() {
    // stress_inertia_ratio's axial spring joins two rigid bodies, which turn: its line turns
    // with them.
    let out = ExplicitEngine::finite()
        .run(
            &scene("stress/stress_inertia_ratio"),
            &RunSettings::default(),
        )
        .unwrap();
    assert_eq!(out.info.counters.get("held_lines"), None);
}
