//! What reaching an accuracy costs an engine on a case, from its sweep: the cheapest run
//! within it (the sweep's, or a run toward it, [`crate::comparison::reach`]); else the floor
//! that stops it above the accuracy; else an extrapolation along the engine's observed order,
//! where that is an asymptotic range that has not begun to level; else not reached.
//!
//! A floor is never extrapolated across. The floors: where a sweep path stalled (the sweep's
//! floor, with its cause); f32 round-off (the f32 engine's f64 twin twice as accurate at its
//! most refined setting); a levelling error (the local order of the fitted path's last two
//! points below half the fitted order); and where runs toward the accuracy levelled.

use crate::comparison::reach::Ended;
use crate::comparison::work_precision::{CaseSweep, EngineFit, Floor, Row, TARGETS};
use serde::{Deserialize, Serialize};

/// How an engine fares against an accuracy target.
#[derive(Debug, Clone, PartialEq)]
pub enum Reach<'a> {
    /// The cheapest ok point (least minimum CPU time) whose error is within the target.
    Reached(&'a Row),
    /// Not reached; the smallest error the engine attains (None: no ok point).
    NotReached(Option<f64>),
}

/// The cheapest row of `engine` within `target`.
pub fn cheapest<'a>(rows: &'a [Row], engine: &str, target: f64) -> Reach<'a> {
    let own = rows
        .iter()
        .filter(|r| r.engine == engine && r.status == "ok");
    let mut best: Option<&Row> = None;
    let mut smallest: Option<f64> = None;
    for r in own {
        let Some(e) = r.error_max else { continue };
        smallest = Some(smallest.map_or(e, |s: f64| s.min(e)));
        if super::within(e, target) && best.is_none_or(|b| r.cpu_s_min < b.cpu_s_min) {
            best = Some(r);
        }
    }
    best.map_or(Reach::NotReached(smallest), Reach::Reached)
}

/// How a time to accuracy was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reached {
    /// A swept point within the target: the cheapest such.
    Measured,
    /// Beyond the sweep, along the observed order from its most accurate point.
    Extrapolated,
    /// Refinement stopped paying above the target (the floor is named).
    Floor,
    /// Runs toward the target checked the extrapolation and did not reach it within their
    /// budget: it costs more than the CPU time given (that of the costliest such run).
    AtLeast,
    /// Beyond its own sweep, the case's cost is its equivalent case's (named in `cause`), whose
    /// extrapolations are checked.
    AsEquivalent,
    /// Neither reached nor extrapolable (no asymptotic range).
    NotReached,
}

/// What reaching an accuracy costs an engine on a case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CostToAccuracy {
    /// The accuracy asked for: largest error over the peak, worst column.
    pub target: f64,
    /// How it was found.
    pub reached: Reached,
    /// CPU seconds per simulated second (measured or extrapolated).
    pub cpu_s_per_simulated_s: Option<f64>,
    /// The order it was extrapolated along (error ∝ hᵖ, CPU time ∝ 1/h).
    pub order: Option<f64>,
    /// The error of the point it was measured at or extrapolated from; for a floor, the floor.
    pub error: Option<f64>,
    /// The increment it was measured at, or that the extrapolation predicts, seconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub increment: Option<f64>,
    /// For a floor, what limits it.
    pub cause: Option<String>,
}

