//! The scaling study: what one increment costs as the scene grows, against what the machine's
//! memory can deliver.
//!
//! For N = 10, 100, …, `max_n` masses of the chain family ([`crate::case::chain`]), the study
//! runs `explicit`, then `rapier_f64` in its matched configuration, each point while its
//! predicted time fits in what is left of [`STUDY_SECONDS`], and measures per point:
//! - the marginal wall time per increment: runs of S and 2S increments (each repeated at least
//!   [`MIN_REPEATS`] times, more often where a point takes under [`POINT_SECONDS`], the
//!   fastest repeat taken, since on a shared machine interference only ever adds time),
//!   (t₂ − t₁)/S, so the setup (building the scene's model, the static step, the stable
//!   increment) drops out; S is long enough that the increments take [`SETUP_SHARE`] times the
//!   setup (at most [`MAX_LENGTHENING`] times the least S, [`steps_for`]), the setup read from
//!   a pilot ([`timed_steps`]), so that the setup's spread from run to run does not fall whole
//!   on the difference; the two runs are taken in turn, and a pair
//!   whose longer run is not slower ([`consistent`]) is timed again, and printed as unresolved
//!   if it stays so;
//! - the peak resident memory of the longer run (the kernel's high-water mark, reset before
//!   it);
//! - the error of the probed displacements against the exact solution, with the error that
//!   central differences must give ([`Chain::predicted_error`]) beside it;
//! - the memory-bandwidth limit: a plain streaming loop over arrays of N values that reads
//!   and writes the bytes per DOF one increment must (position, velocity, inverse mass and
//!   spring stiffness read; position and velocity written: 48 bytes), timed the same way and
//!   in turn with the engine's runs ([`in_turn`]), so a slow spell of the machine falls on
//!   both (the engine's first longer run, timed alone before them for its peak memory,
//!   counts as one of its repeats).

use crate::case::chain::Chain;
use crate::engines::explicit::ExplicitEngine;
use crate::engines::{Engine, RunSettings};
use crate::run::matching;
use crate::scene::Scene;
use std::time::Instant;

/// Wall-clock seconds the chain study may take in all: a point is run only while its time,
/// predicted from the engine's previous point (in proportion to N × increments), fits in what
/// is left. What is
/// not run is listed with its prediction.
pub const STUDY_SECONDS: f64 = 150.0;

/// Wall-clock seconds one point aims at: its runs are repeated as often as that allows (at
/// least [`MIN_REPEATS`], at most [`repeats_for`]), so a slow engine's point is not repeated
/// as often as a fast one's.
pub const POINT_SECONDS: f64 = 10.0;

/// Increments of the shorter of the two timed runs from N = 1000 up, before the setup is
/// weighed (the longer takes twice as many): about 2.5 periods of the mode at h = 0.1·√(m/k).
pub const STEPS: u64 = 400;

/// DOF-increments the shorter timed run takes at least ([`steps_for`]): a smaller chain runs
/// longer, so that the difference of the two runs stands above the timer's and the
/// allocator's noise (at N = 100 and 400 increments it is tens of microseconds, and the
/// fastest repeats of the two runs differed by as much).
const WORK_PER_RUN: f64 = 4.0e5;

/// Increments of the shorter timed run at N before the setup is weighed ([`steps_over_setup`]):
/// [`STEPS`], or more on a chain smaller than [`WORK_PER_RUN`] / [`STEPS`] masses.
pub fn steps_for(n: usize) -> u64 {
    STEPS.max((WORK_PER_RUN / n.max(1) as f64).ceil() as u64)
}

