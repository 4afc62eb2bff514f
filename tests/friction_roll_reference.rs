//! `reference` on a body's ball launched sliding on a held block's face, against the exact
//! solution written out here from each case's data (independent of every engine): the disc of
//! `friction_roll_2d` and the ball of `friction_roll_3d`. For each, the history row by row,
//! the time rolling starts (a stick of the contact point) and the energy friction dissipated.
//!
//! The exact motion. Launched at v0 without spin, the body's contact point slides at v − ω R, so
//! friction μ m g decelerates the centre at μ g and spins the body up at α = μ m g R / I
//! (about −z: rolling along +x turns it clockwise) until v = ω R, at
//! t* = v0 / (μ g (1 + m R² / I)) (the disc: v0/(3 μ g); the ball: 2 v0/(7 μ g)), at
//! v_roll = v0 − μ g t*. From then it rolls at v_roll with no friction force. Throughout, the
//! contact force is m g and the centre stays at height R (and, in 3D, on the x axis, its spin
//! about z). Friction dissipates the kinetic energy lost, ½ m v0² − ½ (m + I/R²) v_roll².
//!
//! Tolerances. The reference integrates by Dop853 at a relative tolerance of 1e-12 (absolute
//! 1e-15) and locates each event by bisection to a few ulps of its time; between events the
//! exact motions are polynomials of degree 2 in t (which an 8th-order scheme integrates to
//! round-off; the rotation is integrated through its quaternion, smooth and resolved to the
//! tolerance). So:
//! - a column's largest error is within [`HISTORY`] = 1e-8 of its exact peak;
//! - a column whose exact value is zero throughout stays within [`ZERO`] = 1e-12 in its own
//!   units (m, rad; coordinates of order 1, round-off of 1e-16 per step accumulated over 1e3
//!   steps, with margin);
//! - the roll's start is within [`EVENT`] = 1e-10 s of t*: the bisection resolves 1e-16 s, and
//!   the slip speed it bisects on carries the integration error, ~1e-12 of a velocity of order 1
//!   against a slip deceleration of order 6 m/s²;
//! - the dissipated energy is within [`ENERGY`] = 1e-9 J of the exact one (1.3–1.5 J): it is
//!   integrated with the state at the same tolerance.
mod common;

use crosscheck::case;
use crosscheck::engines::reference::ReferenceEngine;
use crosscheck::engines::{Engine, RunOutput, RunSettings};
use std::path::Path;

/// Largest error of a column over its exact peak.
const HISTORY: f64 = 1e-8;
/// Largest value of a column that is exactly zero, in its units.
const ZERO: f64 = 1e-12;
/// Largest error of the roll's start, s.
const EVENT: f64 = 1e-10;
/// Largest error of the dissipated energy, J.
const ENERGY: f64 = 1e-9;

/// Gravity in both cases.
const G: f64 = 9.81;

fn run(case: &str) -> RunOutput {
    let path = format!("cases/friction/{case}.toml");
    let scene = case::load(Path::new(&path)).unwrap_or_else(|e| panic!("{case}: {e}"));
    ReferenceEngine
        .run(&scene, &RunSettings::default())
        .unwrap_or_else(|e| panic!("{case}: {e}"))
}

/// A body of mass `m`, inertia `i` about its centre and radius `r`, launched at `v0` without
/// spin on a face with friction `mu`.
struct Roll {
    m: f64,
    i: f64,
    r: f64,
    v0: f64,
    mu: f64,
}

impl Roll {
    /// When it starts rolling.
    fn start(&self) -> f64 {
        self.v0 / (self.mu * G * (1.0 + self.m * self.r * self.r / self.i))
    }

    /// Its speed while it rolls.
    fn rolling_speed(&self) -> f64 {
        self.v0 - self.mu * G * self.start()
    }

    /// The centre's distance along the launch, its speed, and the rotation about z at time t.
    fn at(&self, t: f64) -> (f64, f64, f64) {
        let a = self.mu * G;
        let alpha = self.mu * self.m * G * self.r / self.i;
        let slip = t.min(self.start());
        let (x, v, theta) = (
            self.v0 * slip - 0.5 * a * slip * slip,
            self.v0 - a * slip,
            -0.5 * alpha * slip * slip,
        );
        let rolled = t - slip;
        (x + v * rolled, v, theta - v / self.r * rolled)
    }

    /// The energy friction dissipates.
    fn dissipated(&self) -> f64 {
        let v = self.rolling_speed();
        0.5 * self.m * self.v0 * self.v0 - 0.5 * (self.m + self.i / (self.r * self.r)) * v * v
    }
}

/// One stick (the roll's start) and no other event.
fn assert_one_stick(out: &RunOutput) {
    let m = &out.info.measures;
    let count = |name: &str| m.get(name).copied().unwrap_or(0.0);
    for (name, expected) in [
        ("sticks", 1.0),
        ("slips", 0.0),
        ("reversals", 0.0),
        ("impacts", 0.0),
        ("openings", 0.0),
    ] {
        assert_eq!(count(name), expected, "{name}");
    }
}

#[test]
fn a_disc_launched_sliding_starts_rolling_at_v0_over_3_mu_g() {
    let out = run("friction_roll_2d");
    let disc = Roll {
        m: 1.0,
        i: 0.125,
        r: 0.5,
        v0: 3.0,
        mu: 0.2,
    };
    // The case's comments: t* = v0/(3 mu g), at 2 v0/3, having dissipated 1.5 J.
    assert!((disc.start() - 3.0 / (3.0 * 0.2 * G)).abs() < 1e-15);
    assert!((disc.rolling_speed() - 2.0).abs() < 1e-14);
    assert!((disc.dissipated() - 1.5).abs() < 1e-14);
    let columns = [
        "rz",
        "ux",
        "ux_node",
        "contact_force",
        "vx_node",
        "uy_node",
        "rz_disc",
    ];
    common::assert_history(&out, &columns, (HISTORY, ZERO), |t| {
        let (x, v, theta) = disc.at(t);
        vec![0.0, 0.0, x, disc.m * G, v, 0.0, theta]
    });
    common::assert_measure(&out, "stick_1_time", disc.start(), EVENT);
    common::assert_measure(&out, "frictional_dissipation", disc.dissipated(), ENERGY);
    assert_one_stick(&out);
}

#[test]
fn a_ball_launched_sliding_starts_rolling_at_2_v0_over_7_mu_g() {
    let out = run("friction_roll_3d");
    let ball = Roll {
        m: 1.0,
        i: 0.1,
        r: 0.5,
        v0: 3.0,
        mu: 0.2,
    };
    // The case's comments: t* = 2 v0/(7 mu g), at 5 v0/7.
    assert!((ball.start() - 2.0 * 3.0 / (7.0 * 0.2 * G)).abs() < 1e-15);
    assert!((ball.rolling_speed() - 15.0 / 7.0).abs() < 1e-14);
    let columns = [
        "rz",
        "ux",
        "ux_node",
        "contact_force",
        "vx_node",
        "uy_node",
        "uz_node",
        "rz_ball",
        "rx_ball",
    ];
    common::assert_history(&out, &columns, (HISTORY, ZERO), |t| {
        let (x, v, theta) = ball.at(t);
        vec![0.0, 0.0, x, ball.m * G, v, 0.0, 0.0, theta, 0.0]
    });
    common::assert_measure(&out, "stick_1_time", ball.start(), EVENT);
    common::assert_measure(&out, "frictional_dissipation", ball.dissipated(), ENERGY);
    assert_one_stick(&out);
}
