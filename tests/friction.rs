//! Coulomb friction in `explicit` (penalty friction: an elastic stick of the normal penalty's
//! stiffness k and a return to the slip cone) against the exact answers of the friction cases
//! (`cases/friction/`), written out here from Newton's law and Coulomb's, independently of
//! every engine.
//!
//! While a node slides under a constant friction force its acceleration is constant, which
//! central differences integrate exactly: the histories meet the closed forms to round-off
//! until the node stops. Penalty friction then holds it on an elastic stick: the node rings
//! about its stop point with amplitude μ·m·g/k and speed μ·g·√(m/k), and never slips again.
mod common;

use common::{col as column, largest_error};
use crosscheck::case;
use crosscheck::engines::{History, RunOutput, RunSettings};
use crosscheck::scene::{IncrementRule, Scene};
use std::path::Path;

const G: f64 = 9.81;
/// The cases' penalty stiffness (normal and tangential).
const K: f64 = 1.0e7;

fn friction_case(id: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/friction/{id}.toml"));
    case::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene) -> RunOutput {
    crosscheck::run::registry::named("explicit")
        .unwrap()
        .run(scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id))
}

/// A node launched at v0 = 2 along the face with μ = 0.5 stops at t* = v0/(μg) after
/// d = v0²/(2μg), whatever its direction in the face's plane.
fn slides_to_a_stop(id: &str, along: &str, speed: &str, across: Option<&str>) {
    let (v0, mu) = (2.0, 0.5);
    let (stop, distance) = (v0 / (mu * G), v0 * v0 / (2.0 * mu * G));
    let out = run(&friction_case(id));
    let h = &out.history;
    let sliding = |t: f64| t < stop - 1e-3;
    let stopped = |t: f64| t > stop + 1e-3;
    // Constant deceleration, integrated exactly by central differences (the start puts the
    // node on the slip cone): round-off of a few hundred increments' sums, 1e-10.
    let v_err = largest_error(h, speed, |t| v0 - mu * G * t, sliding);
    let x_err = largest_error(h, along, |t| v0 * t - 0.5 * mu * G * t * t, sliding);
    assert!(
        v_err < 1e-10 && x_err < 1e-10,
        "{id}: sliding errs {v_err:e} (speed), {x_err:e} (distance)"
    );
    // Stopped: on the stick, within 2μmg/k of the stop point (the stick loads from zero to
    // μmg and overshoots by as much), ringing at speed up to μg·√(m/k); 1 % over each bound.
    let held = 2.0 * mu * G / K;
    let x_after = largest_error(h, along, |_| distance, stopped);
    let v_after = largest_error(h, speed, |_| 0.0, stopped);
    assert!(
        x_after < 1.01 * held,
        "{id}: stopped {x_after:e} from d, bound {held:e}"
    );
    let ringing = mu * G * (1.0 / K).sqrt();
    assert!(
        v_after < 1.01 * ringing,
        "{id}: stopped at speed {v_after:e}, bound {ringing:e}"
    );
    if let Some(across) = across {
        // An isotropic law keeps the node on its launch line: round-off of the direction.
        let side = largest_error(h, across, |_| 0.0, |_| true);
        assert!(side < 1e-12, "{id}: left its line by {side:e}");
    }
    // All the kinetic energy goes into friction (μ m g d = m v0²/2), less what the stick
    // spring holds, at most (μmg)²/(2k) = 1.2e-6.
    let dissipated = *column(h, "e_frictional").last().unwrap();
    let stick_energy = (mu * G).powi(2) / (2.0 * K);
    assert!(
        (dissipated - 0.5 * v0 * v0).abs() < stick_energy,
        "{id}: dissipated {dissipated}, exact {}",
        0.5 * v0 * v0
    );
    let balance = column(h, "e_balance")
        .iter()
        .fold(0.0_f64, |m, e| m.max(e.abs()));
    assert!(balance < 1e-9, "{id}: energy balance {balance:e}");
}

