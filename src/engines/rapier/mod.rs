//! `rapier_*`: the scenes run through the rapier physics engine (0.36; 0.34 and 0.35 beside it
//! with the `rapier-versions` feature, [`Release`]), as a third-party cross-check of our
//! central-difference engine and as a measure of what a game-physics solver gives on
//! verification problems.
//!
//! One generic builder ([`plan`]) maps any scene onto rapier bodies, joints and colliders; one
//! simulation ([`backend::simulate`]), written once over the [`backend::World`] trait, builds
//! and steps the world of whichever rapier crate implements it (`world`: 2D scenes in
//! `rapier2d`/`rapier2d-f64`, 3D ones in `rapier3d`/`rapier3d-f64`, and the older releases'
//! f64 crates); one recorder ([`record`]) turns the stepped states into the output contract.
//! See [`plan`] for the mapping.
//!
//! # Engines
//!
//! | name | crate precision | configuration |
//! |---|---|---|
//! | `rapier_f64` | f64 | [`Configuration::Matched`] |
//! | `rapier_f32` | f32 | [`Configuration::Matched`] |
//! | `rapier_f64_default` | f64 | [`Configuration::Default`] |
//! | `rapier_f32_default` | f32 | [`Configuration::Default`] |
//! | `rapier_f64@0.34`, `rapier_f64@0.35` | f64 | [`Configuration::Matched`], on that release |
//! | `rapier_f64_default@0.34`, `rapier_f64_default@0.35` | f64 | [`Configuration::Default`], on that release |
//!
//! # How rapier integrates these scenes
//!
//! Each step of length dt runs [`MatchedSettings::solver_iterations`] substeps of dt/n (rapier's
//! "solver iterations" are substeps of its TGS-soft solver). Per substep: external forces are
//! applied as known forces, the constraints (joints, contacts) are solved by projected Gauss–Seidel
//! ([`MatchedSettings::pgs_iterations`] sweeps, with position bias), the positions advance with
//! the new velocities, and one more sweep without bias relaxes the velocities. A force-based
//! joint motor is an implicit spring: its impulse solves m Δv = −h(k(x + h v⁺) + c v⁺), i.e.
//! backward Euler on the spring, first order and numerically dissipative: an undamped
//! oscillator keeps e^(−ω²hT) of its energy over T (measured to 4 digits: 1.44 % lost by the
//! grounded oscillator over 1 s at the matched increment). Contacts are rigid at velocity level
//! (the relax sweep) and soft in position (the biased sweep corrects penetration with the
//! contact softness as a spring–damper).
//!
//! Contact starts touching (zero gap, no penetration): the ball and the face touch exactly at
//! t = 0 and the velocity-level constraint carries the rigid contact force from the first step,
//! so there is no penalty ringing. The first step's force lacks the curvature (centripetal)
//! part, which rapier only recovers through the position bias once a penetration exists: it is
//! ~20 % low (pinned surface case: 3.4e3 against 4.26e3 from the central-difference engine), then right.
//! The collision detection runs once before the first step, or rapier only registers the new
//! pair during step 1 and that step gets no contact at all. In f32 the rounded initial geometry
//! leaves a gap of ~1.5e-8, so the first step carries no contact impulse either way.
//!
//! The contact force reported at a row is the normal impulse rapier applied over the output
//! interval around it (each step's impulse, summed over its substeps from the narrow phase,
//! spread evenly over the step) divided by the interval ([`record`]): a contact that carries
//! little load is not pressed in every step, and one step's impulse would alias that.
//!
//! Friction: a pair's μ_k on both of its colliders, combined by their average into exactly
//! μ_k (rapier has one coefficient: where a case's static coefficient is larger, the pair sticks
//! and breaks away at μ_k). Each contact's friction impulse is bounded by μ times the normal
//! impulse of the same sweep, in 3D on a cone (the two tangent impulses projected together),
//! so the law is isotropic: the slide-stop case stops at one distance whatever the direction
//! (within 3.4e-12 m at 0°, 30° and 45°, `tests/friction_rapier.rs`). It is solved in each
//! substep's sweep without bias (0.35 and 0.36; 0.34 in both), warm-started from the previous
//! substep; in the first substep nothing is warm-started yet, so a node held by friction on
//! an incline moves by its unresisted g sinθ (h/n)² once (at 20°: 2.1e-11 m matched, 5.8e-5 m
//! in the default configuration) and then holds. A node sliding to a stop falls short of the exact
//! distance by the semi-implicit lag v0 h/(2n) (2.5e-6 m matched). `docs/rapier.md` lists
//! every friction case's figures with their controls.
//!
//! Rapier keeps gyroscopic forces on (its default; a 3D body needs them in general). In f32 its
//! per-substep gyroscopic correction, which rotates ω into the principal frame and back, pumps
//! energy through round-off even about a principal axis where the torque is zero (the pinned
//! lumped body gains 61 J over 0.1 s): the 3D f32 runs drift from their 2D twins by up to
//! 8e-3 of the peak for that reason.
//!
//! Of the run overrides ([`RunSettings`]) only `increment` applies: to the matched
//! configuration, and to the default one only when forced (a study refining its 1/60 s): rapier has no penalty stiffness, its dashpots are implicit whatever the
//! damping treatment, and its contact always starts touching.
//!
//! Sleeping is disabled on every body in both configurations (a body put to sleep would freeze
//! an oscillator: that is a model change, not solver accuracy). Gravity is 0.