/// The increments of the shorter timed run take at least this many times the run's setup
/// (building the model, the static step, the stable increment, the first touch of its memory).
/// A point is the difference of two runs with the same setup, so the setup cancels on average,
/// but not its spread: the fastest of a few runs' setups still differs from run to run by some
/// tenths of it (`explicit` on the chain at N = 10^5: 15 runs of 100 increments took 150 to
/// 215 ms, measured, and [`STEPS`] increments take about 100 ms), and that error falls whole on
/// the difference. With the increments at twice the setup, a spread of δ of the setup
/// is at most δ/2 of the point ([`steps_over_setup`]).
pub const SETUP_SHARE: f64 = 2.0;

/// The shorter run of a point never takes more than this many times [`steps_for`] N increments
/// (the longer twice that), whatever its pilot reads: a point lengthened for its setup stays
/// within a few times its unlengthened cost.
pub const MAX_LENGTHENING: u64 = 8;

/// Increments of the pilot's runs that time the setup (the fewest a chain takes: one per output
/// interval).
const PILOT_STEPS: u64 = 100;

/// A point's increments at its fewest repeats, in shorter runs of S: the first longer run (2S),
/// then [`MIN_REPEATS`] times a shorter and a longer (3S).
const RUNS_OF_S_PER_POINT: f64 = 2.0 + 3.0 * MIN_REPEATS as f64;

/// Increments of the shorter timed run for an engine whose setup takes `setup` seconds and whose
/// increment takes `per_increment` ([`timed_steps`]): `base`, or enough that the increments take
/// [`SETUP_SHARE`] times the setup, at most [`MAX_LENGTHENING`] times `base` and at most what
/// keeps the point's increments within [`POINT_SECONDS`] (at N = 10^6, where a run of `base`
/// increments already takes seconds, little or none). Where the two could not be
/// told apart (a time not positive, or not a number), `base`. ([`Chain::new`] rounds the count
/// up to whole output intervals.)
pub fn steps_over_setup(base: u64, setup: f64, per_increment: f64) -> u64 {
    if !(setup > 0.0 && per_increment > 0.0) {
        return base;
    }
    let needed = (SETUP_SHARE * setup / per_increment).ceil();
    let most = ((MAX_LENGTHENING * base) as f64)
        .min(POINT_SECONDS / (RUNS_OF_S_PER_POINT * per_increment));
    (needed.min(most) as u64).max(base)
}

/// Increments of the shorter timed run at N for an engine whose run of `steps` increments takes
/// `run(steps)` seconds and whose increment takes about `per_increment` seconds (the study's
/// previous point, scaled by N): a pilot times the fastest of two runs of [`PILOT_STEPS`]
/// increments, nearly all of it setup, and takes the setup from it ([`steps_over_setup`]).
/// Without `per_increment` (an engine's first point), the pilot also times a run of
/// [`steps_for`] N increments and reads the increment's time from the two.
fn timed_steps(
    n: usize,
    per_increment: Option<f64>,
    mut run: impl FnMut(u64) -> Result<f64, String>,
) -> Result<u64, String> {
    let base = steps_for(n);
    let few = run(PILOT_STEPS)?.min(run(PILOT_STEPS)?);
    let per_increment = match per_increment {
        Some(seconds) => seconds,
        None => (run(base)? - few) / base.saturating_sub(PILOT_STEPS).max(1) as f64,
    };
    let setup = few - PILOT_STEPS as f64 * per_increment;
    Ok(steps_over_setup(base, setup, per_increment))
}

/// DOF-increments each timed run is repeated up to (R·S·N ≥ this): a small chain's run takes
/// microseconds, so it is repeated often enough that its fastest repeat is not one lucky
/// timer reading.
const WORK_PER_POINT: f64 = 2.0e7;

/// Every timed run is repeated at least this often (the fastest repeat counts): at N = 10^6 a
/// single run's time can move by up to 1.8× from one study to the next (measured on a 2-core VM).
pub const MIN_REPEATS: u64 = 3;