#[test]
fn a_node_slides_to_a_stop_at_v0_over_mu_g() {
    slides_to_a_stop("friction_slide_stop_2d", "ux_node", "vx_node", None);
    slides_to_a_stop(
        "friction_slide_stop_3d",
        "us_node",
        "vs_node",
        Some("us_side"),
    );
}

#[test]
fn the_stop_distance_does_not_depend_on_the_sliding_direction() {
    slides_to_a_stop(
        "friction_isotropy_30",
        "us_node",
        "vs_node",
        Some("us_side"),
    );
    slides_to_a_stop(
        "friction_isotropy_45",
        "us_node",
        "vs_node",
        Some("us_side"),
    );
}

#[test]
fn a_node_on_a_slope_steeper_than_its_friction_angle_slides_at_g_sin_minus_mu_cos() {
    let (theta, mu) = (35f64.to_radians(), 0.3);
    let a = G * (theta.sin() - mu * theta.cos());
    let h = run(&friction_case("friction_incline_slip")).history;
    // Constant acceleration from rest, exact under central differences: round-off.
    let x_err = largest_error(&h, "us_node", |t| 0.5 * a * t * t, |_| true);
    let v_err = largest_error(&h, "vs_node", |t| a * t, |_| true);
    assert!(x_err < 1e-11 && v_err < 1e-10, "errs {x_err:e}, {v_err:e}");
    // Pressed by m g cos θ; the consistent start leaves the penalty's ringing at round-off.
    let f_err = largest_error(&h, "contact_force", |_| G * theta.cos(), |_| true);
    assert!(f_err < 1e-8, "contact force errs {f_err:e}");
    // Dissipation: μ N × the distance slid.
    let (t, d) = (0.5, column(&h, "e_frictional"));
    let exact = mu * G * theta.cos() * 0.5 * a * t * t;
    assert!(
        (d.last().unwrap() - exact).abs() < 1e-9 * exact,
        "dissipated {d:?}"
    );
}

#[test]
fn a_node_on_a_slope_within_its_friction_angle_stays_without_creep() {
    let h = run(&friction_case("friction_incline_stick")).history;
    // The stick spring starts loaded with the weight's tangential part m g sin θ, which it
    // then carries exactly: no slip, no creep over the run (round-off of positions near 0).
    let creep = largest_error(&h, "us_node", |_| 0.0, |_| true);
    assert!(creep < 1e-15, "crept {creep:e} down the slope");
    let dissipated = column(&h, "e_frictional")
        .iter()
        .fold(0.0_f64, |m, e| m.max(*e));
    assert_eq!(dissipated, 0.0, "a stuck node dissipates nothing");
}

/// The Coulomb-damped oscillator from x = 0 at v0 (m = 1, k = 100, μ = 0.3): each phase
/// is harmonic about the centre −c·sign(v), c = μmg/k, until v = 0; it stops where |x| ≤ c.
fn coulomb_oscillator(t: f64) -> (f64, f64) {
    let (omega, c) = (10.0, 0.3 * G / 100.0);
    let (mut x, mut v, mut start) = (0.0, 3.0_f64, 0.0);
    let mut direction = 1.0;
    loop {
        let centre = -c * direction;
        let (a, b) = (x - centre, v / omega);
        // x − centre = a cos ωs + b sin ωs; v = 0 next at ωs = atan2(b, a) (mod π, > 0).
        let phase = b.atan2(a).rem_euclid(std::f64::consts::PI);
        let phase = if phase == 0.0 {
            std::f64::consts::PI
        } else {
            phase
        };
        let end = start + phase / omega;
        let s = t.min(end) - start;
        let (cos, sin) = ((omega * s).cos(), (omega * s).sin());
        if t <= end {
            return (centre + a * cos + b * sin, omega * (b * cos - a * sin));
        }
        x = centre + a * cos + b * sin;
        (v, start, direction) = (0.0, end, -direction);
        if x.abs() <= c {
            return (x, 0.0);
        }
    }
}