pub mod backend;
pub mod controls;
pub mod plan;
pub mod record;
pub mod steps;
mod world;

use super::{
    Coarsest, Control, Engine, EngineError, Needs, RunInfo, RunOutput, RunSettings, Stepping,
};
use crate::scene::{Dimension, IncrementRule, Scene};
use std::collections::BTreeMap;
use std::time::Instant;

/// The rapier crate's scalar.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// `rapier2d` / `rapier3d`.
    F32,
    /// `rapier2d-f64` / `rapier3d-f64`.
    F64,
}

/// The rapier release an engine runs on: 0.36 always, 0.34 and 0.35 (in f64) with the
/// `rapier-versions` feature. The scene-to-rapier [`plan`] is one; only [`backend`]'s calls
/// into rapier's API differ by release.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Release {
    /// 0.34.0, the last release before 0.35 (no `static_contact_softness`, no contact
    /// recycling, no quarantine).
    #[cfg(feature = "rapier-versions")]
    V0_34,
    /// 0.35.3, the last 0.35.
    #[cfg(feature = "rapier-versions")]
    V0_35,
    /// 0.36.1: the release the engines without a version in their name run.
    Current,
}

impl Release {
    /// Every release this build has, oldest first.
    pub fn all() -> Vec<Release> {
        vec![
            #[cfg(feature = "rapier-versions")]
            Release::V0_34,
            #[cfg(feature = "rapier-versions")]
            Release::V0_35,
            Release::Current,
        ]
    }

    /// The crate version it is built on.
    pub fn version(self) -> &'static str {
        match self {
            #[cfg(feature = "rapier-versions")]
            Release::V0_34 => "0.34.0",
            #[cfg(feature = "rapier-versions")]
            Release::V0_35 => "0.35.3",
            Release::Current => "0.36.1",
        }
    }

    /// Whether its reported contact impulse over a step counts one substep's impulse too many
    /// (0.34: the previous step's warm-start impulse is added in; 0.35.2 made it the step's
    /// own).
    pub fn reports_extra_substep_impulse(self) -> bool {
        match self {
            #[cfg(feature = "rapier-versions")]
            Release::V0_34 => true,
            _ => false,
        }
    }

    /// Whether its rigid bodies leave gyroscopic forces out unless asked (0.34; on by default
    /// from 0.35): turning them on is a control for a spin.
    pub fn gyroscopic_off_by_default(self) -> bool {
        self.reports_extra_substep_impulse()
    }

    /// Whether restitution enters every substep's contact constraint (0.34; 0.35 applies it in
    /// one pass after the substeps), so that the rebound depends on the contact softness and
    /// the substeps: a softer contact is a control for it.
    pub fn restitution_in_substeps(self) -> bool {
        self.reports_extra_substep_impulse()
    }

    /// Its default contact softness, in words.
    pub fn default_contact_softness(self) -> &'static str {
        if self.restitution_in_substeps() {
            "30 Hz, damping ratio 5"
        } else {
            "30 Hz and 60 Hz, damping ratio 10"
        }
    }

    /// The release's minor version as the report labels it (`0.34`, `0.35`, `0.36`).
    pub const fn label(self) -> &'static str {
        match self.tag() {
            Some(tag) => tag,
            None => "0.36",
        }
    }

    /// What an engine's name carries after its `@` (`None` for [`Release::Current`], whose
    /// engines keep their plain names).
    pub const fn tag(self) -> Option<&'static str> {
        match self {
            #[cfg(feature = "rapier-versions")]
            Release::V0_34 => Some("0.34"),
            #[cfg(feature = "rapier-versions")]
            Release::V0_35 => Some("0.35"),
            Release::Current => None,
        }
    }
}

