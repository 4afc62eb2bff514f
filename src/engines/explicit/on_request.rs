//! Accuracy on request ([`IncrementRule::Tolerance`]): the increment and the penalty stiffness
//! chosen from the engine's own error model, so that the error against the exact solution of
//! its model is at most the tolerance ε and not ten times less, or a refusal that says why no
//! choice can be sure of that.
//!
//! The model is the scheme's: e(h, k_p) ≈ a h² + e_p(k_p) (second-order phase error of central
//! differences; the penalty's error, c (k₁/k_p)^q). Its constants are measured on the scene
//! itself by pilot runs at the case's penalty stiffness k₁, each against another run of this
//! engine, never against an exact solution, with ‖·‖ the largest change over a contract
//! column's peak, contact forces only before the first impact, as the comparison judges them
//! ([`judged_change`]):
//!
//! - the time ladder: h₁ (0.9 of the stable increment), h₁/2, h₁/4, … until the changes
//!   between successive pilots fall by 4 per halving twice in a row (within [`ORDER_SLACK`]):
//!   there the error is of second order and a = 4/3 · ‖x(h) − x(h/2)‖ / h², the largest over
//!   that range. Above it the error is not a h² (a fast mode whose accumulated phase error has
//!   saturated at its amplitude, an impact resolved by two increments), and the model is not
//!   extrapolated there: a choice above it is one of the pilots, its error measured against the
//!   Richardson extrapolation of the two finest. A change under [`NEGLIGIBLE`] ε ends the
//!   ladder too (the finest pilot is then the reference); no second order within
//!   [`MAX_HALVINGS`] halvings is a refusal.
//! - with penalty contact, the penalty ladder: k₁, 4k₁ at the second increment of that range
//!   and 4k₁, 16k₁ at half of it. The changes fall by 4 per 4× k_p for a resting contact's
//!   compliance (q = 1, c = 4/3 ‖x(k₁) − x(4k₁)‖) and by 2 for contact that strikes (q = ½: a
//!   penalty impact lasts π√(m/k_p), which delays what follows; c = 2 ‖·‖); anything else is a
//!   refusal.
//!
//! The choice then aims at [`AIM`] × ε, the geometric middle of [ε/10, ε]: the stiffness and
//! increment that take the fewest increments with a h² + e_p(k_p) = AIM·ε and h ≤ 0.9 of the
//! stable increment at k_p (which falls as 1/√k_p once the penalty mode is the fastest); the
//! increment is then shortened to divide the output interval, as always. Without contact a
//! choice whose error (modelled, or measured for a pilot) is off [[`ACCEPT_LOW`],
//! [`ACCEPT_HIGH`]] × ε is refused: at the largest increment the scene allows, it can be more
//! accurate than ε/10 already.
//!
//! With contact the time constant measured at k₁ need not hold at the chosen k_p (the time
//! error of the penalty mode grows with it), so the chosen run is checked against itself at
//! h/2; when its estimate (that time error plus e_p(k_p)) is off [`CHECK_LOW`]…[`CHECK_HIGH`]
//! × ε, the increment is chosen again from the constant measured there, at most [`ATTEMPTS`]
//! runs; a run whose own estimate is then outside [ε/10, ε] is refused.

use super::ExplicitEngine;
use super::integrate::Integration;
use crate::contract::{self, History};
use crate::engines::{EngineError, RunSettings};
use crate::scene::{DEFAULT_SAFETY, IncrementRule, PenaltyRule, Scene};

/// The fraction of ε the choice aims at.
pub const AIM: f64 = crate::engines::ON_REQUEST_AIM;

/// Most increments a run on request may take: a tolerance that needs more is refused.
pub const MAX_INCREMENTS: f64 = 1e8;

/// What the pilots measured and what was chosen.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice {
    /// The penalty stiffness (scenes with contact).
    pub penalty: Option<f64>,
    /// The error the model predicts for the choice (max over peak).
    pub predicted: f64,
    /// Increments the pilot runs took.
    pub pilot_increments: u64,
}

