//! The commands that read cases without running them (`list`, `check`), `judge`, and where
//! the cases come from.

use super::{Against, JudgeArgs, Stdout, outcome};
use crate::case;
use crate::comparison;
use crate::pipeline;
use crate::report::staging;
use crate::run::{self, LoadError};
use crate::scene::Dimension;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The case files of `dir`, or a message saying why there are none.
pub(super) fn case_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    if !dir.is_dir() {
        return Err(format!(
            "no case directory {}: --cases and {} must name a directory of case files (with \
             neither, cases/ in the working directory is used, else the shipped cases)",
            dir.display(),
            case::embedded::ENV
        ));
    }
    match case::discover_suite(dir) {
        Ok(f) if f.is_empty() => Err(format!("no case files (*.toml) in {}", dir.display())),
        Ok(f) => Ok(f),
        Err(e) => Err(format!("{}: cannot list cases: {e}", dir.display())),
    }
}

pub(super) fn judge(args: JudgeArgs, dir: &Path) -> ExitCode {
    let request = pipeline::JudgeRequest {
        case: args.case,
        file: args.file,
        columns: args.columns,
        time: args.time,
        scales: args.scales,
        against: match args.against {
            Against::Reference => comparison::FINITE_ROTATION_REFERENCE,
            Against::Analytic => comparison::CLOSED_FORM,
        },
        tolerance: args.tolerance,
    };
    outcome(pipeline::judge(&request, dir).map(|(text, pass)| (text, !pass)))
}

pub(super) fn check(names: Vec<String>, dir: &Path, also: &[&str]) -> ExitCode {
    let files = if names.is_empty() {
        match case_files(dir) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    } else {
        let mut files = Vec::new();
        for name in &names {
            // A path is read as given (a FIFO or a directory is then refused by name); an id
            // is looked up in the case directory.
            let path = Path::new(name);
            if path.exists() || name.contains(std::path::MAIN_SEPARATOR) || name.ends_with(".toml")
            {
                files.push(path.to_path_buf());
                continue;
            }
            match case::resolve(name, dir) {
                Ok(f) => files.push(f),
                Err(e) => {
                    eprint!("{}", e.render());
                    return ExitCode::from(2);
                }
            }
        }
        files
    };
    let mut out = Stdout::default();
    let mut invalid = 0;
    for f in &files {
        match case::load_checked(f, &|s| run::check_scene_for(s, also)) {
            Ok(scene) => out.print(&format!("ok: {} ({})\n", f.display(), scene.id)),
            Err(e) => {
                invalid += 1;
                eprint!("{}", e.render());
            }
        }
    }
    let code = if invalid == 0 {
        ExitCode::SUCCESS
    } else {
        eprintln!("{invalid} of {} case file(s) invalid", files.len());
        ExitCode::from(2)
    };
    out.finish(code)
}

pub(super) fn report_load_errors(errors: &[LoadError]) {
    for e in errors {
        match e {
            LoadError::Case(c) => eprint!("{}", c.render()),
            other => eprintln!("error: {other}"),
        }
    }
}

pub(super) fn list(dir: &Path) -> ExitCode {
    let paths = match case_files(dir) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    // List the valid cases; report the others on stderr.
    let mut scenes = Vec::new();
    let mut errors = Vec::new();
    for p in &paths {
        match case::load(p) {
            Ok(s) => scenes.push(s),
            Err(e) => errors.push(LoadError::from(e)),
        }
    }
    let id_w = scenes.iter().map(|s| s.id.len()).max().unwrap_or(0);
    let fam_w = scenes
        .iter()
        .map(|s| s.family.name().len())
        .max()
        .unwrap_or(0);
    let mut out = Stdout::default();
    for s in &scenes {
        let dim = match s.dimension {
            Dimension::Two => "2D",
            Dimension::Three => "3D",
        };
        let line = format!(
            "{:id_w$}  {:fam_w$}  {dim}  {}",
            s.id,
            s.family.name(),
            s.effects().join(" ")
        );
        out.print(&format!("{}\n", line.trim_end()));
    }
    let code = if errors.is_empty() {
        ExitCode::SUCCESS
    } else {
        report_load_errors(&errors);
        ExitCode::from(2)
    };
    out.finish(code)
}

/// Resolve `--out` and load the cases named (every case with none): exit 2 with the messages
/// when either is invalid.
pub(super) fn target_and_cases(
    out: &Path,
    names: &[String],
    dir: &Path,
    also: &[&str],
) -> Result<(PathBuf, Vec<crate::scene::Scene>), ExitCode> {
    let target = staging::resolve_output(out).map_err(|e| {
        eprintln!("error: {e}; nothing was run");
        ExitCode::from(2)
    })?;
    if names.is_empty()
        && let Err(e) = case_files(dir)
    {
        eprintln!("error: {e}; nothing was run");
        return Err(ExitCode::from(2));
    }
    // With no case named: the seed cases of `dir` and the stress family of `dir/stress`.
    let suite: Vec<String> = if names.is_empty() {
        case::discover_suite(dir)
            .unwrap_or_default()
            .iter()
            .map(|p| p.display().to_string())
            .collect()
    } else {
        names.to_vec()
    };
    let cases = run::load_cases_for(&suite, dir, also).map_err(|errors| {
        report_load_errors(&errors);
        eprintln!("nothing was run");
        ExitCode::from(2)
    })?;
    Ok((target, cases))
}