/// How rapier is set up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Configuration {
    /// Same time increment as the central-difference engine, solver converged, contact tightened: the
    /// settings of [`MatchedSettings::chosen`] (or others, for studies).
    Matched(MatchedSettings),
    /// What a typical user gets: `IntegrationParameters::default()` (4 substeps, 1 PGS sweep,
    /// contact softness 30 Hz / ζ = 10, 60 Hz against fixed bodies, contact recycling) and
    /// dt = 1/60 s whatever the case says (an `--increment` override does not apply; a forced
    /// increment, [`IncrementRule::Forced`], does: studies refine it). The
    /// output times fall between steps: positions and velocities are interpolated linearly
    /// (rotations by slerp) between the two steps around each output time. At 1/60 s the
    /// implicit springs are far past their frequencies (ω·h/4 ≈ 1.6 for the 374 rad/s rigid
    /// mode): the first step all but stops the rigid body at its static equilibrium, and one PGS
    /// sweep leaves the pin 3 cm off; the spring cases lose half their amplitude.
    Default,
}

/// The solver settings of the matched configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchedSettings {
    /// `num_solver_iterations`: substeps per step.
    pub solver_iterations: usize,
    /// `num_internal_pgs_iterations`: Gauss–Seidel sweeps per substep.
    pub pgs_iterations: usize,
    /// Contact softness natural frequency, Hz (both `contact_softness` and
    /// `static_contact_softness`).
    pub contact_frequency: f64,
    /// Contact softness damping ratio.
    pub contact_damping_ratio: f64,
    /// `normalized_allowed_linear_error` (length units).
    pub allowed_linear_error: f64,
    /// `normalized_prediction_distance` (length units).
    pub prediction_distance: f64,
    /// `contact_recycling` (reuse contact points while the pair moved less than 0.05).
    pub contact_recycling: bool,
}

