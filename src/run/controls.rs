//! Control experiments: one job rerun with one suspected cause of its discrepancy varied.
//!
//! - **time step**: a ladder of increments, each a quarter of the one before, from a quarter of
//!   the job's down to the matched increment (the explicit engine's on the scene; the ladder
//!   ends on it exactly): one rung for an engine that already steps there, down to it from
//!   rapier's default 1/60 s;
//! - **penalty**: a ladder of two: the penalty stiffness × [`PENALTY_FACTOR`] and × its square,
//!   each with the increment divided by the factor's square root (ω_p·h unchanged), for an
//!   engine that reports a penalty stiffness;
//! - the engine's own ([`Engine::controls`]): for rapier, f64 for f32, a stiffer contact
//!   softness, restitution 0 on pairs that start closed.
//!
//! Each varies something the exact solution of the case does not depend on (the comparison
//! leaves out a restitution control where the exact solution strikes, since e enters it
//! there). Where no single one explains a cell, the comparison combines them: the penalty and
//! the engine's own controls run again at the ladder's finest increment ([`combined`]). This
//! module only runs them; the comparison measures them and names the cause.

use super::{JobSuccess, matching};
use crate::contract::{self, History};
use crate::engines::{Control, Engine, RunSettings};
use crate::scene::{IncrementRule, PenaltyRule, Scene};

pub use crate::engines::ControlKind;

/// Factor of the penalty control's stiffness (its increment is divided by the square root).
pub const PENALTY_FACTOR: f64 = 16.0;

/// A control experiment of one job, ready to run.
pub struct Planned<'a> {
    /// The variation.
    pub control: Control,
    /// The job's engine (the control's own engine, if it has one, runs instead).
    engine: &'a dyn Engine,
    /// The job's scene (likewise).
    scene: &'a Scene,
    /// The settings it runs with.
    settings: RunSettings,
}

impl Planned<'_> {
    /// What it varies.
    pub fn kind(&self) -> ControlKind {
        self.control.kind
    }

    /// The penalty stiffness it sets, where it sets one.
    pub fn penalty(&self) -> Option<f64> {
        match self.settings.penalty {
            Some(PenaltyRule::Stiffness(k)) => Some(k),
            _ => None,
        }
    }

    /// The increment it is forced to, where it is.
    pub fn increment(&self) -> Option<f64> {
        match self.settings.increment {
            Some(IncrementRule::Forced(h) | IncrementRule::Given(h) | IncrementRule::Exact(h)) => {
                Some(h)
            }
            _ => None,
        }
    }

    /// Its relative cost, for scheduling only ([`super::estimated_cost`]).
    pub fn estimated_cost(&self) -> f64 {
        let engine = self.control.engine.as_deref().unwrap_or(self.engine);
        let scene = self.control.scene.as_ref().unwrap_or(self.scene);
        super::estimated_cost(scene, engine, &self.settings)
    }

    /// Run it: its history (checked against the output contract), or why there is none.
    pub fn run(&self) -> Result<History, String> {
        let engine = self.control.engine.as_deref().unwrap_or(self.engine);
        let scene = self.control.scene.as_ref().unwrap_or(self.scene);
        let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            engine.run(scene, &self.settings)
        }))
        .map_err(|_| "the engine panicked".to_string())?
        .map_err(|e| e.to_string())?;
        contract::check(scene, &out.history).map_err(|e| e.to_string())?;
        contract::check_finite(&out.history)?;
        Ok(out.history)
    }
}

/// The control experiments of a successful job of `engine` on `scene` under the run's
/// `settings`: the time step ladder and the penalty on any engine that steps, then the
/// engine's own.
pub fn plan<'a>(
    scene: &'a Scene,
    engine: &'a dyn Engine,
    settings: &RunSettings,
    job: &JobSuccess,
) -> Vec<Planned<'a>> {
    let base = matching::job_settings(engine, scene, settings);
    let (h, steps) = (job.info.increment, job.info.steps);
    let mut out = Vec::new();
    if h > 0.0 && steps > 0 {
        for rung in ladder(h, matching::matched_increment(scene, settings)) {
            let change = format!(
                "increment h/{} = {rung:.2e} s instead of {h:.2e} s",
                divisor(h / rung)
            );
            let varied = RunSettings {
                increment: Some(IncrementRule::Forced(rung)),
                ..base
            };
            out.push(Planned {
                control: Control {
                    kind: ControlKind::TimeStep,
                    change,
                    engine: None,
                    scene: None,
                },
                engine,
                scene,
                settings: varied,
            });
        }
        if let Some(k) = job.info.penalty_stiffness {
            for factor in [PENALTY_FACTOR, PENALTY_FACTOR * PENALTY_FACTOR] {
                out.push(penalty(
                    scene,
                    engine,
                    &base,
                    h / factor.sqrt(),
                    (k, factor),
                ));
            }
        }
    }
    out.extend(own(scene, engine, settings, None));
    out
}

