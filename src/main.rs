//! `crosscheck`: run the verification cases through the engines and write the report data.
//!
//! Exit codes: 0 every job succeeded; 1 some job failed (the others were written), or the report
//! or standard output could not be written; 2 bad input (invalid or unknown case, unknown
//! engine, bad option, unusable `--out`, a run above its resource limits, an output another run
//! holds with `--no-wait`): nothing was run or written; 130 interrupted (SIGINT, SIGTERM,
//! SIGHUP): the previous report is unchanged.

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use crosscheck::case;
use crosscheck::comparison::{self, work_precision};
use crosscheck::engines::{Engine, RunSettings};
use crosscheck::report::{self, staging};
use crosscheck::run::{self, LoadError, Plan, budget, sweep};
use crosscheck::scene::{ContactStart, DampingTreatment, Dimension, IncrementRule, PenaltyRule};
use crosscheck::{interrupt, pipeline};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The standard macros, shadowed in this file: standard error that cannot be written (a full
/// disk, `/dev/full`) loses the message and never panics; the exit code still says what
/// happened.
macro_rules! eprintln {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// As `eprintln!` above, without the newline.
macro_rules! eprint {
    ($($arg:tt)*) => {{
        let _ = write!(std::io::stderr(), $($arg)*);
    }};
}
use std::process::ExitCode;

/// Verification harness for explicit dynamics: on problems whose exact answer is known, how
/// close does an engine get, what does that cost, and does it stay stable.
///
/// Without a subcommand, runs every case with every engine into `report/`.
#[derive(Debug, Parser)]
#[command(name = "crosscheck", version)]
struct Cli {
    /// Directory of the case files (default: `cases/` in the working directory).
    #[arg(long = "cases", id = "cases_dir", value_name = "DIR", global = true)]
    cases_dir: Option<PathBuf>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the cases: id, family, dimension and the effects each calls for.
    List,
    /// Run cases through engines and write `OUT/data/<case>/<engine>.csv`.
    Run(RunArgs),
    /// Cost studies. `chain`: ns per increment of `explicit` and `rapier_f64` on a chain of N
    /// masses (N = 10, 100, …), against the machine's memory-bandwidth limit; writes
    /// `OUT/scaling.csv` and `OUT/figures/scaling.svg`. `elements`: `explicit`'s cost per
    /// element on a generated family of scenes (1–16 bodies, 0–16 contacts, 1–64 particles),
    /// a cost model fitted to it, and the seed cases predicted by that model; writes
    /// `OUT/elements.csv` and `OUT/figures/elements.svg`.
    Scaling {
        /// Which study.
        #[arg(long, value_enum, default_value = "all")]
        study: ScalingStudy,
        /// Largest chain (masses; at most 10^6, which holds about 0.8 GB).
        #[arg(long, value_name = "N", default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(10..=1_000_000))]
        max_n: u64,
        /// Output directory.
        #[arg(long, value_name = "DIR", default_value = "report/scaling")]
        out: PathBuf,
        /// Do not show the progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Judge a history from another code (a CSV with a header and a time column) against a
    /// case's exact solution, with the comparison and verdict an engine gets. Exit 0 within
    /// the tolerance, 1 outside it, 2 on unusable input.
    Judge(JudgeArgs),
    /// Compare two reports in two tiers: physics (each side's error against the exact
    /// solution; a cell that passed and now fails is a regression) and machine (the histories
    /// row by row; a column that moved by more than the threshold of its peak has drifted).
    /// Exit 0 when neither fails, 1 when one does, 2 when they cannot be compared.
    Compare {
        /// The baseline report directory.
        #[arg(value_name = "BASE")]
        base: PathBuf,
        /// The report to judge against it.
        #[arg(value_name = "NEW")]
        new: PathBuf,
        /// Drift threshold: the largest difference over the column's peak.
        #[arg(long, value_name = "X", default_value_t = report::regression::DRIFT)]
        threshold: f64,
        /// Fail only on the physics tier (drift is reported, not failed).
        #[arg(long)]
        physics_only: bool,
        /// Also write JUnit XML here (a suite per tier, a test per column).
        #[arg(long, value_name = "FILE")]
        junit: Option<PathBuf>,
    },
    /// Validate case files without running them (the same validation every `run` does first).
    Check {
        /// Case files (default: every case in cases/).
        #[arg(value_name = "FILE")]
        files: Vec<PathBuf>,
    },
    /// Sweep each engine's settings (time increment, penalty stiffness, rapier substeps; f32
    /// and f64) and write what each accuracy costs: `OUT/sweep.csv` and
    /// `OUT/figures/<case>.work-precision.svg`; orders, floors and time to accuracy on
    /// standard output.
    Sweep(SweepArgs),
    /// Stability map: every engine that steps in time on every case at increments of 0.25 … 4
    /// × the explicit engine's stable increment, each run classified accurate / inaccurate /
    /// unstable / failed: `OUT/stability.csv` (with each critical increment) and `OUT/figures/stability-<engine>.svg`.
    Stability(StabilityArgs),
}

/// Options of `crosscheck stability`.
#[derive(Debug, Args)]
struct StabilityArgs {
    /// Case ids from cases/ or paths to .toml case files (default: every case in cases/ and
    /// cases/stress/).
    #[arg(value_name = "CASE")]
    cases: Vec<String>,
    /// Comma-separated engines to map (default: every engine that steps in time).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    engines: Vec<String>,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "report")]
    out: PathBuf,
    /// Do not show the progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Refuse (exit 2) when another run is writing the same output, instead of waiting.
    #[arg(long)]
    no_wait: bool,
}

/// Options of `crosscheck sweep`.
#[derive(Debug, Args)]
struct SweepArgs {
    /// Case ids from cases/ or paths to .toml case files (default: every case in cases/).
    #[arg(value_name = "CASE")]
    cases: Vec<String>,
    /// Comma-separated engines to sweep (default: every engine that steps in time).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    engines: Vec<String>,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "report")]
    out: PathBuf,
    /// Runs per point (CPU time reported as min, median and max over them).
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repeat: u64,
    /// Most increments one run of a point may take (rapier: a fifth of it, substeps counted).
    #[arg(long, value_name = "N", default_value_t = sweep::Grid::default().max_increments, value_parser = positive)]
    max_increments: f64,
    /// Do not show the progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Refuse (exit 2) when another run is writing the same output, instead of waiting.
    #[arg(long)]
    no_wait: bool,
}

#[derive(Debug, Args)]
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
    /// Accuracy on request: each engine chooses its increment (and penalty stiffness) so that
    /// its error against its own model's exact solution is at most EPS of each column's peak.
    #[arg(long, value_name = "EPS", value_parser = positive, conflicts_with_all = ["increment", "penalty"])]
    tolerance: Option<f64>,
    /// Stability study: step with R × each engine's computed stable increment (rapier: the
    /// explicit engine's), exactly, R > 1 allowed; rows are interpolated between increments.
    #[arg(long, value_name = "R", value_parser = positive, conflicts_with_all = ["increment", "tolerance"])]
    increment_ratio: Option<f64>,
    /// How dashpots see the velocity.
    #[arg(long, value_enum)]
    damping: Option<DampingArg>,
    /// How a penalty contact starts.
    #[arg(long, value_enum)]
    contact_start: Option<ContactStartArg>,
    /// Do not show the progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Refuse at once (exit 2) when another run is writing the same output, instead of waiting.
    #[arg(long)]
    no_wait: bool,
    /// Most increments one job may take.
    #[arg(long, value_name = "N", default_value_t = budget::Limits::default().max_increments, value_parser = positive)]
    max_increments: f64,
    /// Most output rows one case may have.
    #[arg(long, value_name = "N", default_value_t = budget::Limits::default().max_rows)]
    max_rows: usize,
    /// Most bytes of output histories the run may hold.
    #[arg(long, value_name = "BYTES", default_value_t = budget::Limits::default().max_memory_bytes, value_parser = positive)]
    max_memory: f64,
    /// Also sweep each engine's settings and report what accuracy costs (the compact grid of
    /// `crosscheck sweep`; `crosscheck` with no arguments does).
    #[arg(long)]
    sweep: bool,
    /// Also run the stability map (as `crosscheck stability`, into the same report).
    #[arg(long)]
    stability: bool,
    /// Also ask the explicit engines for each tolerance 1e-3, 1e-4 and 1e-5 (accuracy on
    /// request) and report requested against achieved, with the cost.
    #[arg(long)]
    on_request: bool,
    /// Runs per sweep point (with --sweep).
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repeat: u64,
}

#[derive(Debug, Args)]
struct JudgeArgs {
    /// Case id from cases/ or path to a .toml case file.
    #[arg(value_name = "CASE")]
    case: String,
    /// Their history: CSV with a header row.
    #[arg(value_name = "FILE.csv")]
    file: PathBuf,
    /// Map one of the case's columns to theirs (default: the same name); repeat for more.
    #[arg(long = "column", value_name = "OURS=THEIRS")]
    columns: Vec<String>,
    /// Their time column, in seconds.
    #[arg(long, value_name = "NAME", default_value = "t")]
    time: String,
    /// Multiply their column (named by ours) by FACTOR to convert it to the case's unit
    /// (m, m/s, rad, N); repeat for more.
    #[arg(long = "scale", value_name = "COLUMN=FACTOR")]
    scales: Vec<String>,
    /// The exact solution: `reference` (the full model) or `analytic` (the closed form of the
    /// linearised one).
    #[arg(long, value_enum, default_value = "reference")]
    against: Against,
    /// Largest error over each column's peak (default: the tightest the case declares).
    #[arg(long, value_name = "EPS")]
    tolerance: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Against {
    /// The converged solution of the full (finite-rotation) model.
    Reference,
    /// The closed form of the linearised (small-rotation) model.
    Analytic,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ScalingStudy {
    /// The chain of N masses.
    Chain,
    /// The cost per element on generated scenes and the seed cases.
    Elements,
    /// Both.
    All,
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
    /// Every case, every engine, into `report/`.
    fn everything() -> RunArgs {
        RunArgs {
            cases: Vec::new(),
            engines: Vec::new(),
            out: PathBuf::from("report"),
            increment: None,
            penalty: None,
            tolerance: None,
            increment_ratio: None,
            damping: None,
            contact_start: None,
            quiet: false,
            no_wait: false,
            max_increments: budget::Limits::default().max_increments,
            max_rows: budget::Limits::default().max_rows,
            max_memory: budget::Limits::default().max_memory_bytes,
            sweep: true,
            stability: true,
            on_request: true,
            repeat: 3,
        }
    }

    fn limits(&self) -> budget::Limits {
        budget::Limits {
            max_increments: self.max_increments,
            max_rows: self.max_rows,
            max_memory_bytes: self.max_memory,
        }
    }

    fn settings(&self) -> RunSettings {
        RunSettings {
            increment: self
                .increment
                .map(IncrementRule::Given)
                .or(self.tolerance.map(IncrementRule::Tolerance))
                .or(self.increment_ratio.map(IncrementRule::StableRatio)),
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
    interrupt::install();
    let dir = cli.cases_dir.clone().unwrap_or_else(case::cases_dir);
    match cli.command {
        None => run_command(RunArgs::everything(), &dir),
        Some(Command::List) => list(&dir),
        Some(Command::Run(args)) => run_command(args, &dir),
        Some(Command::Check { files }) => check(files, &dir),
        Some(Command::Judge(args)) => judge(args, &dir),
        Some(Command::Compare {
            base,
            new,
            threshold,
            physics_only,
            junit,
        }) => outcome(pipeline::compare(
            &base,
            &new,
            threshold,
            physics_only,
            junit.as_deref(),
        )),
        Some(Command::Scaling {
            study,
            max_n,
            out,
            quiet,
        }) => scaling(study, max_n as usize, &out, quiet, &dir),
        Some(Command::Sweep(args)) => sweep_command(args, &dir),
        Some(Command::Stability(args)) => stability_command(args, &dir),
    }
}

fn scaling(study: ScalingStudy, max_n: usize, out: &Path, quiet: bool, dir: &Path) -> ExitCode {
    let target = match staging::resolve_output(out) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}; nothing was run");
            return ExitCode::from(2);
        }
    };
    let _lock = match staging::OutputLock::acquire(&target, true) {
        Ok(l) => l,
        Err(staging::OutputError::Interrupted) => return interrupted(),
        Err(e) => {
            eprintln!("error: cannot lock {}: {e}", target.display());
            return ExitCode::FAILURE;
        }
    };
    let mut stdout = Stdout::default();
    if study != ScalingStudy::Elements {
        let code = chain_study(max_n, &target, quiet, &mut stdout);
        if code != ExitCode::SUCCESS {
            return stdout.finish(code);
        }
    }
    if study != ScalingStudy::Chain {
        let code = element_study(&target, quiet, dir, &mut stdout);
        return stdout.finish(code);
    }
    stdout.finish(ExitCode::SUCCESS)
}

/// A progress bar of `len` steps on standard error (hidden when `quiet` or not a terminal).
fn progress_bar(len: u64, quiet: bool, unit: &str) -> indicatif::ProgressBar {
    let bar = if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(len)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:30}} {{pos}}/{{len}} {unit}  {{msg}}"
        ))
        .expect("a valid template"),
    );
    bar
}