impl MatchedSettings {
    /// The matched configuration of `precision` (chosen by the studies in `tests/rapier.rs`
    /// and `tests/rapier_limits.rs`).
    ///
    /// - Time increment: the one the job planner hands over (`run::matching`: what the
    ///   central-difference engine takes on the case, i.e. the case's `[time] increment` or 0.9 ×
    ///   its stable increment, a run's `increment` override honoured), shortened to divide the
    ///   output interval so that rows fall on steps (1e-5 s rigid, 5e-5 s springs).
    /// - `solver_iterations` = 4 substeps, rapier's default. A substep is rapier's time step:
    ///   more of them refine its first-order scheme rather than converge a solve (doubling them
    ///   halves the difference from the central-difference engine, ratio 2.00 measured), so
    ///   the count stays rapier's own and what is matched is the increment. Reaching the 1e-4
    ///   criterion through substeps would take ~256 of them in the rigid cases (60× the cost).
    /// - `pgs_iterations` = 2 Gauss–Seidel sweeps per substep: the smallest count where doubling
    ///   changes no contract column by 1e-4 of its peak (f64 at 10 kHz: 1 → 2: 6.6e-4,
    ///   2 → 4: 5.2e-5, 4 → 8: 3.4e-7, worst case the pinned surface-mass body).
    /// - Contact softness, for contacts between dynamic bodies and against fixed ones (default
    ///   30 Hz and 60 Hz, ζ = 10), damping ratio 1, as stiff as the precision allows:
    ///   - **f64: 10 kHz.** Rapier's error is then first order in the increment from 4e-5 s
    ///     down to 5e-6 s (successive halvings shrink the differences by 1.95–2.00 on every
    ///     column of the sliding lumped case). At 3 kHz it was not: the soft contact's own
    ///     dynamics made that case's differences shrink by 2.17, then 1.64, then 1.23 below
    ///     1e-5 s, so that no extrapolation in h converged there. Stiffer moves every column by
    ///     at most 1.5e-4 of its peak (10 → 100 kHz at 1e-5 s), about 1 % of rapier's
    ///     first-order error, but needs more Gauss–Seidel sweeps (at 30 kHz 2 → 4 sweeps moves
    ///     the pinned surface case by 1.4e-4). A damping ratio below 1 softens rapier's contact
    ///     (more penetration).
    ///   - **f32: 3 kHz.** f32's 6e-8 position quantum times the correction rate makes a
    ///     stiffer contact chatter (separations of 3e-7 and force noise of 0.7 of the peak at
    ///     1e4 Hz, 0.3 at 5e3 Hz); 3 kHz is the stiffest setting tried that stays closed in f32
    ///     (mean penetration 5e-6 pinned, 1.4e-4 sliding, against 2e-4 to 6e-3 with the
    ///     defaults).
    /// - Allowed linear error 1e-6 and prediction distance 1e-4 (defaults 5e-3 and 2e-2), and
    ///   no contact recycling: with recycling (the default) the contact point and normal are
    ///   frozen until the pair has moved 0.05, and the rotating face then feels a stale normal
    ///   (contact force error 1.9 of the peak at the matched increment instead of 0.07).
    pub const fn chosen(precision: Precision) -> MatchedSettings {
        MatchedSettings {
            contact_frequency: match precision {
                Precision::F64 => 1.0e4,
                Precision::F32 => 3.0e3,
            },
            ..Self::CHOSEN
        }
    }

    /// The settings [`MatchedSettings::chosen`] shares between the precisions (its contact
    /// softness is f32's).
    pub const CHOSEN: MatchedSettings = MatchedSettings {
        solver_iterations: 4,
        pgs_iterations: 2,
        contact_frequency: 3.0e3,
        contact_damping_ratio: 1.0,
        allowed_linear_error: 1.0e-6,
        prediction_distance: 1.0e-4,
        contact_recycling: false,
    };
}

/// The contact softness (Hz) of the matched engine named `name` (`rapier_f32`'s for a name
/// with `f32` in it, else `rapier_f64`'s).
pub fn matched_contact_frequency(name: &str) -> f64 {
    let precision = if name.contains("f32") {
        Precision::F32
    } else {
        Precision::F64
    };
    MatchedSettings::chosen(precision).contact_frequency
}

/// The time increment of the default configuration: rapier's default, 1/60 s.
pub const DEFAULT_INCREMENT: f64 = 1.0 / 60.0;

/// The fraction of a sweep's budget of increments (substeps counted) a rapier run may take:
/// one rapier substep costs about 1–3 µs against about 0.1–0.3 µs for a central-difference
/// increment.
pub const SWEEP_BUDGET_SHARE: f64 = 0.2;

/// A rapier engine.
#[derive(Debug, Clone)]
pub struct RapierEngine {
    name: String,
    precision: Precision,
    configuration: Configuration,
    ccd: bool,
    /// The default configuration with another contact softness (a control experiment).
    default_softness: Option<f64>,
    /// How bodies held in every DOF are made ([`plan::Holding::Joints`]: a control experiment).
    holding: plan::Holding,
    /// The rapier release it runs on.
    release: Release,
    /// Step by a length of 0 before the first detection (what 0.34 needs; a control elsewhere).
    zero_step_first: bool,
    /// What the reported contact impulses are multiplied by (1 but in a control experiment).
    impulse_scale: f64,
    /// Gyroscopic forces on the rigid bodies (`None`: the release's default).
    gyroscopic: Option<bool>,
}

impl RapierEngine {
    /// `rapier_f64` / `rapier_f32`: the matched configuration.
    pub fn matched(precision: Precision) -> Self {
        Self::with(
            precision,
            Configuration::Matched(MatchedSettings::chosen(precision)),
        )
    }