/// One measured point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Engine name.
    pub engine: String,
    /// Masses in the chain (= free DOFs).
    pub n: usize,
    /// Increments of the shorter run (the longer takes twice as many).
    pub steps: u64,
    /// Times each run was repeated (the timings are the fastest of the repeats).
    pub repeats: u64,
    /// Marginal wall time per increment, ns.
    pub ns_per_step: f64,
    /// `ns_per_step / n`.
    pub ns_per_dof_step: f64,
    /// Peak resident memory of the longer run, bytes (0 where the platform does not say).
    pub peak_rss_bytes: u64,
    /// Of that, what building the scene added to the resident memory before the run (the
    /// case as the scene holds it: names, frames, conditions), bytes.
    pub scene_rss_bytes: u64,
    /// Largest error of the probed displacements against the exact solution, over the
    /// amplitude, in the longer run.
    pub error: f64,
    /// The error central differences must give (same measure); the engine's own model of its
    /// error applies to `explicit` only.
    pub predicted_error: f64,
    /// The streaming loop's ns per DOF and increment at this N.
    pub limit_ns_per_dof_step: f64,
}

/// A point the study did not run, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Skipped {
    /// Engine name.
    pub engine: String,
    /// Masses.
    pub n: usize,
    /// Why.
    pub reason: String,
}

/// The study's outcome.
#[derive(Debug, Clone, Default)]
pub struct Study {
    /// Measured points, by engine then N.
    pub points: Vec<Point>,
    /// Points not run.
    pub skipped: Vec<Skipped>,
}

/// The chain sizes of a study up to `max_n`: powers of ten from 10.
pub fn sizes(max_n: usize) -> Vec<usize> {
    std::iter::successors(Some(10usize), |n| n.checked_mul(10))
        .take_while(|n| *n <= max_n)
        .collect()
}

/// Times each run is repeated at N, its shorter run `steps` increments long.
pub fn repeats_for(n: usize, steps: u64) -> u64 {
    ((WORK_PER_POINT / (n as f64 * steps as f64)).ceil() as u64).max(MIN_REPEATS)
}

/// Run the study; `progress` is told each point as it starts (engine, N).
pub fn study(max_n: usize, mut progress: impl FnMut(&str, usize)) -> Result<Study, String> {
    let started = Instant::now();
    let mut out = Study::default();
    // `rapier_f64` where the build has the rapier engines (the `rapier` feature).
    let engines: Vec<Box<dyn Engine>> = std::iter::once(Box::new(ExplicitEngine::finite()) as _)
        .chain(crate::run::registry::named("rapier_f64"))
        .collect();
    for engine in &engines {
        // The last N, the increments of its shorter run, and the seconds of its point (all
        // its runs) and of its longer run.
        let mut last: Option<(usize, u64, f64, f64)> = None;
        for n in sizes(max_n) {
            crate::interrupt::checkpoint("scaling").map_err(|_| "interrupted".to_string())?;
            let name = engine.name().to_string();
            let left = STUDY_SECONDS - started.elapsed().as_secs_f64();
            // In proportion to the DOF-increments a run takes (N × increments), the last point's
            // lengthening for its setup ([`steps_over_setup`]) kept: the setup and the
            // increments both grow with N.
            let predicted = last.map(|(n0, steps0, point, long)| {
                let lengthening = steps0 as f64 / steps_for(n0) as f64;
                let steps = steps_for(n) as f64 * lengthening;
                let scale = (n as f64 * steps) / (n0 as f64 * steps0 as f64);
                (point * scale, long * scale)
            });
            // The point at its fewest repeats: the pilot (about half a longer run) and the first
            // longer run, then a short and a long run each, and the loop's, MIN_REPEATS times.
            let fewest = predicted.map(|(_, long)| (1.5 + 2.0 * MIN_REPEATS as f64) * long);
            if let Some(fewest) = fewest.filter(|s| *s > left) {
                out.skipped.push(Skipped {
                    engine: name,
                    n,
                    reason: if left > 0.0 {
                        format!(
                            "predicted {fewest:.0} s at {MIN_REPEATS} repeats (linear in N × increments from the last point), over the {left:.0} s left of the study's {STUDY_SECONDS:.0} s"
                        )
                    } else {
                        format!(
                            "the study's {STUDY_SECONDS:.0} s are spent (predicted {fewest:.0} s at {MIN_REPEATS} repeats, linear in N × increments from the last point)"
                        )
                    },
                });
                break;
            }
            progress(&name, n);
            // The engine's first point has no time to go by: a single repeat of it first.
            let long = match predicted {
                Some((_, long)) => long,
                None => {
                    let pilot = measure_with(engine.as_ref(), n, 1, None)?;
                    1e-9 * pilot.ns_per_step * 2.0 * pilot.steps as f64
                }
            };
            let repeats = ((POINT_SECONDS / (1.5 * long)) as u64).max(MIN_REPEATS);
            let begun = Instant::now();
            // The last point's seconds per increment, in proportion to N.
            let per_increment = last
                .map(|(n0, steps0, _, long)| long / (2.0 * steps0 as f64) * (n as f64 / n0 as f64));
            let point = measure_with(engine.as_ref(), n, repeats, per_increment)?;
            let long = 1e-9 * point.ns_per_step * 2.0 * point.steps as f64;
            last = Some((n, point.steps, begun.elapsed().as_secs_f64(), long));
            out.points.push(point);
        }
    }
    Ok(out)
}

