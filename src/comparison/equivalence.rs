//! Equivalent formulations: cases that build the same problem in different ways (SPRING1,
//! SPRING2 with a held node and SPRINGA along 45° for one oscillator; 2D and 3D; lumped and
//! surface masses of one pinned body) must give the same answer in every engine.
//!
//! Which cases are equivalent is not declared: it is found from the closed form. Two cases of
//! one family, duration and sampling are equivalent on a contract column when their closed-form
//! histories of it are non-zero, not constant, and agree to [`AGREEMENT`] of its peak. Each case is measured
//! against the earliest case (by id) it so agrees with, and every engine's difference between
//! the two runs is reported.

use super::{CLOSED_FORM, first_compared_row, peak, valid_rows};
use crate::contract::{self, History};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Closed-form agreement that makes two cases equivalent on a column, relative to its peak:
/// far above the closed forms' round-off (1e-13 measured), far below any physical difference
/// between the seed cases (the smallest is a few per cent).
pub const AGREEMENT: f64 = 1e-9;

/// One case measured against an equivalent one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Equivalence {
    /// The case measured.
    pub case: String,
    /// The equivalent case it is measured against (the earliest by id that it agrees with).
    pub same_as: String,
    /// The contract columns on which the two closed forms agree (the ones compared).
    pub columns: Vec<String>,
    /// Per engine (the closed form included): the largest difference between the two cases'
    /// histories over those columns, each over the peak of its column in `same_as`'s closed
    /// form.
    pub differences: BTreeMap<String, f64>,
}

/// Columns on which the closed forms of two scenes agree to [`AGREEMENT`] (none when the scenes
/// differ in family, duration or sampling).
fn agreeing_columns(a: (&Scene, &History), b: (&Scene, &History)) -> Vec<String> {
    let ((sa, ha), (sb, hb)) = (a, b);
    let same_grid = sa.family == sb.family
        && ha.rows.len() == hb.rows.len()
        && (sa.duration() - sb.duration()).abs() <= 1e-12 * sa.duration();
    if !same_grid {
        return Vec::new();
    }
    let n = valid_rows(ha).min(valid_rows(hb));
    contract::columns(sa.family)
        .iter()
        .filter(|name| {
            let (Some(x), Some(y)) = (ha.column(name), hb.column(name)) else {
                return false;
            };
            let peak = peak(&x[..n]);
            // A column that holds one value throughout (a contact force under a weight that
            // never changes) tells no two motions apart: it makes no equivalence.
            let moves = x[..n].iter().any(|v| (v - x[0]).abs() > AGREEMENT * peak);
            peak > 0.0 && moves && max_difference(&x[..n], &y[..n]) <= AGREEMENT * peak
        })
        .map(|name| name.to_string())
        .collect()
}

fn max_difference(x: &[f64], y: &[f64]) -> f64 {
    x.iter()
        .zip(y)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
}

/// Find the equivalent cases among `scenes` and measure every engine in `engines` on them.
/// `history(case, engine)` gives a run's history (None where it did not run or failed).
pub fn measure(
    scenes: &[Scene],
    engines: &[String],
    history: impl Fn(&str, &str) -> Option<History>,
) -> Vec<Equivalence> {
    let mut order: Vec<&Scene> = scenes.iter().collect();
    order.sort_by(|a, b| a.id.cmp(&b.id));
    let closed: Vec<Option<History>> = order.iter().map(|s| history(&s.id, CLOSED_FORM)).collect();
    // Each case against the earliest (by id) case it directly agrees with, if any.
    let found: Vec<(usize, usize, Vec<String>)> = (0..order.len())
        .filter_map(|j| {
            let hj = closed[j].as_ref()?;
            (0..j).find_map(|i| {
                let columns = agreeing_columns((order[i], closed[i].as_ref()?), (order[j], hj));
                (!columns.is_empty()).then_some((i, j, columns))
            })
        })
        .collect();
    found
        .into_iter()
        .map(|(i, j, columns)| {
            let (anchor, member) = (order[i], order[j]);
            let peaks: Vec<f64> = columns
                .iter()
                .map(|c| {
                    closed[i]
                        .as_ref()
                        .and_then(|h| h.column(c))
                        .map_or(0.0, |v| peak(&v))
                })
                .collect();
            let differences = std::iter::once(CLOSED_FORM.to_string())
                .chain(engines.iter().filter(|e| *e != CLOSED_FORM).cloned())
                .filter_map(|engine| {
                    let a = history(&anchor.id, &engine)?;
                    let b = history(&member.id, &engine)?;
                    let n = a.rows.len().min(b.rows.len());
                    let worst = columns
                        .iter()
                        .zip(&peaks)
                        .map(|(c, peak)| {
                            let (x, y) = (a.column(c)?, b.column(c)?);
                            let first = first_compared_row(anchor, c).min(n);
                            Some(max_difference(&x[first..n], &y[first..n]) / peak)
                        })
                        .try_fold(0.0f64, |m, d| Some(m.max(d?)))?;
                    Some((engine, worst))
                })
                .collect();
            Equivalence {
                case: member.id.clone(),
                same_as: anchor.id.clone(),
                columns,
                differences,
            }
        })
        .collect()
}
