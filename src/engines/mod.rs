//! Engines: each turns a [`Scene`] into time histories behind the one [`Engine`] trait; the
//! list of engines is kept by the run layer (its `registry`), so that no engine can reach
//! another through it.
//!
//! Engines are cheap to run many times with different [`RunSettings`] (increment, penalty
//! stiffness, damping treatment) and report what the run cost in [`RunInfo`].

pub mod analytic;
pub mod explicit;
#[cfg(feature = "rapier")]
pub mod rapier;
pub mod reference;

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
    /// The run grew without bound: its state turned non-finite, or the engine's own guard
    /// stopped it as growing. The message is the evidence: what grew, by when, at which
    /// increment.
    #[error("{0}")]
    Unstable(String),
    /// The run failed for another reason (a solve that did not converge, an interruption).
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

/// An engine: what turns a scene into a time history.
///
/// **What an engine provides.** [`Engine::name`] (its CSV file stem and its name in every
/// table) and [`Engine::run`]: for a [`Scene`] and the run's overrides, a [`History`] per the
/// output contract ([`crate::contract`]: `t`, then the scene's output columns at its output
/// times; then, if it keeps them, the energy columns, which the stability map reads), with
/// what the run cost ([`RunInfo`]), or [`EngineError::Unsupported`] for a scene it does not
/// model (the report then says "not applicable", never "failed"). The rest is optional:
/// [`Engine::stepping`] puts it in the sweep, the stability map and accuracy on request;
/// [`Engine::needs`] asks the planner for the explicit engine's increment; [`Engine::increments`]
/// lets the run budget refuse a run too long before it starts; [`Engine::controls`] offers
/// control experiments.
///
/// **What the harness does for it.** It checks each history against the contract, measures
/// it against the exact solution of its model (`reference`; `analytic` for `explicit_small`)
/// with the case's tolerance for it (`[tolerances]` in the case file, by engine name), builds
/// the discrepancy budget, sweeps and maps it as its [`Stepping`] says, and writes it into
/// every table of the report. `examples/own_engine` is a complete engine in about 300 lines,
/// run through all of it (`cargo run --release --example own_engine`).
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
    /// How the studies step this engine (the sweep's paths, the stability map, accuracy on
    /// request); `None`: it does not step in time (an exact solution), and no study runs it.
    fn stepping(&self) -> Option<Stepping> {
        None
    }
    /// The same engine with `substeps` solver substeps per increment, for the sweep's substeps
    /// path (`None`: it has no substeps).
    fn with_substeps(&self, _substeps: usize) -> Option<Box<dyn Engine>> {
        None
    }
    /// Control experiments of this engine's own on `scene` (beyond the time step and the
    /// penalty stiffness, which the comparison varies on any engine): each varies one thing
    /// the exact solution does not depend on, so that a discrepancy can be traced to it.
    fn controls(&self, _scene: &Scene) -> Vec<Control> {
        Vec::new()
    }
}

/// How the studies step an engine ([`Engine::stepping`]). The sweep refines its increment
/// from [`Stepping::coarsest`] down (one path per penalty stiffness where it has penalty
/// contact, and a substeps path where [`Engine::with_substeps`] gives one); the stability map
/// runs it at ratios of the explicit engine's stable increment (handed over as the engine's
/// [`Engine::needs`] says); accuracy on request asks it for tolerances when
/// [`Stepping::on_request`] is set.
#[derive(Debug, Clone, Copy)]
pub struct Stepping {
    /// Where the sweep's increment paths start.
    pub coarsest: Coarsest,
    /// Its contact is a penalty whose stiffness the run sets ([`RunSettings::penalty`]): on a
    /// scene with contact the sweep runs one increment path per penalty stiffness.
    pub penalty: bool,
    /// Solver substeps per increment (`None`: one), counted against the sweep's budget.
    pub substeps: Option<usize>,
    /// The fraction of the sweep's budget of increments one of its runs may take (1: all of
    /// it; an engine whose increment costs ten times more takes about a tenth).
    pub budget_share: f64,
    /// `f64` or `f32`: the arithmetic of its state (the figures draw f32 dashed).
    pub precision: &'static str,
    /// The accuracy-on-request study asks it ([`IncrementRule::Tolerance`]): it chooses its
    /// own increment for a tolerance, cheaply enough for the default run.
    pub on_request: bool,
}

/// How far a stable central-difference run's measured energy (kinetic at v(n), plus elastic)
/// may stand above its conserved energy at increment ratio `ratio` = h/(2/ω_max): a mode
/// entered with velocity only (an impact) reads up to 1/(1 − (ω·h/2)²) of its energy at the
/// turns of its discrete oscillation (25× at 0.98; checked to round-off on one mass at
/// ω·h = 0.5 … 1.96), and falls back, bounded. 1 at and above the limit, where nothing is
/// bounded. The explicit engine's energy guard allows for it.
pub fn central_difference_energy_reading(ratio: f64) -> f64 {
    if ratio < 1.0 {
        1.0 / (1.0 - ratio * ratio)
    } else {
        1.0
    }
}

/// Where the sweep's increment paths of an engine start ([`Stepping::coarsest`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Coarsest {
    /// This fraction of the engine's own stable increment ([`IncrementRule::Stable`]); the
    /// path also runs once just above that increment, which must come back unstable.
    Stable {
        /// The fraction (0, 1].
        safety: f64,
    },
    /// The case's output interval.
    OutputInterval,
    /// This increment (s), the engine's own default.
    Increment(f64),
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
    /// How a reported contact impulse is read (the motion unchanged).
    ImpulseReading,
    /// Whether a body's gyroscopic torque is integrated (an engine setting with a default).
    Gyroscopic,
}

impl ControlKind {
    /// Whether it refines a setting the harness varies on any engine that steps (the
    /// increment, the penalty stiffness), rather than being an engine's own control.
    pub fn refines(self) -> bool {
        matches!(self, ControlKind::TimeStep | ControlKind::Penalty)
    }
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