/// Measure one engine at one N, its runs repeated as often as [`repeats_for`] allows.
pub fn measure(engine: &dyn Engine, n: usize) -> Result<Point, String> {
    measure_with(engine, n, u64::MAX, None)
}

/// Measure one engine at one N, its runs repeated `repeats` times, at most [`repeats_for`] N and
/// its increments (the fastest counts), the increments chosen by a pilot ([`timed_steps`];
/// `per_increment`: the seconds an increment is expected to take, where known).
pub fn measure_with(
    engine: &dyn Engine,
    n: usize,
    repeats: u64,
    per_increment: Option<f64>,
) -> Result<Point, String> {
    // A chain of `steps` increments, its scene and the engine's settings for it, and the
    // resident memory building the scene added.
    let prepared = |steps: u64| {
        let chain = Chain::new(n, steps);
        let before = resident_bytes();
        let scene = chain.scene();
        let settings = matching::job_settings(engine, &scene, &RunSettings::default());
        let scene_bytes = resident_bytes().saturating_sub(before);
        (chain, scene, settings, scene_bytes)
    };
    // Seconds of one run, and its output.
    let timed = |scene: &Scene, settings: &RunSettings| {
        let start = Instant::now();
        let output = engine
            .run(scene, settings)
            .map_err(|e| format!("{} on chain N = {n}: {e}", engine.name()))?;
        let seconds = start.elapsed().as_secs_f64();
        crate::interrupt::checkpoint("scaling").map_err(|_| "interrupted".to_string())?;
        Ok::<_, String>((seconds, output))
    };
    // Increments enough that they, not the setup, set a run's time; the repeats bounded by
    // the work they take.
    let steps = timed_steps(n, per_increment, |steps| {
        let pilot = prepared(steps);
        Ok(timed(&pilot.1, &pilot.2)?.0)
    })?;
    let steps = Chain::new(n, steps).steps;
    let repeats = repeats.min(repeats_for(n, steps));
    // The longer run alone first, for its peak memory (and what its scene holds) and error.
    reset_peak_rss();
    let long = prepared(2 * steps);
    let (first_long, output) = timed(&long.1, &long.2)?;
    let rss = (peak_rss_bytes(), long.3);
    if output.info.steps != long.0.steps {
        return Err(format!(
            "{} on chain N = {n}: took {} increments, expected {}",
            engine.name(),
            output.info.steps,
            long.0.steps
        ));
    }
    let error = displacement_error(&long.0, &output.history)?;
    drop(output);
    // Then the shorter and the longer in turn, and the streaming loop's two runs after them
    // in each repeat, so that a slow spell of the machine falls on the engine and on the limit
    // it is read against alike, rather than on all the repeats of one.
    let short = prepared(steps);
    // The first longer run counts as the first repeat's.
    let mut first_long = Some(first_long);
    let mut again = || {
        in_turn(repeats, |run| match run {
            0 => Ok(timed(&short.1, &short.2)?.0),
            1 => match first_long.take() {
                Some(seconds) => Ok(seconds),
                None => Ok(timed(&long.1, &long.2)?.0),
            },
            2 => Ok(streaming_run(n, steps)),
            _ => Ok(streaming_run(n, 2 * steps)),
        })
    };
    let (times, limit) = retimed(again()?, both_consistent, &mut again, fastest_of)?;
    let ns_per_step = resolved(times) * 1e9 / steps as f64;
    let limit = resolved(limit) * 1e9 / (steps as f64 * n as f64);
    crate::interrupt::checkpoint("scaling").map_err(|_| "interrupted".to_string())?;
    Ok(Point {
        engine: engine.name().to_string(),
        n,
        steps,
        repeats,
        ns_per_step,
        ns_per_dof_step: ns_per_step / n as f64,
        peak_rss_bytes: rss.0,
        scene_rss_bytes: rss.1,
        error,
        predicted_error: long.0.predicted_error(long.0.increment),
        limit_ns_per_dof_step: limit,
    })
}