/// A study's result, or the exit code of its failure: interrupted, or an error said on
/// standard error.
fn finished<T>(study: Result<T, String>) -> Result<T, ExitCode> {
    study.map_err(|e| {
        if interrupt::requested() {
            interrupted()
        } else {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    })
}

/// Print a study's `text`, write its CSV (path, text), the commit it was measured at (the
/// CSV's path with `.provenance`) and, where given, its figure (path, SVG), and say where.
fn publish(
    stdout: &mut Stdout,
    text: &str,
    (path, csv): (PathBuf, String),
    figure: Option<(PathBuf, String)>,
) -> ExitCode {
    stdout.print(text);
    let written = report::data::write_atomic(&path, csv.as_bytes())
        .and_then(|_| report::data::write_provenance(&path))
        .and_then(|_| match figure {
            Some((path, svg)) => report::data::write_atomic(&path, svg.as_bytes()),
            None => Ok(()),
        });
    if let Err(e) = written {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    stdout.print(&format!("written: {}\n", path.display()));
    ExitCode::SUCCESS
}

/// The element-cost study: run, print the model and how well it predicts, write the files.
fn element_study(target: &Path, quiet: bool, dir: &Path, stdout: &mut Stdout) -> ExitCode {
    use crosscheck::report::element_cost as written;
    use crosscheck::run::element_cost;
    let seeds = match case::discover(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))
        .and_then(|paths| {
            paths
                .iter()
                .map(|p| case::load(p).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()
        }) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let bar = progress_bar(
        (element_cost::family().len() + seeds.len()) as u64,
        quiet,
        "scenes",
    );
    let study = element_cost::study(&seeds, |id| {
        bar.set_message(id.to_string());
        bar.inc(1);
    });
    bar.finish_and_clear();
    let study = match finished(study) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let text = format!(
        "explicit, ns per increment = sum of coefficient × count:\n\n{}",
        written::summary(&study)
    );
    #[cfg(feature = "figures")]
    let figure = written::render(&study).map(|svg| (written::figure_path(target), svg));
    #[cfg(not(feature = "figures"))]
    let figure = None;
    let csv = (written::csv_path(target), written::csv(&study));
    publish(stdout, &text, csv, figure)
}

/// The chain study: run, print, write the files.
fn chain_study(max_n: usize, target: &Path, quiet: bool, stdout: &mut Stdout) -> ExitCode {
    use crosscheck::report::scaling as written;
    use crosscheck::run::scaling;
    let bar = progress_bar(2 * scaling::sizes(max_n).len() as u64, quiet, "points");
    let lines = !quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr()); // bar hidden
    let started = std::time::Instant::now();
    let study = scaling::study(max_n, |engine, n| {
        bar.set_message(format!("{engine}, N = {n}"));
        bar.inc(1);
        lines.then(|| eprintln!("scaling: {engine}, N = {n} (at {:.1?})", started.elapsed()));
    });
    bar.finish_and_clear();
    let study = match finished(study) {
        Ok(s) => s,
        Err(code) => return code,
    };
    #[cfg(feature = "figures")]
    let figure = written::render(&study).map(|svg| (written::figure_path(target), svg));
    #[cfg(not(feature = "figures"))]
    let figure = None;
    let csv = (written::csv_path(target), written::csv(&study));
    publish(stdout, &written::table(&study), csv, figure)
}

/// Standard output that may be closed (`| head`) or full: the first failure is kept and
/// reported once, never a panic.
#[derive(Default)]
struct Stdout {
    failed: Option<std::io::Error>,
}

impl Stdout {
    fn print(&mut self, text: &str) {
        if self.failed.is_none()
            && let Err(e) = std::io::stdout().lock().write_all(text.as_bytes())
        {
            self.failed = Some(e);
        }
    }

    /// `code`, or 1 with a message when standard output could not be written.
    fn finish(mut self, code: ExitCode) -> ExitCode {
        if self.failed.is_none()
            && let Err(e) = std::io::stdout().lock().flush()
        {
            self.failed = Some(e);
        }
        match self.failed {
            None => code,
            Some(e) => {
                eprintln!("error: cannot write to standard output: {e}");
                if code == ExitCode::SUCCESS {
                    ExitCode::FAILURE
                } else {
                    code
                }
            }
        }
    }
}

/// The case files of `dir`, or a message saying why there are none.
fn case_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    if !dir.is_dir() {
        return Err(format!(
            "no case directory {}: run from a directory that has `cases/`, or give --cases DIR",
            dir.display()
        ));
    }
    match case::discover_suite(dir) {
        Ok(f) if f.is_empty() => Err(format!("no case files (*.toml) in {}", dir.display())),
        Ok(f) => Ok(f),
        Err(e) => Err(format!("{}: cannot list cases: {e}", dir.display())),
    }
}

