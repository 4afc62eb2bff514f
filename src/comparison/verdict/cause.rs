//! Which cells need a cause, and which control experiment names it.
//!
//! A cell needs a cause when its engine misses the case's tolerance, or when a rapier engine's
//! error is over [`FLAG_RATIO`] times `explicit`'s on the same case. Its *line* is the one it
//! crossed: the tolerance, or [`FLAG_RATIO`] × `explicit`'s error.
//!
//! A control names the cause when:
//!
//! - **it brings the cell under its line** (within the tolerance; within [`FLAG_RATIO`] ×
//!   `explicit`'s error): the single control that does with the smallest error (a ladder
//!   counted at its coarsest rung that does), else the combination of the time step with
//!   another control that does; or
//! - **the error falls along an order on one of its ladders**: the least-squares order of the
//!   error over the ladder's points is at least half the least order the varied cause has in
//!   physics ([`min_order`]: a first-order scheme's 1 in the increment; a penalty impact's
//!   duration, √(m/k_p), 0.5 in 1/k_p), and its last pair still falls at no less than half of
//!   the fitted order. The ladders: the time step (the cell's own run and the step
//!   rungs, in the increment); the penalty (the cell's own run and the stiffer penalties, in
//!   1/k_p); and each of the engine's own controls with its combination (the control at the
//!   cell's increment and at the ladder's finest, in the increment: *time step and* that
//!   control). The setting that would reach the line along that order is given. Where the time
//!   step ladder falls and then levels (its last pair at less than half the order), the time
//!   step is the cause *in part*: what is left is the level.
//!
//! A cell no control or combination explains is *unexplained*, and every control tried is
//! listed with its error. No fixed fraction of the error decides any of it.

use super::within;
use crate::comparison::attribution::ControlRun;
use crate::run::controls::ControlKind;
use serde::{Deserialize, Serialize};

/// A rapier cell needs a cause when its error is over this many times `explicit`'s.
pub const FLAG_RATIO: f64 = 10.0;

/// The least order of convergence in the increment that counts as the error falling along an
/// order: half of a first-order scheme's.
pub const MIN_ORDER: f64 = 0.5;

/// The least order a ladder's error must fall at to count: half the least order its cause has
/// in physics. The increment: [`MIN_ORDER`]. The penalty stiffness: 0.25, half of the 0.5 at
/// which a penalty impact's duration √(m/k_p), and with it the timing of what follows, falls
/// in 1/k_p (a closed contact's compliance falls faster, at 1).
pub fn min_order(kind: ControlKind) -> f64 {
    match kind {
        ControlKind::Penalty => MIN_ORDER / 2.0,
        _ => MIN_ORDER,
    }
}

/// Why a cell needs a cause.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "value")]
pub enum Flag {
    /// It misses the case's tolerance (the tolerance).
    MissesTolerance(f64),
    /// A rapier error over [`FLAG_RATIO`] × `explicit`'s (the explicit engine's error).
    OverExplicit(f64),
}

impl Flag {
    /// The line the cell crossed: its tolerance, or [`FLAG_RATIO`] × `explicit`'s error.
    pub fn line(self) -> f64 {
        match self {
            Flag::MissesTolerance(t) => t,
            Flag::OverExplicit(x) => FLAG_RATIO * x,
        }
    }
}

/// Why a cell of `engine` with worst error `error` needs a cause, if it does: it misses its
/// `tolerance`, or (a rapier engine on the current release) it is over [`FLAG_RATIO`] ×
/// `explicit`'s error on the case.
pub fn flag(
    engine: &str,
    error: f64,
    tolerance: Option<f64>,
    explicit: Option<f64>,
) -> Option<Flag> {
    match (tolerance, explicit) {
        (Some(t), _) if error > t => Some(Flag::MissesTolerance(t)),
        (_, Some(x))
            if engine.starts_with("rapier")
                && !crate::contract::on_older_release(engine)
                && error > FLAG_RATIO * x =>
        {
            Some(Flag::OverExplicit(x))
        }
        _ => None,
    }
}

/// How a control explains a cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Explanation {
    /// It brings the cell under its line.
    Under,
    /// Its ladder's error falls along `order`; along it the line is reached at about `needed`
    /// (an increment in seconds, or a penalty stiffness).
    AlongOrder {
        /// The order of the error over the ladder (in the increment, or in 1/k_p).
        order: f64,
        /// The setting that would reach the line along that order.
        needed: f64,
    },
    /// The time step ladder's error falls along `order`, then levels at `level`: the time step
    /// explains the part above it.
    InPart {
        /// The order over the ladder.
        order: f64,
        /// The error its finest rung levels at.
        level: f64,
    },
}

/// The cause of a cell: the control that names it and how.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cause {
    /// Index into the cell's controls (for a ladder: its finest point).
    pub control: usize,
    /// How it explains the cell.
    pub explanation: Explanation,
}

/// The cell's own run: the first point of its ladders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Run {
    /// Its worst error.
    pub error: f64,
    /// Its increment, seconds.
    pub increment: f64,
    /// Its penalty stiffness, where it has one.
    pub penalty: Option<f64>,
}

