//! `analytic` on the friction cases (`cases/friction/`) against their exact answers, computed
//! here from the physics each case's header states (and those headers' figures checked), loads
//! ramped by amplitudes against closed forms written here and, with a spring, against RK4 on the
//! piecewise ODE (its own tolerance stated there), and its refusal of scenes outside its
//! friction form.
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

/// The ramp case's data: pull r t (r = 10 N/s) on m = 1 pressed by N = m g, μ_s = 0.5,
/// μ_k = 0.3.
const RAMP: (f64, f64, f64) = (10.0, 0.5, 0.3);

/// The ramp case's exact (x, v) at t (its header): stuck until t_b = μ_s N/r, then
/// m ẍ = r t − μ_k N.
fn ramp_breakaway(t: f64) -> (f64, f64) {
    let (r, mu_s, mu_k) = RAMP;
    let t_b = mu_s * G / r;
    if t <= t_b {
        return (0.0, 0.0);
    }
    let d = t - t_b;
    (
        r / 6.0 * (t.powi(3) - t_b.powi(3)) - 0.5 * r * t_b * t_b * d - 0.5 * mu_k * G * d * d,
        0.5 * r * (t * t - t_b * t_b) - mu_k * G * d,
    )
}

/// The header's figures: t_b = 0.4905 s, x(1) = 0.475093, v(1) = 2.297590 (to its 6
/// decimals: within 5e-7).
#[test]
fn ramp_breakaway_figures_are_as_the_header_says() {
    let (r, mu_s, _) = RAMP;
    assert!((mu_s * G / r - 0.4905).abs() < 1e-15);
    let (x, v) = ramp_breakaway(1.0);
    eprintln!("x(1) = {x:.9}, v(1) = {v:.9}");
    assert!((x - 0.475093).abs() < 5e-7, "x(1) = {x}");
    assert!((v - 2.297590).abs() < 5e-7, "v(1) = {v}");
}

/// The ramp case: stuck until the pull reaches μ_s N, then the cubic slide of its header.
#[test]
fn ramp_breakaway_sticks_until_mu_s_n_then_slides_as_derived() {
    let h = analytic(&friction_case("friction_ramp_breakaway"));
    assert_matches(&h, &[("rz", 1.0), ("ux", 0.5)], |t| {
        let (x, v) = ramp_breakaway(t);
        vec![
            ("rz", 0.0),
            ("ux", 0.0),
            ("ux_node", x),
            ("contact_force", G),
            ("vx_node", v),
        ]
    });
    // Still at every row up to t_b, moving from the next on.
    let (times, v) = (col(&h, "t"), col(&h, "vx_node"));
    let first_moving = times.iter().position(|t| *t > 0.4905).unwrap();
    assert!(v[..first_moving].iter().all(|v| *v == 0.0));
    assert!(v[first_moving..].iter().all(|v| *v > 0.0));
}

