//! Shared helpers for the integration tests.
#![allow(dead_code)]

use crosscheck::case;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, History, RunOutput, RunSettings};
use crosscheck::scene::{IncrementRule, Scene};
use std::collections::BTreeMap;
use std::path::Path;

/// The built-in engines that step in time, in report order: those the sweep and the stability
/// map run, and every engine the report judges (`tests/sweep.rs` checks that
/// [`crosscheck::run::registry::all`] says the same).
#[cfg(feature = "rapier")]
pub const STEPPING: [&str; 6] = [
    "explicit",
    "explicit_small",
    "rapier_f64",
    "rapier_f32",
    "rapier_f64_default",
    "rapier_f32_default",
];

/// The built-in engines that step in time, without the `rapier` feature.
#[cfg(not(feature = "rapier"))]
pub const STEPPING: [&str; 2] = ["explicit", "explicit_small"];

/// The built-in engines accuracy on request asks.
pub const ON_REQUEST: [&str; 2] = ["explicit", "explicit_small"];

/// The engines named, as the studies take them.
pub fn engines_named(names: &[&str]) -> Vec<Box<dyn Engine>> {
    names
        .iter()
        .map(|n| crosscheck::run::registry::named(n).unwrap_or_else(|| panic!("no engine {n}")))
        .collect()
}

/// Borrowed, as the studies take them.
pub fn refs(engines: &[Box<dyn Engine>]) -> Vec<&dyn Engine> {
    engines.iter().map(|e| e.as_ref()).collect()
}

/// The five springs seed cases.
pub const SPRINGS_CASES: [&str; 5] = [
    "springs_grounded_a",
    "springs_grounded_b",
    "springs_grounded_c",
    "springs_n2n_b",
    "springs_n2n_c",
];

/// The eight rigid-body seed cases.
pub const RIGID_CASES: [&str; 8] = [
    "rigid2d_pin_lumped",
    "rigid2d_pin_surface",
    "rigid2d_slide_lumped",
    "rigid2d_slide_surface",
    "rigid3d_pin_lumped",
    "rigid3d_pin_surface",
    "rigid3d_slide_lumped",
    "rigid3d_slide_surface",
];

/// System C's grounded test with 103 thrown at 102 along the 45° line at 60 m/s (½ m v² =
/// 46.6 J, against the 15 J the spring holds at either side's unit stretch): it passes 102, and
/// the span of the spring between them, held on its line, reverses.
pub fn grounded_c_thrown() -> Scene {
    let masses = "[[masses]]\nnode = \"102\"";
    let thrown = format!(
        "[[initial_velocities]]\nnode = \"103\"\nvelocity = [-42.42640687119285, -42.42640687119285]\n\n{masses}"
    );
    variant("springs_grounded_c", &[(masses, thrown.as_str())])
}