/// A ladder: points (control index, setting, error), coarse to fine, where the setting is what
/// the error is expected to fall with (the increment, or 1/k_p); `usize::MAX` marks the cell's
/// own run.
type Ladder = Vec<(usize, f64, f64)>;

/// The least-squares order of a ladder's error in its setting, and the local order of its last
/// pair; `None` with fewer than two points or an error that is not positive.
pub fn ladder_order(ladder: &[(usize, f64, f64)]) -> Option<(f64, f64)> {
    if ladder.len() < 2 || ladder.iter().any(|p| p.2 <= 0.0 || p.1 <= 0.0) {
        return None;
    }
    let fit: Vec<(f64, f64)> = ladder.iter().map(|p| (p.1, p.2)).collect();
    let (order, _) = crate::run::scaling::fitted_exponent(&fit)?;
    let [a, b] = [ladder[ladder.len() - 2], ladder[ladder.len() - 1]];
    Some((order, (a.2 / b.2).ln() / (a.1 / b.1).ln()))
}

/// The ladders of a cell (see the module doc): the time step's first, then the penalty's, then
/// each own control with its combination.
fn ladders(run: &Run, controls: &[ControlRun]) -> Vec<(ControlKind, Ladder)> {
    let indexed = || controls.iter().enumerate();
    let own = (usize::MAX, run.increment, run.error);
    let step: Ladder = std::iter::once(own)
        .chain(
            indexed()
                .filter(|(_, c)| c.kind == ControlKind::TimeStep && !c.combined)
                .filter_map(|(k, c)| Some((k, c.increment?, c.error?))),
        )
        .collect();
    let penalty: Ladder = run
        .penalty
        .map(|k| (usize::MAX, 1.0 / k, run.error))
        .into_iter()
        .chain(
            indexed()
                .filter(|(_, c)| c.kind == ControlKind::Penalty && !c.combined)
                .filter_map(|(k, c)| Some((k, 1.0 / c.penalty?, c.error?))),
        )
        .collect();
    let mut out = vec![
        (ControlKind::TimeStep, step),
        (ControlKind::Penalty, penalty),
    ];
    for (k, single) in indexed().filter(|(_, c)| !c.combined && !c.kind.refines()) {
        let twin = indexed().find(|(_, c)| c.combined && c.kind == single.kind);
        if let (Some((j, combined)), Some(a), Some(b)) =
            (twin, single.error, twin.and_then(|t| t.1.error))
            && let Some(finest) = combined.increment
        {
            out.push((single.kind, vec![(k, run.increment, a), (j, finest, b)]));
        }
    }
    out
}

