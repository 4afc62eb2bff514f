//! Rapier where the problem gets hard: its implicit springs lose energy as backward Euler
//! predicts, f32 loses the pinned case's accuracy as the scene moves away from the origin, and
//! a fast node tunnels through a thin cuboid unless CCD is on.
#![cfg(feature = "rapier")]
mod common;

use crosscheck::case;
use crosscheck::comparison::compare;
use crosscheck::engines::rapier::{Precision, RapierEngine};
use crosscheck::engines::reference::ReferenceEngine;
use crosscheck::engines::{Engine, History, RunSettings};
use crosscheck::scene::IncrementRule;

fn column(h: &History, name: &str) -> Vec<f64> {
    let i = h.columns.iter().position(|c| c == name).unwrap();
    h.rows.iter().map(|r| r[i]).collect()
}

#[test]
fn rapier_springs_lose_energy_as_backward_euler_predicts() {
    // The undamped grounded oscillator (springs_grounded_a without its dashpot), 2 s. Rapier
    // (matched: 4 substeps per step) treats the spring implicitly; backward Euler on an
    // undamped oscillator multiplies its energy by 1/(1 + (ω·h_s)²) per substep h_s, so after
    // time t it holds E0 · (1 + (ω·h_s)²)^(−t/h_s): 5.2 % lost per period at h = 1e-3 s.
    let omega = (30.0f64 / 0.02588).sqrt();
    let scene = common::variant(
        "springs_grounded_a",
        &[
            ("damping = 0.12", "damping = 0.0"),
            ("duration = 1.0", "duration = 2.0"),
        ],
    );
    for h in [2e-4, 1e-3, 2e-3] {
        for precision in [Precision::F64, Precision::F32] {
            let engine = RapierEngine::matched(precision);
            let out = engine
                .run(
                    &scene,
                    &RunSettings {
                        increment: Some(IncrementRule::Forced(h)),
                        ..Default::default()
                    },
                )
                .unwrap();
            let t = column(&out.history, "t");
            let energy: Vec<f64> = column(&out.history, "e_kinetic")
                .iter()
                .zip(column(&out.history, "e_elastic"))
                .map(|(k, e)| k + e)
                .collect();
            let hs = out.info.increment / 4.0;
            let last = t.len() - 1;
            let predicted = (1.0 + (omega * hs).powi(2)).powf(-t[last] / hs);
            let measured = energy[last] / energy[0];
            let per_period = |r: f64| 1.0 - r.powf(std::f64::consts::TAU / (omega * t[last]));
            println!(
                "{} h = {h:e}: energy after {:.1} s {measured:.6} of E0, backward Euler {predicted:.6}; lost per period {:.4} (predicted {:.4})",
                engine.name(),
                t[last],
                per_period(measured),
                per_period(predicted)
            );
            // The loss per period as predicted to 1 % of itself in f64 (measured within
            // 0.2 %), 5 % in f32 (its round-off on the spring's stretch).
            let allowed = if precision == Precision::F64 {
                0.01
            } else {
                0.05
            };
            let (m, p) = (per_period(measured), per_period(predicted));
            assert!(
                (m / p - 1.0).abs() < allowed,
                "{} h = {h:e}: lost {m} per period, predicted {p}",
                engine.name()
            );
        }
    }
}

/// `rigid2d_pin_lumped` with every point of the scene moved by (d, d), and restitution 0 on its
/// resting contact: with the case's restitution (1) rapier_f32 bounces off the round-off
/// separations of that contact (`tests/fair.rs`), which would mix a second round-off effect
/// into this one (its error at the origin 4.0e-2, at d = 0.01 1.2e-2).
fn translated(d: f64) -> crosscheck::scene::Scene {
    let text =
        std::fs::read_to_string(crosscheck::case::cases_dir().join("rigid2d_pin_lumped.toml"))
            .unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let moved = ["at = [", "face_point = ["].iter().find_map(|key| {
            let rest = line.strip_prefix(key)?.strip_suffix(']')?;
            let xy: Vec<f64> = rest.split(',').map(|v| v.trim().parse().unwrap()).collect();
            Some(format!("{key}{:?}, {:?}]", xy[0] + d, xy[1] + d))
        });
        out += &moved.unwrap_or_else(|| line.to_string());
        out.push('\n');
    }
    let path = crosscheck::case::cases_dir().join("rigid2d_pin_lumped.toml");
    let scene = crosscheck::case::parse(&out, &path).unwrap_or_else(|e| panic!("{e}"));
    crosscheck::engines::rapier::controls::closed_pairs_inelastic(&scene).expect("a closed pair")
}

