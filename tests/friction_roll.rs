//! A disc (2D) and a ball (3D) launched sliding without spin on a held face start rolling:
//! `explicit` (finite rotation) on `cases/friction/friction_roll_2d.toml` and
//! `friction_roll_3d.toml` against the closed forms of Newton's and Coulomb's laws, written out
//! here independently of every engine; `explicit_small` refuses the cases.
//!
//! A body of mass m, radius R and moment of inertia I = κ·m·R² about its centre (disc κ = 1/2,
//! ball κ = 2/5), launched at v0 on a face with friction μ under its weight m·g, slides while
//! its contact point moves at v − ω·R > 0. Friction μ·m·g then decelerates the centre at μ·g
//! and spins the body up at α = μ·m·g·R/I = μ·g/(κ·R):
//!   x(t) = v0·t − μ·g·t²/2,   v(t) = v0 − μ·g·t,   θ(t) = α·t²/2   (θ the turn about −z),
//! until the contact point stops at t* = v0/(μ·g·(1 + 1/κ)) (disc v0/(3μg), ball 2v0/(7μg)),
//! with v* = v0 − μ·g·t* (2v0/3, 5v0/7). It then rolls with no friction force:
//!   x(t) = x(t*) + v*·(t − t*),   v(t) = v*,   θ(t) = θ(t*) + (v*/R)·(t − t*).
//! The centre stays at height R. Friction dissipates (1/2)m·v0² − (1/2)(m + I/R²)·v*².
//!
//! Penalty friction (an elastic stick of the normal penalty's stiffness k) carries the slip
//! phase exactly (a constant force, which central differences integrate exactly). The friction
//! force acts at the contact point, so it leaves the angular momentum about the contact line,
//! L = m·v·R + I·ω, as it was: v = v* + (m_eff/m)·v_c at every instant, v_c = v − ω·R the
//! contact point's slip speed and m_eff = m·I/(I + m·R²) = m·κ/(1 + κ) (disc m/3, ball 2m/7)
//! the mass of its tangential mode. Where the contact point stops, the stick catches it loaded
//! with μ·m·g, stretched by s0 = μ·m·g/k: it then rings about the unloaded stick at
//! ω_t = √(k/m_eff), with stretch amplitude s0 and slip speed amplitude s0·ω_t. The centre's
//! speed rings by (m_eff/m)·s0·ω_t = μ·g·√(m_eff/k) about v*; its position, (m_eff/m) times the
//! contact point's, swings from where the stick caught it through the unloaded stick to the
//! other side, up to 2·(m_eff/m)·s0 = 2·μ·g·m_eff/k behind the closed form, and its turn, by
//! ω·R = v − v_c, up to 2·s0/((1 + κ)·R). The stick stores up to (μ·m·g)²/(2k).
//!
//! In increments of h the stick catches the contact point within the increment its slip
//! crosses 0, so it may already move back at up to μ·g·(1 + 1/κ)·h = s0·ω_t·(ω_t·h): the ring's
//! amplitude is s0·√(1 + (ω_t·h)²), and the slip beyond t* before the catch, at most
//! μ·g·(1 + 1/κ)·h²/2 = s0·(ω_t·h)²/2, shifts where it rings about. Central differences ring
//! at an amplitude (1 + (ω_t·h)²/8) of the exact one's at most. Each bound above thus holds to
//! a factor 1 + (ω_t·h)² (ω_t·h = 0.055 disc, 0.059 ball: 1.003 and 1.0035).
mod common;

use common::{col as column, largest_error};
use crosscheck::case;
use crosscheck::contract::{E_BALANCE, E_FRICTIONAL};
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::engines::{Engine, EngineError, History, RunSettings};
use crosscheck::scene::{IncrementRule, Scene};
use std::path::Path;

const G: f64 = 9.81;
/// The cases' penalty stiffness (normal and tangential).
const K: f64 = 1.0e7;
const M: f64 = 1.0;
const R: f64 = 0.5;
const V0: f64 = 3.0;
const MU: f64 = 0.2;
/// The output interval of the cases' rows.
const ROW: f64 = 1.0e-3;

/// One of the two cases: its id, its rotation column and I/(m·R²).
struct Roll {
    id: &'static str,
    rotation: &'static str,
    kappa: f64,
}