/// What each of [`TARGETS`] costs `fit`'s engine on `sweep`'s case (see the module doc):
/// extrapolated along the observed order p from the engine's most accurate point on the path
/// the order was fitted on, CPU time × (error / target)^(1/p) at increment × (target /
/// error)^(1/p) (CPU time ∝ 1/h, error ∝ hᵖ).
pub fn costs(sweep: &CaseSweep, fit: &EngineFit) -> Vec<CostToAccuracy> {
    let rows: Vec<Row> = sweep
        .paths
        .iter()
        .filter(|p| p.engine == fit.engine)
        .flat_map(|p| sweep.path_rows(p))
        .collect();
    // The points to extrapolate from: the fitted path's (every path of the engine for the
    // penalty diagonal, which is not one path).
    let along: Vec<Row> = match &fit.observed_order {
        Some(o) => {
            let path: Vec<Row> = sweep
                .paths
                .iter()
                .filter(|p| p.engine == fit.engine && p.label() == o.path)
                .flat_map(|p| sweep.path_rows(p))
                .collect();
            if path.is_empty() { rows.clone() } else { path }
        }
        None => Vec::new(),
    };
    let ok: Vec<&Row> = along
        .iter()
        .filter(|r| r.status == "ok" && r.error_max.is_some())
        .collect();
    let best = ok
        .iter()
        .filter_map(|r| Some((r.error_max?, r.cpu_s_min, r.increment)))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let order = fit.observed_order.as_ref().map(|o| o.value);
    let round_off = |value: f64| twin_below(sweep, &fit.engine, value);
    let floor = fit
        .floor
        .clone()
        .or_else(|| order.and_then(|p| levelling(&ok, p, round_off)));
    TARGETS
        .iter()
        .map(|&target| {
            let mut cost = CostToAccuracy {
                target,
                reached: Reached::NotReached,
                cpu_s_per_simulated_s: None,
                order: None,
                error: None,
                increment: None,
                cause: None,
            };
            if let Reach::Reached(r) = cheapest(&rows, &fit.engine, target) {
                cost.reached = Reached::Measured;
                cost.cpu_s_per_simulated_s = Some(r.cpu_s_min);
                cost.error = r.error_max;
                cost.increment = Some(r.increment);
                return cost;
            }
            let smallest = rows
                .iter()
                .filter(|r| r.status == "ok")
                .filter_map(|r| r.error_max)
                .reduce(f64::min);
            if let Some(other) = &sweep.same_as {
                cost.reached = Reached::AsEquivalent;
                cost.cause = Some(other.clone());
                return cost;
            }
            // A check that fell short at this accuracy or a coarser one bounds this one from
            // below; one that levelled at any accuracy is a floor for every finer one.
            let mine = || sweep.checks.iter().filter(|c| c.engine == fit.engine);
            let short = mine()
                .find(|c| c.target >= target && c.ended == Ended::Budget && !c.runs.is_empty());
            let checked = mine().find(|c| c.ended == Ended::Levelled);
            if let Some(c) = short {
                cost.reached = Reached::AtLeast;
                cost.cpu_s_per_simulated_s = c.runs.iter().map(|r| r.2).reduce(f64::max);
                cost.error = c.runs.iter().filter_map(|r| r.1).reduce(f64::min);
                cost.increment = c.runs.iter().map(|r| r.0).reduce(f64::min);
                return cost;
            }
            match (&floor, checked, order, best) {
                (Some(f), _, _, _) if f.value > target => {
                    cost.reached = Reached::Floor;
                    cost.error = Some(f.value);
                    cost.cause = Some(f.cause.clone());
                }
                (_, Some(_), _, _) if smallest.is_some_and(|e| e > target) => {
                    cost.reached = Reached::Floor;
                    cost.error = smallest;
                    cost.cause = Some(if smallest.is_some_and(round_off) {
                        "f32 round-off: runs toward the accuracy level off, its f64 twin goes lower"
                            .into()
                    } else {
                        "runs toward the accuracy level off".into()
                    });
                }
                (_, _, Some(p), Some((e, cpu, h))) if p >= MIN_EXTRAPOLATED_ORDER => {
                    cost.reached = Reached::Extrapolated;
                    cost.cpu_s_per_simulated_s = Some(cpu * (e / target).powf(1.0 / p));
                    cost.increment = Some(h * (target / e).powf(1.0 / p));
                    cost.order = Some(p);
                    cost.error = Some(e);
                }
                _ => cost.error = smallest,
            }
            cost
        })
        .collect()
}

/// A floor where the fitted path's error is levelling: the local order of its last two ok
/// points below half the fitted order `p` (its smallest error; f32 round-off where
/// `round_off` says the engine's f64 twin goes lower).
fn levelling(ok: &[&Row], p: f64, round_off: impl Fn(f64) -> bool) -> Option<Floor> {
    let [a, b] = [ok.get(ok.len().checked_sub(2)?)?, ok.last()?];
    let (ea, eb) = (a.error_max?, b.error_max?);
    let local = (ea / eb).ln() / (a.increment / b.increment).ln();
    let value = eb.min(ea);
    (local < p / 2.0).then(|| Floor {
        value,
        cause: if round_off(value) {
            format!("f32 round-off: levelling (local order {local:.2}, fitted {p:.2})")
        } else {
            format!("levelling: local order {local:.2}, under half the fitted {p:.2}")
        },
        path: b.path.clone(),
    })
}

/// Whether `engine` is an f32 engine whose f64 twin, on the same case, reaches an error under
/// half of `value`: a level the f64 arithmetic goes below is the f32 engine's round-off.
fn twin_below(sweep: &CaseSweep, engine: &str, value: f64) -> bool {
    let twin = engine.replace("f32", "f64");
    twin != engine
        && sweep
            .paths
            .iter()
            .filter(|p| p.engine == twin)
            .flat_map(|p| p.points.iter())
            .filter(|q| q.status == crate::run::sweep::Status::Ok)
            .filter_map(|q| q.error)
            .any(|e| e.0 < value / 2.0)
}

