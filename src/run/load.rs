//! Loading the cases of a run: resolving ids and paths, validating every file, and the checks
//! that need the engines (tolerance names, a given increment against the stable one).

use crate::case::{self, CaseError};
use crate::engines::explicit::ExplicitEngine;
use crate::engines::{Engine, RunSettings};
use crate::scene::{IncrementRule, Scene, SceneError};
use std::path::{Path, PathBuf};

/// Checks that need the engines: tolerance names must be engine names, and a given increment
/// must not exceed the stable one.
pub fn check_scene(scene: &Scene) -> Result<(), SceneError> {
    check_scene_for(scene, &[])
}

/// [`check_scene`], with the names of engines beyond crosscheck's own (a user's) accepted in
/// `[tolerances]`.
pub fn check_scene_for(scene: &Scene, also: &[&str]) -> Result<(), SceneError> {
    let mut names = crate::run::registry::known_names();
    names.extend(also.iter().map(|n| n.to_string()));
    for engine in scene.tolerances.keys() {
        if !names.contains(engine) {
            return Err(SceneError {
                field: format!("tolerances.{engine}"),
                message: format!(
                    "`{engine}` is not an engine; valid names: {}",
                    names.join(", ")
                ),
            });
        }
    }
    check_increment(scene)
}

/// The stable increment must be computable (finite and positive: no overflow or singular
/// mass), and a case's given time increment must not exceed it for either explicit kinematics
/// (finite rotation adds geometric stiffness, so the two can differ).
pub fn check_increment(scene: &Scene) -> Result<(), SceneError> {
    let settings = RunSettings::default();
    let mut stable = Vec::new();
    for engine in [ExplicitEngine::finite(), ExplicitEngine::small()] {
        let computed = std::panic::catch_unwind(|| engine.stable_increment(scene, &settings));
        match computed {
            Ok(Some(s)) if s.increment.is_finite() && s.increment > 0.0 => stable.push(s),
            Ok(None) => {}
            Ok(Some(s)) => {
                return Err(SceneError {
                    field: "time".into(),
                    message: format!(
                        "the stable increment cannot be computed (highest frequency {:e} rad/s gives {:e}): the scene's numbers overflow; rescale its units",
                        s.omega_max, s.increment
                    ),
                });
            }
            Err(_) => {
                return Err(SceneError {
                    field: "time".into(),
                    message: "the stable increment cannot be computed (the linearised scene is singular or overflows); rescale its units".into(),
                });
            }
        }
    }
    let IncrementRule::Given(h) = scene.settings.increment else {
        return Ok(());
    };
    let stable = stable
        .into_iter()
        .min_by(|a, b| a.increment.total_cmp(&b.increment));
    match stable {
        Some(s) if h > s.increment * (1.0 + 1e-12) => Err(SceneError {
            field: "time.increment".into(),
            message: format!(
                "{h:e} is above this scene's stable increment {:e} (highest frequency {:.4e} rad/s, penalty included); use at most that, or give `safety` instead",
                s.increment, s.omega_max
            ),
        }),
        _ => Ok(()),
    }
}

/// An engine name that matches no engine.
#[derive(Debug, Clone, thiserror::Error)]
#[error("unknown engine `{name}`{}; valid engines: {}", case::diagnostic::did_you_mean(.name, .valid), .valid.join(", "))]
pub struct UnknownEngine {
    /// The name given.
    pub name: String,
    /// Every valid name, in report order.
    pub valid: Vec<String>,
}

/// Every engine name, in report order.
pub fn engine_names() -> Vec<String> {
    crate::run::registry::all()
        .iter()
        .map(|e| e.name().to_string())
        .collect()
}

/// Engines by name, in the order given (duplicates dropped); every engine when `names` is empty.
pub fn select_engines(names: &[String]) -> Result<Vec<Box<dyn Engine>>, UnknownEngine> {
    select_among(crate::run::registry::all(), names)
}

/// [`select_engines`] among `available` (crosscheck's engines and a user's, in report order).
pub fn select_among(
    available: Vec<Box<dyn Engine>>,
    names: &[String],
) -> Result<Vec<Box<dyn Engine>>, UnknownEngine> {
    if names.is_empty() {
        return Ok(available);
    }
    let valid: Vec<String> = available.iter().map(|e| e.name().to_string()).collect();
    let mut slots: Vec<Option<Box<dyn Engine>>> = available.into_iter().map(Some).collect();
    let mut out: Vec<Box<dyn Engine>> = Vec::new();
    for name in names {
        let name = name.trim();
        match valid.iter().position(|v| v == name) {
            Some(i) => out.extend(slots[i].take()),
            None => {
                return Err(UnknownEngine {
                    name: name.to_string(),
                    valid,
                });
            }
        }
    }
    Ok(out)
}

