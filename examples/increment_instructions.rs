//! BENCHMARKS.md's instruction counts: per seed case, the instructions per increment of
//! `explicit`, of the case's arithmetic floor (`run::floor::in_slices`) and of `rapier_f64` in
//! its matched configuration, counted by valgrind's cachegrind. A count does not move with the
//! machine's load, as a time does: it says how much work the engine adds to the arithmetic its
//! numerics need, and how much less it does than rapier, where the times say what that work
//! costs on the machine that day.
//!
//! The count of `explicit` and of the floor is the difference of two whole runs, at a tenth and
//! a twentieth of the case's increment, over the difference of their increments, so what a run
//! does once (compiling the scene, the static steps, the 501 output rows) cancels. It is the
//! cost of one increment where that does not change with the increment (the seed cases whose
//! centred velocity reads the body's rate solve it in closed form at both). The count of
//! `rapier_f64` is one whole run at a tenth of the case's increment (the run criterion times)
//! over its increments: an increment costs it some 25 000 to 100 000 instructions, so what the
//! run does once is a small part of the count (the difference of two runs, as above, gave the
//! same to within 0.15 % on every seed case), and a second run would triple the minutes
//! cachegrind takes. The runs are this program started again under
//! `valgrind --tool=cachegrind`, with the arguments `run CASE REFINEMENT WHAT`. Run by
//! `scripts/benchmarks.sh`, which passes the commit and the date.
//!
//! `cargo run --release --example increment_instructions -- COMMIT DATE`

use crosscheck::case;
use crosscheck::engines::RunSettings;
use crosscheck::run::floor::{self, REFINEMENT};
use crosscheck::run::{matching, registry};
use crosscheck::scene::{IncrementRule, Scene};
use std::process::Command;

/// What a counted run steps: the engine, or the case's floor.
const ENGINE: &str = "explicit";
const FLOOR: &str = "floor";
const RAPIER: &str = "rapier_f64";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.as_slice() {
        [run, case, refinement, what] if run == "run" => {
            let refinement: f64 = refinement.parse().expect("a refinement");
            println!("{}", counted_run(&load(case), refinement, what));
        }
        [commit, date] => print_table(commit, date),
        _ => {
            eprintln!("usage: increment_instructions COMMIT DATE");
            std::process::exit(2);
        }
    }
}

fn load(id: &str) -> Scene {
    let path = case::cases_dir().join(format!("{id}.toml"));
    case::load(&path).expect("a valid seed case")
}

/// The increment of `scene` over `refinement`; None for a case whose increment is not given.
fn increment(scene: &Scene, refinement: f64) -> Option<f64> {
    match scene.settings.increment {
        IncrementRule::Given(h) => Some(h / refinement),
        _ => None,
    }
}

/// One whole run of `what` on `scene` at its increment over `refinement`: the increments it
/// took.
fn counted_run(scene: &Scene, refinement: f64, what: &str) -> u64 {
    let h = increment(scene, refinement).expect("a given increment");
    if what == FLOOR {
        let floor = floor::in_slices(scene).expect("a case with a floor");
        let increments = (floor.duration / h).round() as u64;
        floor.run(h, increments);
        return increments;
    }
    let engine = registry::named(what).expect("a registered engine");
    let finer = RunSettings {
        increment: Some(IncrementRule::Given(h)),
        ..RunSettings::default()
    };
    let settings = matching::job_settings(engine.as_ref(), scene, &finer);
    let out = engine.run(scene, &settings).expect("a seed case runs");
    out.info.steps
}

/// Instructions and increments of one run under cachegrind.
fn counted(id: &str, refinement: f64, what: &str) -> (u64, u64) {
    let exe = std::env::current_exe().expect("this program's path");
    let out_file = std::env::temp_dir().join(format!(
        "increment_instructions.{}.{id}.{what}.{refinement}",
        std::process::id()
    ));
    let output = Command::new("valgrind")
        .args(["--tool=cachegrind", "--cache-sim=no"])
        .arg(format!("--cachegrind-out-file={}", out_file.display()))
        .arg(&exe)
        .args(["run", id, &refinement.to_string(), what])
        .output();
    let output = match output {
        Ok(output) => output,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!(
                "error: valgrind not found; it counts the instructions (Debian: apt install valgrind)"
            );
            std::process::exit(2);
        }
        Err(e) => panic!("valgrind: {e}"),
    };
    let instructions = std::fs::read_to_string(&out_file).map(|t| instruction_total(&t));
    let _ = std::fs::remove_file(&out_file);
    assert!(
        output.status.success(),
        "{id} {what} under cachegrind: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let increments = String::from_utf8_lossy(&output.stdout)
        .trim()
        .parse()
        .expect("the increments the run took");
    let instructions = instructions
        .expect("cachegrind's output file")
        .expect("an Ir total in cachegrind's output file");
    (instructions, increments)
}

/// The total of the `Ir` event in a cachegrind output file: the field of its `summary:` line
/// at the place `Ir` takes in its `events:` line.
fn instruction_total(text: &str) -> Option<u64> {
    let field = |prefix: &str| text.lines().find_map(|l| l.strip_prefix(prefix));
    let place = field("events:")?
        .split_whitespace()
        .position(|e| e == "Ir")?;
    field("summary:")?
        .split_whitespace()
        .nth(place)?
        .parse()
        .ok()
}

/// Instructions per increment of `what` on case `id`: two runs, at a tenth and a twentieth of
/// its increment, differenced.
fn per_increment(id: &str, what: &str) -> f64 {
    let (coarse, fine) = (
        counted(id, REFINEMENT, what),
        counted(id, 2.0 * REFINEMENT, what),
    );
    (fine.0 as f64 - coarse.0 as f64) / (fine.1 as f64 - coarse.1 as f64)
}

/// Instructions per increment of `what` on case `id`: one whole run at a tenth of its
/// increment, over its increments.
fn whole_run_average(id: &str, what: &str) -> f64 {
    let (instructions, increments) = counted(id, REFINEMENT, what);
    instructions as f64 / increments as f64
}

fn print_table(commit: &str, date: &str) {
    println!(
        "Counted at commit {commit}, {date}, by `scripts/benchmarks.sh` (valgrind's cachegrind; `explicit` and its floor: the difference of whole runs at a tenth and a twentieth of each case's increment, per increment; `rapier_f64`, matched: one whole run at a tenth, per increment)."
    );
    println!();
    println!(
        "| seed case | `explicit`, instructions | floor, instructions | `explicit` / floor | `rapier_f64`, instructions | `rapier_f64` / `explicit` |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    let paths = case::discover(&case::cases_dir()).expect("cases/");
    for scene in paths
        .iter()
        .map(|p| case::load(p).expect("a valid seed case"))
    {
        if increment(&scene, REFINEMENT).is_none() {
            continue;
        }
        let engine = per_increment(&scene.id, ENGINE);
        let (floor, ratio) = match floor::in_slices(&scene) {
            Some(_) => {
                let floor = per_increment(&scene.id, FLOOR);
                (format!("{floor:.0}"), format!("{:.2}", engine / floor))
            }
            None => ("–".to_string(), "–".to_string()),
        };
        let rapier = whole_run_average(&scene.id, RAPIER);
        println!(
            "| {} | {engine:.0} | {floor} | {ratio} | {rapier:.0} | {:.0}× |",
            scene.id,
            rapier / engine
        );
    }
}