/// Below this observed order a time to accuracy is not extrapolated (a slope that shallow is
/// not an asymptotic range).
pub const MIN_EXTRAPOLATED_ORDER: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comparison::work_precision::fit;
    use crate::run::sweep::{self, PathKind, Status, SweepPath};

    /// A first-order engine whose CPU time per simulated second is 1/h: error h, so the time to
    /// an error ε is 1/ε, measured or not.
    fn first_order(finest: i32) -> CaseSweep {
        along(
            (0..=finest)
                .map(|k| 10f64.powi(-k))
                .map(|h| (h, h))
                .collect(),
        )
    }

    /// A sweep of `rapier_f64` over the (increment, error) points given, CPU time 1/h.
    fn along(errors: Vec<(f64, f64)>) -> CaseSweep {
        let points = errors
            .into_iter()
            .map(|(h, e)| sweep::Point {
                increment: h,
                penalty_stiffness: None,
                iterations: None,
                steps: (1.0 / h) as u64,
                stable_increment: None,
                error: Some((e, e)),
                cpu_seconds: vec![1.0 / h],
                status: Status::Ok,
                message: None,
            })
            .collect();
        let path = SweepPath {
            engine: "rapier_f64".into(),
            precision: "f64",
            kind: PathKind::Increment {
                penalty_ratio: None,
            },
            points,
            ended: "budget",
        };
        let fits = vec![fit("rapier_f64", std::slice::from_ref(&path), false)];
        CaseSweep {
            case: "synthetic".into(),
            duration: 1.0,
            paths: vec![path],
            fits,
            checks: Vec::new(),
            same_as: None,
        }
    }

    #[test]
    fn a_cost_beyond_the_sweep_is_extrapolated_along_the_observed_order() {
        let sweep = first_order(2); // errors 1, 0.1, 0.01
        let found = costs(&sweep, &sweep.fits[0]);
        let at = |t: f64| found.iter().find(|c| c.target == t).unwrap();
        assert_eq!(at(1e-2).reached, Reached::Measured);
        assert_eq!(at(1e-2).cpu_s_per_simulated_s, Some(100.0));
        // 1e-4 and 1e-6: along order 1 from the finest point, 1/ε (to round-off).
        for t in [1e-4, 1e-6] {
            let c = at(t);
            assert_eq!(c.reached, Reached::Extrapolated);
            assert!((c.order.unwrap() - 1.0).abs() < 1e-12);
            let cpu = c.cpu_s_per_simulated_s.unwrap();
            assert!((cpu * t - 1.0).abs() < 1e-9, "{t}: {cpu}");
        }
        // Swept further, the same figure is measured.
        let further = first_order(4);
        let measured = costs(&further, &further.fits[0]);
        assert_eq!(measured[1].reached, Reached::Measured);
        assert!((measured[1].cpu_s_per_simulated_s.unwrap() * 1e-4 - 1.0).abs() < 1e-9);
    }

    /// An error that falls as h and then levels (its last local order 0.10, under half the
    /// fitted one) is a floor: 1e-4 is not extrapolated across it.
    #[test]
    fn a_levelling_error_is_a_floor_not_an_extrapolation() {
        let sweep = along(vec![(1.0, 1.0), (0.1, 0.1), (0.01, 0.01), (0.001, 0.008)]);
        let found = costs(&sweep, &sweep.fits[0]);
        let c = found.iter().find(|c| c.target == 1e-4).unwrap();
        assert_eq!(c.reached, Reached::Floor, "{c:?}");
        assert_eq!(c.error, Some(0.008));
        assert!(
            c.cause.as_deref().unwrap().starts_with("levelling"),
            "{c:?}"
        );
    }

    /// A run at the increment an extrapolation predicts that falls short, with the next over
    /// the budget, turns the cost into a lower bound: the CPU time of that run, and its error.
    #[test]
    fn a_checked_extrapolation_that_falls_short_is_a_lower_bound() {
        use crate::comparison::reach::{Check, Ended};
        let mut sweep = first_order(2);
        sweep.checks.push(Check {
            case: "synthetic".into(),
            engine: "rapier_f64".into(),
            target: 1e-4,
            order: 1.0,
            predicted_increment: 1e-4,
            predicted_cpu: 1e4,
            runs: vec![(1e-4, Some(1.62e-4), 1e4)],
            ended: Ended::Budget,
        });
        let found = costs(&sweep, &sweep.fits[0]);
        let c = found.iter().find(|c| c.target == 1e-4).unwrap();
        assert_eq!(c.reached, Reached::AtLeast);
        assert_eq!(
            (c.cpu_s_per_simulated_s, c.error),
            (Some(1e4), Some(1.62e-4))
        );
        // A check that levelled is a floor at the smallest error reached.
        sweep.checks[0].ended = Ended::Levelled;
        let found = costs(&sweep, &sweep.fits[0]);
        let c = found.iter().find(|c| c.target == 1e-4).unwrap();
        assert_eq!((c.reached, c.error), (Reached::Floor, Some(1e-2)));
    }
}