/// Successive changes confirm an order when their ratio is within this factor of the order's
/// (4 per halving of h for the time error; 4 or 2 per 4× k_p for the penalty's).
const ORDER_SLACK: f64 = 1.3;
/// Most halvings of the pilot increment in search of the time error's second-order range.
const MAX_HALVINGS: usize = 8;
/// A change between two pilots under this fraction of ε ends the time ladder: finer pilots
/// would change nothing that matters against ε.
const NEGLIGIBLE: f64 = 1e-2;
/// Without contact, a choice is made only when its error (modelled within the second-order
/// range, or measured for a pilot) is within [ACCEPT_LOW ε, ACCEPT_HIGH ε].
const ACCEPT_LOW: f64 = 0.12;
/// See [`ACCEPT_LOW`].
const ACCEPT_HIGH: f64 = 0.8;

/// Run `scene` at tolerance `eps`: pilots, the choice, and (with contact) a check of the choice
/// that corrects it when its measured error estimate is off the aim. Returns the run and what
/// was chosen.
pub fn run(
    engine: &ExplicitEngine,
    scene: &Scene,
    settings: &RunSettings,
    eps: f64,
) -> Result<(Integration, Choice), EngineError> {
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    let contact = !scene.contacts.is_empty();
    let k1 = contact.then(|| scene.penalty_stiffness(super::merged(scene, settings).penalty));
    let with = |rule: IncrementRule, k: Option<f64>| RunSettings {
        increment: Some(rule),
        penalty: k.map(PenaltyRule::Stiffness).or(settings.penalty),
        ..*settings
    };
    let pilot_increments = std::cell::Cell::new(0u64);
    let pilot = |rule: IncrementRule, k: Option<f64>| -> Result<Integration, EngineError> {
        let run = engine.integrate(scene, &with(rule, k))?;
        pilot_increments.set(pilot_increments.get() + run.steps);
        Ok(run)
    };
    let default_rule = IncrementRule::Stable {
        safety: DEFAULT_SAFETY,
    };
    // At 4k the increment h/2 is within 0.9 of the stable one when h was within 0.9 of the
    // stable one at k; where it is not (a structural mode limits), 0.9 of the stable one.
    let stiffer = |h: f64, k: f64| match pilot(IncrementRule::Given(h), Some(k)) {
        Err(EngineError::UnstableIncrement { .. }) => pilot(default_rule, Some(k)),
        other => other,
    };
    let change = |a: &Integration, b: &Integration| {
        4.0 / 3.0 * judged_change(scene, &a.history, &b.history, first_impact(&[a, b]))
    };
    let coarse = pilot(default_rule, k1)?;
    let stable_at = |k: Option<f64>| {
        engine
            .stable_increment(scene, &with(IncrementRule::Stable { safety: 1.0 }, k))
            .map(|s| s.increment)
    };
    let s1 = stable_at(k1).ok_or_else(|| {
        EngineError::Unsupported("accuracy on request needs a stable increment".into())
    })?;
    let aim = AIM * eps;

    // The time ladder, at k₁.
    let mut ladder = vec![coarse];
    let mut changes: Vec<f64> = Vec::new();
    let confirmed = loop {
        let last = ladder.last().expect("the coarse pilot");
        let h = last.increment / 2.0;
        if scene.duration() / h > MAX_INCREMENTS || changes.len() >= MAX_HALVINGS {
            return Err(not_second_order(eps, &ladder, &changes));
        }
        let next = pilot(IncrementRule::Forced(h), k1)?;
        changes.push(change(last, &next));
        ladder.push(next);
        let n = changes.len();
        if n >= 3
            && near(changes[n - 3] / changes[n - 2], 4.0)
            && near(changes[n - 2] / changes[n - 1], 4.0)
        {
            break Some(n - 3);
        }
        if changes[n - 1] <= NEGLIGIBLE * eps {
            break None;
        }
    };
    // a over the confirmed range (the largest of its three measures); h_conf its top.
    let (a, top) = match confirmed {
        Some(i) => {
            let a = (i..i + 3)
                .map(|j| changes[j] / (ladder[j].increment * ladder[j].increment))
                .fold(0.0, f64::max);
            (a, i)
        }
        // Changes negligible against ε: no time constant that matters.
        None => (0.0, ladder.len() - 2),
    };
    let h_conf = ladder[top].increment;

    let Some(k1) = k1 else {
        // Time error only. The modelled choice, within the second-order range.
        let wanted = if a > 0.0 { (aim / a).sqrt() } else { h_conf };
        if wanted < h_conf {
            let h = interval / (interval / wanted - 1e-9).ceil().max(1.0);
            let predicted = a * h * h;
            if (ACCEPT_LOW * eps..=ACCEPT_HIGH * eps).contains(&predicted) {
                check_increments(scene, h, eps)?;
                let run = engine.integrate(scene, &with(IncrementRule::Given(h), None))?;
                let choice = Choice {
                    penalty: None,
                    predicted: a * run.increment * run.increment,
                    pilot_increments: pilot_increments.get(),
                };
                return Ok((run, choice));
            }
        }
        // At or above the top of that range: the coarsest pilot whose error, measured against
        // the extrapolation of the two finest, is in the band.
        let n = ladder.len();
        let exact = match confirmed {
            Some(_) => extrapolate(&ladder[n - 2].history, &ladder[n - 1].history),
            None => ladder[n - 1].history.clone(),
        };
        let cut = first_impact(&ladder.iter().collect::<Vec<_>>());
        let measured: Vec<f64> = ladder
            .iter()
            .map(|r| judged_change(scene, &r.history, &exact, cut))
            .collect();
        let within = |e: f64| (ACCEPT_LOW * eps..=ACCEPT_HIGH * eps).contains(&e);
        let Some(j) = measured.iter().position(|e| within(*e)) else {
            return Err(no_landing(eps, &ladder, &measured, s1, interval));
        };
        let predicted = measured[j];
        let run = ladder.swap_remove(j);
        let choice = Choice {
            penalty: None,
            predicted,
            pilot_increments: pilot_increments.get(),
        };
        return Ok((run, choice));
    };

    // The penalty ladder: k₁ and 4k₁ at the second increment of the second-order range, 4k₁
    // and 16k₁ at half of it.
    let h_p = ladder[top + 1].increment;
    let stiff = stiffer(h_p, 4.0 * k1)?;
    let first = change(&ladder[top + 1], &stiff);
    let penalty = if first <= NEGLIGIBLE * eps {
        Penalty::first_order(first, k1)
    } else {
        let stiff_half = stiffer(h_p / 2.0, 4.0 * k1)?;
        let stiffest = stiffer(h_p / 2.0, 16.0 * k1)?;
        let second = change(&stiff_half, &stiffest);
        let ratio = first / second;
        if near(ratio, 4.0) {
            Penalty::first_order(first, k1)
        } else if near(ratio, 2.0) {
            // change = 4/3 ‖·‖, and e(k₁) = ‖·‖ / (1 − 4^(−½)) = 2 ‖·‖.
            Penalty {
                b: 0.0,
                at_k1: 1.5 * first,
                order: 0.5,
                k1,
            }
        } else {
            return Err(EngineError::Unsupported(format!(
                "tolerance {eps:e} is out of reach: the penalty error does not fall as 1/k_p \
                 (resting contact) nor as 1/√k_p (contact that strikes) between k_p = {k1:e}, \
                 4× and 16× it (its changes fell by ×{ratio:.2} per 4× k_p: 4 or 2 expected), \
                 so no penalty stiffness can be chosen for it"
            )));
        }
    };
    // Choose; run; check the time error at the chosen stiffness (the run against itself at
    // h/2: the time error of the penalty mode grows with k_p, so the constant measured at k₁
    // underestimates it there) and correct the increment when the check is off the aim.
    let (mut h, k) = pick(a, &penalty, aim, k1, s1, interval).ok_or_else(|| {
        EngineError::Unsupported(format!(
            "tolerance {eps:e} is out of reach: the penalty error alone (falling as \
             k_p^-{}) would need a stiffness above 1e6 × {k1:e}",
            penalty.order
        ))
    })?;
    let limit = stable_at(Some(k)).map_or(h, |s| DEFAULT_SAFETY * s);
    h = h.min(limit);
    for attempt in 1..=ATTEMPTS {
        check_increments(scene, h, eps)?;
        let run = engine.integrate(scene, &with(IncrementRule::Given(h), Some(k)))?;
        let hc = run.increment;
        let half = pilot(IncrementRule::Forced(hc / 2.0), Some(k))?;
        let time = change(&run, &half);
        let estimate = time + penalty.error(k);
        let rest = aim - penalty.error(k);
        let wanted = if time > 0.0 {
            (hc * (rest / time).sqrt()).min(limit)
        } else {
            limit
        };
        // Accept when the estimate is on the aim, or when the increment cannot change.
        let settled = (CHECK_LOW * eps..=CHECK_HIGH * eps).contains(&estimate)
            || (wanted - hc).abs() <= 0.05 * hc
            || attempt == ATTEMPTS;
        if settled {
            // The engine's own estimate of its error must be within the band it was asked for.
            if !(0.1 * eps..=eps).contains(&estimate) {
                return Err(EngineError::Unsupported(format!(
                    "tolerance {eps:e} is out of reach: after {attempt} choices (last: \
                     k_p = {k:e}, h = {hc:.3e} s) the run's own check (against itself at h/2, \
                     plus the penalty error) estimates its error at {estimate:.2e}, outside \
                     [ε/10, ε]"
                )));
            }
            let choice = Choice {
                penalty: Some(k),
                predicted: estimate,
                pilot_increments: pilot_increments.get(),
            };
            return Ok((run, choice));
        }
        h = wanted;
    }
    unreachable!("the last attempt settles")
}

