//! Refinement ladders: one job's engine run again at other time increments and, for a penalty
//! engine, stiffer penalties, so that the comparison can extrapolate its answer to h → 0 and
//! k_p → ∞ (the discrepancy budget, `comparison::discrepancy`).
//!
//! - **Time.** An engine with a stability limit (it reports a stable increment: the explicit
//!   engines) is *refined*: h, h/2, h/4. An engine without one (rapier) whose increment is at
//!   most a quarter of the output interval is *coarsened* instead: h, 2h, 4h, which costs less
//!   than the run itself while the rows still fall on steps (a matched rapier run of the rigid
//!   cases takes 10 000 steps; refining it would cost six runs). Rapier's default 1/60 s, longer
//!   than the output interval, is refined. The increments actually taken are recorded (rapier
//!   shortens one to divide the output interval), so ratios need not be exactly 2.
//! - **Penalty.** An engine that reports a penalty stiffness k₀ is also run at 4k₀ and 16k₀,
//!   each with its own time ladder from its own base increment: the job's, or 0.9 of the stable
//!   one where the stiffer penalty lowers it.
//! - **One level more** ([`Depth::Extra`]): a finer increment (h/8, or h/2 for a coarsened
//!   engine) and a stiffer penalty (64k₀), so that the extrapolation can be repeated one level
//!   further and its change measured (the tests do).
//!
//! Every rung is an ordinary run of the same engine with the job's settings but for the
//! increment (forced) and the penalty stiffness; its history is checked like a job's.

use super::{JobSuccess, matching};
use crate::contract::{self, History};
use crate::engines::{Engine, EngineError, RunSettings};
use crate::scene::{DEFAULT_SAFETY, IncrementRule, PenaltyRule, Scene};

/// Ratio between successive penalty stiffnesses of a ladder.
pub const PENALTY_RATIO: f64 = 4.0;

/// How many levels a ladder has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Three time levels (and three penalty levels): what one extrapolation needs.
    Basic,
    /// One more of each, to repeat the extrapolation one level further.
    Extra,
}

/// Which way a time ladder goes from the job's increment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// h, h/2, h/4 (h/8).
    Refine,
    /// h, 2h, 4h (and h/2 one level further).
    Coarsen,
}

/// One run of a ladder.
#[derive(Debug, Clone)]
pub struct Rung {
    /// The increment the run took.
    pub increment: f64,
    /// Its history.
    pub history: History,
}

/// The time ladder at one penalty stiffness.
#[derive(Debug, Clone)]
pub struct PenaltyLevel {
    /// The penalty stiffness (`None`: the engine has none).
    pub stiffness: Option<f64>,
    /// Runs in ladder order: the base increment first, then away from it in the ladder's
    /// direction; with [`Depth::Extra`], the extra level last.
    pub rungs: Vec<Rung>,
}

/// Every rerun of one job.
#[derive(Debug, Clone)]
pub struct Ladder {
    /// How the time levels go.
    pub direction: Direction,
    /// Penalty levels k₀, 4k₀, 16k₀ (64k₀), or the one level of an engine without penalty.
    pub levels: Vec<PenaltyLevel>,
}

/// Build the ladder of a successful job of `engine` on `scene` (run with the plan's
/// `settings`). An engine that does not step in time (no increment) has none (`Ok(None)`).
pub fn ladder(
    scene: &Scene,
    engine: &dyn Engine,
    settings: &RunSettings,
    job: &JobSuccess,
    depth: Depth,
) -> Result<Option<Ladder>, String> {
    let info = &job.info;
    if info.steps == 0 || info.increment <= 0.0 {
        return Ok(None);
    }
    let settings = matching::job_settings(engine, scene, settings);
    let interval = scene.duration() / (scene.output_rows - 1) as f64;
    let direction = if info.stable_increment.is_none() && info.increment <= interval / 4.0 {
        Direction::Coarsen
    } else {
        Direction::Refine
    };
    let factors: &[f64] = match (direction, depth) {
        (Direction::Refine, Depth::Basic) => &[0.5, 0.25],
        (Direction::Refine, Depth::Extra) => &[0.5, 0.25, 0.125],
        (Direction::Coarsen, Depth::Basic) => &[2.0, 4.0],
        (Direction::Coarsen, Depth::Extra) => &[2.0, 4.0, 0.5],
    };
    let stiffnesses: Vec<Option<f64>> = match info.penalty_stiffness {
        None => vec![None],
        Some(k) => {
            let n = if depth == Depth::Basic { 3 } else { 4 };
            (0..n).map(|j| Some(k * PENALTY_RATIO.powi(j))).collect()
        }
    };
    let run = |settings: &RunSettings| -> Result<Rung, EngineError> {
        crate::interrupt::checkpoint("budget")
            .map_err(|_| EngineError::Failed("interrupted".into()))?;
        let out = engine.run(scene, settings)?;
        contract::check(scene, &out.history)
            .and_then(|_| contract::check_finite(&out.history))
            .map_err(EngineError::Failed)?;
        Ok(Rung {
            increment: out.info.increment,
            history: out.history,
        })
    };
    let mut levels = Vec::new();
    for (j, stiffness) in stiffnesses.into_iter().enumerate() {
        let at_penalty = RunSettings {
            penalty: stiffness.map(PenaltyRule::Stiffness),
            ..settings
        };
        let base = if j == 0 {
            Rung {
                increment: info.increment,
                history: job.history.clone(),
            }
        } else {
            // The job's increment where the stiffer penalty still allows it, else 0.9 of the
            // stable one.
            let given = |h| RunSettings {
                increment: Some(IncrementRule::Given(h)),
                ..at_penalty
            };
            match run(&given(info.increment)) {
                Err(EngineError::UnstableIncrement { stable, .. }) => {
                    run(&given(DEFAULT_SAFETY * stable))
                }
                other => other,
            }
            .map_err(|e| format!("penalty {:e}: {e}", stiffness.unwrap_or(0.0)))?
        };
        let h = base.increment;
        let mut rungs = vec![base];
        for f in factors {
            let forced = RunSettings {
                increment: Some(IncrementRule::Forced(h * f)),
                ..at_penalty
            };
            rungs.push(run(&forced).map_err(|e| format!("increment {:e}: {e}", h * f))?);
        }
        levels.push(PenaltyLevel { stiffness, rungs });
    }
    Ok(Some(Ladder { direction, levels }))
}