#[test]
fn f32_loses_the_pinned_case_far_from_the_origin() {
    // The contract columns are displacements and rotations, so every translated scene has the
    // same exact answer: the reference of the untranslated one.
    let origin = translated(0.0);
    let exact = ReferenceEngine
        .run(&origin, &RunSettings::default())
        .unwrap()
        .history;
    let error = |d: f64, precision: Precision| {
        let scene = translated(d);
        let out = RapierEngine::matched(precision)
            .run(&scene, &RunSettings::default())
            .unwrap();
        compare(&origin, &exact, &out.history)
            .worst_max
            .expect("a compared column")
    };
    let base32 = error(0.0, Precision::F32);
    let base64 = error(0.0, Precision::F64);
    let mut doubled_at = None;
    let mut far = 0.0;
    // 10^-2 … 10^5 in half decades (the issue asks from 10 up; f32 has doubled before that).
    for k in -4..=10 {
        let d = 10f64.powf(k as f64 / 2.0);
        let e32 = error(d, Precision::F32);
        let e64 = error(d, Precision::F64);
        println!(
            "translated by {d:.3e}: rapier_f32 error {e32:.3e} ({:.2}× at the origin), rapier_f64 {e64:.3e} ({:.4}×)",
            e32 / base32,
            e64 / base64
        );
        // f64 does not notice: its round-off at 1e5 is 1e5 · 1.1e-16 = 1e-11, against motions
        // of 1e-3 and more.
        assert!((e64 / base64 - 1.0).abs() < 0.01, "f64 at {d:e}: {e64:e}");
        // Close to the origin f32 hardly does: its round-off on coordinates of ~3 is 2e-7, and
        // its error stays within 1.5× f64's (measured 1.18e-2 and 1.56e-2 by turns up to
        // d = 0.32, against 1.19e-2).
        if d <= 0.32 {
            assert!(e32 <= 1.5 * e64, "f32 at {d:e}: {e32:e}");
        }
        if doubled_at.is_none() && e32 >= 2.0 * base32 {
            doubled_at = Some(d);
        }
        far = e32;
    }
    println!("rapier_f32's error doubles at a translation of {doubled_at:?}");
    assert!(doubled_at.is_some());
    // At 1e5 an f32 coordinate is a multiple of 2^-7 = 7.8e-3, so a position is off by up to
    // 3.9e-3: 19 % of the contact node's peak displacement (2.1e-2), and the penalty-like
    // contact turns such offsets into forces. The error cannot stay below 0.1 of the peak
    // (measured: 26, the run is lost).
    assert!(far >= 0.1, "f32 at 1e5: error {far:e}");
}