const DISC: Roll = Roll {
    id: "friction_roll_2d",
    rotation: "rz_disc",
    kappa: 0.5,
};
const BALL: Roll = Roll {
    id: "friction_roll_3d",
    rotation: "rz_ball",
    kappa: 0.4,
};

impl Roll {
    /// Spin-up α = μ·g/(κ·R).
    fn alpha(&self) -> f64 {
        MU * G / (self.kappa * R)
    }
    /// The roll start t* = v0/(μ·g·(1 + 1/κ)).
    fn start(&self) -> f64 {
        V0 / (MU * G * (1.0 + 1.0 / self.kappa))
    }
    /// The rolling speed v* = v0 − μ·g·t*.
    fn rolling_speed(&self) -> f64 {
        V0 - MU * G * self.start()
    }
    /// The mass the tangential stick moves, m·κ/(1 + κ).
    fn effective_mass(&self) -> f64 {
        M * self.kappa / (1.0 + self.kappa)
    }
    /// Centre's x(t).
    fn x(&self, t: f64) -> f64 {
        let s = self.start();
        let sliding = |t: f64| V0 * t - 0.5 * MU * G * t * t;
        if t < s {
            sliding(t)
        } else {
            sliding(s) + self.rolling_speed() * (t - s)
        }
    }
    /// Centre's v(t).
    fn v(&self, t: f64) -> f64 {
        if t < self.start() {
            V0 - MU * G * t
        } else {
            self.rolling_speed()
        }
    }
    /// The turn θ(t) about −z.
    fn theta(&self, t: f64) -> f64 {
        let s = self.start();
        let sliding = |t: f64| 0.5 * self.alpha() * t * t;
        if t < s {
            sliding(t)
        } else {
            sliding(s) + self.rolling_speed() / R * (t - s)
        }
    }
    /// The energy friction dissipates: (1/2)m·v0² − (1/2)(m + I/R²)·v*².
    fn dissipated(&self) -> f64 {
        let v = self.rolling_speed();
        0.5 * M * V0 * V0 - 0.5 * M * (1.0 + self.kappa) * v * v
    }
    fn scene(&self) -> Scene {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/friction/{}.toml", self.id));
        case::load(&path).unwrap_or_else(|e| panic!("{e}"))
    }
}

/// The history of `explicit` on the case and the increment it ran at.
fn run(roll: &Roll) -> (History, f64) {
    let out = crosscheck::run::registry::named("explicit")
        .unwrap()
        .run(&roll.scene(), &RunSettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", roll.id));
    (out.history, out.info.increment)
}

/// A closed form of time.
type Exact<'a> = &'a dyn Fn(f64) -> f64;

/// The contact point's slip speed v − ω·R at each row, ω from the central difference of the
/// turn over the neighbouring rows (exact for the quadratic turn of the slip phase); the ends
/// take the one-sided difference.
fn slip_speeds(h: &History, roll: &Roll) -> Vec<f64> {
    let (v, turn) = (column(h, "vx_node"), column(h, roll.rotation));
    let n = v.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let omega = -(turn[b] - turn[a]) / ((b - a) as f64 * ROW);
            v[i] - omega * R
        })
        .collect()
}

/// The roll start: the time at which the slip speed, linearly interpolated between the last
/// row above `threshold` and the next, falls to `threshold`, plus the time the exact slip
/// takes from there to 0 (it falls at μ·g·(1 + 1/κ)). Also returns the first row from which
/// the slip speed stays below `threshold`.
fn roll_start(h: &History, roll: &Roll, threshold: f64) -> (f64, f64) {
    let (t, slip) = (column(h, "t"), slip_speeds(h, roll));
    let last = slip
        .iter()
        .rposition(|s| s.abs() > threshold)
        .expect("the body slides at t = 0");
    let (s0, s1) = (slip[last], slip[last + 1]);
    let crossing = t[last] + (s0 - threshold) / (s0 - s1) * ROW;
    let rate = MU * G * (1.0 + 1.0 / roll.kappa);
    (crossing + threshold / rate, t[last + 1])
}

