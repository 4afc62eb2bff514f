//! The command line: options, dispatch, and what each command prints. [`main_with`] is the
//! whole program for the built-in engines and any a user adds.
//!
//! Exit codes: 0 every job succeeded; 1 some job failed (the others were written), or the report
//! or standard output could not be written; 2 bad input (invalid or unknown case, unknown
//! engine, bad option, unusable `--out`, a run above its resource limits, an output another run
//! holds with `--no-wait`): nothing was run or written; 130 interrupted (SIGINT, SIGTERM,
//! SIGHUP): the previous report is unchanged.

/// The standard macros, shadowed in this module and its children: standard error that cannot
/// be written (a full disk, `/dev/full`) loses the message and never panics; the exit code
/// still says what happened.
macro_rules! eprintln {
    ($($arg:tt)*) => {{
        let _ = std::io::Write::write_fmt(&mut std::io::stderr(), format_args!("{}\n", format_args!($($arg)*)));
    }};
}

/// As `eprintln!` above, without the newline.
macro_rules! eprint {
    ($($arg:tt)*) => {{
        let _ = std::io::Write::write_fmt(&mut std::io::stderr(), format_args!($($arg)*));
    }};
}

mod baseline;
mod cases;
mod run;
mod studies;

use baseline::{compare_command, merge_command};
use cases::{check, judge, list};
use run::run_command;
use studies::{scaling, stability_command, sweep_command};

