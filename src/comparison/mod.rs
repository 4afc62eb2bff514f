//! Comparison: every engine's history measured against the exact solution of its own model
//! (its *baseline*, [`baseline`]) and against the closed form.
//!
//! One module owns the metrics, so the report and the tests compute them the same way. Per
//! contract column, over the rows where the baseline is valid:
//! - `max`: the largest absolute error divided by the peak of the baseline column (a rotation
//!   column: the orientation error over the smaller of its peak and π, [`orientation`]);
//! - `rms`: the root-mean-square error divided by the same peak;
//! - `end`: the error at the last valid row divided by the same peak.
//!
//! A column whose exact solution is zero over its window (a held DOF, a contact force before
//! the first impact, a node that friction holds), identically or to round-off
//! ([`round_off`]), has no peak to divide by: it is compared in its own
//! unit ([`ColumnError::relative`] false, [`ColumnError::unit`]) and never enters
//! [`Comparison::worst_max`], the largest *relative* error, which is what tolerances apply to.
//! A comparison over no rows (the exact solution is invalid from the start) has no worst
//! error at all. The energy balance error of an engine that writes `e_balance` is its largest
//! magnitude divided by the largest kinetic + elastic energy of the run.
//!
//! A contact force is compared from the first increment on ([`first_compared_row`]): an engine
//! that resolves contact by impulses (rapier) can only report at t = 0 the mean force of its
//! first increment, not the instantaneous force of the initial state, so the t = 0 value is
//! measured separately (`initial_errors`) and reported beside the others, not mixed into them.

pub mod attribution;
pub mod contact;
pub mod discrepancy;
pub mod equivalence;
pub mod friction;
pub mod invariance;
pub mod judge;
pub mod on_request;
pub mod orientation;
pub mod reach;
pub mod stability;
pub mod summary;
pub mod verdict;
pub mod work_precision;

use crate::contract::{self, History, IMPACTS_COLUMN, VALID_COLUMN};
use crate::scene::{Probe, Scene};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The closed form (the benchmark's small-rotation model): every engine's total error is
/// measured against it, and it is the baseline of the small-rotation engines.
pub const CLOSED_FORM: &str = "analytic";

/// The converged solution of the finite-rotation model, the baseline of the engines that
/// simulate finite rotation.
pub const FINITE_ROTATION_REFERENCE: &str = "reference";

/// The worst largest error (over each column's peak) of `engine`'s history `h` on `scene`
/// against the exact solution of its own model among `outcome`'s histories (`None` where that
/// solution did not run): how the stability map and accuracy on request judge a run.
pub fn against_own_model(
    outcome: &crate::run::Outcome,
    scene: &Scene,
    engine: &str,
    h: &History,
) -> Option<f64> {
    compare(scene, outcome.history(&scene.id, baseline(engine)?)?, h).worst_max
}

/// The exact solutions: the engines every other is judged against, and that are not judged
/// themselves (the gap between the two is model form, reported apart).
pub const EXACT_SOLUTIONS: [&str; 2] = [CLOSED_FORM, FINITE_ROTATION_REFERENCE];

/// The exact solution an engine is judged against: that of its own model. `explicit_small`
/// (the small-rotation idealisation) and `reference` (whose gap to it is model form) against
/// the closed form; every finite-rotation engine (`explicit`, `rapier_*`) against `reference`;
/// the closed form against nothing.
pub fn baseline(engine: &str) -> Option<&'static str> {
    match engine {
        CLOSED_FORM => None,
        FINITE_ROTATION_REFERENCE | "explicit_small" => Some(CLOSED_FORM),
        _ => Some(FINITE_ROTATION_REFERENCE),
    }
}

/// Errors of one column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColumnError {
    /// Column name.
    pub column: String,
    /// Peak |value| of the exact solution's column over its window: the rows where it is
    /// valid (a contact force's up to the first impact, its t = 0 row included, which is
    /// measured apart in [`Comparison::initial_errors`]).
    pub peak: f64,
    /// Max |error| / peak (absolute, in [`ColumnError::unit`], when the peak is 0).
    pub max: f64,
    /// RMS error / peak (absolute when the peak is 0).
    pub rms: f64,
    /// Error at the last valid row / peak (absolute when the peak is 0).
    pub end: f64,
    /// Whether the errors are relative to the peak (false: absolute, the peak being 0).
    pub relative: bool,
    /// Whether `peak` is the scene's extent, a displacement's exact solution being zero over
    /// its window (a held DOF, a node friction holds).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub over_extent: bool,
    /// The column's unit (m, m/s, rad, N), what an absolute error is in.
    #[serde(default)]
    pub unit: String,
}

