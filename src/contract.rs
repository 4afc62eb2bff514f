//! The output contract (`docs/problems.md`, section 3): what every engine's time
//! history looks like, stated once so that engines, the comparison and the report read the
//! same names.
//!
//! A history has a header row and one row per output time. The first column is `t`; then the
//! family's contract columns ([`columns`]); then whatever an engine adds: the energy
//! bookkeeping ([`ENERGY_COLUMNS`]) of the engines that keep it, and the validity mark
//! ([`VALID_COLUMN`]) of a closed form. The rows sample the duration uniformly, at least
//! [`MIN_ROWS`] of them, from t = 0 to t = the duration ([`check`]).

use crate::scene::{Family, Scene};

/// The contract columns of a family, in order, after `t`.
pub fn columns(family: Family) -> &'static [&'static str] {
    match family {
        Family::RigidBody => &["rz", "ux", "ux_node", "contact_force"],
        Family::Springs => &["u_end", "u_mid", "v_end", "v_mid"],
    }
}

/// Energy columns an engine that keeps energies appends after the contract columns: kinetic,
/// elastic (springs and penalty), viscous dissipation, external work since the dynamic start,
/// and their balance (kinetic + elastic + viscous − work − initial energy; zero when exact).
pub const ENERGY_COLUMNS: [&str; 5] = [E_KINETIC, E_ELASTIC, E_VISCOUS, W_EXTERNAL, E_BALANCE];

/// Kinetic energy.
pub const E_KINETIC: &str = "e_kinetic";
/// Elastic energy of springs and penalty contact.
pub const E_ELASTIC: &str = "e_elastic";
/// Energy dissipated by dashpots since the dynamic start.
pub const E_VISCOUS: &str = "e_viscous";
/// Work of the loads since the dynamic start.
pub const W_EXTERNAL: &str = "w_external";
/// Energy dissipated by friction since the dynamic start: a column only of a scene with
/// friction, after [`E_VISCOUS`] (frictionless histories keep [`ENERGY_COLUMNS`]).
pub const E_FRICTIONAL: &str = "e_frictional";

/// The energy columns of a scene: [`ENERGY_COLUMNS`], with [`E_FRICTIONAL`] after
/// [`E_VISCOUS`] where the scene has friction (the balance then includes it).
pub fn energy_columns(friction: bool) -> Vec<&'static str> {
    let mut columns = ENERGY_COLUMNS.to_vec();
    if friction {
        columns.insert(3, E_FRICTIONAL);
    }
    columns
}
/// Kinetic + elastic + viscous − work − the initial energy (zero for an exact integration).
pub const E_BALANCE: &str = "e_balance";

/// Column of a closed form marking the rows where its assumptions hold (1) or not (0).
pub const VALID_COLUMN: &str = "valid";

/// Column of an event-driven exact solution: the number of impacts so far. An impact is
/// instantaneous there, so its contact force carries no impulse, and contact forces are
/// compared only on the rows before the first impact.
pub const IMPACTS_COLUMN: &str = "impacts";

/// Contact events whose times an engine reports as measures (`impact_<i>_time` for i up to
/// this; the measure `impacts` counts them all).
pub const IMPACTS_REPORTED: usize = 5;

/// The fewest output rows a history may have.
pub const MIN_ROWS: usize = 200;

/// An engine's name in file names: its `@` (an engine on another release of a third-party
/// code, `rapier_f64@0.34`) written `-` (`rapier_f64-0.34`), so that every file name keeps to
/// the portable characters (letters, digits, `.`, `_`, `-`).
pub fn file_stem(engine: &str) -> String {
    engine.replace('@', "-")
}

/// The engine a file stem names: [`file_stem`] undone (`rapier_f64-0.34` → `rapier_f64@0.34`;
/// a stem whose last `-` is not followed by a release, digits and dots, is the name itself).
pub fn engine_of_stem(stem: &str) -> String {
    match stem.rsplit_once('-') {
        Some((name, release))
            if !release.is_empty() && release.chars().all(|c| c.is_ascii_digit() || c == '.') =>
        {
            format!("{name}@{release}")
        }
        _ => stem.to_string(),
    }
}