/// How often a point whose longer run was timed no slower than its shorter one
/// ([`consistent`]) has both timed again, the fastest of all repeats counting.
pub const RETIMINGS: usize = 3;

/// The fastest timings of runs of S and 2S increments of the same scene, seconds.
pub type Times = (f64, f64);

/// The fastest timings of a point's runs: the engine's, then the streaming loop's.
pub type PointTimes = (Times, Times);

/// No timing yet: every later one is faster.
const UNTIMED: PointTimes = (
    (f64::INFINITY, f64::INFINITY),
    (f64::INFINITY, f64::INFINITY),
);

/// Whether `(short, long)` can be read as a setup plus S increments, then S more: the longer
/// run slower. (A setup is never negative, so the longer run should also take at most twice
/// the shorter; where the setup is a small part of a run, as the streaming loop's is, the
/// timer's noise alone breaks that half the time, so it is not asked.)
pub fn consistent((short, long): Times) -> bool {
    long > short
}

/// The seconds the S increments of the longer run add, `long − short`: NaN where the pair is
/// not [`consistent`], which a difference of the two cannot resolve (reported as such, never
/// as a number).
pub fn resolved(times: Times) -> f64 {
    if consistent(times) {
        times.1 - times.0
    } else {
        f64::NAN
    }
}

/// The faster of two timings of each run.
fn fastest(a: Times, b: Times) -> Times {
    (a.0.min(b.0), a.1.min(b.1))
}

/// A point's four runs, `run(0)` to `run(3)` (the engine's S and 2S increments, the streaming
/// loop's S and 2S), each timed once per round, `repeats` rounds; the fastest of each. Within a
/// round the runs follow each other, so a slow spell of the machine longer than a round falls
/// on all four alike, and one shorter than half the repeats leaves each run fast repeats.
fn in_turn(
    repeats: u64,
    mut run: impl FnMut(usize) -> Result<f64, String>,
) -> Result<PointTimes, String> {
    let mut times = UNTIMED;
    for _ in 0..repeats {
        let round = ((run(0)?, run(1)?), (run(2)?, run(3)?));
        times = fastest_of(times, round);
    }
    Ok(times)
}

/// The faster of two timings of each of a point's runs.
fn fastest_of(a: PointTimes, b: PointTimes) -> PointTimes {
    (fastest(a.0, b.0), fastest(a.1, b.1))
}

