//! BENCHMARKS.md's table from criterion's last run of `benches/increment.rs`: per seed case,
//! ns per increment of `explicit` and of `rapier_f64` (matched), their ratio, and the
//! arithmetic floor where the case has one; then, timed in turn here at the benchmark's
//! increment, `rapier_f64` against `explicit` (`run::floor::engines_pair`) and `explicit`
//! against its floor (`run::floor::floor_pair`), every case's pairs interleaved round by round
//! (`run::floor::interleaved`), each as the median and the quartiles of the rounds' ratios and
//! the ratio of the two runs' fastest rounds. Criterion times each benchmark apart, minutes
//! from the others, and a ratio of two of its medians moves with the machine in between; a
//! ratio timed in turn moves much less.
//! Run by `scripts/benchmarks.sh`, which passes the commit and the date; the machine is read
//! from `/proc/cpuinfo`.
//!
//! `cargo run --release --example benchmark_table -- COMMIT DATE [CRITERION_DIR]`

use crosscheck::case;
use crosscheck::engines::Engine;
use crosscheck::engines::RunSettings;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::run::floor::{self, InTurn, Pair, REFINEMENT};
use crosscheck::run::{matching, registry};
use crosscheck::scene::{IncrementRule, Scene};
use std::collections::BTreeMap;
use std::path::Path;

/// Rounds of the engine and its floor timed in turn, per case.
const ROUNDS: usize = 21;

/// Rounds of `rapier_f64` and `explicit` timed in turn, per case (a run of `rapier_f64` at the
/// benchmark's increment takes about a second).
const ENGINE_ROUNDS: usize = 7;

/// "median`unit` (lower–upper quartile; fastest ratio)" of rounds timed in turn, each ratio
/// scaled by `scale`.
fn as_text(paired: &InTurn, scale: f64, digits: usize, unit: &str) -> String {
    let (low, high) = paired.quartiles();
    let (median, low, high) = (paired.median() * scale, low * scale, high * scale);
    let fastest = paired.fastest() * scale;
    format!("{median:.digits$}{unit} ({low:.digits$}–{high:.digits$}; {fastest:.digits$})")
}

/// A seed case as the benchmark runs it: at a tenth of its increment, `explicit` and
/// `rapier_f64` each under their job settings.
struct Benchmarked {
    scene: Scene,
    explicit: RunSettings,
    rapier: Option<RunSettings>,
}

/// What a pair times `explicit` against.
#[derive(Clone, Copy)]
enum Against {
    Rapier,
    Floor,
}

/// One pair's case, what it times `explicit` against, and the scale from its whole runs'
/// ratio to a ratio per increment.
struct Measured<'a> {
    case: &'a str,
    against: Against,
    scale: f64,
}

/// Every seed case whose increment is given, as the benchmark runs it.
fn benchmarked(explicit: &dyn Engine, rapier: Option<&dyn Engine>) -> Vec<Benchmarked> {
    let paths = case::discover(&case::cases_dir()).expect("cases/");
    paths
        .iter()
        .map(|p| case::load(p).expect("a valid seed case"))
        .filter_map(|scene| {
            let IncrementRule::Given(h) = scene.settings.increment else {
                return None;
            };
            let finer = RunSettings {
                increment: Some(IncrementRule::Given(h / REFINEMENT)),
                ..RunSettings::default()
            };
            Some(Benchmarked {
                explicit: matching::job_settings(explicit, &scene, &finer),
                rapier: rapier.map(|r| matching::job_settings(r, &scene, &finer)),
                scene,
            })
        })
        .collect()
}