#[test]
fn a_mass_on_a_spring_sliding_on_a_rough_face_stops_inside_the_dead_band() {
    let (c, omega) = (0.3 * G / 100.0, 10.0);
    // The closed form's own figures, from the case's comment: stop at x = 0.022290 at
    // t = atan2(v0/ω, c)/ω + 5π/ω = 1.718097 s.
    let stop = (0.3_f64).atan2(c) / omega + 5.0 * std::f64::consts::PI / omega;
    assert!((stop - 1.718097).abs() < 1e-6);
    assert!((coulomb_oscillator(2.5).0 - 0.022290).abs() < 1e-6);
    let h = run(&friction_case("friction_spring_stickslip")).history;
    // Each of the six stops loads the stick over about √(m/k_t) = 3.2e-4 s, in which the
    // spring's force moves the node little; the phase shift it leaves, ω·3.2e-4 = 3.2e-3 of
    // the amplitude per turn, is what the errors measure: 1e-3 of the peak displacement 0.272
    // and of v0 = 3 bounds them (measured 8.4e-4 and 7.7e-4).
    let x_err = largest_error(&h, "ux_node", |t| coulomb_oscillator(t).0, |_| true);
    let v_err = largest_error(&h, "vx_node", |t| coulomb_oscillator(t).1, |_| true);
    assert!(
        x_err < 1e-3 * 0.272 && v_err < 1e-3 * 3.0,
        "errs {x_err:e}, {v_err:e}"
    );
    // At rest inside the dead band, where the closed form stops: each of the six reversals
    // carries the node through the stick's travel 2μmg/k = 5.9e-7 without slip, which shifts
    // the later turning points by as much: within six times that (measured 3.0e-6).
    let x_end = *column(&h, "ux_node").last().unwrap();
    let shift = (x_end - coulomb_oscillator(2.5).0).abs();
    assert!(
        shift < 6.0 * 2.0 * 0.3 * G / K,
        "stopped {shift:e} from the exact stop"
    );
    // Dissipation: μ N × the path length, 0 → x1 → x2 → … → the stop.
    let mut path = 0.0;
    let mut last = 0.0;
    for j in 0..6 {
        let at = (0.3_f64).atan2(c) / omega + j as f64 * std::f64::consts::PI / omega;
        let x = coulomb_oscillator(at).0;
        path += (x - last).abs();
        last = x;
    }
    let dissipated = *column(&h, "e_frictional").last().unwrap();
    let exact = 0.3 * G * path;
    assert!(
        (dissipated - exact).abs() < 1e-4 * exact,
        "dissipated {dissipated}, exact {exact}"
    );
}

#[test]
fn friction_does_not_move_the_stable_increment_of_a_node_on_a_held_face() {
    // The stick is a tangential penalty of the normal one's stiffness: against a held face
    // it adds modes at the normal penalty's frequency, so the limit stays 2√(m/k).
    let scene = friction_case("friction_slide_stop_3d");
    let mut frictionless = scene.clone();
    frictionless.contacts[0].friction = None;
    let with = run(&scene).info.stable_increment.unwrap();
    let without = run(&frictionless).info.stable_increment.unwrap();
    let exact = 2.0 * (1.0 / K).sqrt();
    assert!(
        (with - exact).abs() < 1e-6 * exact,
        "with friction {with:e}, exact {exact:e}"
    );
    assert!(
        (with - without).abs() < 1e-6 * exact,
        "{with:e} against {without:e}"
    );
}

#[test]
fn at_mu_one_a_pull_just_under_mu_n_holds_and_just_over_slides() {
    // Under: 0.99 μN from rest. The stick starts loaded with the pull and carries it: no
    // creep at all (measured exactly 0 over 10^5 increments).
    let h = run(&friction_case("friction_limit_under")).history;
    let creep = largest_error(&h, "ux_node", |_| 0.0, |_| true);
    assert!(creep < 1e-15, "crept {creep:e} under 0.99 mu N");
    // Over: 1.01 μN slides at a = 0.01 g, exactly under central differences: round-off.
    let a = 0.01 * G;
    let h = run(&friction_case("friction_limit_over")).history;
    let x_err = largest_error(&h, "ux_node", |t| 0.5 * a * t * t, |_| true);
    let v_err = largest_error(&h, "vx_node", |t| a * t, |_| true);
    assert!(x_err < 1e-12 && v_err < 1e-11, "errs {x_err:e}, {v_err:e}");
}

