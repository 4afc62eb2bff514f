//! Accuracy on request ([`IncrementRule::Tolerance`]): the increment and the penalty stiffness
//! chosen from the engine's own error model, so that the error against the exact solution of
//! its model is at most the tolerance ε and not ten times less.
//!
//! The model is the scheme's: e(h, k_p) ≈ a h² + b / k_p (second-order phase error of central
//! differences, penalty compliance of first order in 1/k_p). Its two constants are measured on
//! the scene itself by three pilot runs at the case's penalty stiffness k₁ and 0.9 of its
//! stable increment h₁ (by Richardson, each against another run of this engine, never against
//! an exact solution):
//!
//! - a h₁² = 4/3 · ‖x(h₁, k₁) − x(h₁/2, k₁)‖,
//! - b / k₁ = 4/3 · ‖x(h₁/2, k₁) − x(h₁/2, 4k₁)‖ (scenes with penalty contact),
//!
//! with ‖·‖ the largest change over a contract column's peak ([`contract::relative_change`]).
//! The choice then aims at [`AIM`] × ε, the geometric middle of [ε/10, ε]: the stiffness and
//! increment that take the fewest increments with a h² + b/k_p = AIM·ε and h ≤ 0.9 of the
//! stable increment at k_p (which falls as 1/√k_p once the penalty mode is the fastest); the
//! increment is then shortened to divide the output interval, as always.
//!
//! With contact the time constant measured at k₁ need not hold at the chosen k_p (the time
//! error of the penalty mode grows with it), so the chosen run is checked against itself at
//! h/2; when its estimate (that time error plus b/k_p) is off [`CHECK_LOW`]…[`CHECK_HIGH`] × ε,
//! the increment is chosen again from the constant measured there, at most [`ATTEMPTS`] runs.

use super::ExplicitEngine;
use super::integrate::Integration;
use crate::contract;
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
        4.0 / 3.0 * contract::relative_change(scene.family, &a.history, &b.history)
    };
    let coarse = pilot(default_rule, k1)?;
    let h1 = coarse.increment;
    let fine = pilot(IncrementRule::Forced(h1 / 2.0), k1)?;
    let stable_at = |k: Option<f64>| {
        engine
            .stable_increment(scene, &with(IncrementRule::Stable { safety: 1.0 }, k))
            .map(|s| s.increment)
    };
    let s1 = stable_at(k1).ok_or_else(|| {
        EngineError::Unsupported("accuracy on request needs a stable increment".into())
    })?;
    let aim = AIM * eps;
    let a = change(&coarse, &fine) / (h1 * h1);
    let Some(k1) = k1 else {
        // Time error only: one constant, measured where it is largest.
        let h = if a > 0.0 {
            (aim / a).sqrt().min(h1)
        } else {
            h1
        };
        let h = interval / (interval / h - 1e-9).ceil().max(1.0);
        check_increments(scene, h, eps)?;
        let run = engine.integrate(scene, &with(IncrementRule::Given(h), None))?;
        let choice = Choice {
            penalty: None,
            predicted: a * run.increment * run.increment,
            pilot_increments: pilot_increments.get(),
        };
        return Ok((run, choice));
    };
    let stiff = stiffer(h1 / 2.0, 4.0 * k1)?;
    let b = change(&fine, &stiff) * k1;
    // Choose; run; check the time error at the chosen stiffness (the run against itself at
    // h/2: the time error of the penalty mode grows with k_p, so the constant measured at k₁
    // underestimates it there) and correct the increment when the check is off the aim.
    let (mut h, k) = pick(a, b, aim, k1, s1, interval).ok_or_else(|| {
        EngineError::Unsupported(format!(
            "tolerance {eps:e} is out of reach: the penalty compliance alone would need a \
             stiffness above 1e6 × {k1:e}"
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
        let estimate = time + b / k;
        let rest = aim - b / k;
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

/// The (increment, stiffness) with a h² + b/k = aim that takes the fewest increments, the
/// increment at most 0.9 of the stable one (s₁ at k₁, falling as 1/√k above it) and the output
/// interval; stiffnesses on a 1/8-decade grid from k₁/100 to 10⁶ k₁.
fn pick(a: f64, b: f64, aim: f64, k1: f64, s1: f64, interval: f64) -> Option<(f64, f64)> {
    let mut best: Option<(f64, f64)> = None;
    for j in -16..=48 {
        let k = k1 * 10f64.powf(j as f64 / 8.0);
        let rest = aim - b / k;
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