/// Slip and roll phases against the closed forms, the height, the energies; prints the
/// measured numbers.
fn rolls_as_newton_and_coulomb_say(roll: &Roll) {
    let (h, increment) = run(roll);
    let (start, v_roll, m_eff) = (roll.start(), roll.rolling_speed(), roll.effective_mass());
    let omega_t = (K / m_eff).sqrt();
    // The tangential mode's loading time √(m_eff/k).
    let loading = 1.0 / omega_t;
    // The stick rings with the contact point's speed up to μ·m·g/(m_eff·ω_t); four times that
    // is slip, not ringing.
    let threshold = 4.0 * MU * M * G / (m_eff * omega_t);
    let (t_roll, t_row) = roll_start(&h, roll, threshold);
    println!(
        "{}: roll starts at {t_roll:.6} s (first row {t_row:.3} s), t* = {start:.6} s, loading time {loading:.3e} s",
        roll.id
    );
    // Within a few loading times of t*: the stick catches the contact point within the
    // increment it stops in and holds it.
    assert!(
        (t_roll - start).abs() < 3.0 * loading,
        "{}: roll starts at {t_roll}, t* = {start}",
        roll.id
    );
    // The first row below the threshold: from where the exact slip falls to it, to the row
    // after t* and the loading.
    let early = threshold / (MU * G * (1.0 + 1.0 / roll.kappa));
    assert!(
        t_row >= start - early && t_row <= start + ROW + 3.0 * loading,
        "{}: first rolling row {t_row}",
        roll.id
    );

    // The discrete slide is exact until the increment in which the stick catches, within an
    // increment of t*; from t* on, the closed form rolls.
    let sliding = |t: f64| t < start - increment;
    let rolling = |t: f64| t > start;
    let errors = [
        ("x", largest_error(&h, "ux_node", |t| roll.x(t), sliding)),
        ("v", largest_error(&h, "vx_node", |t| roll.v(t), sliding)),
        (
            "theta",
            largest_error(&h, roll.rotation, |t| -roll.theta(t), sliding),
        ),
    ];
    println!("{}: slip phase worst errors {errors:?}", roll.id);
    // Constant forces, integrated exactly by central differences (the start puts the contact
    // point on the slip cone): round-off of some 50 000 increments' sums.
    for (what, e) in errors {
        assert!(e < 1e-10, "{}: sliding, {what} errs {e:e}", roll.id);
    }
    // The stick's ringing (module doc): speed (m_eff/m)·s0·ω_t about v*, position
    // 2·(m_eff/m)·s0 and turn 2·s0/((1 + κ)·R) behind the closed form at most, each to a factor
    // 1 + (ω_t·h)² for the catch within an increment and central differences' ring.
    let s0 = MU * M * G / K;
    let share = m_eff / M;
    let catch = 1.0 + (omega_t * increment).powi(2);
    let (x, theta) = (|t: f64| roll.x(t), |t: f64| -roll.theta(t));
    let rings: [(&str, &str, f64, Exact); 3] = [
        ("v", "vx_node", share * s0 * omega_t, &|_| v_roll),
        ("x", "ux_node", 2.0 * share * s0, &x),
        (
            "theta",
            roll.rotation,
            2.0 * s0 / ((1.0 + roll.kappa) * R),
            &theta,
        ),
    ];
    for (what, name, ring, exact) in rings {
        let e = largest_error(&h, name, exact, rolling);
        println!(
            "{}: roll phase worst {what} error {e:.6e}, ring bound {ring:.6e} (ratio {:.6}, allowed {catch:.6})",
            roll.id,
            e / ring
        );
        assert!(
            e < catch * ring,
            "{}: {what} errs {e:e} > {ring:e}",
            roll.id
        );
        // And the ring is there (the stick holds the contact point elastically): the rows,
        // 0.87 (disc) and 0.94 (ball) of its period apart, sample its phase densely over the
        // ~400 rows of the roll, so their worst is the swing's full extent, which the catch at
        // s0 sets to within (ω_t·h)² of the bound.
        assert!(e > 0.95 * ring, "{}: {what} rings by {e:e} only", roll.id);
    }

    // The centre sits at R less the penalty's sink m·g/k throughout: the consistent start
    // leaves the normal mode unexcited and friction, along the held face, never loads it.
    let sink = M * G / K;
    let dy = largest_error(&h, "uy_node", |_| -sink, |_| true);
    println!(
        "{}: height off R − mg/k by {dy:.3e} (mg/k = {sink:.3e})",
        roll.id
    );
    assert!(dy < 1e-3 * sink, "{}: height errs {dy:e}", roll.id);

    // Friction dissipates the exact energy: central differences' slip is exact up to the
    // increment the stick catches in, which slips up to μ·g·(1 + 1/κ)·h²/2 = s0·(ω_t·h)²/2 past
    // t*, and the ring, up to s0·(1 + (ω_t·h)²·5/8) (module doc), slips by the excess over s0 at
    // its far swing: at most μ·m·g·s0·(ω_t·h)²·9/8, bounded by twice that.
    let (frictional, balance) = (column(&h, E_FRICTIONAL), column(&h, E_BALANCE));
    let stick = (MU * M * G).powi(2) / (2.0 * K);
    let late = 2.0 * MU * M * G * s0 * (omega_t * increment).powi(2);
    let (e_f, e_b) = (*frictional.last().unwrap(), *balance.last().unwrap());
    let worst_balance = balance.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    println!(
        "{}: e_frictional {e_f:.12} (exact {:.12}, off by {:.3e}, bound {late:.3e}; stick energy {stick:.3e}), e_balance at the end {e_b:.3e}, worst {worst_balance:.3e}",
        roll.id,
        roll.dissipated(),
        e_f - roll.dissipated()
    );
    assert!((e_f - roll.dissipated()).abs() < late, "{}", roll.id);
    // The balance keeps the round-off of the contact point's place (~1 m, ulp 2.2e-16) in the
    // slip each increment measures, times μ·m·g, over 90 000 increments: ~8e-11 J; 1e-9 J is
    // 1e-9 of the energy dissipated and 1/200 of the stick's.
    assert!(
        worst_balance < 1e-9,
        "{}: e_balance {worst_balance:e}",
        roll.id
    );
}

