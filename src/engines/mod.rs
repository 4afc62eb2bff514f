//! Engines: each turns a [`Scene`] into time histories behind the one [`Engine`] trait.
//!
//! Engines are cheap to run many times with different [`RunSettings`] (increment, penalty
//! stiffness, damping treatment) and report what the run cost in [`RunInfo`].

pub mod analytic;
pub mod explicit;
pub mod rapier;

use crate::scene::{ContactStart, DampingTreatment, IncrementRule, PenaltyRule, Scene};
use std::collections::BTreeMap;

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

/// An engine.
pub trait Engine: Send + Sync {
    /// Name, used as the CSV file stem and in reports.
    fn name(&self) -> &str;
    /// Run a scene.
    fn run(&self, scene: &Scene, settings: &RunSettings) -> Result<RunOutput, EngineError>;
}

/// Every engine crosscheck has, in report order.
pub fn all() -> Vec<Box<dyn Engine>> {
    vec![
        Box::new(analytic::AnalyticEngine),
        Box::new(explicit::ExplicitEngine::finite()),
        Box::new(explicit::ExplicitEngine::small()),
        Box::new(rapier::RapierEngine::matched(rapier::Precision::F64)),
        Box::new(rapier::RapierEngine::matched(rapier::Precision::F32)),
        Box::new(rapier::RapierEngine::default_configuration(
            rapier::Precision::F64,
        )),
        Box::new(rapier::RapierEngine::default_configuration(
            rapier::Precision::F32,
        )),
    ]
}

/// Engine by name.
pub fn named(name: &str) -> Option<Box<dyn Engine>> {
    all().into_iter().find(|e| e.name() == name)
}