/// A checked choice is accepted when its error estimate is within [CHECK_LOW ε, CHECK_HIGH ε].
const CHECK_LOW: f64 = 0.15;
/// See [`CHECK_LOW`].
const CHECK_HIGH: f64 = 0.7;
/// Choices run (the last is taken whatever its check says).
const ATTEMPTS: usize = 3;

/// Whether a ratio of successive changes is `expected` within [`ORDER_SLACK`].
fn near(ratio: f64, expected: f64) -> bool {
    ratio.is_finite() && (ratio / expected).ln().abs() <= ORDER_SLACK.ln()
}

/// The penalty's error model, e_p(k) = c (k₁/k)^q.
struct Penalty {
    /// b = c k₁ (q = 1: the same arithmetic as b / k).
    b: f64,
    /// c, the error at k₁.
    at_k1: f64,
    /// q.
    order: f64,
    /// k₁.
    k1: f64,
}

impl Penalty {
    fn first_order(change: f64, k1: f64) -> Self {
        Self {
            b: change * k1,
            at_k1: change,
            order: 1.0,
            k1,
        }
    }

    fn error(&self, k: f64) -> f64 {
        if self.order == 1.0 {
            self.b / k
        } else {
            self.at_k1 * (self.k1 / k).powf(self.order)
        }
    }
}

