//! Engines: each turns a [`Scene`] into time histories behind the one [`Engine`] trait; the
//! list of engines is [`registry`]'s ([`all`], [`named`]).
//!
//! Engines are cheap to run many times with different [`RunSettings`] (increment, penalty
//! stiffness, damping treatment) and report what the run cost in [`RunInfo`].

pub mod analytic;
pub mod explicit;
pub mod rapier;
pub mod reference;
pub mod registry;

pub use registry::{all, named};

pub use crate::contract::History;
use crate::scene::{ContactStart, DampingTreatment, IncrementRule, PenaltyRule, Scene};
use std::collections::BTreeMap;

/// Accuracy on request ([`IncrementRule::Tolerance`]): the fraction of the tolerance ε an
/// engine's choice aims at, 1/√10, the middle of [ε/10, ε] on a log scale.
pub const ON_REQUEST_AIM: f64 = 0.316;

/// Per-run overrides of the settings a case declares (`None`: keep the case's).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunSettings {
    /// Time increment rule.
    pub increment: Option<IncrementRule>,
    /// Penalty stiffness rule.
    pub penalty: Option<PenaltyRule>,
    /// Damping treatment.
    pub damping: Option<DampingTreatment>,
    /// Contact start.
    pub contact_start: Option<ContactStart>,
}

/// What a run used and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct RunInfo {
    /// Time increment used.
    pub increment: f64,
    /// Number of increments taken over the dynamic steps.
    pub steps: u64,
    /// Stable increment of the scene as the engine computed it, where it has one.
    pub stable_increment: Option<f64>,
    /// Penalty stiffness, where the scene has contact.
    pub penalty_stiffness: Option<f64>,
    /// Wall-clock seconds of the run.
    pub wall_seconds: f64,
    /// Work counters (force evaluations, contact evaluations, ...).
    pub counters: BTreeMap<String, u64>,
    /// Measured quantities an engine reports about its own run (for example the mean contact
    /// penetration), by name.
    pub measures: BTreeMap<String, f64>,
}

/// An engine's answer for one scene.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// Engine name (the CSV file stem).
    pub engine: String,
    /// Time history per the output contract.
    pub history: History,
    /// Cost and settings.
    pub info: RunInfo,
}

/// Why an engine could not produce a history.
#[derive(Debug, Clone, thiserror::Error)]
pub enum EngineError {
    /// The requested increment exceeds the stable one.
    #[error("time increment {requested:e} is above the stable increment {stable:e}")]
    UnstableIncrement {
        /// Requested.
        requested: f64,
        /// Stable.
        stable: f64,
    },
    /// The scene asks for something this engine does not do.
    #[error("{0}")]
    Unsupported(String),
    /// The run diverged or failed to converge.
    #[error("{0}")]
    Failed(String),
}

/// What an engine needs decided for it, beyond the case and the run's overrides, before it
/// runs. The layer that plans jobs decides it (`run::matching`); engines never ask each other.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Needs {
    /// Nothing: the engine takes the case's settings and the run's overrides as they are.
    #[default]
    Nothing,
    /// The explicit engine's increment for the scene, so that the two can be compared step for
    /// step; handed over as [`IncrementRule::Forced`] in [`RunSettings::increment`].
    MatchedIncrement,
    /// Its own increment, except in a stability study (`--increment-ratio`, the stability
    /// map), where it steps exactly with the ratio × the explicit engine's stable increment,
    /// handed over as [`IncrementRule::Exact`].
    StudyIncrement,
}

/// An engine.
pub trait Engine: Send + Sync {
    /// Name, used as the CSV file stem and in reports.
    fn name(&self) -> &str;
    /// What the planner must decide for this engine's runs.
    fn needs(&self) -> Needs {
        Needs::Nothing
    }
    /// The number of increments a run would take, estimated without running (`None`: the
    /// engine does not step in time, or cannot tell before running). For bounding runs.
    fn increments(&self, _scene: &Scene, _settings: &RunSettings) -> Option<f64> {
        None
    }
    /// Run a scene.
    fn run(&self, scene: &Scene, settings: &RunSettings) -> Result<RunOutput, EngineError>;
    /// Control experiments of this engine's own on `scene` (beyond the time step and the
    /// penalty stiffness, which the comparison varies on any engine): each varies one thing
    /// the exact solution does not depend on, so that a discrepancy can be traced to it.
    fn controls(&self, _scene: &Scene) -> Vec<Control> {
        Vec::new()
    }
}

/// What a control experiment varies: the suspected cause of a discrepancy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlKind {
    /// The time increment.
    TimeStep,
    /// The penalty stiffness of a penalty contact.
    Penalty,
    /// The floating-point precision (f64 for f32).
    Precision,
    /// The softness of a constraint-based contact.
    ContactSoftness,
    /// The restitution of contact pairs that start closed and never strike.
    Restitution,
}

/// A control experiment an engine offers ([`Engine::controls`]): the same run with one thing
/// varied.
pub struct Control {
    /// What is varied.
    pub kind: ControlKind,
    /// The variation in words (for example "`contact_softness` 1e5 Hz instead of 1e4 Hz").
    pub change: String,
    /// The engine that runs it (`None`: the same engine).
    pub engine: Option<Box<dyn Engine>>,
    /// The varied scene (`None`: the same scene).
    pub scene: Option<Scene>,
}
