//! BENCHMARKS.md's table from criterion's last run of `benches/increment.rs`: per seed case,
//! ns per increment of `explicit` and of `rapier_f64` (matched), their ratio, and the
//! arithmetic floor where the case has one; then `explicit` against its floor timed in turn
//! here (`run::floor::time_in_turn`, at the benchmark's increment), the median and the range
//! of the rounds' ratios. Run by `scripts/benchmarks.sh`, which passes the commit and the date;
//! the machine is read from `/proc/cpuinfo`.
//!
//! `cargo run --release --example benchmark_table -- COMMIT DATE [CRITERION_DIR]`

use crosscheck::case;
use crosscheck::engines::RunSettings;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::run::floor::{self, REFINEMENT};
use crosscheck::run::matching;
use crosscheck::scene::IncrementRule;
use std::collections::BTreeMap;
use std::path::Path;

/// Rounds of the engine and its floor timed in turn, per case.
const ROUNDS: usize = 21;

/// Per seed case with a floor: `explicit` against it timed in turn at the benchmark's
/// increment, as "median (lower–upper quartile)".
fn in_turn() -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let paths = case::discover(&case::cases_dir()).expect("cases/");
    let engine = ExplicitEngine::finite();
    for scene in paths
        .iter()
        .map(|p| case::load(p).expect("a valid seed case"))
    {
        let (IncrementRule::Given(h), Some(floor)) =
            (scene.settings.increment, floor::in_slices(&scene))
        else {
            continue;
        };
        let finer = RunSettings {
            increment: Some(IncrementRule::Given(h / REFINEMENT)),
            ..RunSettings::default()
        };
        let settings = matching::job_settings(&engine, &scene, &finer);
        let paired = floor::time_in_turn(&engine, &scene, &settings, &floor, ROUNDS)
            .unwrap_or_else(|e| panic!("{e}"));
        let (low, high) = paired.quartiles();
        let text = format!("{:.2} ({low:.2}–{high:.2})", paired.median());
        out.insert(scene.id.clone(), text);
    }
    out
}

/// ns per increment of every benchmark under `dir/group`, by criterion's id without the group
/// (`springs_grounded_a/explicit`): the median over the increments of one iteration.
fn ns_per_increment(dir: &Path, group: &str) -> BTreeMap<String, f64> {
    let mut out = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(dir.join(group)) else {
        return out;
    };
    for entry in entries.flatten() {
        let new = entry.path().join("new");
        let read = |name: &str| -> Option<serde_json::Value> {
            serde_json::from_str(&std::fs::read_to_string(new.join(name)).ok()?).ok()
        };
        let (Some(bench), Some(estimates)) = (read("benchmark.json"), read("estimates.json"))
        else {
            continue;
        };
        let id = bench["function_id"]
            .as_str()
            .unwrap_or_default()
            .to_string();
        let increments = bench["throughput"]["Elements"].as_f64();
        let median = estimates["median"]["point_estimate"].as_f64();
        if let (Some(n), Some(ns)) = (increments, median) {
            out.insert(id, ns / n);
        }
    }
    out
}

fn machine() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = info
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map_or("unknown CPU".to_string(), |m| m.trim().to_string());
    let cores = info.lines().filter(|l| l.starts_with("processor")).count();
    format!("{model}, {cores} cores")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(commit), Some(date)) = (args.first(), args.get(1)) else {
        eprintln!("usage: benchmark_table COMMIT DATE [CRITERION_DIR]");
        std::process::exit(2);
    };
    let dir = Path::new(args.get(2).map_or("target/criterion", String::as_str));
    let increment = ns_per_increment(dir, "increment");
    let floor = ns_per_increment(dir, "floor");
    let cases: Vec<&str> = increment
        .keys()
        .filter_map(|id| id.strip_suffix("/explicit"))
        .collect();
    if cases.is_empty() {
        eprintln!(
            "no `increment/<case>/explicit` results under {}",
            dir.display()
        );
        std::process::exit(2);
    }
    let paired = in_turn();
    println!(
        "Measured on {}, commit {commit}, {date}, by `scripts/benchmarks.sh` (criterion's \
         median; one thread; at a tenth of each case's increment; `explicit` / floor: {ROUNDS} \
         rounds timed in turn, the median of their ratios and their quartiles).\n",
        machine()
    );
    println!(
        "| seed case | `explicit`, ns | `rapier_f64` (matched), ns | `rapier_f64` / `explicit` | floor, ns | `explicit` / floor, in turn |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    let ns = |x: Option<&f64>| x.map_or("–".to_string(), |v| format!("{v:.1}"));
    for case in cases {
        let explicit = increment[&format!("{case}/explicit")];
        let rapier = increment.get(&format!("{case}/rapier_f64"));
        let slices = floor.get(&format!("{case}/slices"));
        println!(
            "| {case} | {explicit:.1} | {} | {} | {} | {} |",
            ns(rapier),
            rapier.map_or("–".to_string(), |r| format!("{:.0}×", r / explicit)),
            ns(slices),
            paired.get(case).map_or("–", String::as_str),
        );
    }
}
