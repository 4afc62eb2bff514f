//! The settings a case declares: how the time increment is chosen, the damping treatment,
//! the penalty stiffness and contact start, and the tolerances per engine.

use super::{Builder, err, in_range, number};
use crate::case::file::{CaseFile, ContactTable, TimeTable};
use crate::scene::*;
use std::collections::BTreeMap;

/// The case's `[time]` and `[contact]` settings.
pub(super) fn settings(b: &Builder, case: &CaseFile) -> Result<SceneSettings, SceneError> {
    let t = &case.time;
    let increment = increment(b, t)?;
    let damping = match t.damping.as_deref() {
        None | Some("centred") => DampingTreatment::Centred,
        Some("lagged") => DampingTreatment::Lagged,
        Some(other) => return err("time.damping", format!("`{other}`: use centred or lagged")),
    };
    let c = &case.contact;
    let penalty = penalty(b, c)?;
    let contact_start = match c.start.as_deref() {
        None | Some("consistent") => ContactStart::Consistent,
        Some("touching") => ContactStart::Touching,
        Some(other) => {
            return err(
                "contact.start",
                format!("`{other}`: use consistent or touching"),
            );
        }
    };
    Ok(SceneSettings {
        increment,
        damping,
        penalty,
        contact_start,
    })
}

/// How the increment is chosen: given, from an accuracy, from a tolerance, or a safety factor
/// times the stable increment (one of them, and a safety factor only with the last).
fn increment(b: &Builder, t: &TimeTable) -> Result<IncrementRule, SceneError> {
    if t.tolerance.is_some()
        && (t.increment.is_some() || t.accuracy.is_some() || t.safety.is_some())
    {
        return err(
            "time.tolerance",
            "chooses the increment itself: give no `increment`, `accuracy` or `safety` with it",
        );
    }
    if t.safety.is_some() && (t.increment.is_some() || t.accuracy.is_some()) {
        return err(
            "time.safety",
            "applies only when neither `increment` nor `accuracy` is given; remove one",
        );
    }
    Ok(match (t.increment, t.accuracy) {
        (Some(_), Some(_)) => {
            return err("time", "give `increment` or `accuracy`, not both");
        }
        (Some(h), None) => IncrementRule::Given(b.positive("time.increment", h, "an increment")?),
        (None, Some(a)) => {
            IncrementRule::Accuracy(b.positive("time.accuracy", a, "an accuracy")?)
        }
        (None, None) if t.tolerance.is_some() => IncrementRule::Tolerance(b.positive(
            "time.tolerance",
            t.tolerance.unwrap_or(0.0),
            "a tolerance",
        )?),
        (None, None) => {
            let safety = t.safety.unwrap_or(DEFAULT_SAFETY);
            if !(safety > 0.0 && safety <= 1.0) {
                return err("time.safety", format!("must be in (0, 1], got {safety}"));
            }
            in_range("time.safety", safety)?;
            IncrementRule::Stable { safety }
        }
    })
}

/// The penalty stiffness: given, or as a ratio (one of them; the default ratio if neither).
fn penalty(b: &Builder, c: &ContactTable) -> Result<PenaltyRule, SceneError> {
    Ok(match (c.penalty_stiffness, c.penalty_ratio) {
        (Some(_), Some(_)) => {
            return err(
                "contact",
                "give `penalty_stiffness` or `penalty_ratio`, not both",
            );
        }
        (Some(k), None) => {
            PenaltyRule::Stiffness(b.positive("contact.penalty_stiffness", k, "k_p")?)
        }
        (None, Some(r)) => PenaltyRule::Ratio(b.positive("contact.penalty_ratio", r, "a ratio")?),
        (None, None) => PenaltyRule::Ratio(DEFAULT_PENALTY_RATIO),
    })
}

/// The case's tolerances, by engine name: each a positive number.
pub(super) fn tolerances(
    b: &Builder,
    case: &CaseFile,
) -> Result<BTreeMap<String, f64>, SceneError> {
    let mut tolerances = BTreeMap::new();
    for (engine, value) in &case.tolerances {
        let field = format!("tolerances.{engine}");
        let v = number(&field, value)?;
        tolerances.insert(engine.clone(), b.positive(&field, v, "a tolerance")?);
    }
    Ok(tolerances)
}