/// Whether both the engine's pair and the loop's are [`consistent`].
fn both_consistent((engine, limit): PointTimes) -> bool {
    consistent(engine) && consistent(limit)
}

/// `times`, taken `again` up to [`RETIMINGS`] times while `accept` refuses them, the fastest of
/// every timing of each run counting (`merge`).
fn retimed<T: Copy>(
    mut times: T,
    accept: impl Fn(T) -> bool,
    mut again: impl FnMut() -> Result<T, String>,
    merge: fn(T, T) -> T,
) -> Result<T, String> {
    for _ in 0..RETIMINGS {
        if accept(times) {
            break;
        }
        times = merge(times, again()?);
    }
    Ok(times)
}

/// Largest error of the displacement columns against the exact solution, over the amplitude.
fn displacement_error(chain: &Chain, history: &crate::contract::History) -> Result<f64, String> {
    let t = history.column("t").ok_or("history without t")?;
    let mut worst: f64 = 0.0;
    for (name, node) in chain.probes() {
        let column = format!("u_{name}");
        let u = history
            .column(&column)
            .ok_or_else(|| format!("history without {column}"))?;
        for (t, u) in t.iter().zip(&u) {
            let e = (u - chain.displacement(node, *t)).abs() / chain.amplitude;
            if !e.is_finite() {
                return Err(format!("non-finite {column} at t = {t:e}"));
            }
            worst = worst.max(e);
        }
    }
    Ok(worst)
}

/// The streaming loop's marginal ns per DOF and increment at N, measured alone: central
/// differences of the chain over plain arrays (x, v, 1/m, k), runs of `steps` and `2·steps`
/// increments ([`streaming_run`]) taken in turn, the fastest of `repeats` each, timed again as a
/// point is ([`RETIMINGS`]), the difference taken, so it reads and writes what one increment of
/// the chain must and nothing more; NaN where unresolved ([`resolved`]). A point of the study
/// times the same runs in turn with the engine's.
pub fn streaming_limit(n: usize, steps: u64, repeats: u64) -> f64 {
    let in_turn = || {
        let fastest_pair = |times, _| {
            fastest(
                times,
                (streaming_run(n, steps), streaming_run(n, 2 * steps)),
            )
        };
        Ok((0..repeats).fold((f64::INFINITY, f64::INFINITY), fastest_pair))
    };
    let times = retimed(
        in_turn().expect("the loop cannot fail"),
        consistent,
        in_turn,
        fastest,
    )
    .expect("the loop cannot fail");
    resolved(times) * 1e9 / (steps as f64 * n as f64)
}

