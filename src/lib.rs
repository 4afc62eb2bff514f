//! crosscheck: a verification harness for explicit dynamics.
//!
//! Data flows cases → scene → engines → run → comparison → report, and every module imports
//! only from modules before it in that flow (`case` reads the file format and builds the
//! scene, so it also uses [`scene`] and [`contract`]):
//!
//! - [`scene`]: the validated model, the one type every engine reads (knows no file format);
//! - [`contract`]: the output contract every engine's history meets (column names, sampling);
//! - [`interrupt`]: signals set a flag that long work polls at safe points;
//! - [`case`]: `cases/*.toml` → [`scene::Scene`], with located diagnostics;
//! - [`engines`]: scene + run settings → history, one module per engine behind one trait;
//!   engines never import each other;
//! - [`run`]: loads the cases, plans every (case × engine) job (what "matched settings" means
//!   lives here), runs them in parallel and returns data; it writes nothing;
//! - [`comparison`]: the metrics of one history against another;
//! - [`report`]: writes what a run returned: CSVs, figures, summary, REPORT.md, staged and
//!   swapped into place;
//! - [`pipeline`]: a run from end to end: the jobs, the studies, the report put in place;
//! - [`cli`]: the command line, which parses the options and calls the pipeline
//!   ([`cli::main_with`]: every subcommand, for crosscheck's engines and a user's).

pub mod case;
#[cfg(feature = "cli")]
pub mod cli;
pub mod comparison;
pub mod contract;
pub mod engines;
pub mod interrupt;
pub mod pipeline;
pub mod report;
pub mod run;
pub mod scene;