/// Why the cases of a run could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// A case argument that is not a case, or a case file that is not valid.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// The case directory could not be listed.
    #[error("{path}: cannot list cases: {source}")]
    Directory {
        /// The directory.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// Two different files with the same case id (their CSVs would collide).
    #[error("case id `{id}` is given by both {first} and {second}")]
    DuplicateId {
        /// The id.
        id: String,
        /// The first file.
        first: PathBuf,
        /// The second file.
        second: PathBuf,
    },
    /// No case to run.
    #[error("no case files (*.toml) in {0}")]
    NoCases(PathBuf),
}

/// Resolve and validate the cases named by `args` (ids from `dir` or paths to `.toml` files),
/// or every case in `dir` when `args` is empty. Every case is loaded before returning, so the
/// caller sees every problem at once; a case given twice is kept once. The scenes come back
/// sorted by id (the report order).
pub fn load_cases(args: &[String], dir: &Path) -> Result<Vec<Scene>, Vec<LoadError>> {
    load_cases_for(args, dir, &[])
}

/// [`load_cases`] for a plan with engines beyond crosscheck's own: their names (`also`) may
/// have tolerances in the case files.
pub fn load_cases_for(
    args: &[String],
    dir: &Path,
    also: &[&str],
) -> Result<Vec<Scene>, Vec<LoadError>> {
    let check = |scene: &Scene| check_scene_for(scene, also);
    let paths: Vec<Result<PathBuf, LoadError>> = if args.is_empty() {
        match case::discover(dir) {
            Ok(v) if v.is_empty() => return Err(vec![LoadError::NoCases(dir.to_path_buf())]),
            Ok(v) => v.into_iter().map(Ok).collect(),
            Err(source) => {
                return Err(vec![LoadError::Directory {
                    path: dir.to_path_buf(),
                    source,
                }]);
            }
        }
    } else {
        args.iter()
            .map(|a| case::resolve(a, dir).map_err(LoadError::from))
            .collect()
    };
    let mut scenes: Vec<(PathBuf, Scene)> = Vec::new();
    let mut errors = Vec::new();
    for p in paths {
        let path = match p {
            Ok(p) => p,
            Err(e) => {
                errors.push(e);
                continue;
            }
        };
        let scene = match case::load_checked(&path, &check) {
            Ok(s) => s,
            Err(e) => {
                errors.push(e.into());
                continue;
            }
        };
        let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
        match scenes.iter().find(|(_, s)| s.id == scene.id) {
            Some((first, _)) if *first == canonical => {}
            Some((first, _)) => errors.push(LoadError::DuplicateId {
                id: scene.id.clone(),
                first: first.clone(),
                second: canonical,
            }),
            None => scenes.push((canonical, scene)),
        }
    }
    if errors.is_empty() {
        scenes.sort_by(|a, b| a.1.id.cmp(&b.1.id));
        Ok(scenes.into_iter().map(|(_, s)| s).collect())
    } else {
        Err(errors)
    }
}

/// Validate the command line's overrides exactly as the same values in a case file: each
/// scene with the override applied must pass [`check_scene`] (a given increment not above the
/// stable one with the given penalty; a stable increment that can be computed). Returns one
/// message per refusal, naming the option and the case.
pub fn check_overrides(scenes: &[Scene], settings: &RunSettings) -> Vec<String> {
    let mut errors = Vec::new();
    let range = crate::case::build::MIN_MAGNITUDE..=crate::case::build::MAX_MAGNITUDE;
    if let Some(IncrementRule::Given(h) | IncrementRule::Forced(h)) = settings.increment
        && !(h.is_finite() && range.contains(&h))
    {
        errors.push(format!(
            "--increment {h:e}: outside the supported range [{:e}, {:e}]",
            range.start(),
            range.end()
        ));
    }
    if let Some(crate::scene::PenaltyRule::Stiffness(k) | crate::scene::PenaltyRule::Ratio(k)) =
        settings.penalty
        && !(k.is_finite() && range.contains(&k))
    {
        errors.push(format!(
            "--penalty {k:e}: outside the supported range [{:e}, {:e}]",
            range.start(),
            range.end()
        ));
    }
    if !errors.is_empty() {
        return errors;
    }
    let option = match (settings.increment, settings.penalty) {
        (Some(_), Some(_)) => "--increment/--penalty",
        (Some(_), None) => "--increment",
        (None, Some(_)) => "--penalty",
        (None, None) => return errors,
    };
    for scene in scenes {
        let mut s = scene.clone();
        if let Some(rule) = settings.increment {
            s.settings.increment = rule;
        }
        if let Some(rule) = settings.penalty {
            s.settings.penalty = rule;
        }
        if let Some(d) = settings.damping {
            s.settings.damping = d;
        }
        if let Err(e) = check_increment(&s) {
            errors.push(format!("{option}: case {}: {e}", scene.id));
        }
    }
    errors
}
