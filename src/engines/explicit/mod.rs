//! `explicit`: our central-difference explicit integrator with penalty contact.

pub mod axis;
pub mod body_solve;
pub mod centred;
pub mod constraints;
pub mod diagnosis;
pub mod forces;
pub mod friction;
pub mod impacts;
pub mod integrate;
pub mod linear;
pub mod model;
pub mod motion;
pub mod on_request;
pub mod ramps;
pub mod rolling;
pub mod rows;
pub mod space;
pub mod start;
pub mod state;
pub mod velocity;

use super::{Coarsest, Engine, EngineError, RunInfo, RunOutput, RunSettings, Stepping};
use crate::scene::{ContactState, Dimension, Dof, IncrementRule, Scene, SceneSettings, StepKind};
use integrate::{Integration, integrate};
use space::{Planar, Spatial};
use std::collections::BTreeMap;
use std::time::Instant;

/// Rotation kinematics of rigid bodies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematics {
    /// Finite rotation (engine `explicit`).
    Finite,
    /// The benchmark's small-rotation idealisation (engine `explicit_small`).
    Small,
}

/// The explicit engine in one of its kinematics.
#[derive(Debug, Clone, Copy)]
pub struct ExplicitEngine {
    kinematics: Kinematics,
}

impl ExplicitEngine {
    /// Finite rotation: engine `explicit`.
    pub fn finite() -> Self {
        Self {
            kinematics: Kinematics::Finite,
        }
    }
    /// Small rotation: engine `explicit_small`.
    pub fn small() -> Self {
        Self {
            kinematics: Kinematics::Small,
        }
    }
}

/// A contact pair whose node carries a ball (a body rolling on a face) touches where the ball
/// meets the face, a point that moves over the body as it rolls. The small-rotation model
/// fixes every moment arm at its t = 0 value, so it would apply the pair's forces where the
/// ball touched at t = 0: refused (the finite-rotation engine takes the contact point where it
/// is, [`rolling`]).
fn rolling_applies(kinematics: Kinematics, scene: &Scene) -> Result<(), EngineError> {
    match scene.contacts.iter().find(|c| c.rolls()) {
        Some(pair) if kinematics == Kinematics::Small => Err(EngineError::Unsupported(format!(
            "explicit_small: contact `{}`: its node carries a ball (a body rolling on a face), \
             whose contact point moves over the body as it rolls, and the small-rotation model \
             fixes moment arms where they are at t = 0",
            pair.name
        ))),
        _ => Ok(()),
    }
}

/// The small-rotation model fixes a contact reaction's moment arm at its t = 0 value, which
/// is where the node touches only if it starts on the surface. A pair that starts open on a
/// body free to turn would get the moment of a force applied where the node was at t = 0:
/// refused (the finite-rotation engine takes the arm where the node is). A pair that starts
/// closed and opens later keeps its t = 0 arm, which is where the node touches while closed, so
/// that stays (its error is the model's, measured against the closed form).
fn small_rotation_applies(scene: &Scene) -> Result<(), EngineError> {
    let rotations: &[usize] = match scene.dimension {
        Dimension::Two => &[2],
        Dimension::Three => &[0, 1, 2],
    };
    for pair in &scene.contacts {
        if pair.initially != ContactState::Open {
            continue;
        }
        let reference = scene.bodies[pair.body].reference;
        let turns = scene
            .steps
            .iter()
            .filter(|s| matches!(s.kind, StepKind::Dynamic { .. }))
            .any(|s| {
                rotations.iter().any(|&axis| {
                    // Held where it is; a prescribed turn moves the arm as much as a free one.
                    !s.conditions.iter().any(|c| {
                        c.node == reference
                            && c.dof == Dof::Rotation(axis)
                            && c.value.is_none_or(|v| v == 0.0)
                    })
                })
            });
        if turns {
            return Err(EngineError::Unsupported(format!(
                "explicit_small: contact `{}` starts open on a body free to turn, and the \
                 small-rotation model fixes its reaction's moment arm where the node is at t = 0",
                pair.name
            )));
        }
    }
    Ok(())
}

