//! `analytic` on the friction cases (`cases/friction/`) against their exact answers, computed
//! here from the physics each case's header states (and those headers' figures checked), and
//! its refusal of scenes outside its friction form.
//!
//! Tolerance: both sides evaluate closed forms in f64 from the same data; the module's phase
//! starts are sums of a few rounded terms and each row is a handful of flops (a sine and cosine
//! of an argument of at most π past a phase's start), so the two agree to a few ulps of each
//! column's scale. Every comparison allows 1e-13 of the column's scale (its peak, or the case's
//! characteristic size where the exact column is 0): ~450 ulps, far above the round-off
//! (measured: at most 7.4e-16 of the scale, the oscillator's velocity; the tests print it) and
//! far below any modelling error (a stop time off by one row moves a velocity by μ g × 1e-3,
//! ~5e-3 of v0).
mod common;
use common::*;
use crosscheck::case;
use crosscheck::engines::analytic::AnalyticEngine;
use crosscheck::engines::{Engine, EngineError, History, RunSettings};
use crosscheck::scene::Scene;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// g of every case.
const G: f64 = 9.81;
/// The allowed difference over a column's scale (see the module doc).
const ROUND_OFF: f64 = 1e-13;

fn case_path(id: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/friction/{id}.toml"))
}

fn friction_case(id: &str) -> Scene {
    case::load(&case_path(id)).unwrap_or_else(|e| panic!("{e}"))
}