    /// `rapier_f64_default` / `rapier_f32_default`: rapier out of the box.
    pub fn default_configuration(precision: Precision) -> Self {
        Self::with(precision, Configuration::Default)
    }

    /// Any configuration (studies); named like the matched or default engine.
    pub fn with(precision: Precision, configuration: Configuration) -> Self {
        let p = match precision {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        };
        let name = match configuration {
            Configuration::Matched(_) => format!("rapier_{p}"),
            Configuration::Default => format!("rapier_{p}_default"),
        };
        Self {
            name,
            precision,
            configuration,
            ccd: false,
            default_softness: None,
            holding: plan::Holding::Fixed,
            release: Release::Current,
            zero_step_first: false,
            impulse_scale: 1.0,
            gyroscopic: None,
        }
    }

    /// The same engine with gyroscopic forces on or off on every rigid body whatever its
    /// release's default (off on 0.34, on from 0.35), named with a `_gyroscopic` suffix (a
    /// control experiment).
    pub fn with_gyroscopic(mut self, on: bool) -> Self {
        self.gyroscopic = Some(on);
        self.name
            .push_str(if on { "_gyroscopic" } else { "_no_gyroscopic" });
        self
    }

    /// The same engine stepping the world by a length of 0 before its first collision
    /// detection, as the backend on rapier 0.34 must (a control experiment: on 0.35 and 0.36 it
    /// changes no history by a bit), named with a `_zero_step` suffix.
    pub fn with_zero_step_first(mut self) -> Self {
        self.zero_step_first = true;
        self.name.push_str("_zero_step");
        self
    }

    /// The same engine on another rapier release, named `<name>@<release>` (`rapier_f64@0.34`;
    /// [`crate::contract::file_stem`] keeps its file names portable). Older releases are built
    /// in f64 only: `None` for an f32 engine on one.
    pub fn on_release(mut self, release: Release) -> Option<Self> {
        if release == Release::Current {
            return Some(self);
        }
        if self.precision != Precision::F64 {
            return None;
        }
        self.release = release;
        if let Some(tag) = release.tag() {
            self.name = format!("{}@{tag}", self.name);
        }
        Some(self)
    }

    /// The rapier release it runs on.
    pub fn release(&self) -> Release {
        self.release
    }

    /// The same engine with rapier's continuous collision detection on every particle (the
    /// tunnelling study), named with a `_ccd` suffix.
    pub fn with_ccd(mut self) -> Self {
        self.ccd = true;
        self.name.push_str("_ccd");
        self
    }

    /// The same engine with every body held in every DOF made a dynamic body held by joints
    /// instead of a fixed body (a control experiment: what the construct costs at an impact),
    /// named with a `_joints` suffix.
    pub fn held_by_joints(mut self) -> Self {
        self.holding = plan::Holding::Joints;
        self.name.push_str("_joints");
        self
    }

    /// The configuration.
    pub fn configuration(&self) -> Configuration {
        self.configuration
    }