/// The earliest first impact of these runs (∞ without one).
fn first_impact(runs: &[&Integration]) -> f64 {
    runs.iter()
        .filter_map(|r| r.impacts.first())
        .fold(f64::INFINITY, |m, t| m.min(*t))
}

/// [`contract::relative_change`] of `a` against `b`, the contact force compared only before
/// `impact`, as the comparison judges it against an event-driven solution (after an impact it
/// is a pulse of π√(m/k_p), which output rows sample at random).
fn judged_change(scene: &Scene, a: &History, b: &History, impact: f64) -> f64 {
    if impact.is_infinite() {
        return contract::relative_change(scene.family, a, b);
    }
    let cut = |h: &History| {
        let mut h = h.clone();
        if let Some(k) = h.columns.iter().position(|c| c == "contact_force") {
            for row in h.rows.iter_mut().filter(|r| r[0] >= impact) {
                row[k] = 0.0;
            }
        }
        h
    };
    contract::relative_change(scene.family, &cut(a), &cut(b))
}

/// Richardson's extrapolation of a second-order history from runs at h (`coarse`) and h/2.
fn extrapolate(coarse: &History, fine: &History) -> History {
    let mut out = fine.clone();
    for (row, c) in out.rows.iter_mut().zip(&coarse.rows) {
        for (x, y) in row.iter_mut().zip(c).skip(1) {
            *x = (4.0 * *x - y) / 3.0;
        }
    }
    out
}