#[test]
fn a_ramped_pull_breaks_the_node_away_at_mu_s_n_and_it_slides_against_mu_k_n() {
    // F = r t (r = 10), N = 9.81, μ_s = 0.5, μ_k = 0.3: stuck until t_b = μ_s N / r, then
    // m x'' = r t − μ_k N.
    let (r, n, mu_s, mu_k) = (10.0, G, 0.5, 0.3);
    let t_b = mu_s * n / r;
    let v = |t: f64| {
        if t <= t_b {
            0.0
        } else {
            0.5 * r * (t * t - t_b * t_b) - mu_k * n * (t - t_b)
        }
    };
    let h = run(&friction_case("friction_ramp_breakaway")).history;
    // Stuck: the elastic stick stretches by F/k (at most μ_s N/k = 4.9e-7 m) plus its ringing
    // from the ramp's start (force amplitude r/ω_t: r/(k ω_t) = 3.2e-10 m); 1 % over that.
    let omega_t = (K / 1.0_f64).sqrt();
    let stuck = largest_error(&h, "ux_node", |_| 0.0, |t| t < t_b - 1.0 / omega_t);
    let stretch = mu_s * n / K + r / (K * omega_t);
    assert!(
        stuck < 1.01 * stretch,
        "moved {stuck:e} before the break-away"
    );
    // Sliding: that ringing may break it away up to 1/ω_t early, a velocity lead of
    // (μ_s − μ_k) N/(m ω_t) = 6.2e-4 at most; 1 % over it.
    let lead = (mu_s - mu_k) * n / omega_t;
    let v_err = largest_error(&h, "vx_node", v, |t| t > t_b + 1.0 / omega_t);
    assert!(
        v_err < 1.01 * lead,
        "velocity errs {v_err:e}, bound {lead:e}"
    );
    // The ramped load's work, summed by the trapezoidal rule, keeps the balance: a residual
    // under 1e-6 of the work (measured 1.9e-7 J of 4.04 J: 4.7e-8).
    let work = *column(&h, "w_external").last().unwrap();
    let balance = column(&h, "e_balance")
        .iter()
        .fold(0.0_f64, |m, e| m.max(e.abs()));
    assert!(balance < 1e-6 * work, "balance {balance:e} of work {work}");
}

/// A history of the stick case's contract columns with `ux_node` from `node` and the contact
/// force N = m g cos θ.
fn stick_history(scene: &Scene, node: impl Fn(usize) -> f64) -> History {
    let columns = ["t", "rz", "ux", "ux_node", "contact_force"];
    let n = G * 20f64.to_radians().cos();
    History {
        columns: columns.iter().map(|c| c.to_string()).collect(),
        rows: (0..scene.output_rows)
            .map(|i| vec![i as f64 * 1e-3, 0.0, 0.0, node(i), n])
            .collect(),
    }
}