    /// Run and also return the contact diagnostics.
    pub fn run_with_diagnostics(
        &self,
        scene: &Scene,
        settings: &RunSettings,
    ) -> Result<(RunOutput, record::Diagnostics), EngineError> {
        let start = Instant::now();
        let plan = plan::plan_with(scene, self.holding)?;
        let (dt, solver) = match self.configuration {
            Configuration::Matched(m) => (own_increment(scene, settings), Some(m)),
            Configuration::Default => (default_increment(settings), None),
        };
        let run = backend::Run {
            dt,
            matched: solver,
            ccd: self.ccd,
            default_softness: self.default_softness,
            zero_step_first: self.zero_step_first,
            impulse_scale: self.impulse_scale,
            gyroscopic: self.gyroscopic,
            friction: scene.has_friction(),
        };
        let mut recorder = record::Recorder::new(scene, &plan);
        let mut sink = |r: backend::Record| recorder.push(r);
        let trace = self.simulate(scene.dimension, &plan, &run, &mut sink)?;
        let (history, diagnostics) = recorder.finish()?;
        let wall_seconds = start.elapsed().as_secs_f64();
        let (iterations, pgs) = match solver {
            Some(m) => (m.solver_iterations, m.pgs_iterations),
            None => (
                backend::DEFAULT_SOLVER_ITERATIONS,
                backend::DEFAULT_PGS_ITERATIONS,
            ),
        };
        let counters = BTreeMap::from([
            ("solver_iterations".to_string(), iterations as u64),
            ("pgs_iterations".to_string(), pgs as u64),
            ("colliders".to_string(), trace.colliders as u64),
            ("joints".to_string(), trace.joints as u64),
            ("rigid_bodies".to_string(), trace.bodies as u64),
            ("substeps".to_string(), trace.steps * iterations as u64),
        ]);
        Ok((
            RunOutput {
                engine: self.name.clone(),
                history,
                info: RunInfo {
                    increment: dt,
                    steps: trace.steps,
                    stable_increment: None,
                    penalty_stiffness: None,
                    wall_seconds,
                    counters,
                    measures: std::collections::BTreeMap::new(),
                },
            },
            diagnostics,
        ))
    }
}

impl RapierEngine {
    /// The backend of this engine's dimension, precision and release.
    fn simulate(
        &self,
        dimension: Dimension,
        plan: &plan::Plan,
        run: &backend::Run,
        sink: &mut dyn FnMut(backend::Record) -> Result<(), EngineError>,
    ) -> Result<backend::Trace, EngineError> {
        use Dimension::{Three, Two};
        use Precision::{F32, F64};
        match (self.release, dimension, self.precision) {
            (Release::Current, Two, F32) => backend::simulate::<world::R2F32>(plan, run, sink),
            (Release::Current, Two, F64) => backend::simulate::<world::R2F64>(plan, run, sink),
            (Release::Current, Three, F32) => backend::simulate::<world::R3F32>(plan, run, sink),
            (Release::Current, Three, F64) => backend::simulate::<world::R3F64>(plan, run, sink),
            #[cfg(feature = "rapier-versions")]
            (Release::V0_34, Two, _) => backend::simulate::<world::R2F64V034>(plan, run, sink),
            #[cfg(feature = "rapier-versions")]
            (Release::V0_34, Three, _) => backend::simulate::<world::R3F64V034>(plan, run, sink),
            #[cfg(feature = "rapier-versions")]
            (Release::V0_35, Two, _) => backend::simulate::<world::R2F64V035>(plan, run, sink),
            #[cfg(feature = "rapier-versions")]
            (Release::V0_35, Three, _) => backend::simulate::<world::R3F64V035>(plan, run, sink),
        }
    }
}