/// A friction case with `edits` (from → to, each present in the file) applied to its text.
fn edited(id: &str, edits: &[(&str, &str)]) -> Scene {
    let path = case_path(id);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{id} has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    case::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// Compare every named column of `h` with `expected(t)` at every row: the largest difference
/// over the column's scale (`scale` where the exact column's peak is below it) must be within
/// [`ROUND_OFF`]. Prints and returns the largest relative difference.
fn assert_matches(
    h: &History,
    scale: &[(&str, f64)],
    expected: impl Fn(f64) -> Vec<(&'static str, f64)>,
) -> f64 {
    let times = col(h, "t");
    let want: Vec<Vec<(&str, f64)>> = times.iter().map(|&t| expected(t)).collect();
    let mut worst = 0.0f64;
    for (k, (name, _)) in want[0].iter().enumerate() {
        let got = col(h, name);
        let exact: Vec<f64> = want.iter().map(|w| w[k].1).collect();
        let floor = scale.iter().find(|s| s.0 == *name).map_or(0.0, |s| s.1);
        let size = peak(&exact).max(floor);
        assert!(size > 0.0, "column {name} needs a scale");
        let diff = max_diff(&got, &exact) / size;
        eprintln!("  {name}: largest difference {diff:.2e} of {size:.6}");
        assert!(diff <= ROUND_OFF, "{name}: {diff:e} of its scale {size}");
        worst = worst.max(diff);
    }
    worst
}

fn analytic(scene: &Scene) -> History {
    run(&AnalyticEngine, scene, RunSettings::default())
}

/// Slide and stop at constant deceleration μ g: (x, v) at t.
fn slide_stop(v0: f64, mu: f64, t: f64) -> (f64, f64) {
    let (stop, distance) = (v0 / (mu * G), v0 * v0 / (2.0 * mu * G));
    if t < stop {
        (v0 * t - 0.5 * mu * G * t * t, v0 - mu * G * t)
    } else {
        (distance, 0.0)
    }
}

/// The header's figures: t* = v0/(μ g) = 0.407747 s and d = v0²/(2 μ g) = 0.407747 m
/// (printed to 6 decimals: within 5e-7).
#[test]
fn slide_stop_figures_are_as_the_headers_say() {
    assert!((2.0 / (0.5 * G) - 0.407747).abs() < 5e-7);
    assert!((4.0 / (2.0 * 0.5 * G) - 0.407747).abs() < 5e-7);
}

#[test]
fn slide_stop_2d_stops_at_v0_over_mu_g() {
    let h = analytic(&friction_case("friction_slide_stop_2d"));
    assert_matches(&h, &[("rz", 1.0), ("ux", 0.4)], |t| {
        let (x, v) = slide_stop(2.0, 0.5, t);
        vec![
            ("rz", 0.0),
            ("ux", 0.0),
            ("ux_node", x),
            ("contact_force", G),
            ("vx_node", v),
        ]
    });
}

/// 3D: launched at 0°, 30° and 45° from x in the face's plane, the node slides along its launch
/// line and stops after the same time and distance.
#[test]
fn slide_stop_3d_is_isotropic() {
    for (id, degrees) in [
        ("friction_slide_stop_3d", 0.0f64),
        ("friction_isotropy_30", 30.0),
        ("friction_isotropy_45", 45.0),
    ] {
        eprintln!("{id}");
        let h = analytic(&friction_case(id));
        let cos = degrees.to_radians().cos();
        assert_matches(&h, &[("rz", 1.0), ("ux", 0.4), ("us_side", 0.4)], |t| {
            let (x, v) = slide_stop(2.0, 0.5, t);
            vec![
                ("rz", 0.0),
                ("ux", 0.0),
                ("ux_node", x * cos),
                ("contact_force", G),
                ("us_node", x),
                ("vs_node", v),
                ("us_side", 0.0),
            ]
        });
    }
}

/// θ = 35°, μ = 0.3: tan θ = 0.700208 > μ, so it slides at a = g (sin θ − μ cos θ) = 3.216020
/// pressed by g cos θ = 8.035882 (the header's figures, within 5e-7).
#[test]
fn incline_slip_slides_at_g_sin_minus_mu_cos() {
    let (theta, mu) = (35.0f64.to_radians(), 0.3);
    let a = G * (theta.sin() - mu * theta.cos());
    let normal = G * theta.cos();
    assert!((theta.tan() - 0.700208).abs() < 5e-7);
    assert!((a - 3.216020).abs() < 5e-7);
    assert!((normal - 8.035882).abs() < 5e-7);
    let h = analytic(&friction_case("friction_incline_slip"));
    assert_matches(&h, &[("rz", 1.0), ("ux", 0.4)], |t| {
        let us = 0.5 * a * t * t;
        vec![
            ("rz", 0.0),
            ("ux", 0.0),
            ("ux_node", -theta.cos() * us),
            ("contact_force", normal),
            ("us_node", us),
            ("vs_node", a * t),
        ]
    });
}

/// θ = 20°, μ = 0.5: tan θ = 0.363970 < μ; the tangential weight g sin θ = 3.355218 is under
/// μ g cos θ = 4.609192, so it stays, pressed by g cos θ = 9.218385 (the header's figures).
#[test]
fn incline_stick_stays() {
    let (theta, mu) = (20.0f64.to_radians(), 0.5);
    assert!((theta.tan() - 0.363970).abs() < 5e-7);
    assert!((G * theta.sin() - 3.355218).abs() < 5e-7);
    assert!((mu * G * theta.cos() - 4.609192).abs() < 5e-7);
    assert!((G * theta.cos() - 9.218385).abs() < 5e-7);
    let h = analytic(&friction_case("friction_incline_stick"));
    // The displacement columns must be exactly 0: any slip at all would be a modelling error.
    for name in ["rz", "ux", "ux_node", "us_node", "vs_node"] {
        assert!(col(&h, name).iter().all(|x| *x == 0.0), "{name}");
    }
    assert_matches(&h, &[], |_| vec![("contact_force", G * theta.cos())]);
}

/// The Coulomb-damped oscillator (m = 1, k = 100, ω = 10, v0 = 3, N = m g, δ = μ_k N/k),
/// from its turning points: the first half cycle, from x = 0 at v0 about the centre −δ, turns
/// at √(δ² + (v0/ω)²) − δ after (π/2 − atan(δ ω/v0))/ω; each next one starts at rest at x_i,
/// runs π/ω about the centre sgn(x_i) δ and turns at 2 sgn(x_i) δ − x_i, while
/// k |x_i| > μ_s N; then the node stays at its last turning point.
struct Oscillator {
    omega: f64,
    v0: f64,
    delta: f64,
    /// Turning points and the times the node reaches them.
    turns: Vec<(f64, f64)>,
}

impl Oscillator {
    fn new(mu_s: f64, mu_k: f64) -> Self {
        let (k, m, v0) = (100.0f64, 1.0f64, 3.0f64);
        let omega = (k / m).sqrt();
        let delta = mu_k * m * G / k;
        let first = (delta * delta + (v0 / omega).powi(2)).sqrt() - delta;
        let mut turns = vec![(first, (PI / 2.0 - (delta * omega / v0).atan()) / omega)];
        while let Some(&(x, t)) = turns.last().filter(|(x, _)| k * x.abs() > mu_s * m * G) {
            turns.push((2.0 * x.signum() * delta - x, t + PI / omega));
        }
        Oscillator {
            omega,
            v0,
            delta,
            turns,
        }
    }

    /// (x, v) at t.
    fn at(&self, t: f64) -> (f64, f64) {
        let w = self.omega;
        if t < self.turns[0].1 {
            let (s, c) = (w * t).sin_cos();
            return (
                -self.delta + self.delta * c + self.v0 / w * s,
                -self.delta * w * s + self.v0 * c,
            );
        }
        let i = self.turns.iter().rposition(|turn| turn.1 <= t).unwrap();
        let (x, start) = self.turns[i];
        if i + 1 == self.turns.len() {
            return (x, 0.0);
        }
        let centre = x.signum() * self.delta;
        let (s, c) = (w * (t - start)).sin_cos();
        (centre + (x - centre) * c, -w * (x - centre) * s)
    }
}

/// The turning points 0.27201, −0.21315, 0.15429, −0.09543, 0.03657, 0.02229 (the header's, to
/// its 5 decimals); the last inside |x| ≤ μ N/k, reached at t1 + 5π/ω = 1.718097 s (the header
/// says 6π/ω = 1.884956 s: the first half cycle, started at x = 0 moving, lasts
/// 0.147301 s, not π/ω).
#[test]
fn spring_stickslip_turns_and_stops_as_derived() {
    let osc = Oscillator::new(0.3, 0.3);
    let points: Vec<f64> = osc.turns.iter().map(|t| t.0).collect();
    let header = [0.27201, -0.21315, 0.15429, -0.09543, 0.03657, 0.02229];
    assert_eq!(points.len(), header.len(), "{points:?}");
    for (x, want) in points.iter().zip(header) {
        assert!((x - want).abs() < 5e-6, "{x} against {want}");
    }
    let (last, stop) = *osc.turns.last().unwrap();
    assert!(last.abs() <= osc.delta);
    assert!((stop - (osc.turns[0].1 + 5.0 * PI / osc.omega)).abs() < 1e-15);
    assert!((stop - 1.718097).abs() < 5e-7, "stop at {stop}");

    let h = analytic(&friction_case("friction_spring_stickslip"));
    assert_matches(&h, &[("rz", 1.0), ("ux", 0.3)], |t| {
        let (x, v) = osc.at(t);
        vec![
            ("rz", 0.0),
            ("ux", 0.0),
            ("ux_node", x),
            ("contact_force", G),
            ("vx_node", v),
        ]
    });
    // The history's own stop: moving at the last row before 1.718097 s, still from the next on.
    let (times, v) = (col(&h, "t"), col(&h, "vx_node"));
    let first_still = times.iter().position(|t| *t > stop).unwrap();
    assert!(v[first_still - 1] != 0.0);
    assert!(v[first_still..].iter().all(|v| *v == 0.0));
}

/// μ_s = 0.4 > μ_k = 0.3: the turning point 0.03657 lies inside |x| ≤ μ_s N/k = 0.03924, so
/// the node stops there, at t1 + 4π/ω, one half cycle early; the spring's ends swapped (and its
/// direction reversed) is the same spring.
#[test]
fn spring_stickslip_with_static_above_kinetic_stops_a_half_cycle_early() {
    let osc = Oscillator::new(0.4, 0.3);
    assert_eq!(osc.turns.len(), 5);
    assert!((osc.turns[4].0 - 0.03657).abs() < 5e-6);
    let mu = (
        "friction = 0.3",
        "static_friction = 0.4\nkinetic_friction = 0.3",
    );
    for spring in [
        ("nodes = [\"N\", \"G\"]", "nodes = [\"N\", \"G\"]"),
        (
            "nodes = [\"N\", \"G\"]\ndirection = [1.0, 0.0]",
            "nodes = [\"G\", \"N\"]\ndirection = [-1.0, 0.0]",
        ),
    ] {
        let h = analytic(&edited("friction_spring_stickslip", &[mu, spring]));
        assert_matches(&h, &[("rz", 1.0), ("ux", 0.3)], |t| {
            let (x, v) = osc.at(t);
            vec![("rz", 0.0), ("ux", 0.0), ("ux_node", x), ("vx_node", v)]
        });
    }
}

/// A constant tangential load P on a node at rest (μ_s = 0.5, μ_k = 0.2, N = m g): it stays for
/// P ≤ μ_s N = 4.905 and slides at (P − μ_k N)/m above it.
#[test]
fn tangential_load_breaks_away_only_above_static_friction() {
    for p in [4.9f64, 4.91, -6.0] {
        let load = format!("force = [{p:?}, -9.81]");
        let h = analytic(&edited(
            "friction_slide_stop_2d",
            &[
                ("velocity = [2.0, 0.0]", "velocity = [0.0, 0.0]"),
                (
                    "friction = 0.5",
                    "static_friction = 0.5\nkinetic_friction = 0.2",
                ),
                ("force = [0.0, -9.81]", load.as_str()),
            ],
        ));
        let a = if p.abs() <= 0.5 * G {
            0.0
        } else {
            p - p.signum() * 0.2 * G
        };
        eprintln!("P = {p}: a = {a}");
        assert_matches(&h, &[("ux_node", 1.0), ("vx_node", 1.0)], |t| {
            vec![
                ("ux_node", 0.5 * a * t * t),
                ("vx_node", a * t),
                ("contact_force", G),
            ]
        });
    }
}

/// The reason the analytic engine gives for refusing `scene` (it must refuse it).
fn refusal(scene: &Scene) -> String {
    match AnalyticEngine.run(scene, &RunSettings::default()) {
        Err(EngineError::Unsupported(why)) => why,
        Err(e) => panic!("{}: failed instead of refusing: {e}", scene.id),
        Ok(_) => panic!("{}: solved a scene outside the friction form", scene.id),
    }
}

/// Scenes outside the form are refused with the reason, not solved along a wrong line.
#[test]
fn scenes_outside_the_form_are_refused_with_the_reason() {
    // A ground node G and springs from the node to it, inserted before the block.
    let with_springs = |directions: &[&str]| {
        let mut text = "[[nodes]]\nid = \"G\"\nat = [1.0, 0.0, 0.0]\nfixed = true\n\n".to_string();
        for (i, d) in directions.iter().enumerate() {
            text += &format!(
                "[[springs]]\nid = \"s{i}\"\nkind = \"fixed_direction\"\nnodes = [\"N\", \"G\"]\ndirection = {d}\nstiffness = 100.0\n\n"
            );
        }
        edited(
            "friction_slide_stop_3d",
            &[("[[bodies]]", &(text + "[[bodies]]"))],
        )
    };
    let (along, across, normal) = ("[1.0, 0.0, 0.0]", "[0.0, 0.0, 1.0]", "[0.0, 1.0, 0.0]");
    let cases: Vec<(Scene, &str)> = vec![
        (with_springs(&[along, across]), "at most one spring"),
        (
            with_springs(&[across]),
            "the spring's direction and the initial velocity on one line (the slip direction would turn)",
        ),
        (
            with_springs(&[normal]),
            "a spring in the face's plane (`s0` is not)",
        ),
        (
            edited(
                "friction_isotropy_30",
                &[("force = [0.0, -9.81, 0.0]", "force = [1.0, -9.81, 0.0]")],
            ),
            "the loads' tangential part and the initial velocity on one line (the slip direction would turn)",
        ),
        (
            edited(
                "friction_slide_stop_2d",
                &[("force = [0.0, -9.81]", "force = [0.0, 9.81]")],
            ),
            "loads that press the particle into the face",
        ),
        (
            edited(
                "friction_slide_stop_2d",
                &[("dofs = [\"ux\", \"uy\", \"rz\"]", "dofs = [\"ux\", \"uy\"]")],
            ),
            "every body held in every DOF in every step (`block` is not)",
        ),
        (
            edited(
                "friction_spring_stickslip",
                &[(
                    "[[springs]]",
                    "[[dashpots]]\nid = \"d\"\nkind = \"fixed_direction\"\nnodes = [\"N\", \"G\"]\ndirection = [1.0, 0.0]\ndamping = 1.0\n\n[[springs]]",
                )],
            ),
            "no dashpot (`d`)",
        ),
        (
            edited(
                "friction_slide_stop_2d",
                &[("velocity = [2.0, 0.0]", "velocity = [2.0, 0.5]")],
            ),
            "an initial velocity in the face's plane",
        ),
    ];
    for (scene, reason) in cases {
        let why = refusal(&scene);
        eprintln!("{why}");
        assert!(why.contains(reason), "{why}\n does not say: {reason}");
    }
}