#[test]
fn a_disc_starts_rolling_at_a_third_of_its_slide() {
    rolls_as_newton_and_coulomb_say(&DISC);
}

#[test]
fn a_ball_starts_rolling_at_two_sevenths_of_its_slide() {
    rolls_as_newton_and_coulomb_say(&BALL);
    // It keeps to the x axis and its spin to z: the launch and every force lie in the x–y
    // plane (round-off).
    let (h, _) = run(&BALL);
    for name in ["uz_node", "rx_ball"] {
        let off = largest_error(&h, name, |_| 0.0, |_| true);
        assert!(off < 1e-12, "{name} leaves the plane by {off:e}");
    }
}

/// The stable increment is set by the stick on the contact point, whose effective mass
/// m·I/(I + m·R²) is below the mass the normal penalty moves: 2/√(k/m_eff), √3 (disc) and
/// √(7/2) (ball) below the normal mode's 2/√(k/m).
#[test]
fn the_stick_on_a_rolling_body_sets_the_stable_increment() {
    for roll in [&DISC, &BALL] {
        let stable = ExplicitEngine::finite()
            .stable_increment(&roll.scene(), &RunSettings::default())
            .expect("a stable increment");
        let expected = 2.0 / (K / roll.effective_mass()).sqrt();
        println!(
            "{}: stable increment {:.6e} (undamped {:.6e}), 2/√(k/m_eff) = {expected:.6e}, normal 2/√(k/m) = {:.6e}",
            roll.id,
            stable.increment,
            stable.undamped,
            2.0 / (K / M).sqrt()
        );
        // The linearisation's central differences of forces linear in the perturbation:
        // round-off of 1e-6 steps, ~1e-9 relative.
        assert!(
            (stable.undamped / expected - 1.0).abs() < 1e-6,
            "{}: {} against {expected}",
            roll.id,
            stable.undamped
        );
    }
}