/// The increments of the time step ladder below `h`: a quarter of `h`, then quarters of that
/// while they stay more than twice `matched`, then `matched` itself (so that the last rung is
/// at least a factor 2 from the one before); one rung, h/4, where that is already at or below
/// `matched`.
pub fn ladder(h: f64, matched: f64) -> Vec<f64> {
    let mut rungs = vec![h / 4.0];
    if rungs[0] <= matched * (1.0 + 1e-9) {
        return rungs;
    }
    while rungs[rungs.len() - 1] / 4.0 > 2.0 * matched {
        let next = rungs[rungs.len() - 1] / 4.0;
        rungs.push(next);
    }
    rungs.push(matched);
    rungs
}

/// A ratio of increments as a divisor: whole where it is one (4, 16), to three digits else.
fn divisor(x: f64) -> String {
    if (x - x.round()).abs() < 1e-6 * x {
        format!("{x:.0}")
    } else {
        format!("{x:.3}")
    }
}

/// A penalty control: the job's stiffness `k` × `factor` at `increment`.
fn penalty<'a>(
    scene: &'a Scene,
    engine: &'a dyn Engine,
    base: &RunSettings,
    increment: f64,
    (k, factor): (f64, f64),
) -> Planned<'a> {
    let settings = RunSettings {
        increment: Some(IncrementRule::Forced(increment)),
        penalty: Some(PenaltyRule::Stiffness(factor * k)),
        ..*base
    };
    let change = format!(
        "penalty stiffness {:.2e} instead of {k:.2e}, increment {increment:.2e} s",
        factor * k,
    );
    Planned {
        control: Control {
            kind: ControlKind::Penalty,
            change,
            engine: None,
            scene: None,
        },
        engine,
        scene,
        settings,
    }
}

/// The engine's own controls ([`Engine::controls`]), each with the settings its job would
/// have, forced to `increment` where one is given.
fn own<'a>(
    scene: &'a Scene,
    engine: &'a dyn Engine,
    settings: &RunSettings,
    increment: Option<f64>,
) -> Vec<Planned<'a>> {
    engine
        .controls(scene)
        .into_iter()
        .map(|mut control| {
            let runner = control.engine.as_deref().unwrap_or(engine);
            let varied = control.scene.as_ref().unwrap_or(scene);
            let mut settings = matching::job_settings(runner, varied, settings);
            if let Some(h) = increment {
                settings.increment = Some(IncrementRule::Forced(h));
                control.change = format!("{}, at increment {h:.2e} s", control.change);
            }
            Planned {
                control,
                engine,
                scene,
                settings,
            }
        })
        .collect()
}

/// The controls combined with the time step: the penalty (where the job reports one) and the
/// engine's own controls, each run at `increment`, the time step ladder's finest.
pub fn combined<'a>(
    scene: &'a Scene,
    engine: &'a dyn Engine,
    settings: &RunSettings,
    job: &JobSuccess,
    increment: f64,
) -> Vec<Planned<'a>> {
    let base = matching::job_settings(engine, scene, settings);
    // The penalty control already runs at a quarter of the job's increment.
    let finer = increment < job.info.increment / PENALTY_FACTOR.sqrt() * (1.0 - 1e-9);
    let mut out: Vec<Planned> = job
        .info
        .penalty_stiffness
        .filter(|_| finer)
        .map(|k| penalty(scene, engine, &base, increment, (k, PENALTY_FACTOR)))
        .into_iter()
        .collect();
    out.extend(own(scene, engine, settings, Some(increment)));
    out
}