impl Engine for RapierEngine {
    fn name(&self) -> &str {
        &self.name
    }
    fn controls(&self, scene: &Scene) -> Vec<Control> {
        controls::of(self, scene)
    }
    fn needs(&self) -> Needs {
        match self.configuration {
            Configuration::Matched(_) => Needs::MatchedIncrement,
            Configuration::Default => Needs::StudyIncrement,
        }
    }
    fn stepping(&self) -> Option<Stepping> {
        // An older release is compared case by case (the report's versions section), not
        // swept or mapped again.
        if self.release != Release::Current {
            return None;
        }
        let (coarsest, substeps) = match self.configuration {
            Configuration::Matched(m) => (Coarsest::OutputInterval, m.solver_iterations),
            Configuration::Default => (
                Coarsest::Increment(DEFAULT_INCREMENT),
                backend::DEFAULT_SOLVER_ITERATIONS,
            ),
        };
        Some(Stepping {
            coarsest,
            penalty: false,
            substeps: Some(substeps),
            budget_share: SWEEP_BUDGET_SHARE,
            precision: match self.precision {
                Precision::F32 => "f32",
                Precision::F64 => "f64",
            },
            // It answers `--tolerance` too, but its pilot runs cost about 40 s on the seed
            // cases at 1e-3 (measured), more than the default run's whole budget for the study.
            on_request: false,
        })
    }
    fn with_substeps(&self, substeps: usize) -> Option<Box<dyn Engine>> {
        if self.release != Release::Current {
            return None;
        }
        match self.configuration {
            Configuration::Matched(m) => {
                let mut engine = self.clone();
                engine.configuration = Configuration::Matched(MatchedSettings {
                    solver_iterations: substeps,
                    ..m
                });
                Some(Box::new(engine))
            }
            Configuration::Default => None,
        }
    }
    fn increments(&self, scene: &Scene, settings: &RunSettings) -> Option<f64> {
        let dt = match self.configuration {
            Configuration::Matched(_) => own_increment(scene, settings),
            Configuration::Default => default_increment(settings),
        };
        Some(scene.duration() / dt)
    }
    fn run(&self, scene: &Scene, settings: &RunSettings) -> Result<RunOutput, EngineError> {
        let start = Instant::now();
        let mut request = None;
        let chosen;
        let settings = match settings.increment.unwrap_or(scene.settings.increment) {
            IncrementRule::Tolerance(eps) => {
                let (h, predicted, pilots) = self.on_request(scene, settings, eps)?;
                request = Some((eps, predicted, pilots));
                chosen = RunSettings {
                    increment: Some(IncrementRule::Forced(h)),
                    ..*settings
                };
                &chosen
            }
            _ => settings,
        };
        let (mut output, diagnostics) = self.run_with_diagnostics(scene, settings)?;
        if let Some((eps, predicted, pilots)) = request {
            let m = &mut output.info.measures;
            m.insert("requested_tolerance".to_string(), eps);
            m.insert("predicted_error".to_string(), predicted);
            output
                .info
                .counters
                .insert("pilot_increments".to_string(), pilots);
            output.info.wall_seconds = start.elapsed().as_secs_f64();
        }
        if !scene.contacts.is_empty() {
            let m = &mut output.info.measures;
            m.insert("impacts".to_string(), diagnostics.impacts.len() as f64);
            for (i, t) in diagnostics
                .impacts
                .iter()
                .take(crate::contract::IMPACTS_REPORTED)
                .enumerate()
            {
                m.insert(format!("impact_{}_time", i + 1), *t);
            }
        }
        for (k, contact) in scene.contacts.iter().enumerate() {
            for (name, values) in [
                ("mean_penetration", &diagnostics.mean_penetration),
                ("max_penetration", &diagnostics.max_penetration),
                ("max_separation", &diagnostics.max_separation),
            ] {
                if let Some(v) = values.get(k) {
                    output
                        .info
                        .measures
                        .insert(format!("{name}:{}", contact.name), *v);
                }
            }
        }
        Ok(output)
    }
}

/// Most increments a rapier run on request may take (about 1–3 s of CPU at 4 substeps).
pub const MAX_INCREMENTS_ON_REQUEST: f64 = 2e5;