/// The ball's contact has restitution 0: its dashpot is critical for the mass the normal
/// penalty moves, c = 2·√(k·m), so the centred velocity's fixed-point iteration contracts by
/// (h/2)·c/m = h·√(k/m) per pass: 2·r·√(m_eff/m) = 1.069·r at r times the stable increment
/// 2/√(k/m_eff), too slow to converge from r ≈ 0.85 and diverging from r = 0.94. The step is
/// then solved directly, the ball's velocity terms (its turning) read at the last solution
/// (for this ball, isotropic about its reference node, they are round-off: the solve settles
/// in two passes). Up to the stable increment the ball rolls at v* within its ring's bound,
/// and friction dissipates the exact energy within the catch's and the ring's.
#[test]
fn a_ball_rolls_up_to_its_stable_increment_whatever_its_contact_dashpot() {
    let ball = &BALL;
    let (m_eff, v_roll) = (ball.effective_mass(), ball.rolling_speed());
    let omega_t = (K / m_eff).sqrt();
    for ratio in [0.9, 0.95, 0.99] {
        let settings = RunSettings {
            increment: Some(IncrementRule::StableRatio(ratio)),
            ..RunSettings::default()
        };
        let out = crosscheck::run::registry::named("explicit")
            .unwrap()
            .run(&ball.scene(), &settings)
            .unwrap_or_else(|e| panic!("{} at {ratio}: {e}", ball.id));
        let (h, increment) = (out.history, out.info.increment);
        let wt = omega_t * increment;
        // Near ω_t·h = 2 the ring is not small-ω_t·h's (module doc). Central differences keep
        // u(n+½)² + ω_t²·x(n)·x(n+1) for the stretch x and its rate u; at the catch x is s0
        // and u at most the slip's fall over an increment, s0·ω_t²·h. That bounds the
        // contact point's centred speed by s0·ω_t·√(1 + 2(ω_t·h)²) ≤ s0·ω_t·(1 + (ω_t·h)²), the
        // centre's by m_eff/m of it; the largest stretch is s0/√(1 − (ω_t·h/2)²), beyond the
        // cone, so the stick may slip at its swings. Friction then dissipates the exact energy
        // but for the catch's slip past t* (μ·m·g·s0·(ω_t·h)²/2 at most) and what the ring
        // carries, at most ½·k·s0²/(1 − (ω_t·h/2)²): the rolling state itself has no slip
        // to lose energy to. Rows interpolated between increments read within a swing.
        let s0 = MU * M * G / K;
        let catch = 1.0 + wt * wt;
        let ring = m_eff / M * s0 * omega_t;
        // From the first row after the catch's increment.
        let rolling = |t: f64| t > ball.start() + 2.0 * increment;
        let dv = largest_error(&h, "vx_node", |_| v_roll, rolling);
        let e_f = *column(&h, E_FRICTIONAL).last().unwrap() - ball.dissipated();
        let late = MU * M * G * s0 * (wt * wt / 2.0 + 0.5 / (1.0 - wt * wt / 4.0));
        // The direct solve ran: each of its increments evaluates the dashpots at the unit
        // rate of each of the ball's 6 free DOFs and twice more, 8 times or more; the
        // fixed-point iteration, at the case's own increment, 1.5 times an increment.
        let passes = out.info.counters["damping_evaluations"] as f64 / out.info.steps as f64;
        println!(
            "{} at {ratio} (h = {increment:.4e} s, ω_t·h = {wt:.3}): rolling speed off v* by {dv:.3e} (bound {:.3e}), e_frictional off by {e_f:.3e} (bound {late:.3e}), {passes:.2} dashpot evaluations per increment",
            ball.id,
            catch * ring
        );
        assert!(passes > 4.0, "{} at {ratio}: {passes} evaluations", ball.id);
        assert!(dv < catch * ring, "{} at {ratio}: v errs {dv:e}", ball.id);
        assert!(
            e_f.abs() < late,
            "{} at {ratio}: e_frictional errs {e_f:e}",
            ball.id
        );
    }
}

/// The small-rotation model fixes moment arms at t = 0, and a rolling contact point moves
/// over the body: `explicit_small` refuses the pair and says so.
#[test]
fn the_small_rotation_engine_refuses_a_rolling_pair() {
    for roll in [&DISC, &BALL] {
        let refused = ExplicitEngine::small().run(&roll.scene(), &RunSettings::default());
        match refused {
            Err(EngineError::Unsupported(why)) => {
                assert!(why.contains("ball") && why.contains("t = 0"), "{why}")
            }
            other => panic!("{}: {:?}", roll.id, other.map(|o| o.engine)),
        }
    }
}