fn judge(args: JudgeArgs, dir: &Path) -> ExitCode {
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

/// Print a judgement's or a comparison's text: exit 0, or 1 when it `failed`; 2 with the
/// message when its input was unusable.
fn outcome(result: Result<(String, bool), String>) -> ExitCode {
    match result {
        Ok((text, failed)) => {
            let mut out = Stdout::default();
            out.print(&text);
            out.finish(if failed {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            })
        }
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

fn check(files: Vec<PathBuf>, dir: &Path) -> ExitCode {
    let files = if files.is_empty() {
        match case_files(dir) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    } else {
        files
    };
    let mut out = Stdout::default();
    let mut invalid = 0;
    for f in &files {
        match case::load_checked(f, &run::check_scene) {
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

fn report_load_errors(errors: &[LoadError]) {
    for e in errors {
        match e {
            LoadError::Case(c) => eprint!("{}", c.render()),
            other => eprintln!("error: {other}"),
        }
    }
}

fn list(dir: &Path) -> ExitCode {
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

fn interrupted() -> ExitCode {
    eprintln!("interrupted: the previous report is unchanged");
    ExitCode::from(interrupt::EXIT_CODE)
}

/// Resolve `--out` and load the cases named (every case with none): exit 2 with the messages
/// when either is invalid.
fn target_and_cases(
    out: &Path,
    names: &[String],
    dir: &Path,
) -> Result<(PathBuf, Vec<crosscheck::scene::Scene>), ExitCode> {
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
    let cases = run::load_cases(&suite, dir).map_err(|errors| {
        report_load_errors(&errors);
        eprintln!("nothing was run");
        ExitCode::from(2)
    })?;
    Ok((target, cases))
}

/// Take the output's lock (waiting unless `wait` is false: then a busy output is exit 2) and
/// start a staging directory for `entries`.
fn lock_and_stage(
    target: &Path,
    wait: bool,
    entries: &[&str],
) -> Result<(staging::OutputLock, staging::Staging), ExitCode> {
    let lock = match staging::OutputLock::acquire(target, wait) {
        Ok(l) => l,
        Err(staging::OutputError::Interrupted) => return Err(interrupted()),
        Err(e @ staging::OutputError::Busy { .. }) => {
            eprintln!("error: {e}");
            return Err(ExitCode::from(2));
        }
        Err(e) => {
            eprintln!("error: cannot lock the report: {e}");
            return Err(ExitCode::FAILURE);
        }
    };
    match staging::Staging::begin(target, entries) {
        Ok(s) => Ok((lock, s)),
        Err(e) => {
            eprintln!(
                "error: cannot prepare the report in {}: {e}",
                target.display()
            );
            Err(ExitCode::FAILURE)
        }
    }
}

/// `crosscheck run`: check the options and load the cases, run them through the pipeline, and
/// print the jobs' table, the tolerance count and the stage times.
fn run_command(args: RunArgs, dir: &Path) -> ExitCode {
    let started = std::time::Instant::now();
    let engines = match run::select_engines(&args.engines) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let (target, cases) = match target_and_cases(&args.out, &args.cases, dir) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let settings = args.settings();
    let refused = run::check_overrides(&cases, &settings);
    let plan = Plan {
        cases,
        engines,
        settings,
    };
    let refused = if refused.is_empty() {
        budget::check(&plan, &settings, &args.limits())
    } else {
        refused
    };
    if !refused.is_empty() {
        for r in &refused {
            eprintln!("error: {r}");
        }
        eprintln!("nothing was run");
        return ExitCode::from(2);
    }
    if interrupt::checkpoint("load").is_err() {
        return interrupted();
    }
    let (_lock, staging) = match lock_and_stage(&target, !args.no_wait, &report::ENTRIES) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let studies = pipeline::Studies {
        sweep: args.sweep.then_some(args.repeat as usize),
        stability: args.stability,
        on_request: args.on_request,
    };
    match pipeline::run(&plan, dir, &studies, staging, started, !args.quiet) {
        Ok(finished) => print_run(&finished, &studies, &args.out),
        Err(e) => stopped("the report", e),
    }
}

/// What a finished run prints: the jobs' table, the tolerance count, the stage times; exit 1
/// when a job failed.
fn print_run(
    finished: &pipeline::Finished,
    studies: &pipeline::Studies,
    out_dir: &Path,
) -> ExitCode {
    let (outcome, t) = (&finished.outcome, &finished.times);
    let mut out = Stdout::default();
    out.print(&outcome.table());
    let checks = finished.summary.tolerance_checks();
    out.print(&format!(
        "{} job(s), {} failed; report: {} ({} of {} cells meet their tolerance)\n",
        outcome.jobs.len(),
        outcome.failures(),
        report::report_path(out_dir).display(),
        checks.iter().filter(|c| c.met()).count(),
        checks.len()
    ));
    let parts: Vec<String> = t
        .parts(studies)
        .iter()
        .map(|(name, seconds)| format!("{name} {seconds:.2} s"))
        .collect();
    out.print(&format!(
        "time: {}, report {:.2} s, swap {:.2} s; total {:.2} s\n",
        parts.join(", "),
        t.written - t.requested,
        t.swapped - t.written,
        t.swapped
    ));
    if interrupt::requested() {
        eprintln!("interrupted after the new report was put in place");
        return ExitCode::from(interrupt::EXIT_CODE);
    }
    out.finish(if outcome.all_ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The exit code of a run or study that stopped before its files were in place (130
/// interrupted, 1 else), with the message saying why; `what` names the files.
fn stopped(what: &str, e: pipeline::Stopped) -> ExitCode {
    match e {
        pipeline::Stopped::Interrupted => interrupted(),
        pipeline::Stopped::Write(e) => {
            eprintln!("error: cannot write {what} (the previous one is unchanged): {e}");
            ExitCode::FAILURE
        }
        pipeline::Stopped::Swap(e) => {
            eprintln!("error: cannot put {what} in place (the previous one is unchanged): {e}");
            ExitCode::FAILURE
        }
    }
}

fn sweep_command(args: SweepArgs, dir: &Path) -> ExitCode {
    use crosscheck::report::work_precision as written;
    let engines = match chosen_engines(&args.engines, "cannot be swept") {
        Ok(e) => e,
        Err(code) => return code,
    };
    let (target, cases) = match target_and_cases(&args.out, &args.cases, dir) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let (_lock, staging) = match lock_and_stage(&target, !args.no_wait, &["sweep.csv", "figures"]) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let (plan, outcome) = pipeline::exact_solutions(cases);
    if interrupt::requested() {
        return interrupted();
    }
    let grid = sweep::Grid {
        repeat: args.repeat as usize,
        max_increments: args.max_increments,
        ..sweep::Grid::default()
    };
    let engines: Vec<&dyn Engine> = engines.iter().map(|e| e.as_ref()).collect();
    let sweeps = work_precision::measure(&plan, &outcome, &engines, &grid, !args.quiet);
    if interrupt::requested() {
        return interrupted();
    }
    if let Err(e) = pipeline::put_in_place(staging, |dir| written::write(dir, &sweeps, &plan.cases))
    {
        return stopped("the sweep", e);
    }
    let mut out = Stdout::default();
    out.print(&written::text(&sweeps));
    out.print(&format!(
        "written: {} and {}\n",
        args.out.join("sweep.csv").display(),
        args.out.join("figures").display()
    ));
    out.finish(ExitCode::SUCCESS)
}

fn stability_command(args: StabilityArgs, dir: &Path) -> ExitCode {
    use crosscheck::report::stability as written;
    let engines = match chosen_engines(&args.engines, "has no stability map") {
        Ok(e) => e,
        Err(code) => return code,
    };
    let (target, cases) = match target_and_cases(&args.out, &args.cases, dir) {
        Ok(x) => x,
        Err(code) => return code,
    };
    let (_lock, staging) =
        match lock_and_stage(&target, !args.no_wait, &["stability.csv", "figures"]) {
            Ok(x) => x,
            Err(code) => return code,
        };
    let (plan, outcome) = pipeline::exact_solutions(cases);
    if interrupt::requested() {
        return interrupted();
    }
    let engines: Vec<&dyn Engine> = engines.iter().map(|e| e.as_ref()).collect();
    let map = comparison::stability::measure(&plan, &outcome, &engines, !args.quiet);
    if interrupt::requested() {
        return interrupted();
    }
    if let Err(e) = pipeline::put_in_place(staging, |dir| written::write(dir, &map)) {
        return stopped("the stability map", e);
    }
    let mut out = Stdout::default();
    let mut text = String::new();
    written::overview(&mut text, &written::read_all(&args.out));
    out.print(&text);
    out.finish(ExitCode::SUCCESS)
}

/// The engines named in `asked` among those that step in time (all of them when none is
/// named); another is an error (exit 2) saying `refusal` and listing those that step.
fn chosen_engines(asked: &[String], refusal: &str) -> Result<Vec<Box<dyn Engine>>, ExitCode> {
    let allowed: Vec<Box<dyn Engine>> = crosscheck::engines::all()
        .into_iter()
        .filter(|e| e.stepping().is_some())
        .collect();
    if asked.is_empty() {
        return Ok(allowed);
    }
    let names: Vec<&str> = allowed.iter().map(|e| e.name()).collect();
    if let Some(name) = asked.iter().find(|n| !names.contains(&n.trim())) {
        eprintln!(
            "error: `{}` {refusal}; engines that step in time: {}",
            name.trim(),
            names.join(", ")
        );
        return Err(ExitCode::from(2));
    }
    // Each once, in report order.
    Ok(allowed
        .into_iter()
        .filter(|e| asked.iter().any(|n| n.trim() == e.name()))
        .collect())
}