impl Engine for ExplicitEngine {
    fn name(&self) -> &str {
        match self.kinematics {
            Kinematics::Finite => "explicit",
            Kinematics::Small => "explicit_small",
        }
    }
    fn stepping(&self) -> Option<Stepping> {
        Some(Stepping {
            coarsest: Coarsest::Stable { safety: 0.9 },
            penalty: true,
            substeps: None,
            budget_share: 1.0,
            precision: "f64",
            on_request: true,
        })
    }
    fn increments(&self, scene: &Scene, settings: &RunSettings) -> Option<f64> {
        let h = self.increment(scene, settings).ok()?;
        Some(scene.duration() / h)
    }
    fn run(&self, scene: &Scene, settings: &RunSettings) -> Result<RunOutput, EngineError> {
        let start = Instant::now();
        rolling_applies(self.kinematics, scene)?;
        if self.kinematics == Kinematics::Small {
            small_rotation_applies(scene)?;
        }
        // Accuracy on request: pilot runs choose the increment and the penalty stiffness.
        let mut measures = BTreeMap::new();
        let mut pilot_increments = None;
        let merged = merged(scene, settings);
        let mut penalty =
            (!scene.contacts.is_empty()).then(|| scene.penalty_stiffness(merged.penalty));
        let run = match merged.increment {
            IncrementRule::Tolerance(eps) => {
                let (run, choice) = on_request::run(self, scene, settings, eps)?;
                measures.insert("requested_tolerance".to_string(), eps);
                measures.insert("predicted_error".to_string(), choice.predicted);
                pilot_increments = Some(choice.pilot_increments);
                penalty = choice.penalty.or(penalty);
                run
            }
            _ => self.integrate(scene, settings)?,
        };
        let wall_seconds = start.elapsed().as_secs_f64();
        let c = run.counters;
        let mut counters = BTreeMap::from([
            ("force_evaluations".to_string(), c.force_evaluations),
            ("contact_evaluations".to_string(), c.contact_evaluations),
            ("damping_evaluations".to_string(), c.damping_evaluations),
            ("rotation_updates".to_string(), c.rotation_updates),
            ("body_solves".to_string(), c.body_solves),
        ]);
        if c.impact_balances > 0 {
            counters.insert("impact_balances".to_string(), c.impact_balances);
        }
        if scene.has_friction() {
            counters.insert("friction_evaluations".into(), c.friction_evaluations);
            counters.insert("slip_increments".into(), c.slip_increments);
        }
        if let Some(n) = pilot_increments {
            counters.insert("pilot_increments".to_string(), n);
        }
        if !scene.contacts.is_empty() {
            measures.insert("impacts".to_string(), run.impacts.len() as f64);
            let reported = run.impacts.iter().take(crate::contract::IMPACTS_REPORTED);
            for (i, t) in reported.enumerate() {
                measures.insert(format!("impact_{}_time", i + 1), *t);
            }
        }
        Ok(RunOutput {
            engine: self.name().to_string(),
            history: run.history,
            info: RunInfo {
                increment: run.increment,
                steps: run.steps,
                stable_increment: run.stable.map(|s| s.increment),
                penalty_stiffness: penalty,
                wall_seconds,
                counters,
                measures,
            },
        })
    }
}

/// The case's settings with the run's overrides applied.
pub fn merged(scene: &Scene, settings: &RunSettings) -> SceneSettings {
    let base = scene.settings;
    SceneSettings {
        increment: settings.increment.unwrap_or(base.increment),
        damping: settings.damping.unwrap_or(base.damping),
        penalty: settings.penalty.unwrap_or(base.penalty),
        contact_start: settings.contact_start.unwrap_or(base.contact_start),
    }
}

impl ExplicitEngine {
    /// Run and return everything the integration measured (counters, stable increment).
    pub fn integrate(
        &self,
        scene: &Scene,
        settings: &RunSettings,
    ) -> Result<Integration, EngineError> {
        let s = merged(scene, settings);
        match (scene.dimension, self.kinematics) {
            (Dimension::Two, Kinematics::Finite) => integrate::<Planar, true>(scene, &s),
            (Dimension::Two, Kinematics::Small) => integrate::<Planar, false>(scene, &s),
            (Dimension::Three, Kinematics::Finite) => integrate::<Spatial, true>(scene, &s),
            (Dimension::Three, Kinematics::Small) => integrate::<Spatial, false>(scene, &s),
        }
    }

    /// The increment a run of this scene under these settings uses: the increment rule, never
    /// above the stable increment (except `Forced`), shortened to divide the output interval.
    pub fn increment(&self, scene: &Scene, settings: &RunSettings) -> Result<f64, EngineError> {
        rolling_applies(self.kinematics, scene)?;
        let s = merged(scene, settings);
        let stable = self.stable_increment(scene, settings);
        let interval = scene.duration() / (scene.output_rows - 1) as f64;
        integrate::choose_increment(s.increment, stable.as_ref(), scene.duration(), interval)
    }

    /// The stable increment of a scene under these settings, without running it.
    pub fn stable_increment(
        &self,
        scene: &Scene,
        settings: &RunSettings,
    ) -> Option<linear::StableIncrement> {
        rolling_applies(self.kinematics, scene).ok()?;
        let s = merged(scene, settings);
        match (scene.dimension, self.kinematics) {
            (Dimension::Two, Kinematics::Finite) => stable::<Planar, true>(scene, &s),
            (Dimension::Two, Kinematics::Small) => stable::<Planar, false>(scene, &s),
            (Dimension::Three, Kinematics::Finite) => stable::<Spatial, true>(scene, &s),
            (Dimension::Three, Kinematics::Small) => stable::<Spatial, false>(scene, &s),
        }
    }
}

fn stable<S: space::Space, const FINITE: bool>(
    scene: &Scene,
    s: &SceneSettings,
) -> Option<linear::StableIncrement> {
    let penalty = scene.penalty_stiffness(s.penalty);
    let m = model::Model::<S, FINITE>::compile(scene, penalty);
    let mut cfg = m.initial_config();
    let mut counters = model::Counters::default();
    let first_dynamic = scene
        .steps
        .iter()
        .position(|st| matches!(st.kind, StepKind::Dynamic { .. }))?;
    for step in &scene.steps[..first_dynamic] {
        let held = m.constraints(step);
        linear::static_step(&m, &mut cfg, &held, &mut counters).ok()?;
    }
    integrate::stable_increment(&m, scene, &cfg, first_dynamic, s.damping, &mut counters)
}