/// An engine's name without its release (`rapier_f64@0.34` → `rapier_f64`), and the release
/// (`0.34`) where it names one.
pub fn release_of(engine: &str) -> (&str, Option<&str>) {
    match engine.split_once('@') {
        Some((base, release)) => (base, Some(release)),
        None => (engine, None),
    }
}

/// Whether an engine runs another release of a third-party code than the current one
/// (`rapier_f64@0.34`): the report's versions section is where its cells are judged and shown.
pub fn on_older_release(engine: &str) -> bool {
    release_of(engine).1.is_some()
}

/// A time history: a header and rows, the first column `t`.
#[derive(Debug, Clone, PartialEq)]
pub struct History {
    /// Column names, starting with `t`.
    pub columns: Vec<String>,
    /// Rows, each as long as `columns`.
    pub rows: Vec<Vec<f64>>,
}

impl History {
    /// Values of a named column.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

/// How far two runs of one engine on one scene are apart: over the family's contract columns,
/// the largest |a − b| divided by the peak |b| of the column (a contact force from its second
/// row: an impulse-based engine's first row is a mean over its first increment). What an engine
/// uses to estimate its own error from runs at two settings (accuracy on request); not a
/// measure against an exact solution.
///
/// A column whose peak is below 1e-6 of the largest column peak (a held DOF that a soft joint
/// lets drift by 1e-9) is left out: its relative change is noise.
pub fn relative_change(family: Family, a: &History, b: &History) -> f64 {
    let measured: Vec<(f64, f64)> = columns(family)
        .iter()
        .filter_map(|name| {
            let (x, y) = (a.column(name)?, b.column(name)?);
            let first = usize::from(*name == "contact_force");
            let n = x.len().min(y.len());
            let peak = y[..n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let worst = x[first.min(n)..n]
                .iter()
                .zip(&y[first.min(n)..n])
                .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
            Some((peak, worst))
        })
        .collect();
    let largest = measured.iter().fold(0.0f64, |m, c| m.max(c.0));
    measured
        .iter()
        .filter(|(peak, _)| *peak > 1e-6 * largest)
        .map(|(peak, worst)| worst / peak)
        .fold(0.0, f64::max)
}

/// Every value of a history must be finite: the first non-finite one fails it, naming the
/// column and the time.
pub fn check_finite(history: &History) -> Result<(), String> {
    for row in &history.rows {
        if let Some(k) = row.iter().position(|x| !x.is_finite()) {
            return Err(format!(
                "non-finite value {} in column `{}` at t = {:e}; nothing of this run is written",
                row[k],
                history.columns.get(k).map_or("?", String::as_str),
                row.first().copied().unwrap_or(f64::NAN)
            ));
        }
    }
    Ok(())
}

/// Check a history against the output contract for `scene`: header `t` then the family's
/// contract columns; every row as long as the header; at least [`MIN_ROWS`] rows sampling the
/// duration uniformly, first t = 0, last t = the duration.
pub fn check(scene: &Scene, history: &History) -> Result<(), String> {
    let want: Vec<&str> = std::iter::once("t")
        .chain(columns(scene.family).iter().copied())
        .collect();
    let got: Vec<&str> = history.columns.iter().map(String::as_str).collect();
    if !got.starts_with(&want) {
        return Err(format!(
            "columns must start with {}; got {}",
            want.join(","),
            got.join(",")
        ));
    }
    if let Some((i, r)) = history
        .rows
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != history.columns.len())
    {
        return Err(format!(
            "row {i} has {} values for {} columns",
            r.len(),
            history.columns.len()
        ));
    }
    let n = history.rows.len();
    if n < MIN_ROWS {
        return Err(format!("{n} rows; at least {MIN_ROWS} are needed"));
    }
    let duration = scene.duration();
    let tol = 1e-9 * duration;
    for (i, r) in history.rows.iter().enumerate() {
        let expected = duration * i as f64 / (n - 1) as f64;
        let on_grid = (r[0] - expected).abs() <= tol; // false for NaN too
        if !on_grid {
            return Err(format!(
                "row {i} has t = {:e}; uniform sampling of 0..{duration:e} over {n} rows needs {expected:e}",
                r[0]
            ));
        }
    }
    Ok(())
}
