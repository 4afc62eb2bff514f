//! Your own engine in every subcommand: `cargo run --release --example own_engine -- [ARGS]`.
//!
//! [`engine::SemiImplicitEuler`] is a user's engine written against the public [`Engine`]
//! trait (`engine.rs`). [`crosscheck::cli::main_with`] gives it the whole command line:
//! `run` (with `--sweep`, `--stability`, `--fail-on-miss`, `--junit`), `sweep`, `stability`,
//! `list`, `check`, `judge` and `compare`, through the same jobs, exact solutions,
//! discrepancy budgets, studies and report as the built-in engines, where it has a row in
//! every table of engines that step in time. With no arguments it runs every case into
//! `report/`, as `crosscheck` does; for example
//!
//! ```text
//! cargo run --release --example own_engine -- run --sweep --stability --out target/own_engine
//! ```
//!
//! Case files may declare a tolerance for it under its name.

mod engine;

use crosscheck::engines::Engine;

fn main() -> std::process::ExitCode {
    crosscheck::cli::main_with(vec![Box::new(engine::SemiImplicitEuler) as Box<dyn Engine>])
}