/// Seconds of one run of the streaming loop over N DOFs, `steps` increments.
fn streaming_run(n: usize, steps: u64) -> f64 {
    let h = 1e-3;
    let mut x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin() * 1e-3).collect();
    let mut v = vec![0.0; n];
    let inverse_mass = vec![1.0; n];
    let stiffness = vec![1.0e4; n + 1];
    let start = Instant::now();
    for _ in 0..steps {
        // An interruption leaves the timing meaningless; the study stops at its next
        // checkpoint.
        if crate::interrupt::requested() {
            break;
        }
        let mut left = 0.0;
        for i in 0..n {
            let right = if i + 1 < n { x[i + 1] } else { 0.0 };
            let xi = x[i];
            let force = stiffness[i] * (left - xi) + stiffness[i + 1] * (right - xi);
            v[i] += h * inverse_mass[i] * force;
            left = xi;
            x[i] = xi + h * v[i];
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    std::hint::black_box((&x, &v));
    seconds
}

/// Reset the process's peak resident set size (Linux: `/proc/self/clear_refs`, value 5);
/// elsewhere a no-op.
fn reset_peak_rss() {
    // Hand freed memory back to the kernel first (glibc keeps it otherwise), so the mark
    // restarts from what is live now, not from the last point's peak.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free heap pages; it has no preconditions.
    unsafe {
        libc::malloc_trim(0);
    }
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The process's peak resident set size since the last reset, bytes (`VmHWM`; 0 where the
/// platform does not say).
pub fn peak_rss_bytes() -> u64 {
    status_bytes("VmHWM:")
}

/// The process's resident set size now, bytes (`VmRSS`; 0 where the platform does not say).
pub fn resident_bytes() -> u64 {
    status_bytes("VmRSS:")
}

/// A `/proc/self/status` field given in kB, in bytes (0 where there is none).
fn status_bytes(field: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kib| kib * 1024)
}

/// Least-squares slope of log(y) against log(x), and its intercept (natural logs).
pub fn fitted_exponent(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let k = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / k, b + y / k));
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| {
        let slope = sxy / sxx;
        (slope, my - slope * mx)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_longer_run_no_slower_than_the_shorter_is_unresolved_not_free() {
        assert_eq!(resolved((1.0, 1.5)), 0.5);
        assert!(resolved((1.0, 1.0)).is_nan());
        assert!(resolved((1.0, 0.9)).is_nan());
    }

    #[test]
    fn a_refused_pair_is_timed_again_and_the_fastest_counts() {
        // The first shorter run slowed by noise (2.1 s for a true 1.0 s): timed again, once.
        let mut calls = 0;
        let times = retimed(
            (2.1, 2.0),
            consistent,
            || {
                calls += 1;
                Ok((1.0, 2.2))
            },
            fastest,
        )
        .unwrap();
        assert_eq!((times, calls), ((1.0, 2.0), 1));
        // Never accepted: RETIMINGS attempts, then left to `resolved` to refuse.
        let mut calls = 0;
        let times = retimed(
            (1.0, 0.9),
            consistent,
            || {
                calls += 1;
                Ok((1.0, 0.95))
            },
            fastest,
        )
        .unwrap();
        assert_eq!((times, calls), ((1.0, 0.9), RETIMINGS));
        assert!(resolved(times).is_nan());
    }

    #[test]
    fn a_slow_spell_over_half_the_runs_leaves_the_ratio_to_the_limit_exact() {
        // A machine on which the engine's runs take 1 and 2 s and the loop's 0.5 and 1 s (the
        // engine at exactly twice the limit), and every run in one stretch of consecutive runs,
        // half of all, three times as long. Wherever the stretch falls, each of the four runs
        // keeps a repeat outside it, so the ratio read is 2 to the last bit; timing every
        // repeat of the engine before the loop's would read 6 where the stretch covers the
        // engine's.
        let repeats = 6u64;
        let calls = 4 * repeats as usize;
        for start in 0..=calls / 2 {
            let mut call = 0;
            let times = in_turn(repeats, |run| {
                let slow = (start..start + calls / 2).contains(&call);
                call += 1;
                Ok([1.0, 2.0, 0.5, 1.0][run] * if slow { 3.0 } else { 1.0 })
            })
            .unwrap();
            assert_eq!(call, calls);
            assert_eq!(
                resolved(times.0) / resolved(times.1),
                2.0,
                "stretch from {start}"
            );
        }
    }

    #[test]
    fn a_run_whose_setup_outweighs_its_increments_is_lengthened() {
        // `explicit` at N = 10^5: a setup of 0.15 s, 0.21 ms an increment; 400 increments take
        // about half the setup, 1429 (2 · 0.15 / 0.21e-3 = 1428.6, rounded up) twice it.
        assert_eq!(steps_over_setup(400, 0.15, 0.21e-3), 1429);
        // A setup the base increments already outweigh twice: the base.
        assert_eq!(steps_over_setup(400, 0.01, 0.2e-3), 400);
        // Never more than MAX_LENGTHENING times the base.
        assert_eq!(steps_over_setup(400, 100.0, 1.0e-6), 3200);
        // Nor than the point's time allows: at N = 10^6 (a setup of 1.5 s, 4 ms an increment)
        // 750 increments would take twice the setup, but 11 runs of 400 already take 17.6 s.
        assert_eq!(steps_over_setup(400, 1.5, 4.0e-3), 400);
        // At 0.5 ms an increment, 10 s allow 10 / (11 · 0.5e-3) = 1818 of the 6000 asked.
        assert_eq!(steps_over_setup(400, 1.5, 0.5e-3), 1818);
        // A pilot that could not separate the setup from the increments: the base.
        for (setup, per_increment) in [(-0.01, 1.0e-3), (0.1, 0.0), (f64::NAN, 1.0e-3)] {
            assert_eq!(steps_over_setup(400, setup, per_increment), 400);
        }
    }

    #[test]
    fn the_pilot_reads_the_setup_and_the_increment_of_a_run() {
        // A run of s increments taking 0.15 s + s · 0.21 ms: on its own, the pilot's three runs
        // read the setup and the increment back (1429 increments, as above); told the
        // increment's time, it runs only the two that time the setup.
        let run = |runs: &mut Vec<u64>, s: u64| {
            runs.push(s);
            Ok(0.15 + s as f64 * 0.21e-3)
        };
        let mut runs = Vec::new();
        let steps = timed_steps(100_000, None, |s| run(&mut runs, s)).unwrap();
        assert_eq!((steps, runs), (1429, vec![PILOT_STEPS, PILOT_STEPS, STEPS]));
        let mut runs = Vec::new();
        let steps = timed_steps(100_000, Some(0.21e-3), |s| run(&mut runs, s)).unwrap();
        assert_eq!((steps, runs), (1429, vec![PILOT_STEPS, PILOT_STEPS]));
        // Told twice the increment's time (a guess scaled from a smaller chain, say), it reads
        // less setup, 0.171 − 100 · 0.42e-3 = 0.129 s, and asks 2 · 0.129 / 0.42e-3 = 614.3
        // increments: 615.
        let mut runs = Vec::new();
        let steps = timed_steps(100_000, Some(0.42e-3), |s| run(&mut runs, s)).unwrap();
        assert_eq!(steps, 615);
    }

    #[test]
    fn a_setup_that_spreads_costs_the_point_at_most_its_share() {
        // A machine whose setup takes from 0.15 s to 30 % more, the worst way round: every
        // shorter run's setup at the top, every longer run's at the bottom; 0.2 ms an
        // increment, the loop exact. At STEPS increments the difference reads the increment at
        // 44 % of its time; lengthened for the setup, within δ/SETUP_SHARE = 15 % of it.
        let (setup, spread, increment) = (0.15, 0.3, 0.2e-3);
        let read = |steps: u64| {
            let s = steps as f64;
            let times = in_turn(MIN_REPEATS, |run| {
                Ok(match run {
                    0 => setup * (1.0 + spread) + s * increment,
                    1 => setup + 2.0 * s * increment,
                    2 => s * 1e-4,
                    _ => 2.0 * s * 1e-4,
                })
            })
            .unwrap();
            resolved(times.0) / s
        };
        let short = read(STEPS) / increment;
        assert!((short - 0.4375).abs() < 1e-12, "{short}");
        let lengthened = read(steps_over_setup(STEPS, setup, increment)) / increment;
        assert!(
            1.0 - lengthened <= spread / SETUP_SHARE + 1e-12,
            "{lengthened}"
        );
    }

    #[test]
    fn a_small_chain_runs_long_enough_to_time() {
        assert_eq!(steps_for(1_000_000), STEPS);
        assert_eq!(steps_for(1000), STEPS);
        assert_eq!(steps_for(100), 4000);
        assert_eq!(steps_for(10), 40_000);
        for n in sizes(1_000_000) {
            assert!(n as f64 * steps_for(n) as f64 >= WORK_PER_RUN);
        }
    }
}