/// Load a shipped case by id.
pub fn scene(id: &str) -> Scene {
    case::load(&case::cases_dir().join(format!("{id}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Load a shipped stress case by id.
pub fn stress_scene(id: &str) -> Scene {
    case::load(&case::stress_dir(&case::cases_dir()).join(format!("{id}.toml")))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Every shipped case.
pub fn all_scenes() -> Vec<Scene> {
    case::discover(&case::cases_dir())
        .unwrap()
        .iter()
        .map(|f| case::load(f).unwrap_or_else(|e| panic!("{e}")))
        .collect()
}

/// Run an engine with settings, panicking with the case id on failure.
pub fn run(engine: &dyn Engine, scene: &Scene, settings: RunSettings) -> History {
    engine
        .run(scene, &settings)
        .unwrap_or_else(|e| panic!("{} / {}: {e}", scene.id, engine.name()))
        .history
}

/// Run the finite-rotation explicit engine with a given increment.
pub fn explicit_at(scene: &Scene, h: f64) -> History {
    run(
        &ExplicitEngine::finite(),
        scene,
        RunSettings {
            increment: Some(IncrementRule::Given(h)),
            ..Default::default()
        },
    )
}

/// A column's values.
pub fn col(h: &History, name: &str) -> Vec<f64> {
    h.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

/// Largest |x − exact(t)| of column `name` over the rows whose time t satisfies `when`.
pub fn largest_error(
    h: &History,
    name: &str,
    exact: impl Fn(f64) -> f64,
    when: impl Fn(f64) -> bool,
) -> f64 {
    let (t, x) = (col(h, "t"), col(h, name));
    t.iter()
        .zip(&x)
        .filter(|(t, _)| when(**t))
        .map(|(t, x)| (x - exact(*t)).abs())
        .fold(0.0, f64::max)
}

/// Largest absolute value.
pub fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Largest absolute difference.
pub fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// The contract columns of a scene that are not identically zero.
pub fn live_columns(scene: &Scene) -> Vec<String> {
    crosscheck::contract::columns(scene.family)
        .iter()
        .zip(&scene.columns)
        .filter(|(_, c)| !matches!(c.probe, crosscheck::scene::Probe::Zero { .. }))
        .map(|(n, _)| n.to_string())
        .collect()
}

/// Every file under `dir`, relative path → bytes.
pub fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().display().to_string(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// A shipped case with some of its text replaced (each pattern must occur).
pub fn variant(id: &str, edits: &[(&str, &str)]) -> Scene {
    let path = case::cases_dir().join(format!("{id}.toml"));
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{id}: no `{from}`");
        text = text.replace(from, to);
    }
    case::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// Proptest's configuration for `cases` cases drawn from a fixed seed, so that every run (CI's
/// included) draws the same inputs and a test either always passes or always fails.
/// `PROPTEST_CASES` and `PROPTEST_RNG_SEED` in the environment draw more or other inputs (a
/// deeper run, as the bounds' margins were checked with).
pub fn proptest_config(cases: u32) -> proptest::test_runner::Config {
    let env = |name| std::env::var(name).ok().and_then(|v| v.parse::<u64>().ok());
    proptest::test_runner::Config {
        cases: env("PROPTEST_CASES").map_or(cases, |c| c as u32),
        rng_seed: proptest::test_runner::RngSeed::Fixed(env("PROPTEST_RNG_SEED").unwrap_or(11)),
        ..proptest::test_runner::Config::default()
    }
}

/// The springs family's contract columns as case text: `u_end`, `u_mid`, `v_end`, `v_mid`,
/// the displacements and velocities of nodes `end` and `mid` along `direction` (TOML array
/// text, such as `[1.0, 0.0]`).
pub fn springs_columns(end: &str, mid: &str, direction: &str) -> String {
    [
        ("u_end", "displacement", end),
        ("u_mid", "displacement", mid),
        ("v_end", "velocity", end),
        ("v_mid", "velocity", mid),
    ]
    .iter()
    .map(|(name, probe, node)| {
        format!(
            "[[output.columns]]\nname = \"{name}\"\n{probe} = \"{node}\"\ndirection = {direction}\n\n"
        )
    })
    .collect()
}

/// A run's work counter `name` (0 where the run did not report it).
pub fn counter(out: &RunOutput, name: &str) -> u64 {
    out.info.counters.get(name).copied().unwrap_or(0)
}

/// The increments of a single dynamic step of `steps` increments, with a row every `stride`,
/// that a batched step (the affine step, the turning step) may take: every one but the first
/// (which starts the half-step velocity), the rows and the step's last two (the last one's
/// acceleration would start a next step).
pub fn eligible(steps: u64, stride: u64) -> u64 {
    (1..=steps - 2).filter(|n| n % stride != 0).count() as u64
}

/// The largest difference between the two runs over every column, each over its own peak
/// (the energy balance, a difference of energies near zero, over the peak of the kinetic and
/// elastic energy).
pub fn largest_difference(a: &RunOutput, b: &RunOutput) -> (f64, String) {
    let energy: Vec<f64> = col(&a.history, "e_kinetic")
        .iter()
        .zip(col(&a.history, "e_elastic"))
        .map(|(k, e)| k + e)
        .collect();
    let mut worst = (0.0, String::new());
    for name in a.history.columns.iter().skip(1) {
        let (x, y) = (col(&a.history, name), col(&b.history, name));
        let scale = if name == "e_balance" {
            peak(&energy)
        } else {
            peak(&x)
        };
        let d = if scale == 0.0 {
            max_diff(&x, &y)
        } else {
            max_diff(&x, &y) / scale
        };
        if d > worst.0 {
            worst = (d, name.clone());
        }
    }
    worst
}

/// The contact force's difference between two runs over its peak may be the positions'
/// round-off (`round_off` of their peak) times the penalty's leverage: the contact force is
/// k_p times a penetration that is a small fraction of the motion, so a rounding of the
/// positions moves it by k_p·δ, against a peak of k_p·(peak penetration). The bound is
/// round_off · k_p · (peak of the displacement columns) / (peak contact force).
pub fn contact_bound(out: &RunOutput, displacements: &[&str], round_off: f64) -> f64 {
    let penalty = out.info.penalty_stiffness.expect("a contact scene");
    let motion = displacements
        .iter()
        .map(|name| peak(&col(&out.history, name)))
        .fold(0.0, f64::max);
    round_off * penalty * motion / peak(&col(&out.history, "contact_force"))
}

/// The largest difference between the two runs over the columns other than the contact force
/// (see [`largest_difference`]), and the contact force's over its peak.
pub fn differences(a: &RunOutput, b: &RunOutput) -> ((f64, String), f64) {
    let (mut a, mut b) = (a.clone(), b.clone());
    let force = |out: &mut RunOutput| {
        let i = out
            .history
            .columns
            .iter()
            .position(|c| c == "contact_force");
        let i = i.expect("a contact_force column");
        out.history.columns.remove(i);
        let mut column = Vec::new();
        for row in &mut out.history.rows {
            column.push(row.remove(i));
        }
        column
    };
    let (fa, fb) = (force(&mut a), force(&mut b));
    let contact = max_diff(&fa, &fb) / peak(&fb);
    (largest_difference(&a, &b), contact)
}

/// The number in `text` between `marker` and the next `end` (a time or a figure an error
/// message names).
pub fn number_after(text: &str, marker: &str, end: char) -> f64 {
    text.split(marker)
        .nth(1)
        .and_then(|rest| rest.split(end).next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no number after `{marker}` in: {text}"))
}

/// Each named column of `out` against `exact(t)` (one value per name) at every row: within
/// `history` of the exact peak, or within `zero` where the exact column is zero.
pub fn assert_history(
    out: &RunOutput,
    names: &[&str],
    (history, zero): (f64, f64),
    exact: impl Fn(f64) -> Vec<f64>,
) {
    let h = &out.history;
    let t = h.column("t").unwrap();
    let expected: Vec<Vec<f64>> = t.iter().map(|t| exact(*t)).collect();
    for (i, name) in names.iter().enumerate() {
        let got = h.column(name).unwrap_or_else(|| panic!("no column {name}"));
        let peak = expected.iter().fold(0.0_f64, |m, e| m.max(e[i].abs()));
        let error = got
            .iter()
            .zip(&expected)
            .fold(0.0_f64, |m, (g, e)| m.max((g - e[i]).abs()));
        if peak == 0.0 {
            println!("{name}: exact 0, largest |value| {error:.2e}");
            assert!(error <= zero, "{name}: {error:e} where it is exactly 0");
        } else {
            println!("{name}: error {:.2e} of the peak {peak:.6}", error / peak);
            assert!(
                error <= history * peak,
                "{name}: {:e} of the peak",
                error / peak
            );
        }
    }
}

/// A measure against its exact value, within `tolerance` (absolute).
pub fn assert_measure(out: &RunOutput, name: &str, exact: f64, tolerance: f64) {
    let got = *out
        .info
        .measures
        .get(name)
        .unwrap_or_else(|| panic!("no measure {name}"));
    println!(
        "{name}: {got:.15} against {exact:.15} ({:.1e})",
        got - exact
    );
    assert!(
        (got - exact).abs() <= tolerance,
        "{name}: {got} against {exact}"
    );
}