/// One engine's history against the analytic one, for one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Per contract column.
    pub columns: Vec<ColumnError>,
    /// The largest relative `max` over the columns (the figure tolerances apply to); `None`
    /// where no row was compared or no column has a peak.
    pub worst_max: Option<f64>,
    /// Rows compared (where the exact solution is valid).
    pub rows: usize,
    /// Energy balance error, for engines that keep energies.
    pub energy_balance: Option<f64>,
    /// Per column compared from the first increment on ([`first_compared_row`]): the signed
    /// error at t = 0 over the peak (candidate − reference), measured separately.
    #[serde(default)]
    pub initial_errors: BTreeMap<String, f64>,
}

/// What the closed form says about its own validity (rigid-contact cases).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactValidity {
    /// Contact force at t = 0.
    pub initial_force: f64,
    /// Smallest compressive contact force over the valid rows divided by the largest.
    pub margin: f64,
    /// Time the contact force first turns tensile (the end of validity), if it does.
    pub valid_until: Option<f64>,
}

/// The largest magnitude of a column (its peak; 0 for an empty one).
pub fn peak(values: &[f64]) -> f64 {
    values.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The first row at which `column` is compared: 1 for a contact force (its t = 0 value is
/// measured separately, see the module doc), 0 for everything else.
pub fn first_compared_row(scene: &Scene, column: &str) -> usize {
    let contact = scene
        .columns
        .iter()
        .any(|c| c.name == column && matches!(c.probe, Probe::ContactForce { .. }));
    usize::from(contact)
}

/// Rows before the first one an exact solution marks invalid (all rows without a `valid` column).
pub fn valid_rows(reference: &History) -> usize {
    match reference.column(VALID_COLUMN) {
        Some(v) => v.iter().position(|x| *x == 0.0).unwrap_or(v.len()),
        None => reference.rows.len(),
    }
}

/// Measure `candidate` against `reference` (an exact solution, with its `valid` column) on the
/// scene's contract columns; a rotation column as an orientation ([`orientation`]: from the
/// body's points where the case has three).
pub fn compare(scene: &Scene, reference: &History, candidate: &History) -> Comparison {
    let n = valid_rows(reference).min(candidate.rows.len());
    let mut initial_errors = BTreeMap::new();
    let columns: Vec<ColumnError> = contract::columns(scene.family)
        .iter()
        .filter_map(|name| {
            let a = reference.column(name)?;
            let b = candidate.column(name)?;
            // Contact forces only before the first impact of an event-driven solution.
            let n = if first_compared_row(scene, name) > 0 {
                reference
                    .column(IMPACTS_COLUMN)
                    .and_then(|i| i.iter().position(|x| *x > 0.0))
                    .map_or(n, |k| k.min(n))
            } else {
                n
            };
            let first = first_compared_row(scene, name);
            if n <= first {
                // No row of this column is compared.
                return None;
            }
            let (a, b) = (&a[..n], &b[..n]);
            // An exact solution that is zero over the rows compared (a held DOF, a node that
            // friction holds, a contact force before the first impact), or only round-off away
            // from it, has no peak of its own. A displacement's errors are then divided by the
            // scene's extent ([`scene_scale`]: a creep of 1e-5 m on a scene 1 m across is
            // 1e-5); any other column is compared in its unit (a contact force before an
            // impact has no scale an instantaneous impact's impulse could be judged against).
            let own = peak(a) > round_off(scene, name);
            let peak = match (own, unit(scene, name)) {
                (true, _) => peak(a),
                (false, "m") => scene_scale(scene, name),
                (false, _) => 0.0,
            };
            let relative = peak > 0.0;
            let (errors, scale): (Vec<f64>, f64) = match rotated_body(scene, name) {
                Some(body) => {
                    let (errors, scale) =
                        orientation::errors(scene, body, (reference, candidate), (a, b), first..n);
                    let scale = match (own, relative) {
                        (true, _) => scale,
                        (false, true) => peak,
                        (false, false) => 1.0,
                    };
                    (errors, scale)
                }
                None => (
                    a[first..]
                        .iter()
                        .zip(&b[first..])
                        .map(|(x, y)| (y - x).abs())
                        .collect(),
                    if relative { peak } else { 1.0 },
                ),
            };
            if first > 0 {
                initial_errors.insert(name.to_string(), (b[0] - a[0]) / scale);
            }
            let max = errors.iter().fold(0.0f64, |m, e| m.max(*e));
            let rms =
                (errors.iter().map(|e| e * e).sum::<f64>() / errors.len().max(1) as f64).sqrt();
            Some(ColumnError {
                column: name.to_string(),
                peak,
                max: max / scale,
                rms: rms / scale,
                end: errors.last().copied().unwrap_or(0.0) / scale,
                relative,
                over_extent: relative && !own,
                unit: unit(scene, name).to_string(),
            })
        })
        .collect();
    let worst_max = columns
        .iter()
        .filter(|c| c.relative)
        .map(|c| c.max)
        .reduce(f64::max);
    Comparison {
        worst_max,
        rows: n,
        energy_balance: energy_balance(candidate),
        initial_errors,
        columns,
    }
}

/// The body whose rotation `column` measures, where it is a rotation column.
fn rotated_body(scene: &Scene, column: &str) -> Option<crate::scene::BodyId> {
    scene.columns.iter().find_map(|c| match c.probe {
        Probe::Rotation { body, .. } if c.name == column => Some(body),
        _ => None,
    })
}

/// Whether an exact solution has an impact: a contact pair that strikes (its `impacts` column
/// above zero at some row). Restitution enters an exact solution only there.
pub fn strikes(exact: &History) -> bool {
    exact
        .column(IMPACTS_COLUMN)
        .is_some_and(|i| i.iter().any(|x| *x > 0.0))
}

/// The unit of a contract column: what the scene's probe measures (m, m/s, rad, N; "" for an
/// identically zero column).
pub fn unit(scene: &Scene, column: &str) -> &'static str {
    match scene
        .columns
        .iter()
        .find(|c| c.name == column)
        .map(|c| &c.probe)
    {
        Some(Probe::Displacement { .. } | Probe::Gap { .. }) => "m",
        Some(Probe::Velocity { .. }) => "m/s",
        Some(Probe::Rotation { .. }) => "rad",
        Some(Probe::ContactForce { .. }) => "N",
        Some(Probe::Zero { .. }) | None => "",
    }
}

/// The largest magnitude an exact solution's `column` may have and still be zero: 1e-12 of
/// the scene's own scale in the column's unit (a few thousand units of round-off): its extent
/// (the largest distance of a node from the origin) for lengths, the extent over the duration
/// for speeds, 1 rad for rotations, the largest load for forces; 0 where the scene has no
/// such scale.
pub fn round_off(scene: &Scene, column: &str) -> f64 {
    const ROUND_OFF: f64 = 1e-12;
    ROUND_OFF * scene_scale(scene, column)
}

/// The scene's own scale in `column`'s unit: its extent (the largest distance of a node from
/// the origin) for lengths, the extent over the duration for speeds, 1 rad for rotations, the
/// largest load for forces; 0 where the scene has no such scale.
pub fn scene_scale(scene: &Scene, column: &str) -> f64 {
    let extent = scene
        .nodes
        .iter()
        .fold(0.0_f64, |m, n| m.max(n.position.norm()));
    let load = scene.loads.iter().fold(0.0_f64, |m, l| {
        let most = l.amplitude.as_ref().map_or(1.0, |a| {
            a.points.iter().fold(0.0_f64, |m, (_, v)| m.max(v.abs()))
        });
        m.max(l.force.norm() * most)
    });
    match unit(scene, column) {
        "m" => extent,
        "m/s" => extent / scene.duration(),
        "rad" => 1.0,
        "N" => load,
        _ => 0.0,
    }
}

/// Each output column's [`scene_scale`] where the scene has a finite one (contract columns
/// and the case's own; the energy columns are read against [`energy_scale`] instead), by
/// name: what [`change_scale`] reads a column whose peak is smaller against, kept in
/// `summary.json` so that two reports can be compared without their case files.
pub fn scene_scales(scene: &Scene) -> BTreeMap<String, f64> {
    scene
        .columns
        .iter()
        .map(|c| (c.name.clone(), scene_scale(scene, &c.name)))
        .filter(|(_, s)| *s > 0.0 && s.is_finite())
        .collect()
}

/// What a change of history column `column` is read against when two runs of one cell are
/// compared row by row (the machine tier of `crosscheck compare`): its peak or, where larger,
/// the scale its round-off comes from. Another order of the same operations moves a value by
/// a few ulps of the magnitudes it is computed from, not of the value itself: an energy column
/// (the balance above all, itself a residual of round-off) by ulps of the energy the balance
/// is read against ([`energy_scale`]), and any other column by ulps of the scene's scale in
/// its unit (`scene_scale`, from [`scene_scales`]; 0 where unknown): a displacement by ulps of
/// the positions it is the difference of, so that a sideways displacement at rest but for
/// round-off is not read against its own 1e-17 m, and a displacement smaller than the scene's
/// extent is read against the extent. 0 where all are.
pub fn change_scale(h: &History, column: &str, scene_scale: f64) -> f64 {
    let peak = h
        .column(column)
        .map_or(0.0, |c| c.iter().fold(0.0_f64, |m, x| m.max(x.abs())));
    let floor = if contract::energy_columns(true).contains(&column) {
        energy_scale(h).unwrap_or(0.0)
    } else {
        scene_scale
    };
    peak.max(floor)
}

/// Largest |e_balance| divided by [`energy_scale`] (in joules where that is 0).
pub fn energy_balance(h: &History) -> Option<f64> {
    let balance = h.column(contract::E_BALANCE)?;
    let scale = energy_scale(h)?;
    let worst = balance.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    Some(if scale > 0.0 { worst / scale } else { worst })
}

/// The energy an energy balance is read against: the largest of the kinetic + elastic energy,
/// the external work and the energy dissipated (viscous, frictional), over the rows. A node
/// that friction holds has almost no kinetic or elastic energy while its load works on its
/// sinking into the face; the balance is read against that work, not against the ~1e-40 J of
/// its resting motion.
pub fn energy_scale(h: &History) -> Option<f64> {
    let kinetic = h.column(contract::E_KINETIC)?;
    let elastic = h.column(contract::E_ELASTIC)?;
    let largest = |name: &str| {
        h.column(name)
            .map_or(0.0, |c| c.iter().fold(0.0_f64, |m, x| m.max(x.abs())))
    };
    let mechanical = kinetic
        .iter()
        .zip(&elastic)
        .fold(0.0f64, |m, (k, e)| m.max(k + e));
    Some(
        [
            contract::W_EXTERNAL,
            contract::E_VISCOUS,
            contract::E_FRICTIONAL,
        ]
        .iter()
        .fold(mechanical, |m, c| m.max(largest(c))),
    )
}

/// Contact validity of an analytic rigid-contact history (None without a contact column).
pub fn contact_validity(reference: &History) -> Option<ContactValidity> {
    let force = reference.column("contact_force")?;
    let t = reference.column("t")?;
    let n = valid_rows(reference);
    let valid = &force[..n];
    let max = valid.iter().fold(0.0f64, |m, x| m.max(*x));
    let min = valid.iter().fold(f64::INFINITY, |m, x| m.min(*x));
    Some(ContactValidity {
        initial_force: force[0],
        margin: if max > 0.0 { min / max } else { 0.0 },
        valid_until: (n < force.len()).then(|| t[n]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A history of 1 kJ swapped between kinetic and elastic energy, its balance a residual
    /// of 1e-10 J, a displacement of 0.2 m and one at rest but for 1e-17 m of round-off.
    fn history() -> History {
        let columns = ["t", "ux", "uy", "e_kinetic", "e_elastic", "e_balance"];
        let rows = (0..=100)
            .map(|i| {
                let phase = f64::from(i) * 0.1;
                let (c, s) = (phase.cos(), phase.sin());
                vec![
                    phase,
                    0.2 * s,
                    1e-17 * c,
                    1e3 * c * c,
                    1e3 * s * s,
                    1e-10 * s,
                ]
            })
            .collect();
        History {
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rows,
        }
    }

    #[test]
    fn a_change_is_read_against_the_scale_its_round_off_comes_from() {
        let h = history();
        // The mechanical energy is 1 kJ on every row (up to round-off of cos² + sin²).
        let energy = energy_scale(&h).unwrap();
        assert!((energy - 1e3).abs() < 1e-12, "{energy}");
        // The balance, 1e-10 J at its peak, is read against that energy.
        assert_eq!(change_scale(&h, "e_balance", 0.0), energy);
        assert_eq!(change_scale(&h, "e_kinetic", 5e3), energy);
        // A column at rest is read against the scene's scale in its unit (3 m), one that moves
        // more than it against its own peak (0.2 m, reached at phase 4.7 rad to within
        // 1 − |sin 4.7| = 7.7e-5 of it).
        assert_eq!(change_scale(&h, "uy", 3.0), 3.0);
        assert_eq!(change_scale(&h, "uy", 0.0), 1e-17);
        let ux = change_scale(&h, "ux", 0.1);
        assert!((ux - 0.2).abs() < 0.2 * 2e-4 && ux < 0.2, "{ux}");
    }
}