use crate::engines::{Engine, RunSettings};
use crate::report;
use crate::run::{budget, sweep};
use crate::scene::{ContactStart, DampingTreatment, IncrementRule, PenaltyRule};
use crate::{case, interrupt, pipeline};
use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// Verification harness for explicit dynamics: on problems whose exact answer is known, how
/// close does an engine get, what does that cost, and does it stay stable.
///
/// Without a subcommand, runs every case with every engine into `report/`.
#[derive(Debug, Parser)]
#[command(name = "crosscheck", version = concat!(env!("CARGO_PKG_VERSION"), " (", env!("CROSSCHECK_COMMIT"), ")"))]
struct Cli {
    /// Directory of the case files (default: $CROSSCHECK_CASES, else `cases/` in the working
    /// directory, else the cases shipped in the binary).
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
        /// Largest chain (masses; at most 10^6, whose two runs hold about 1.0 GB at once).
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
    /// row by row; a column that moved by more than the threshold of its scale, its peak or the
    /// scale its round-off comes from where larger, has drifted).
    /// Exit 0 when neither fails, 1 when one does, 2 when they cannot be compared.
    Compare(CompareArgs),
    /// Merge the reports of a partitioned run's shards (`run --partition k/n`, each into a
    /// directory of its own) into the report one run over all their cases writes.
    Merge {
        /// The shards' report directories.
        #[arg(value_name = "SHARD", required = true)]
        shards: Vec<PathBuf>,
        /// Output directory.
        #[arg(long, value_name = "DIR", default_value = "report")]
        out: PathBuf,
        /// Refuse (exit 2) when another run is writing the same output, instead of waiting.
        #[arg(long)]
        no_wait: bool,
    },
    /// Validate case files without running them (the same validation every `run` does first).
    Check {
        /// Case ids or paths to .toml case files (default: every case).
        #[arg(value_name = "CASE")]
        files: Vec<String>,
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
    #[command(flatten)]
    study: StudyArgs,
}

/// What the studies that run on their own (`sweep`, `stability`) share.
#[derive(Debug, Args)]
struct StudyArgs {
    /// Case ids or paths to .toml case files (default: every case).
    #[arg(value_name = "CASE")]
    cases: Vec<String>,
    /// Comma-separated engines (default: every engine that steps in time).
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
    #[command(flatten)]
    study: StudyArgs,
    /// Runs per point (CPU time reported as min, median and max over them).
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repeat: u64,
    /// Most increments one run of a point may take (rapier: a fifth of it, substeps counted).
    #[arg(long, value_name = "N", default_value_t = sweep::Grid::default().max_increments, value_parser = positive, allow_negative_numbers = true)]
    max_increments: f64,
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
    #[arg(long, value_name = "H", value_parser = positive, allow_negative_numbers = true)]
    increment: Option<f64>,
    /// Use this penalty stiffness instead of the case's rule.
    #[arg(long, value_name = "K", value_parser = positive, allow_negative_numbers = true)]
    penalty: Option<f64>,
    /// Accuracy on request: each engine chooses its increment (and penalty stiffness) so that
    /// its error against its own model's exact solution is at most EPS of each column's peak.
    #[arg(long, value_name = "EPS", value_parser = positive, allow_negative_numbers = true, conflicts_with_all = ["increment", "penalty"])]
    tolerance: Option<f64>,
    /// Stability study: step with R × each engine's computed stable increment (rapier: the
    /// explicit engine's), exactly, R > 1 allowed; rows are interpolated between increments.
    #[arg(long, value_name = "R", value_parser = positive, allow_negative_numbers = true, conflicts_with_all = ["increment", "tolerance"])]
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
    #[arg(long, value_name = "N", default_value_t = budget::Limits::default().max_increments, value_parser = positive, allow_negative_numbers = true)]
    max_increments: f64,
    /// Most output rows one case may have.
    #[arg(long, value_name = "N", default_value_t = budget::Limits::default().max_rows)]
    max_rows: usize,
    /// Most bytes of output histories the run may hold.
    #[arg(long, value_name = "BYTES", default_value_t = budget::Limits::default().max_memory_bytes, value_parser = positive, allow_negative_numbers = true)]
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
    /// Exit 1 when a judged cell of these engines (comma-separated; every engine without a
    /// value) misses its tolerance or fails; the report is written either way.
    #[arg(long, value_name = "ENGINES", num_args = 0..=1, require_equals = true, value_delimiter = ',', default_missing_value = "")]
    fail_on_miss: Option<Vec<String>>,
    /// Also write the run's judged cells as JUnit XML: a test case per case and engine, with
    /// its error, tolerance and cause.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Compare the finished report with the baseline NAME (saved by --save-baseline), as
    /// `crosscheck compare` does: exit 1 when a tier fails.
    #[arg(long, value_name = "NAME", value_parser = baseline::name)]
    baseline: Option<String>,
    /// Save the finished report as the baseline NAME (replaced where it exists), after any
    /// --baseline comparison.
    #[arg(long, value_name = "NAME", value_parser = baseline::name)]
    save_baseline: Option<String>,
    /// Where baselines are kept: `DIR/NAME`.
    #[arg(long, value_name = "DIR", default_value = "baselines")]
    baseline_dir: PathBuf,
    /// Run shard k of n of the cases (nextest's convention; equivalent cases stay in one
    /// shard) into its own --out; `crosscheck merge` joins the shards' reports.
    #[arg(long, value_name = "k/n")]
    partition: Option<pipeline::Partition>,
}

/// Options of `crosscheck compare`.
#[derive(Debug, Args)]
struct CompareArgs {
    /// The baseline report directory.
    #[arg(value_name = "BASE")]
    base: PathBuf,
    /// The report to judge against it.
    #[arg(value_name = "NEW")]
    new: PathBuf,
    /// Drift threshold: the largest difference over the column's scale (its peak, or where larger
    /// the energy or scene scale its round-off comes from).
    #[arg(long, value_name = "X", default_value_t = report::regression::DRIFT)]
    threshold: f64,
    /// Fail only on the physics tier (drift is reported, not failed).
    #[arg(long)]
    physics_only: bool,
    /// Also write JUnit XML here (a suite per tier, a test per column).
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Then make NEW the baseline: BASE's report replaced by a copy of NEW's (through the same
    /// staging and swap as a run; BASE is created where it does not exist). Exit 0 once done.
    #[arg(long)]
    accept: bool,
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
            fail_on_miss: None,
            junit: None,
            baseline: None,
            save_baseline: None,
            baseline_dir: PathBuf::from("baselines"),
            partition: None,
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

/// The program: parse the command line and run the command, with the built-in engines and
/// `extra` (a user's, after them in every table; a case file may declare their tolerances).
pub fn main_with(extra: Vec<Box<dyn Engine>>) -> ExitCode {
    let extra_names: Vec<String> = extra.iter().map(|e| e.name().to_string()).collect();
    let names = crate::run::registry::all()
        .iter()
        .map(|e| e.name().to_string())
        .chain(extra_names.iter().cloned())
        .collect::<Vec<_>>()
        .join(", ");
    let command = Cli::command().mut_subcommand("run", |c| {
        c.mut_arg("engines", |a| {
            a.help(format!(
                "Comma-separated engine names (default: every engine: {names})"
            ))
        })
    });
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    interrupt::install();
    match cli.command {
        // These read reports, not cases.
        Some(Command::Compare(args)) => return compare_command(args),
        Some(Command::Merge {
            shards,
            out,
            no_wait,
        }) => return merge_command(&shards, &out, !no_wait),
        _ => {}
    }
    let dir = match case::embedded::case_dir(cli.cases_dir.clone()) {
        Ok(source) => source.dir().to_path_buf(),
        Err(e) => {
            eprintln!(
                "error: cannot write the shipped cases out ({e}); give --cases DIR or set {}",
                case::embedded::ENV
            );
            return ExitCode::from(2);
        }
    };
    let also: Vec<&str> = extra_names.iter().map(String::as_str).collect();
    let also = also.as_slice();
    match cli.command {
        None => run_command(RunArgs::everything(), &dir, extra),
        Some(Command::List) => list(&dir),
        Some(Command::Run(args)) => run_command(args, &dir, extra),
        Some(Command::Check { files }) => check(files, &dir, also),
        Some(Command::Judge(args)) => judge(args, &dir),
        Some(Command::Compare(_)) => unreachable!("compare reads reports and is dispatched first"),
        Some(Command::Merge { .. }) => unreachable!("merge reads reports and is dispatched first"),
        Some(Command::Scaling {
            study,
            max_n,
            out,
            quiet,
        }) => scaling(study, max_n as usize, &out, quiet, &dir),
        Some(Command::Sweep(args)) => sweep_command(args, &dir, extra),
        Some(Command::Stability(args)) => stability_command(args, &dir, extra),
    }
}

fn interrupted() -> ExitCode {
    eprintln!("interrupted: the previous report is unchanged");
    ExitCode::from(interrupt::EXIT_CODE)
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
            // The reader left (`| head`): what it read was written; nothing to say.
            Some(e) if e.kind() == std::io::ErrorKind::BrokenPipe => code,
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