/// The ramp turned down at t₁ = 0.7 s (pull 7 − 10 (t − t₁) from there, to −8 at 2.2 s): the
/// node breaks away at t_b = 0.4905 s as before; from t₁ it slides at ẍ = g₀ − 10 τ
/// (g₀ = 7 − μ_k N, τ = t − t₁), stops where v₁ + g₀ τ − 5 τ² = 0 (τ_s = 0.945 s, the pull
/// −2.45 then, inside μ_s N), sticks until the pull reaches −μ_s N at τ = (7 + μ_s N)/10 and
/// slides back at ẍ = −(μ_s − μ_k) N − 10 (t − t_b2).
#[test]
fn a_ramp_down_stops_the_node_sticks_it_and_breaks_it_away_backwards() {
    let (r, mu_s, mu_k) = RAMP;
    let t1 = 0.7;
    let (x1, v1) = ramp_breakaway(t1);
    let g0 = r * t1 - mu_k * G;
    let tau_s = (g0 + (g0 * g0 + 4.0 * 5.0 * v1).sqrt()) / (2.0 * 5.0);
    let slide = |tau: f64| {
        (
            x1 + v1 * tau + 0.5 * g0 * tau * tau - 5.0 * tau.powi(3) / 3.0,
            v1 + g0 * tau - 5.0 * tau * tau,
        )
    };
    let x_s = slide(tau_s).0;
    let t_b2 = t1 + (r * t1 + mu_s * G) / r;
    let pull_at_stop = r * t1 - r * tau_s;
    eprintln!(
        "stop at {:.6} (x {x_s:.6}, pull {pull_at_stop:.4}), back at {t_b2:.6}",
        t1 + tau_s
    );
    assert!(pull_at_stop.abs() < mu_s * G && t1 + tau_s < t_b2 && t_b2 < 2.2);
    let h = analytic(&edited(
        "friction_ramp_breakaway",
        &[
            (
                "amplitude = [[0.0, 0.0], [2.0, 20.0]]",
                "amplitude = [[0.0, 0.0], [0.7, 7.0], [2.2, -8.0]]",
            ),
            ("duration = 1.0", "duration = 2.2"),
            ("rows = 501", "rows = 1101"),
        ],
    ));
    assert_matches(&h, &[], |t| {
        let (x, v) = if t <= t1 {
            ramp_breakaway(t)
        } else if t <= t1 + tau_s {
            slide(t - t1)
        } else if t <= t_b2 {
            (x_s, 0.0)
        } else {
            let d = t - t_b2;
            let a = -(mu_s - mu_k) * G;
            (
                x_s + 0.5 * a * d * d - r * d.powi(3) / 6.0,
                a * d - 0.5 * r * d * d,
            )
        };
        vec![("ux_node", x), ("vx_node", v), ("contact_force", G)]
    });
    let (times, v) = (col(&h, "t"), col(&h, "vx_node"));
    let still: Vec<f64> = times
        .iter()
        .zip(&v)
        .filter(|(t, v)| **t > 1.0 && **v == 0.0)
        .map(|(t, _)| *t)
        .collect();
    assert!(still.first().unwrap() - (t1 + tau_s) < 2e-3 && t_b2 - still.last().unwrap() < 2e-3);
}

/// The slide-stop case with its weight eased off, N(t) = m g (1 − t/2) over the first second:
/// ẍ = −μ g (1 − t/2) stops it where 2 − μ g (t − t²/4) = 0, at t_s = 2 (1 − √(1 − 2/(μ g)))
/// = 0.4608 s, and the falling normal force keeps it there (its tangential load is 0).
#[test]
fn a_normal_load_that_eases_off_lowers_friction_with_it() {
    let mu_g = 0.5 * G;
    let t_s = 2.0 * (1.0 - (1.0 - 2.0 / mu_g).sqrt());
    eprintln!("stop at {t_s:.6}");
    let motion = |t: f64| {
        let t = t.min(t_s);
        (
            2.0 * t - mu_g * (0.5 * t * t - t.powi(3) / 12.0),
            2.0 - mu_g * (t - 0.25 * t * t),
        )
    };
    let h = analytic(&edited(
        "friction_slide_stop_2d",
        &[(
            "force = [0.0, -9.81]",
            "force = [0.0, -9.81]\namplitude = [[0.0, 1.0], [1.0, 0.5]]",
        )],
    ));
    assert_matches(&h, &[("rz", 1.0), ("ux", 0.4)], |t| {
        let (x, v) = motion(t);
        vec![
            ("rz", 0.0),
            ("ux", 0.0),
            ("ux_node", x),
            ("contact_force", G * (1.0 - 0.5 * t)),
            ("vx_node", if t < t_s { v } else { 0.0 }),
        ]
    });
}

/// One particle on a line under Coulomb friction, pull P(t) and spring k, integrated by RK4 at a
/// fixed step, its events located by bisection: a slip's stop (the step length at which s v
/// reaches 0) and a stick's break-away (the time at which |P − k x| passes μ_s N). At rest it
/// sticks while |P − k x| ≤ μ_s N, else slips along sgn(P − k x).
struct Rk4Line<P: Fn(f64) -> f64> {
    mass: f64,
    stiffness: f64,
    normal: f64,
    mu_s: f64,
    mu_k: f64,
    pull: P,
}