#[test]
fn an_exact_displacement_at_round_off_is_judged_over_the_scenes_extent() {
    use crosscheck::comparison::{compare, round_off, scene_scale};
    let scene = friction_case("friction_incline_stick");
    // The stick case's scale: its farthest node 0.5 m from the origin, so lengths below
    // 5e-13 m are round-off.
    assert_eq!(scene_scale(&scene, "ux_node"), 0.5);
    assert_eq!(round_off(&scene, "ux_node"), 1e-12 * 0.5);
    // An exact solution that holds the node to round-off (±1e-17 m), against an engine
    // whose penalty sinks it 3.15e-7 m into the face: an error of 3.15e-7 m over the scene's
    // 0.5 m, 6.3e-7, not 3e10 of a round-off peak, and judged: the worst of the columns.
    let exact = stick_history(&scene, |i| if i % 2 == 0 { 1e-17 } else { -1e-17 });
    let penalty = stick_history(&scene, |_| 3.15e-7);
    let c = compare(&scene, &exact, &penalty);
    let node = c.columns.iter().find(|c| c.column == "ux_node").unwrap();
    assert!(
        node.relative && (node.max - 6.3e-7).abs() < 1e-16,
        "{node:?}"
    );
    assert_eq!(c.worst_max, Some(node.max), "creep is judged");
    // A rotation held at zero has no scale: compared in radians, not judged.
    let rz = c.columns.iter().find(|c| c.column == "rz").unwrap();
    assert!(!rz.relative && rz.max == 0.0, "{rz:?}");
    // A small motion that is not round-off (a peak of 1e-9 m, 2000 × the floor) stays judged
    // over its peak: 1e-10 m off is 0.1 of it.
    let small = stick_history(&scene, |i| 1e-9 * (i as f64 / 500.0));
    let off = stick_history(&scene, |i| 1e-9 * (i as f64 / 500.0) + 1e-10);
    let c = compare(&scene, &small, &off);
    let node = c.columns.iter().find(|c| c.column == "ux_node").unwrap();
    assert!(node.relative && (node.max - 0.1).abs() < 1e-9, "{node:?}");
}

/// A slide-stop history: v = v0 − a t until t* = v0/a, then at rest but for a speed between
/// ½ and 1½ × `ringing`; `side` on the sideways column throughout.
fn slide_history(scene: &Scene, ringing: f64, side: f64) -> History {
    let (v0, a) = (2.0, 0.5 * G);
    let stop = v0 / a;
    let columns = [
        "t",
        "rz",
        "ux",
        "ux_node",
        "contact_force",
        "us_node",
        "vs_node",
        "us_side",
    ];
    let rows = (0..scene.output_rows)
        .map(|i| {
            let t = i as f64 * 1e-3;
            let s = t.min(stop);
            let x = v0 * s - 0.5 * a * s * s;
            let v = if t < stop {
                v0 - a * t
            } else {
                ringing * (1.0 + 0.5 * (i as f64).sin())
            };
            vec![t, 0.0, 0.0, x, G, x, v, side]
        })
        .collect();
    History {
        columns: columns.iter().map(|c| c.to_string()).collect(),
        rows,
    }
}

#[test]
fn the_friction_events_rule_reads_a_known_slide() {
    use crosscheck::comparison::friction::{REST, measure};
    let scene = friction_case("friction_slide_stop_3d");
    // At rest below REST × 2 (the exact peak speed): v0 − a t ≤ 0.02 from t = 0.403670 s,
    // the first output row at or after it is 0.404 s.
    let exact = slide_history(&scene, 0.0, 0.0);
    let ringing = slide_history(&scene, 0.6 * REST * 2.0, 3e-6);
    let f = measure(&scene, &exact, &ringing).unwrap();
    assert_eq!(f.exact.starts, Some(0.0));
    assert_eq!(f.exact.rests, Some(0.404));
    // A ringing under the threshold is at rest; the sideways column (exact 0) is what strays.
    assert_eq!(f.engine.rests, Some(0.404));
    assert_eq!(f.engine.stray, 3e-6);
    let d = 4.0 / (2.0 * 0.5 * G);
    assert!((f.engine.end - d).abs() < 1e-12, "ends at {}", f.engine.end);
    // A ringing over it is still moving at the end.
    let moving = slide_history(&scene, 2.5 * REST * 2.0, 0.0);
    assert_eq!(measure(&scene, &exact, &moving).unwrap().engine.rests, None);
    // A frictionless scene has no friction events.
    let mut frictionless = scene.clone();
    frictionless.contacts[0].friction = None;
    assert!(measure(&frictionless, &exact, &ringing).is_none());
}