/// The elastic drop turned into a shot at a cuboid 2 mm thick: the node starts 0.1 above its
/// top face moving down at `speed`, for 1 s (the gravity load stays: negligible here).
fn shot(speed: f64) -> crosscheck::scene::Scene {
    let path = case::stress_dir(&case::cases_dir()).join("contact_drop_e1.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("half_extents = [0.05, 0.5]", "half_extents = [0.001, 0.5]")
        .replace("centre = [-0.05, 0.0]", "centre = [-0.001, 0.0]")
        .replace(
            "at = [1.0, 0.0]\n\n# The block",
            "at = [0.1, 0.0]\n\n# The block",
        )
        .replace("increment = 1.0e-5", "increment = 1.0e-4")
        .replace(
            "[[steps]]",
            &format!(
                "[[initial_velocities]]\nnode = \"N\"\nvelocity = [{:e}, 0.0]\n\n[[steps]]",
                -speed
            ),
        );
    case::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// Where a shot node ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ending {
    /// On or above the top face (x = -0.1, within 1e-4): it bounced or stopped on it.
    Held,
    /// Inside the cuboid.
    Inside,
    /// Below the bottom face (x = -0.102): through.
    Through,
}

fn ending(engine: &dyn Engine, speed: f64) -> Ending {
    let out = engine
        .run(&shot(speed), &RunSettings::default())
        .unwrap_or_else(|e| panic!("{} at {speed}: {e}", engine.name()));
    let x = *column(&out.history, "ux_node").last().unwrap();
    if x >= -0.1001 {
        Ending::Held
    } else if x > -0.102 {
        Ending::Inside
    } else {
        Ending::Through
    }
}

/// Shot speeds and how each ends.
type Shots<'a> = &'a [(f64, Ending)];

/// Rapier's tunnelling through a cuboid 2 mm thick, with and without its continuous collision
/// detection (CCD), frozen as measured with rapier 0.36 (f64), and the explicit engine on the
/// same shots: held or refused, never through.
///
/// The cuboid's body is held in every DOF, so it is a fixed rapier body, and rapier 0.36 runs
/// CCD on fast dynamic bodies against fixed colliders whatever a body's own CCD flag (it caps
/// speeds at 400 m/s too, `normalized_max_linear_velocity`):
/// - Matched (h = 1e-4 s): held at every speed tried, 1 to 3000 m/s.
/// - Default (1/60 s): held at 1 to 2.4, 2.6 and from 5 m/s up; through at 2.5 and 3 m/s
///   (unexplained: v·h is 4e-2 to 5e-2 m there, and the automatic CCD does not catch it); its
///   own CCD changes none of it.
///
/// Control: the cuboid a dynamic body held by a joint (the construct a held body had before),
/// which the automatic CCD does not see: matched through from 22 m/s (the ending then depends
/// on where the steps fall: held at 25, 40, 50, 100, 200; through at 30, 70 and from 300 on),
/// default through from 2 m/s. The tunnelling those speeds showed was the construct's.
#[test]
fn rapier_tunnels_where_a_step_outruns_the_thickness_and_explicit_never_does() {
    use Ending::*;
    let joints = |e: RapierEngine| e.held_by_joints();
    let matched = RapierEngine::matched(Precision::F64);
    let default = RapierEngine::default_configuration(Precision::F64);
    let cases: [(&dyn Engine, Shots); 6] = [
        (
            &matched,
            &[(21.0, Held), (22.0, Held), (300.0, Held), (3000.0, Held)],
        ),
        (
            &joints(RapierEngine::matched(Precision::F64)),
            &[
                (21.0, Held),
                (22.0, Through),
                (300.0, Through),
                (3000.0, Through),
            ],
        ),
        (
            &RapierEngine::matched(Precision::F64).with_ccd(),
            &[(20.0, Held), (21.0, Held), (300.0, Held), (3000.0, Held)],
        ),
        (
            &default,
            &[
                (2.4, Held),
                (2.5, Through),
                (3.0, Through),
                (5.0, Held),
                (3000.0, Held),
            ],
        ),
        (
            &joints(RapierEngine::default_configuration(Precision::F64)),
            &[(2.0, Through), (30.0, Through), (3000.0, Through)],
        ),
        (
            &RapierEngine::default_configuration(Precision::F64).with_ccd(),
            &[(2.5, Through), (3.0, Through), (21.0, Held), (3000.0, Held)],
        ),
    ];
    for (engine, expected) in cases {
        for (speed, end) in expected {
            assert_eq!(
                ending(engine, *speed),
                *end,
                "{} at {speed} m/s",
                engine.name()
            );
        }
    }
    // The explicit engine (k_p = 1e7, h = 1e-4) holds the slow shots and refuses the fast
    // ones, naming what would catch them.
    let explicit = crosscheck::engines::explicit::ExplicitEngine::finite();
    for speed in [1.0, 2.0, 21.0, 300.0, 3000.0] {
        match explicit.run(&shot(speed), &RunSettings::default()) {
            Ok(out) => {
                let x = *column(&out.history, "ux_node").last().unwrap();
                assert!(x >= -0.1001, "explicit at {speed}: ends at {x}");
                assert!(speed < 3.0, "explicit at {speed}: held");
            }
            Err(e) => {
                assert!(e.to_string().contains("went through the cuboid"), "{e}");
                assert!(speed > 3.0, "explicit at {speed}: refused");
            }
        }
    }
}

/// Why rapier_f64's matched contact is 10 kHz and not f32's 3 kHz: on the sliding lumped case
/// its differences between successive halvings of the increment shrink by 2 (first order, so
/// the budget's extrapolation in h converges) from 4e-5 s down to 5e-6 s at 10 kHz (measured
/// 1.95–2.00), while at 3 kHz the soft contact's own dynamics stall them below 1e-5 s (rz:
/// 2.17, then 1.64, then 1.23); and stiffer than 10 kHz changes little against rapier's
/// first-order error of ~1e-2 (100 kHz: every column within 3e-4 of its peak at 1e-5 s,
/// measured ≤ 1.5e-4).
#[test]
fn rapier_f64_contact_is_stiff_enough_to_be_first_order_in_the_increment() {
    use crosscheck::engines::rapier::{Configuration, MatchedSettings};
    let scene = common::scene("rigid2d_slide_lumped");
    let columns = ["rz", "ux", "ux_node", "contact_force"];
    let at = |frequency: f64, hs: &[f64]| -> Vec<History> {
        let m = MatchedSettings {
            contact_frequency: frequency,
            ..MatchedSettings::chosen(Precision::F64)
        };
        let engine = RapierEngine::with(Precision::F64, Configuration::Matched(m));
        hs.iter()
            .map(|&h| {
                let settings = RunSettings {
                    increment: Some(IncrementRule::Forced(h)),
                    ..Default::default()
                };
                engine.run(&scene, &settings).unwrap().history
            })
            .collect()
    };
    // Ratios of successive differences per column, from the first increment on (row 0's
    // contact force is the first impulse).
    let ratios = |runs: &[History], c: &str| -> Vec<f64> {
        let cols: Vec<Vec<f64>> = runs.iter().map(|h| column(h, c)[1..].to_vec()).collect();
        let d: Vec<f64> = cols
            .windows(2)
            .map(|w| common::max_diff(&w[0], &w[1]))
            .collect();
        d.windows(2).map(|w| w[0] / w[1]).collect()
    };
    let chosen = MatchedSettings::chosen(Precision::F64).contact_frequency;
    let runs = at(chosen, &[4e-5, 2e-5, 1e-5, 5e-6]);
    for c in columns {
        let r = ratios(&runs, c);
        println!("{chosen:e} Hz, {c}: ratios {r:.3?}");
        // First order: 2 per halving, within the next term's share (measured 1.95–2.00).
        assert!(r.iter().all(|r| (r - 2.0).abs() < 0.1), "{c}: {r:?}");
    }
    let soft = at(3.0e3, &[1e-5, 5e-6, 2.5e-6]);
    let r = ratios(&soft, "rz");
    println!("3 kHz, rz: ratio {r:.3?}");
    assert!(r[0] < 1.8, "3 kHz no longer stalls: {r:?}");
    let stiffer = at(1.0e5, &[1e-5]);
    for c in columns {
        let (a, b) = (column(&runs[2], c), column(&stiffer[0], c));
        let d = common::max_diff(&a[1..], &b[1..]) / common::peak(&a);
        println!("{c}: 100 kHz against {chosen:e} Hz {d:.2e} of the peak");
        assert!(d < 3e-4, "{c}: {d:e}");
    }
}