impl<P: Fn(f64) -> f64> Rk4Line<P> {
    /// One RK4 step of length h from (t, x, v), slipping along s.
    fn step(&self, s: f64, (t, x, v): (f64, f64, f64), h: f64) -> (f64, f64) {
        let acc = |t: f64, x: f64| {
            ((self.pull)(t) - self.stiffness * x - s * self.mu_k * self.normal) / self.mass
        };
        let (k1x, k1v) = (v, acc(t, x));
        let (k2x, k2v) = (v + 0.5 * h * k1v, acc(t + 0.5 * h, x + 0.5 * h * k1x));
        let (k3x, k3v) = (v + 0.5 * h * k2v, acc(t + 0.5 * h, x + 0.5 * h * k2x));
        let (k4x, k4v) = (v + h * k3v, acc(t + h, x + h * k3x));
        (
            x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    }

    /// The slip direction at rest at x at t, if it does not stick.
    fn slips(&self, t: f64, x: f64) -> Option<f64> {
        let net = (self.pull)(t) - self.stiffness * x;
        (net.abs() > self.mu_s * self.normal).then(|| net.signum())
    }

    /// Advance (t, x, v) with its slip direction (None: stuck) to `to`.
    fn advance(&self, state: &mut (f64, f64, f64), slip: &mut Option<f64>, to: f64) {
        while state.0 < to {
            let (t, x, _) = *state;
            match *slip {
                Some(s) => {
                    let (x1, v1) = self.step(s, *state, to - t);
                    if s * v1 > 0.0 {
                        *state = (to, x1, v1);
                        continue;
                    }
                    let (mut lo, mut hi) = (0.0, to - t);
                    for _ in 0..200 {
                        let mid = 0.5 * (lo + hi);
                        if s * self.step(s, *state, mid).1 > 0.0 {
                            lo = mid
                        } else {
                            hi = mid
                        }
                    }
                    *state = (t + hi, self.step(s, *state, hi).0, 0.0);
                    *slip = self.slips(state.0, state.1);
                }
                None => {
                    if self.slips(to, x).is_none() {
                        state.0 = to;
                        continue;
                    }
                    let (mut lo, mut hi) = (t, to);
                    for _ in 0..200 {
                        let mid = 0.5 * (lo + hi);
                        if self.slips(mid, x).is_some() {
                            hi = mid
                        } else {
                            lo = mid
                        }
                    }
                    state.0 = hi;
                    *slip = self.slips(hi, x);
                }
            }
        }
    }

    /// (x, v) at each of `times` (from 0, increasing) from rest-or-slip at v0, with `substeps`
    /// RK4 steps between consecutive times (each kink of P must be one of `times`).
    fn history(&self, v0: f64, times: &[f64], substeps: usize) -> Vec<(f64, f64)> {
        let mut state = (0.0, 0.0, v0);
        let mut slip = if v0 != 0.0 {
            Some(v0.signum())
        } else {
            self.slips(0.0, 0.0)
        };
        let mut out = vec![(0.0, v0)];
        for pair in times.windows(2) {
            for i in 1..=substeps {
                let to = pair[0] + (pair[1] - pair[0]) * i as f64 / substeps as f64;
                self.advance(&mut state, &mut slip, to);
            }
            out.push((state.1, state.2));
        }
        out
    }
}

/// The Coulomb-damped oscillator (m = 1, k = 100, v0 = 3, N = m g) pulled by
/// P(t) = c t to c N at 1 s, then down at c N/s (to −c/2 N at 2.5 s), against RK4 in the test at
/// 20 steps per row (h = 1e-4 s):
///
/// - c = 40, μ_s = 0.4 > μ_k = 0.3: slips, stops, sticks and break-aways back and forth, a slip
///   across the kink, each in the closed form's harmonic about a centre moving at ±c/k;
/// - c = 40, μ_s = μ_k = 0.3: break-aways at zero net force, whose slips touch v = 0 a full
///   period later;
/// - c = 400: the centre moves at 4 m/s, faster than the oscillation about it: slips that never
///   stop (|p| > R), one reversal at the kink.
///
/// Tolerance: RK4's global error on the harmonic phases is ~(ω h)⁴ ω T/120 of the amplitude
/// (ω h = 1e-3, ω T = 25: 2e-13), RK4 is exact on the stick's linear break-away condition
/// and bisection puts each event within an ulp of the RK4 solution's, where a stop's position
/// is stationary (v = 0) and a break-away's start from rest; round-off over 25,000 steps is
/// ~1e-12 (measured: at most 2.9e-14 of the peak). 1e-11 of each column's peak is above both
/// and far below any modelling error (an event one row off moves v by ~μ g × 2e-3 = 6e-3, 1e-3
/// of its peak).
#[test]
fn a_ramped_pull_on_the_spring_case_matches_rk4_on_the_piecewise_ode() {
    for (c, mu_s, friction, stuck_rows) in [
        (
            40.0,
            0.4,
            "static_friction = 0.4\nkinetic_friction = 0.3",
            10,
        ),
        (40.0, 0.3, "friction = 0.3", 10),
        (
            400.0,
            0.4,
            "static_friction = 0.4\nkinetic_friction = 0.3",
            0,
        ),
    ] {
        let amplitude = format!(
            "[[loads]]\nnode = \"N\"\nforce = [1.0, 0.0]\namplitude = [[0.0, 0.0], [1.0, {c:?}], [2.5, {:?}]]\n\n[[steps]]",
            -0.5 * c
        );
        let h = analytic(&edited(
            "friction_spring_stickslip",
            &[("friction = 0.3", friction), ("[[steps]]", &amplitude)],
        ));
        let rk4 = Rk4Line {
            mass: 1.0,
            stiffness: 100.0,
            normal: G,
            mu_s,
            mu_k: 0.3,
            pull: |t: f64| if t <= 1.0 { c * t } else { c - c * (t - 1.0) },
        };
        let times = col(&h, "t");
        let want = rk4.history(3.0, &times, 20);
        let (x, v) = (col(&h, "ux_node"), col(&h, "vx_node"));
        let stuck = v.iter().filter(|v| **v == 0.0).count();
        let rows: Vec<f64> = want.iter().map(|w| w.0).collect();
        let speeds: Vec<f64> = want.iter().map(|w| w.1).collect();
        let (dx, dv) = (
            max_diff(&x, &rows) / peak(&rows),
            max_diff(&v, &speeds) / peak(&speeds),
        );
        eprintln!(
            "c = {c}, mu_s = {mu_s}: {stuck} rows stuck; x errs {dx:.2e}, v {dv:.2e} of the peak"
        );
        assert!(stuck >= stuck_rows, "the pull should make it stick");
        assert!(dx < 1e-11 && dv < 1e-11, "{dx:e}, {dv:e}");
    }
}

/// The slide-stop node (v0 = 2, μ_s = 0.5, μ_k = 0.3, N = m g) against a pull
/// P(t) = −8 + 10 t (to 2 N at 1 s, held): ẍ = P − μ_k N stops it at the smaller root t₁ of
/// 2 − (8 + μ_k N) t + 5 t² = 0; there |P| > μ_s N, so it slides back at once, at
/// ẍ = P + μ_k N, and stops again (from rest: after τ = 2 (8 − μ_k N − 10 t₁)/10), where
/// |P| < μ_s N: it stays, the pull held at 2 N from 1 s.
#[test]
fn a_pull_that_reverses_the_node_and_eases_off_stops_it_from_rest() {
    let (mu_s, mu_k) = (0.5, 0.3);
    let b = 8.0 + mu_k * G;
    let t1 = (b - (b * b - 40.0).sqrt()) / 10.0;
    let x1 = 2.0 * t1 - 0.5 * b * t1 * t1 + 10.0 * t1.powi(3) / 6.0;
    let a1 = -8.0 + 10.0 * t1 + mu_k * G;
    let tau = -2.0 * a1 / 10.0;
    let t2 = t1 + tau;
    let back = |d: f64| {
        (
            x1 + 0.5 * a1 * d * d + 10.0 * d.powi(3) / 6.0,
            a1 * d + 5.0 * d * d,
        )
    };
    let x2 = back(tau).0;
    eprintln!(
        "stops at {t1:.6} (pull {:.4}), back to rest at {t2:.6} (x {x2:.6})",
        -8.0 + 10.0 * t1
    );
    assert!((-8.0 + 10.0 * t1).abs() > mu_s * G && (-8.0 + 10.0 * t2).abs() < mu_s * G);
    assert!(a1 < 0.0 && t2 < 1.0);
    let h = analytic(&edited(
        "friction_slide_stop_2d",
        &[
            (
                "friction = 0.5",
                "static_friction = 0.5\nkinetic_friction = 0.3",
            ),
            (
                "[[initial_velocities]]",
                "[[loads]]\nnode = \"N\"\nforce = [1.0, 0.0]\namplitude = [[0.0, -8.0], [1.0, 2.0]]\n\n[[initial_velocities]]",
            ),
            ("duration = 0.6", "duration = 1.2"),
            ("rows = 601", "rows = 1201"),
        ],
    ));
    assert_matches(&h, &[], |t| {
        let (x, v) = if t <= t1 {
            (
                2.0 * t - 0.5 * b * t * t + 10.0 * t.powi(3) / 6.0,
                2.0 - b * t + 5.0 * t * t,
            )
        } else if t <= t2 {
            back(t - t1)
        } else {
            (x2, 0.0)
        };
        vec![("ux_node", x), ("vx_node", v), ("contact_force", G)]
    });
}

/// Loads that vary in time outside the form are refused with the reason.
#[test]
fn ramps_outside_the_form_are_refused_with_the_reason() {
    let ramped = |force: &str, amplitude: &str| {
        format!(
            "[[loads]]\nnode = \"N\"\nforce = {force}\namplitude = {amplitude}\n\n[[initial_velocities]]"
        )
    };
    let cases: Vec<(Scene, &str)> = vec![
        (
            edited(
                "friction_slide_stop_2d",
                &[
                    ("friction = 0.5", ""),
                    (
                        "force = [0.0, -9.81]",
                        "force = [0.0, -9.81]\namplitude = [[0.0, 1.0], [1.0, 0.5]]",
                    ),
                ],
            ),
            "a load that varies in time (an amplitude) in a scene without friction",
        ),
        (
            edited(
                "friction_ramp_breakaway",
                &[(
                    "force = [0.0, -9.81]",
                    "force = [0.0, -9.81]\namplitude = [[0.0, 1.0], [0.5, -1.0], [1.0, 1.0]]",
                )],
            ),
            "loads that press the particle into the face throughout (at t = 0.5, their normal component is 9.81e0 outward)",
        ),
        (
            edited(
                "friction_slide_stop_3d",
                &[(
                    "[[initial_velocities]]",
                    &ramped("[0.0, 0.0, 1.0]", "[[0.0, 0.0], [1.0, 1.0]]"),
                )],
            ),
            "a ramped load's tangential part and the initial velocity on one line",
        ),
        (
            edited(
                "friction_slide_stop_3d",
                &[
                    ("force = [0.0, -9.81, 0.0]", "force = [1.0, -9.81, 0.0]"),
                    ("velocity = [2, 0.0, 0]", "velocity = [0, 0.0, 0]"),
                    (
                        "[[initial_velocities]]",
                        &ramped("[0.0, -1.0, 1.0]", "[[0.0, 0.0], [1.0, 1.0]]"),
                    ),
                ],
            ),
            "the loads' tangential part and a ramped load's tangential part on one line",
        ),
    ];
    for (scene, reason) in cases {
        let why = refusal(&scene);
        eprintln!("{why}");
        assert!(why.contains(reason), "{why}\n does not say: {reason}");
    }
}

/// A ball or disc launched at v0 without spin, slipping at μ g until its contact point stops
/// slipping at t* = v0 / (μ g (1 + m R²/I)), then rolling at v0 − μ g t*: centre (x, v) and
/// rotation about z (negative: rolling along +x turns it clockwise) at t, with the spin-up
/// rate μ m g R / I written out by hand.
fn slide_to_roll(v0: f64, mu: f64, radius: f64, inertia_over_mass: f64, t: f64) -> [f64; 3] {
    let spin_up = mu * G * radius / inertia_over_mass;
    let roll = v0 / (mu * G + spin_up * radius);
    let slip = |t: f64| {
        [
            v0 * t - 0.5 * mu * G * t * t,
            v0 - mu * G * t,
            -0.5 * spin_up * t * t,
        ]
    };
    if t < roll {
        return slip(t);
    }
    let [x, v, phi] = slip(roll);
    [x + v * (t - roll), v, phi - v / radius * (t - roll)]
}

/// The headers' figures: the disc (I = m R²/2) rolls from v0/(3 μ g) = 0.509684 s at 2 v0/3 = 2,
/// turned by 1.019 rad, 2.58 rad at 0.9 s; the ball (I = 2 m R²/5) from 2 v0/(7 μ g) =
/// 0.436872 s at 5 v0/7 = 2.142857, turned by 0.936 rad, 2.92 rad at 0.9 s (printed to the
/// digits shown: within half a unit of the last).
#[test]
fn roll_figures_are_as_the_headers_say() {
    let (v0, mu, r) = (3.0, 0.2, 0.5);
    let disc_roll = v0 / (3.0 * mu * G);
    assert!((disc_roll - 0.509684).abs() < 5e-7);
    let [_, v, phi] = slide_to_roll(v0, mu, r, 0.125, disc_roll);
    assert!(
        (v - 2.0).abs() < 1e-12 && (phi + 1.019).abs() < 5e-4,
        "{v} {phi}"
    );
    assert!((slide_to_roll(v0, mu, r, 0.125, 0.9)[2] + 2.58).abs() < 5e-3);
    let ball_roll = 2.0 * v0 / (7.0 * mu * G);
    assert!((ball_roll - 0.436872).abs() < 5e-7);
    let [_, v, phi] = slide_to_roll(v0, mu, r, 0.1, ball_roll);
    assert!(
        (v - 2.142857).abs() < 5e-7 && (phi + 0.936).abs() < 5e-4,
        "{v} {phi}"
    );
    assert!((slide_to_roll(v0, mu, r, 0.1, 0.9)[2] + 2.92).abs() < 5e-3);
}

/// The disc and the ball slide, then roll: `analytic` against the hand-written answer, its centre
/// on the face (uy_node 0) and, in 3D, on its launch line with its spin about z only.
#[test]
fn a_disc_and_a_ball_launched_sliding_start_rolling() {
    for (id, inertia, turn) in [
        ("friction_roll_2d", 0.125, "rz_disc"),
        ("friction_roll_3d", 0.1, "rz_ball"),
    ] {
        eprintln!("{id}");
        let h = analytic(&friction_case(id));
        let scales = [
            ("rz", 1.0),
            ("ux", 0.5),
            ("uy_node", 0.5),
            ("uz_node", 0.5),
            ("rx_ball", 1.0),
        ];
        assert_matches(&h, &scales, |t| {
            let [x, v, phi] = slide_to_roll(3.0, 0.2, 0.5, inertia, t);
            let mut columns = vec![
                ("rz", 0.0),
                ("ux", 0.0),
                ("ux_node", x),
                ("contact_force", G),
                ("vx_node", v),
                ("uy_node", 0.0),
                (turn, phi),
            ];
            if id.ends_with("3d") {
                columns.extend([("uz_node", 0.0), ("rx_ball", 0.0)]);
            }
            columns
        });
    }
}

/// Outside the rolling form: a ball whose rotation is read about an axis neither along its spin
/// nor across it is refused, with the reason.
#[test]
fn a_rolling_scene_outside_the_form_is_refused() {
    let scene = edited(
        "friction_roll_3d",
        &[("axis = [1.0, 0.0, 0.0]", "axis = [0.6, 0.0, 0.8]")],
    );
    match AnalyticEngine.run(&scene, &RunSettings::default()) {
        Err(EngineError::Unsupported(why)) => assert!(
            why.contains("the ball's rotation read about its spin axis or across it"),
            "{why}"
        ),
        other => panic!("expected a refusal, got {:?}", other.map(|o| o.info.steps)),
    }
}

/// The events rule reads a roll by the speed the exact solution ends at: the exact disc
/// settles at 2 m/s from the first row within REST × 3 = 0.03 of it, t ≥ (1 − 0.03)/(μ g) =
/// 0.49439 s: 0.495 s; a history that slows at 1.5 m/s² instead (v = max(3 − 1.5 t, 2)) is
/// within 0.03 from t ≥ 0.64667 s: 0.647 s. A node at rest reads as before (its final speed 0).
#[test]
fn the_friction_events_rule_reads_a_roll_by_its_final_speed() {
    use crosscheck::comparison::friction::{REST, measure};
    let scene = friction_case("friction_roll_2d");
    let exact = analytic(&scene);
    let mut slow = exact.clone();
    let (t, v) = (column_index(&slow, "t"), column_index(&slow, "vx_node"));
    for row in &mut slow.rows {
        row[v] = (3.0 - 1.5 * row[t]).max(2.0);
    }
    assert_eq!(REST, 1e-2);
    let f = measure(&scene, &exact, &slow).unwrap();
    let (exact_settles, slow_settles) = (f.exact.rests.unwrap(), f.engine.rests.unwrap());
    assert!((exact_settles - 0.495).abs() < 1e-12, "{exact_settles}");
    assert!((slow_settles - 0.647).abs() < 1e-12, "{slow_settles}");
    assert_eq!(f.exact.starts, Some(0.0));
}

fn column_index(h: &History, name: &str) -> usize {
    h.columns.iter().position(|c| c == name).unwrap()
}