#[test]
fn counters_show_friction_only_where_a_scene_has_it() {
    // One pair evaluated every increment, slipping in each until the stop at v0/(μg) =
    // 0.407747 s (40775 increments of 1e-5 s), and in a few more while the stick takes the
    // load at the stop: within its loading time √(m/k)/h = 32 increments (measured 4).
    let out = run(&friction_case("friction_slide_stop_2d"));
    let counter = |name: &str| out.info.counters.get(name).copied();
    assert_eq!(counter("friction_evaluations"), Some(out.info.steps + 1));
    let slips = counter("slip_increments").unwrap() as f64;
    assert!(
        (slips - 40775.0).abs() <= 32.0,
        "slipped in {slips} increments"
    );
    // Without friction, no friction counter at all.
    let mut frictionless = friction_case("friction_slide_stop_2d");
    frictionless.contacts[0].friction = None;
    let out = run(&frictionless);
    assert!(!out.info.counters.contains_key("friction_evaluations"));
}

/// A run of explicit at `ratio` × its own stable increment.
fn run_at_stable_ratio(scene: &Scene, ratio: f64) -> RunOutput {
    let settings = RunSettings {
        increment: Some(IncrementRule::StableRatio(ratio)),
        ..RunSettings::default()
    };
    crosscheck::run::registry::named("explicit")
        .unwrap()
        .run(scene, &settings)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.id))
}

#[test]
fn a_stuck_node_does_not_chatter_at_the_stable_increment() {
    // The slide-stop case at 0.95 × the stable increment 2√(m/k) (h = 6.0e-4 s, 60 × the
    // case's own): the node stops within the increment where v0 − μ g t crosses 0, and the
    // stick catches it with a speed of up to μ g h, which it turns into a tangential force of
    // up to μ g h √(k m) ≈ 9.3 N, above μ m g = 4.9 N. So it slips in some of the increments
    // that follow the stop while it takes the load (measured: 10), then holds for the rest of
    // the run (0.19 s, half as long as the slide): its undamped ringing reaches the cone at
    // most by round-off, dissipating nothing measurable.
    let (v0, mu) = (2.0, 0.5);
    let stop = v0 / (mu * G);
    let out = run_at_stable_ratio(&friction_case("friction_slide_stop_2d"), 0.95);
    let h = out.info.increment;
    let exact_stable = 2.0 * (1.0 / K).sqrt();
    assert!((h - 0.95 * exact_stable).abs() < 1e-9, "increment {h:e}");
    let slips = out.info.counters["slip_increments"] as f64;
    let sliding = (stop / h).ceil();
    // Settling: at most 16 increments with slip after the stop (measured 10).
    assert!(
        slips >= sliding - 1.0 && slips <= sliding + 16.0,
        "slipped in {slips} increments, slide {sliding}"
    );
    let t = column(&out.history, "t");
    let (x, d) = (
        column(&out.history, "ux_node"),
        column(&out.history, "e_frictional"),
    );
    // From 50 increments after the stop (0.03 s) on: rows are interpolated through increments
    // by a quadratic, so a row reads the dissipated energy to about the size of one
    // increment's change. 1e-9 J is what a slip of 2e-10 m dissipates against μ m g, 1e-4 of
    // the stick's elastic range (measured 2.5e-10 J over the 0.16 s).
    let after = t.iter().position(|t| *t > stop + 50.0 * h).unwrap();
    let spread = |v: &[f64]| {
        v.iter().fold(f64::MIN, |m, x| m.max(*x)) - v.iter().fold(f64::MAX, |m, x| m.min(*x))
    };
    let settled = spread(&d[after..]);
    assert!(settled < 1e-9, "dissipated {settled:e} once settled");
    // It rings on its stick within its elastic range 2μmg/k, where it stopped: within a
    // step's travel at the end of the slide, ½ μ g h², and that range of v0²/(2μg).
    let held = 2.0 * mu * G / K;
    let ring = spread(&x[after..]);
    assert!(ring < 1.01 * held, "rings over {ring:e}, bound {held:e}");
    let distance = v0 * v0 / (2.0 * mu * G);
    let reach = 0.5 * mu * G * h * h + held;
    assert!(
        (x[after] - distance).abs() < reach,
        "stopped at {}, exact {distance}",
        x[after]
    );
}
