//! `crosscheck`: run the verification cases through the engines and write the report data.
//!
//! Exit codes: 0 every job succeeded; 1 some job failed (the others were written);
//! 2 bad input (invalid or unknown case, unknown engine, bad option): nothing was run or written.

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use crosscheck::case;
use crosscheck::engines::RunSettings;
use crosscheck::report::{self, staging};
use crosscheck::run::{self, LoadError, Plan};
use crosscheck::scene::{ContactStart, DampingTreatment, Dimension, IncrementRule, PenaltyRule};
use std::path::PathBuf;
use std::process::ExitCode;

/// Verification harness for explicit dynamics: on problems whose exact answer is known, how
/// close does an engine get, what does that cost, and does it stay stable.
///
/// Without a subcommand, runs every case with every engine into `report/`.
#[derive(Debug, Parser)]
#[command(name = "crosscheck", version)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the cases: id, family, dimension and the effects each calls for.
    List,
    /// Run cases through engines and write `OUT/data/<case>/<engine>.csv`.
    Run(RunArgs),
    /// Validate case files without running them (the same validation every `run` does first).
    Check {
        /// Case files (default: every case in cases/).
        #[arg(value_name = "FILE")]
        files: Vec<PathBuf>,
    },
}

#[derive(Debug, Args, Default)]
struct RunArgs {
    /// Case ids from cases/ or paths to .toml case files (default: every case in cases/).
    #[arg(value_name = "CASE")]
    cases: Vec<String>,
    /// Comma-separated engine names (default: every engine).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    engines: Vec<String>,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "report")]
    out: PathBuf,
    /// Use this time increment instead of the case's rule.
    #[arg(long, value_name = "H", value_parser = positive)]
    increment: Option<f64>,
    /// Use this penalty stiffness instead of the case's rule.
    #[arg(long, value_name = "K", value_parser = positive)]
    penalty: Option<f64>,
    /// How dashpots see the velocity.
    #[arg(long, value_enum)]
    damping: Option<DampingArg>,
    /// How a penalty contact starts.
    #[arg(long, value_enum)]
    contact_start: Option<ContactStartArg>,
    /// Do not show the progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum DampingArg {
    /// Mid-step velocity, second order.
    Centred,
    /// Previous half-step velocity (classic explicit).
    Lagged,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ContactStartArg {
    /// At the penetration that carries the initial contact force.
    Consistent,
    /// At zero penetration.
    Touching,
}

fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(x) => Err(format!("must be a finite number > 0, got {x}")),
        Err(e) => Err(e.to_string()),
    }
}

impl RunArgs {
    fn settings(&self) -> RunSettings {
        RunSettings {
            increment: self.increment.map(IncrementRule::Given),
            penalty: self.penalty.map(PenaltyRule::Stiffness),
            damping: self.damping.map(|d| match d {
                DampingArg::Centred => DampingTreatment::Centred,
                DampingArg::Lagged => DampingTreatment::Lagged,
            }),
            contact_start: self.contact_start.map(|c| match c {
                ContactStartArg::Consistent => ContactStart::Consistent,
                ContactStartArg::Touching => ContactStart::Touching,
            }),
        }
    }
}

fn main() -> ExitCode {
    let names = run::engine_names().join(", ");
    let command = Cli::command().mut_subcommand("run", |c| {
        c.mut_arg("engines", |a| {
            a.help(format!(
                "Comma-separated engine names (default: every engine: {names})"
            ))
        })
    });
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    staging::install_signal_cleanup();
    match cli.command {
        None => run_command(RunArgs {
            out: PathBuf::from("report"),
            ..RunArgs::default()
        }),
        Some(Command::List) => list(),
        Some(Command::Run(args)) => run_command(args),
        Some(Command::Check { files }) => check(files),
    }
}

fn check(files: Vec<PathBuf>) -> ExitCode {
    let files = if files.is_empty() {
        match case::discover(&case::cases_dir()) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("error: cannot list cases: {e}");
                return ExitCode::from(2);
            }
        }
    } else {
        files
    };
    let mut invalid = 0;
    for f in &files {
        match case::load_checked(f, &run::check_scene) {
            Ok(scene) => println!("ok: {} ({})", f.display(), scene.id),
            Err(e) => {
                invalid += 1;
                eprint!("{}", e.render());
            }
        }
    }
    if invalid == 0 {
        ExitCode::SUCCESS
    } else {
        eprintln!("{invalid} of {} case file(s) invalid", files.len());
        ExitCode::from(2)
    }
}

fn report_load_errors(errors: &[LoadError]) {
    for e in errors {
        match e {
            LoadError::Case(c) => eprint!("{}", c.render()),
            other => eprintln!("error: {other}"),
        }
    }
}

fn list() -> ExitCode {
    let dir = case::cases_dir();
    let paths = match case::discover(&dir) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {}: cannot list cases: {e}", dir.display());
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
        println!("{}", line.trim_end());
    }
    if errors.is_empty() {
        ExitCode::SUCCESS
    } else {
        report_load_errors(&errors);
        ExitCode::from(2)
    }
}

fn run_command(args: RunArgs) -> ExitCode {
    let engines = match run::select_engines(&args.engines) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let cases = match run::load_cases(&args.cases, &case::cases_dir()) {
        Ok(c) => c,
        Err(errors) => {
            report_load_errors(&errors);
            eprintln!("nothing was run");
            return ExitCode::from(2);
        }
    };
    let staging = match staging::Staging::begin(&args.out) {
        Ok(s) => s,
        Err(e) => {
            eprintln!(
                "error: cannot prepare the report beside {}: {e}",
                args.out.display()
            );
            return ExitCode::FAILURE;
        }
    };
    let plan = Plan {
        cases,
        engines,
        settings: args.settings(),
    };
    let outcome = run::execute(&plan, !args.quiet);
    print!("{}", outcome.table());
    let summary = match report::write(staging.path(), &plan, &outcome, staging.target()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: cannot write the report (the previous one is unchanged): {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = staging.commit() {
        eprintln!("error: cannot put the report in place (the previous one is unchanged): {e}");
        return ExitCode::FAILURE;
    }
    let checks = summary.tolerance_checks();
    println!(
        "{} job(s), {} failed; report: {} ({} of {} tolerances met)",
        outcome.jobs.len(),
        outcome.failures(),
        report::report_path(&args.out).display(),
        checks.iter().filter(|c| c.4).count(),
        checks.len()
    );
    if outcome.all_ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
