//! Control experiments: one job rerun with one suspected cause of its discrepancy varied.
//!
//! - **time step**: the increment divided by 4 (and by 16 and 64 for an engine that steps more
//!   coarsely than the output rows, rapier's default 1/60 s);
//! - **penalty**: the penalty stiffness × [`PENALTY_FACTOR`] with the increment divided by its
//!   square root (ω_p·h unchanged), for an engine that reports a penalty stiffness;
//! - the engine's own ([`Engine::controls`]): for rapier, f64 for f32, a stiffer contact
//!   softness, restitution 0 on pairs that start closed.
//!
//! Each varies something the exact solution of the case does not depend on (the comparison
//! leaves out a restitution control where the exact solution strikes, since e enters it
//! there). This module only runs them; the comparison measures them and names the cause.

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
/// `settings`: the time step and penalty on any engine that steps, then the engine's own.
pub fn plan<'a>(
    scene: &'a Scene,
    engine: &'a dyn Engine,
    settings: &RunSettings,
    job: &JobSuccess,
) -> Vec<Planned<'a>> {
    let base = matching::job_settings(engine, scene, settings);
    let (h, steps) = (job.info.increment, job.info.steps);
    let forced = |h: f64| Some(IncrementRule::Forced(h));
    let same = |kind, change: String, settings| Planned {
        control: Control {
            kind,
            change,
            engine: None,
            scene: None,
        },
        engine,
        scene,
        settings,
    };
    let mut out = Vec::new();
    if h > 0.0 && steps > 0 {
        let interval = scene.duration() / (scene.output_rows - 1) as f64;
        let divisors: &[f64] = if h > interval {
            &[4.0, 16.0, 64.0]
        } else {
            &[4.0]
        };
        for d in divisors {
            let settings = RunSettings {
                increment: forced(h / d),
                ..base
            };
            let change = format!("increment h/{d} = {:.2e} s instead of {h:.2e} s", h / d);
            out.push(same(ControlKind::TimeStep, change, settings));
        }
        if let Some(k) = job.info.penalty_stiffness {
            let settings = RunSettings {
                increment: forced(h / PENALTY_FACTOR.sqrt()),
                penalty: Some(PenaltyRule::Stiffness(PENALTY_FACTOR * k)),
                ..base
            };
            let change = format!(
                "penalty stiffness {:.2e} instead of {k:.2e}, increment h/{}",
                PENALTY_FACTOR * k,
                PENALTY_FACTOR.sqrt()
            );
            out.push(same(ControlKind::Penalty, change, settings));
        }
    }
    for control in engine.controls(scene) {
        let runner = control.engine.as_deref().unwrap_or(engine);
        let varied = control.scene.as_ref().unwrap_or(scene);
        let settings = matching::job_settings(runner, varied, settings);
        out.push(Planned {
            control,
            engine,
            scene,
            settings,
        });
    }
    out
}
