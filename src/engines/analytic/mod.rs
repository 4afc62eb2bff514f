//! `analytic`: closed-form solutions, derived from the problems' equations and written
//! independently of the central-difference engine's force assembly.
//!
//! - [`springs`]: the spring/dashpot/mass systems by hand: the damped single-DOF oscillator,
//!   and the two-DOF system through the exponential of its 4×4 state matrix.
//! - [`rigid`]: the rigid body with a contact node slaved to its face (small rotation, rigid
//!   persistent contact), through the exponential of the augmented state; it reports the
//!   contact force, its smallest compressive margin and its validity window.
//! - [`linear`]: a general exact solver for any linear scene without contact (springs,
//!   dashpots, masses, small-rotation bodies); the seed cases keep their hand-derived forms so
//!   the two cross-check each other. [`AnalyticEngine`] falls back to it for every scene
//!   without contact that no hand-derived form covers, so it refuses only contact scenes
//!   outside the rigid-contact form.
//! - [`friction`]: Coulomb friction: one particle on the plane face of a held body under
//!   constant or tabular-amplitude loads and at most one spring, along one line, by its stick and
//!   slip phases. Every scene with friction goes to it, and it refuses what it does not cover.
//! - [`roll`]: a ball (a disc in 2D) launched on the plane face of a held body, sliding until it
//!   rolls: the slip of its contact point as the friction form's line. Every scene whose contact
//!   node carries a ball goes to it.
//!
//! A load that varies in time (an amplitude) is taken only by the friction form: a scene
//! without friction that has one is refused.

pub mod friction;
mod friction_phases;
pub mod linear;
pub mod rigid;
pub mod roll;
pub mod springs;

use super::{Engine, EngineError, History, RunInfo, RunOutput, RunSettings};
use crate::contract::{self, VALID_COLUMN};
use crate::scene::{Family, Scene};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use std::time::Instant;

/// The closed-form engine.
#[derive(Debug, Clone, Copy, Default)]
pub struct AnalyticEngine;

impl Engine for AnalyticEngine {
    fn name(&self) -> &str {
        "analytic"
    }

    fn run(&self, scene: &Scene, _settings: &RunSettings) -> Result<RunOutput, EngineError> {
        let start = Instant::now();
        let history = if scene.contacts.iter().any(|c| c.rolls()) {
            roll::solve(scene)?
        } else if scene.has_friction() {
            friction::solve(scene)?
        } else if scene.has_amplitudes() {
            return unsupported(
                "a load that varies in time (an amplitude) in a scene without friction (only the friction closed form takes amplitudes)",
            );
        } else {
            frictionless(scene)?
        };
        Ok(RunOutput {
            engine: self.name().into(),
            history,
            info: RunInfo {
                increment: 0.0,
                steps: 0,
                stable_increment: None,
                penalty_stiffness: None,
                wall_seconds: start.elapsed().as_secs_f64(),
                counters: BTreeMap::new(),
                measures: BTreeMap::new(),
            },
        })
    }
}

/// A scene without friction: its hand-derived form, else (without contact) the linear solver.
fn frictionless(scene: &Scene) -> Result<History, EngineError> {
    let hand = match scene.family {
        Family::Springs => springs::solve(scene),
        Family::RigidBody => rigid::solve(scene).map(|s| s.history),
    };
    // A scene without contact that no hand-derived form covers (another topology, an
    // element off the line of action, any damping) is linear: solve it exactly.
    match hand {
        Err(EngineError::Unsupported(_)) if scene.contacts.is_empty() => linear::solve(scene),
        other => other,
    }
}

/// The state `s(t) = exp(A t) s0` at each time (each from t = 0, so no error accumulates).
///
/// A matrix or state with a non-finite entry (an overflowing scene) is refused rather than
/// handed to the exponential, which would not terminate on it.
pub fn exponential_states(
    a: &DMatrix<f64>,
    s0: &DVector<f64>,
    times: &[f64],
) -> Result<Vec<DVector<f64>>, EngineError> {
    if !(a.iter().all(|x| x.is_finite()) && s0.iter().all(|x| x.is_finite())) {
        return Err(EngineError::Failed(
            "the state matrix has a non-finite entry (the scene's numbers overflow)".into(),
        ));
    }
    times
        .iter()
        .map(|&t| {
            let at = a * t;
            if at.iter().all(|x| x.is_finite()) {
                Ok(at.exp() * s0)
            } else {
                Err(EngineError::Failed(format!(
                    "exp(A t) overflows at t = {t:e}"
                )))
            }
        })
        .collect()
}

/// A history with the contract columns of `scene` and a `valid` column.
pub(crate) fn history(scene: &Scene, times: &[f64], rows: Vec<Vec<f64>>) -> History {
    let columns = std::iter::once("t".to_string())
        .chain(
            contract::columns(scene.family)
                .iter()
                .map(|s| s.to_string()),
        )
        .chain(std::iter::once(VALID_COLUMN.to_string()))
        .collect();
    History {
        columns,
        rows: times
            .iter()
            .zip(rows)
            .map(|(t, r)| std::iter::once(*t).chain(r).collect())
            .collect(),
    }
}

/// A history of the scene's own columns at the times `times`: `values(i, t)` gives the columns'
/// values at the i-th time, in the scene's order; every row is valid.
pub(crate) fn columns_history(
    scene: &Scene,
    times: &[f64],
    mut values: impl FnMut(usize, f64) -> Vec<f64>,
) -> History {
    let rows = (times.iter().enumerate())
        .map(|(i, &t)| {
            std::iter::once(t)
                .chain(values(i, t))
                .chain(std::iter::once(1.0))
                .collect()
        })
        .collect();
    let columns = std::iter::once("t".to_string())
        .chain(scene.columns.iter().map(|c| c.name.clone()))
        .chain(std::iter::once(VALID_COLUMN.to_string()))
        .collect();
    History { columns, rows }
}

fn unsupported<T>(what: impl Into<String>) -> Result<T, EngineError> {
    Err(EngineError::Unsupported(format!(
        "analytic: {}",
        what.into()
    )))
}