/// Per case, `rapier_f64` against `explicit` and `explicit` against the case's floor where it
/// has one, with what each pair measures.
fn pairs<'a>(
    cases: &'a [Benchmarked],
    explicit: &'a dyn Engine,
    rapier: Option<&'a dyn Engine>,
) -> (Vec<Pair<'a>>, Vec<Measured<'a>>) {
    let (mut pairs, mut measured) = (Vec::new(), Vec::new());
    for case in cases {
        let scene = &case.scene;
        if let (Some(rapier), Some(settings)) = (rapier, case.rapier.as_ref()) {
            let steps = |e: &dyn Engine, s: &RunSettings| {
                let output = e.run(scene, s).unwrap_or_else(|e| panic!("{e}"));
                output.info.steps as f64
            };
            // Per increment: the whole runs' ratio times explicit's increments over rapier's.
            let scale = steps(explicit, &case.explicit) / steps(rapier, settings);
            let timed = ((rapier, settings), (explicit, &case.explicit));
            pairs.push(floor::engines_pair(scene, timed.0, timed.1, ENGINE_ROUNDS));
            let against = Against::Rapier;
            measured.push(Measured {
                case: &scene.id,
                against,
                scale,
            });
        }
        if let Some(slices) = floor::in_slices(scene) {
            let pair = floor::floor_pair(explicit, scene, &case.explicit, slices, ROUNDS)
                .unwrap_or_else(|e| panic!("{e}"));
            pairs.push(pair);
            let against = Against::Floor;
            measured.push(Measured {
                case: &scene.id,
                against,
                scale: 1.0,
            });
        }
    }
    (pairs, measured)
}

/// Per seed case, timed in turn at the benchmark's increment, every case's pairs interleaved
/// (`run::floor::interleaved`): `rapier_f64` (matched) against `explicit`, per increment, and
/// `explicit` against the case's floor where it has one.
fn in_turn() -> (BTreeMap<String, String>, BTreeMap<String, String>) {
    let explicit = ExplicitEngine::finite();
    let rapier = registry::all()
        .into_iter()
        .find(|e| e.name() == "rapier_f64");
    let cases = benchmarked(&explicit, rapier.as_deref());
    let (pairs, measured) = pairs(&cases, &explicit, rapier.as_deref());
    let timed = floor::interleaved(&pairs).unwrap_or_else(|e| panic!("{e}"));
    let (mut against_rapier, mut against_floor) = (BTreeMap::new(), BTreeMap::new());
    for (m, paired) in measured.iter().zip(&timed) {
        let (case, scale) = (m.case.to_string(), m.scale);
        match m.against {
            Against::Rapier => against_rapier.insert(case, as_text(paired, scale, 0, "×")),
            Against::Floor => against_floor.insert(case, as_text(paired, scale, 2, "")),
        };
    }
    (against_rapier, against_floor)
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
    let (against_rapier, against_floor) = in_turn();
    println!(
        "Measured on {}, commit {commit}, {date}, by `scripts/benchmarks.sh` (criterion's \
         median; one thread; at a tenth of each case's increment; in turn: whole runs timed \
         back to back, {ENGINE_ROUNDS} rounds of `rapier_f64` and `explicit`, {ROUNDS} of \
         `explicit` and its floor, every case's rounds interleaved with the others'; the median \
         of the rounds' ratios, their quartiles, and after the semicolon the ratio of the two \
         runs' fastest rounds).\n",
        machine()
    );
    println!(
        "| seed case | `explicit`, ns | `rapier_f64` (matched), ns | `rapier_f64` / `explicit` | `rapier_f64` / `explicit`, in turn | floor, ns | `explicit` / floor, in turn |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let ns = |x: Option<&f64>| x.map_or("–".to_string(), |v| format!("{v:.1}"));
    for case in cases {
        let explicit = increment[&format!("{case}/explicit")];
        let rapier = increment.get(&format!("{case}/rapier_f64"));
        let slices = floor.get(&format!("{case}/slices"));
        let text = |map: &BTreeMap<String, String>| map.get(case).cloned();
        println!(
            "| {case} | {explicit:.1} | {} | {} | {} | {} | {} |",
            ns(rapier),
            rapier.map_or("–".to_string(), |r| format!("{:.0}×", r / explicit)),
            text(&against_rapier).unwrap_or("–".to_string()),
            ns(slices),
            text(&against_floor).unwrap_or("–".to_string()),
        );
    }
}