/// The refusal of a tolerance whose pilots never showed a second-order error.
fn not_second_order(eps: f64, ladder: &[Integration], changes: &[f64]) -> EngineError {
    let ratios: Vec<String> = changes
        .windows(2)
        .map(|w| format!("×{:.2}", w[0] / w[1]))
        .collect();
    EngineError::Unsupported(format!(
        "tolerance {eps:e} is out of reach: the time error of the pilots at {:.3e} … {:.3e} s \
         did not settle into second order (their successive changes fell by {} per halving of \
         the increment, not ×4 twice in a row), so the a h² model cannot choose the increment",
        ladder[0].increment,
        ladder[ladder.len() - 1].increment,
        if ratios.is_empty() {
            "–".to_string()
        } else {
            ratios.join(", ")
        }
    ))
}

/// The refusal of a tolerance no increment is known to meet within a decade (no contact).
fn no_landing(
    eps: f64,
    ladder: &[Integration],
    measured: &[f64],
    stable: f64,
    interval: f64,
) -> EngineError {
    let h1 = ladder[0].increment;
    if measured[0] < ACCEPT_LOW * eps {
        return EngineError::Unsupported(format!(
            "tolerance {eps:e} is out of reach from below: the largest increment this scene \
             allows, {h1:.3e} s (0.9 of its stable increment {stable:.3e} s, shortened to \
             divide the output interval {interval:.3e} s), already gives an error of {:.2e} of \
             the peak (measured against the pilots' extrapolation), under ε/10",
            measured[0]
        ));
    }
    let j = measured
        .iter()
        .position(|e| *e < ACCEPT_LOW * eps)
        .unwrap_or(measured.len() - 1);
    EngineError::Unsupported(format!(
        "tolerance {eps:e} is out of reach: the error measured at the pilots falls from {:.2e} \
         at {:.3e} s to {:.2e} at {:.3e} s, across the band [ε/10, ε] and where it does not \
         fall as h², so no increment is known to land in it",
        measured[j.saturating_sub(1)],
        ladder[j.saturating_sub(1)].increment,
        measured[j],
        ladder[j].increment
    ))
}

/// Refuse a tolerance whose increment would take more than [`MAX_INCREMENTS`].
fn check_increments(scene: &Scene, h: f64, eps: f64) -> Result<(), EngineError> {
    let increments = scene.duration() / h;
    if increments > MAX_INCREMENTS {
        return Err(EngineError::Unsupported(format!(
            "tolerance {eps:e} is out of reach: it needs an increment of {h:.2e} s, \
             {increments:.1e} increments (at most {MAX_INCREMENTS:e})"
        )));
    }
    Ok(())
}

/// The (increment, stiffness) with a h² + e_p(k) = aim that takes the fewest increments, the
/// increment at most 0.9 of the stable one (s₁ at k₁, falling as 1/√k above it) and the output
/// interval; stiffnesses on a 1/8-decade grid from k₁/100 to 10⁶ k₁.
fn pick(
    a: f64,
    penalty: &Penalty,
    aim: f64,
    k1: f64,
    s1: f64,
    interval: f64,
) -> Option<(f64, f64)> {
    let mut best: Option<(f64, f64)> = None;
    for j in -16..=48 {
        let k = k1 * 10f64.powf(j as f64 / 8.0);
        let rest = aim - penalty.error(k);
        if rest <= 0.0 {
            continue;
        }
        let limit = DEFAULT_SAFETY * s1 * (k1 / k).sqrt().min(1.0 / DEFAULT_SAFETY);
        let h = if a > 0.0 { (rest / a).sqrt() } else { limit };
        let h = h.min(limit).min(interval);
        if best.is_none_or(|(bh, _)| h > bh * (1.0 + 1e-12)) {
            best = Some((h, k));
        }
    }
    best
}
