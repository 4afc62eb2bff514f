//! Verdicts: the one place where measurements become judgements. Every pass or fail, every
//! stability outcome, every cause named for a discrepancy and every cost-to-accuracy figure
//! is decided here, from the runs' typed outcomes ([`Status`]: ok, not applicable with its
//! reason, unstable with its evidence, failed) and the comparison's metrics, under one
//! tolerance rule ([`tolerance`]). The report writes what it is given; it decides nothing,
//! and no outcome is recovered from a message's text.
//!
//! - this module: the tolerance an engine is held to, and a cell's verdict;
//! - [`growth`]: whether a run is unstable (its energy keeps growing) or bounded, with the
//!   transient amplification reported beside it, and a stability map run's outcome;
//! - [`cause`]: which control experiment explains a cell's discrepancy;
//! - [`cost`]: what reaching an accuracy costs, measured, extrapolated or stopped by a floor.

pub mod cause;
pub mod cost;
pub mod growth;

use crate::run::Status;
use crate::scene::Scene;

/// The tolerance an engine is held to on a case: the one the case declares for it
/// (`[tolerances] <engine> = <max error / peak>`), or, for an engine on another release of a
/// third-party code (`rapier_f64@0.34`), the one declared for the same engine on the release
/// the case files are written for (`rapier_f64`). `None`: the case declares none (a user's
/// engine until its cases do): its cells are measured and shown, not judged.
pub fn tolerance(scene: &Scene, engine: &str) -> Option<f64> {
    let declared = |name: &str| scene.tolerances.get(name).copied();
    declared(engine).or_else(|| declared(crate::contract::release_of(engine).0))
}

/// The tolerance another code's history is held to by default (`crosscheck judge` without
/// `--tolerance`): the tightest the case declares for any engine.
pub fn tightest(scene: &Scene) -> Option<f64> {
    scene.tolerances.values().copied().reduce(f64::min)
}

/// Whether an error is within a tolerance (the comparison is inclusive: an error equal to the
/// tolerance meets it). Every pass of a column, a cell or a judgement is this.
pub fn within(error: f64, tolerance: f64) -> bool {
    error <= tolerance
}

/// Whether accuracy on request landed: its error against its own model's exact solution in
/// [ε/10, ε] of the peak.
pub fn in_band(achieved: f64, requested: f64) -> bool {
    within(achieved, requested) && achieved >= requested / 10.0
}

/// Whether a run meets its tolerance: `Some(true)` when it ran and its worst error is within
/// the tolerance; `Some(false)` when it is over it, or the run failed or went unstable (an
/// engine that applies and gives no answer misses); `None` when there is nothing to judge (no
/// tolerance declared, the engine does not apply, no column with a peak was compared).
pub fn meets(status: Status, worst: Option<f64>, tolerance: Option<f64>) -> Option<bool> {
    let tolerance = tolerance?;
    match status {
        Status::NotApplicable => None,
        Status::Unstable | Status::Failed => Some(false),
        Status::Ok => worst.map(|w| within(w, tolerance)),
    }
}

/// Whether a run is a *cell*: one engine on one case it applies to, judged. It applies when it
/// ran and was compared over at least one row with the exact solution of its own model, or
/// when it failed or went unstable (a miss); an engine that does not model the scene, or a
/// run compared over no row (the exact solution is valid at none), is not a cell.
pub fn is_cell(status: Status, compared_rows: Option<usize>) -> bool {
    match status {
        Status::NotApplicable => false,
        Status::Unstable | Status::Failed => true,
        Status::Ok => compared_rows.is_some_and(|n| n > 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_that_gives_no_answer_misses_and_one_that_does_not_apply_is_not_judged() {
        assert_eq!(meets(Status::Ok, Some(1e-3), Some(1e-2)), Some(true));
        assert_eq!(meets(Status::Ok, Some(1e-2), Some(1e-2)), Some(true));
        assert_eq!(meets(Status::Ok, Some(1.1e-2), Some(1e-2)), Some(false));
        assert_eq!(meets(Status::Ok, None, Some(1e-2)), None);
        assert_eq!(meets(Status::Unstable, None, Some(1e-2)), Some(false));
        assert_eq!(meets(Status::Failed, None, Some(1e-2)), Some(false));
        assert_eq!(meets(Status::NotApplicable, None, Some(1e-2)), None);
        assert_eq!(meets(Status::Ok, Some(1e-3), None), None);
        assert!(is_cell(Status::Failed, None));
        assert!(!is_cell(Status::NotApplicable, None));
        assert!(!is_cell(Status::Ok, Some(0)));
        assert!(is_cell(Status::Ok, Some(3)));
    }
}