impl RapierEngine {
    /// Accuracy on request: rapier is first order in its increment, so two pilot runs at h₁ (the
    /// output interval, or 1/60 s for the default configuration) and h₁/2 measure its error
    /// e(h₁) ≈ 2 ‖x(h₁) − x(h₁/2)‖, and h = h₁ · [`super::ON_REQUEST_AIM`] ε / e(h₁) aims at the middle of
    /// [ε/10, ε]. Refused, saying why, when that takes more than
    /// [`MAX_INCREMENTS_ON_REQUEST`] increments, or when a check at the chosen increment (the
    /// run against itself at h/2) still estimates more than ε/2. Returns the increment, the
    /// estimated error and the pilots' increments.
    fn on_request(
        &self,
        scene: &Scene,
        settings: &RunSettings,
        eps: f64,
    ) -> Result<(f64, f64, u64), EngineError> {
        let h1 = match self.configuration {
            Configuration::Matched(_) => scene.duration() / (scene.output_rows - 1) as f64,
            Configuration::Default => DEFAULT_INCREMENT,
        };
        let at = |h: f64| RunSettings {
            increment: Some(IncrementRule::Forced(h)),
            ..*settings
        };
        let (coarse, _) = self.run_with_diagnostics(scene, &at(h1))?;
        let (fine, _) = self.run_with_diagnostics(scene, &at(h1 / 2.0))?;
        let pilots = coarse.info.steps + fine.info.steps;
        let e1 =
            2.0 * crate::contract::relative_change(scene.family, &coarse.history, &fine.history);
        let aim = super::ON_REQUEST_AIM * eps;
        let h = if e1 > 0.0 {
            (h1 * aim / e1).min(h1)
        } else {
            h1
        };
        let increments = scene.duration() / h;
        if increments > MAX_INCREMENTS_ON_REQUEST {
            return Err(EngineError::Unsupported(format!(
                "tolerance {eps:e} is out of reach for {}: its first-order error, {e1:.2e} at h = {h1:.2e} s, asks for h = {h:.2e} s, {increments:.1e} increments (at most {MAX_INCREMENTS_ON_REQUEST:e}); below its floor (contact softness, f32 round-off) no increment reaches it",
                self.name
            )));
        }
        // Check at the chosen increment: its own error estimate there, against itself at h/2.
        // Where rapier's error has stopped falling (contact softness, f32 round-off) the first-
        // order model promised too much, and the tolerance is out of reach.
        let (run, _) = self.run_with_diagnostics(scene, &at(h))?;
        let (half, _) = self.run_with_diagnostics(scene, &at(h / 2.0))?;
        let estimate =
            2.0 * crate::contract::relative_change(scene.family, &run.history, &half.history);
        // Accepted at half the tolerance: the first-order estimate runs low where rapier's
        // order has dropped below one (0.8 on the sliding cases).
        if estimate > 0.5 * eps {
            return Err(EngineError::Unsupported(format!(
                "tolerance {eps:e} is out of reach for {}: at h = {h:.2e} s, chosen from its \
                 first-order error ({e1:.2e} at h = {h1:.2e} s), its error estimate is still \
                 {estimate:.2e}: it has stopped falling at first order (contact softness, PGS \
                 sweeps, f32 round-off)",
                self.name
            )));
        }
        Ok((h, estimate, pilots + run.info.steps + half.info.steps))
    }
}

/// The increment of a matched run: the run's increment override, else the case's given one,
/// shortened to divide the output interval so that rows fall on steps; for a case whose rule
/// needs a stable increment (rapier has none), the output interval. The job planner hands the
/// central-difference engine's increment over as an override, so a planned matched run steps
/// with it.
pub fn own_increment(scene: &Scene, settings: &RunSettings) -> f64 {
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    match settings.increment.unwrap_or(scene.settings.increment) {
        IncrementRule::Given(h) | IncrementRule::Forced(h) => {
            interval / (interval / h - 1e-9).ceil().max(1.0)
        }
        // Stability studies: exactly as given (rows are interpolated between steps).
        IncrementRule::Exact(h) => h,
        IncrementRule::Accuracy(_)
        | IncrementRule::Stable { .. }
        | IncrementRule::Tolerance(_)
        | IncrementRule::StableRatio(_) => interval,
    }
}

/// The increment of a default-configuration run: 1/60 s, unless a study forces another
/// ([`IncrementRule::Forced`], as the discrepancy budget's refinement does, or
/// [`IncrementRule::Exact`], as the stability map does); a case's or a
/// run's ordinary increment (`--increment`) does not apply to it.
pub fn default_increment(settings: &RunSettings) -> f64 {
    match settings.increment {
        Some(IncrementRule::Forced(h) | IncrementRule::Exact(h)) => h,
        _ => DEFAULT_INCREMENT,
    }
}

/// The four rapier engines of the current release in report order.
pub fn engines() -> Vec<RapierEngine> {
    vec![
        RapierEngine::matched(Precision::F64),
        RapierEngine::matched(Precision::F32),
        RapierEngine::default_configuration(Precision::F64),
        RapierEngine::default_configuration(Precision::F32),
    ]
}

/// The f64 engines, matched then default, on each older release this build has (none without
/// the `rapier-versions` feature), oldest first.
pub fn older_releases() -> Vec<RapierEngine> {
    Release::all()
        .into_iter()
        .filter(|r| *r != Release::Current)
        .flat_map(|r| {
            [
                RapierEngine::matched(Precision::F64),
                RapierEngine::default_configuration(Precision::F64),
            ]
            .into_iter()
            .filter_map(move |e| e.on_release(r))
        })
        .collect()
}