/// The cause of a cell whose own run is `run`, flagged by `flag`, from its `controls` (see the
/// module doc); `None`: unexplained.
pub fn explain(run: &Run, flag: Flag, controls: &[ControlRun]) -> Option<Cause> {
    let line = flag.line();
    // A ladder shows the cause at its coarsest rung under the line, where its finest rung is
    // under it too (an error that climbs back over the line as the rungs go on is another
    // cause's); any other control at its own run. Of these, the one with the smallest error.
    let is_under = |c: &ControlRun| c.error.is_some_and(|e| within(e, line));
    let counts = |k: usize, c: &ControlRun| {
        let rungs: Vec<(usize, &ControlRun)> = controls
            .iter()
            .enumerate()
            .filter(|(_, d)| d.kind == c.kind && d.combined == c.combined)
            .collect();
        !c.kind.refines()
            || (rungs
                .iter()
                .take_while(|(j, _)| *j < k)
                .all(|(_, d)| !is_under(d))
                && rungs.last().is_some_and(|(_, d)| is_under(d)))
    };
    let under = |combined: bool| {
        controls
            .iter()
            .enumerate()
            .filter(|(k, c)| c.combined == combined && is_under(c) && counts(*k, c))
            .filter_map(|(k, c)| Some((k, c.error?)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| Cause {
                control: k,
                explanation: Explanation::Under,
            })
    };
    if let Some(c) = under(false) {
        return Some(c);
    }
    let ladders = ladders(run, controls);
    let falling = ladders.iter().find_map(|(kind, ladder)| {
        let (order, last) = ladder_order(ladder)?;
        let &(k, x, e) = ladder.last()?;
        (order >= min_order(*kind) && last >= order / 2.0 && k != usize::MAX).then(|| {
            let needed = x * (line / e).powf(1.0 / order);
            Cause {
                control: k,
                explanation: Explanation::AlongOrder {
                    order,
                    // The penalty ladder's setting is 1/k_p: the stiffness that reaches the line.
                    needed: if *kind == ControlKind::Penalty {
                        1.0 / needed
                    } else {
                        needed
                    },
                },
            }
        })
    });
    if let Some(c) = falling.or_else(|| under(true)) {
        return Some(c);
    }
    let (_, step) = &ladders[0];
    let (order, _) = ladder_order(step).filter(|(order, _)| *order >= MIN_ORDER)?;
    let &(k, _, level) = step.last()?;
    Some(Cause {
        control: k,
        explanation: Explanation::InPart { order, level },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(h: f64, e: f64) -> ControlRun {
        ControlRun {
            kind: ControlKind::TimeStep,
            change: format!("increment {h:e}"),
            increment: Some(h),
            penalty: None,
            error: Some(e),
            failure: None,
            combined: false,
        }
    }

    fn other(kind: ControlKind, e: f64, combined: bool) -> ControlRun {
        ControlRun {
            kind,
            change: "other".into(),
            increment: combined.then_some(1e-6),
            penalty: None,
            error: Some(e),
            failure: None,
            combined,
        }
    }

    fn run(error: f64, increment: f64) -> Run {
        Run {
            error,
            increment,
            penalty: None,
        }
    }

    /// A first-order engine 20 % over its tolerance: the ladder h/4 … falls as h (order 1 to
    /// round-off), so the time step is the cause; along it the tolerance is reached at h/1.2.
    /// The same cell 1 % over its line, or 1 % under the old halving line, gets the same cause:
    /// no fixed fraction decides.
    #[test]
    fn an_error_that_falls_along_the_order_is_the_time_step() {
        for over in [1.2, 1.01, 2.0 * 0.99] {
            let (h, e) = (1e-2, 0.05 * over);
            let controls = [step(h / 4.0, e / 4.0)];
            let c = explain(&run(e, h), Flag::MissesTolerance(0.05), &controls).unwrap();
            assert_eq!(c.control, 0);
            assert_eq!(c.explanation, Explanation::Under);
            // The rung not far enough to reach the line: named along the order.
            let short = [step(h / 1.0001, e / 1.0001)];
            let c = explain(&run(e, h), Flag::MissesTolerance(0.05), &short);
            match c.map(|c| c.explanation) {
                Some(Explanation::AlongOrder { order, needed }) => {
                    assert!((order - 1.0).abs() < 1e-6, "{order}");
                    assert!((needed - h / over).abs() < 1e-9 * h, "{needed}");
                }
                other => panic!("{over}: {other:?}"),
            }
        }
    }

    /// An error that does not fall with the step (order 0.25 < 0.5) is not the time step; one
    /// that falls then levels is the time step in part, unless a combination brings it under
    /// the line; a single control under the line is preferred to both.
    #[test]
    fn levelling_errors_are_in_part_and_combinations_come_after_single_controls() {
        let (h, e) = (1.6e-2, 0.48);
        let flat = [step(h / 4.0, e / 4f64.powf(0.25))];
        assert_eq!(
            explain(&run(e, h), Flag::MissesTolerance(0.25), &flat),
            None
        );
        let level = [step(h / 4.0, e / 4.0), step(h / 16.0, e / 4.4)];
        let c = explain(&run(e, h), Flag::MissesTolerance(0.05), &level).unwrap();
        assert!(matches!(c.explanation, Explanation::InPart { .. }), "{c:?}");
        assert_eq!(c.control, 1);
        let mut combined = level.to_vec();
        combined.push(other(ControlKind::ContactSoftness, 0.04, true));
        let c = explain(&run(e, h), Flag::MissesTolerance(0.05), &combined).unwrap();
        assert_eq!((c.control, c.explanation), (2, Explanation::Under));
        combined.push(other(ControlKind::Precision, 0.045, false));
        let c = explain(&run(e, h), Flag::MissesTolerance(0.05), &combined).unwrap();
        assert_eq!((c.control, c.explanation), (3, Explanation::Under));
    }

    /// A rapier cell within its tolerance but over 10× `explicit`'s error is under its line
    /// once the control is within 10× `explicit`'s.
    #[test]
    fn a_cell_far_from_explicit_is_explained_under_ten_times_explicit() {
        let c = [other(ControlKind::Precision, 9e-3, false)];
        let e = explain(&run(2e-2, 1e-3), Flag::OverExplicit(1e-3), &c).unwrap();
        assert_eq!(e.explanation, Explanation::Under);
        let c = [other(ControlKind::Precision, 1.1e-2, false)];
        assert_eq!(
            explain(&run(2e-2, 1e-3), Flag::OverExplicit(1e-3), &c),
            None
        );
    }

    /// A ladder whose h/64 rung dips under the line and whose finer rungs climb back over it
    /// (f32 round-off growing with the number of steps) does not show the time step.
    #[test]
    fn a_ladder_that_climbs_back_over_its_line_is_not_under_it() {
        let (h, e) = (1.6e-2, 1.0);
        let climbing = [
            step(h / 4.0, 0.8),
            step(h / 16.0, 0.5),
            step(h / 64.0, 0.14),
            step(h / 256.0, 0.94),
        ];
        let c = explain(&run(e, h), Flag::MissesTolerance(0.25), &climbing);
        assert!(
            !matches!(
                c,
                Some(Cause {
                    explanation: Explanation::Under,
                    ..
                })
            ),
            "{c:?}"
        );
        let mut settled = climbing.to_vec();
        settled[3] = step(h / 256.0, 0.05);
        let c = explain(&run(e, h), Flag::MissesTolerance(0.25), &settled).unwrap();
        assert_eq!((c.control, c.explanation), (2, Explanation::Under));
    }
}
