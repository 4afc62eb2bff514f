//! An engine against a floor, or against another engine, timed in turn: each round times the
//! engine's whole run and the floor's run over as many increments of the same length (or the
//! other engine's whole run) back to back (one first in one round, the other in the next), so
//! that a slow spell of the machine that lasts a round slows both alike and leaves that
//! round's ratio as it is; the median over the rounds sets aside the rounds a shorter spell
//! split. Timed apart (criterion measures each benchmark for seconds, the floors minutes after
//! the engine), the same code's ratio moves by up to 1.7× between runs.

use super::FloorRun;
use crate::engines::{Engine, RunSettings};
use crate::scene::{IncrementRule, Scene};
use std::hint::black_box;
use std::time::Instant;

/// The benchmarks run each seed case at its increment divided by this (10^5 to 2·10^5
/// increments), so that a run's setup is spread thin.
pub const REFINEMENT: f64 = 10.0;

/// The ratios of one run time to another's (an engine's to its floor's, or one engine's to
/// another's), one per round, in increasing order.
#[derive(Debug, Clone, PartialEq)]
pub struct InTurn {
    ratios: Vec<f64>,
}

impl InTurn {
    /// From each round's two times, (numerator, denominator).
    pub fn from_times(rounds: &[(f64, f64)]) -> Self {
        let mut ratios: Vec<f64> = rounds.iter().map(|(e, f)| e / f).collect();
        ratios.sort_by(f64::total_cmp);
        InTurn { ratios }
    }

    /// The median of the rounds' ratios (the mean of the middle two for an even count; NaN
    /// without rounds).
    pub fn median(&self) -> f64 {
        let n = self.ratios.len();
        match n {
            0 => f64::NAN,
            _ if n % 2 == 1 => self.ratios[n / 2],
            _ => 0.5 * (self.ratios[n / 2 - 1] + self.ratios[n / 2]),
        }
    }

    /// The lower and upper quartiles of the rounds' ratios, as order statistics: the
    /// ⌊(n−1)/4⌋-th from the lowest and as many from the highest, counting from 0, so that
    /// at least half of the rounds lie between them (11 of 21, 5 of 7). NaN without rounds.
    pub fn quartiles(&self) -> (f64, f64) {
        let n = self.ratios.len();
        if n == 0 {
            return (f64::NAN, f64::NAN);
        }
        let k = (n - 1) / 4;
        (self.ratios[k], self.ratios[n - 1 - k])
    }
}

/// `engine`'s whole run of `scene` under `settings` (an increment given, as the job planner
/// sets it) against `floor` over as many increments of that length as its dynamic step takes
/// (as the benchmark runs it), timed in turn over `rounds` rounds after one untimed run of
/// each. The engine's time includes dropping its output, as criterion's does.
pub fn time_in_turn(
    engine: &dyn Engine,
    scene: &Scene,
    settings: &RunSettings,
    floor: &FloorRun,
    rounds: usize,
) -> Result<InTurn, String> {
    let Some(IncrementRule::Given(h)) = settings.increment else {
        return Err(format!("{}: the floor needs an increment given", scene.id));
    };
    let steps = (floor.duration / h).round() as u64;
    let engine_run = || whole_run(engine, scene, settings);
    let floor_run = || {
        let started = Instant::now();
        floor.run(h, steps);
        Ok(started.elapsed().as_secs_f64())
    };
    in_turn(engine_run, floor_run, rounds)
}

/// Engine `first`'s whole run of `scene` under `first_settings` against engine `second`'s
/// under `second_settings`, timed in turn over `rounds` rounds after one untimed run of each:
/// the ratios are `first`'s time over `second`'s.
pub fn engines_in_turn(
    scene: &Scene,
    (first, first_settings): (&dyn Engine, &RunSettings),
    (second, second_settings): (&dyn Engine, &RunSettings),
    rounds: usize,
) -> Result<InTurn, String> {
    let first_run = || whole_run(first, scene, first_settings);
    let second_run = || whole_run(second, scene, second_settings);
    in_turn(first_run, second_run, rounds)
}

/// The seconds of `engine`'s whole run of `scene` under `settings`, dropping its output
/// included, as criterion's time includes it.
fn whole_run(engine: &dyn Engine, scene: &Scene, settings: &RunSettings) -> Result<f64, String> {
    let started = Instant::now();
    let output = engine.run(black_box(scene), settings);
    drop(output.map_err(|e| format!("{}: {e}", scene.id))?);
    Ok(started.elapsed().as_secs_f64())
}

/// `first` against `second` (each returns its run's seconds) over `rounds` rounds after one
/// untimed run of each, the one that goes first alternating.
fn in_turn(
    first: impl Fn() -> Result<f64, String>,
    second: impl Fn() -> Result<f64, String>,
    rounds: usize,
) -> Result<InTurn, String> {
    first()?;
    second()?;
    let mut times = Vec::with_capacity(rounds);
    for round in 0..rounds {
        let pair = if round % 2 == 0 {
            (first()?, second()?)
        } else {
            let second_seconds = second()?;
            (first()?, second_seconds)
        };
        times.push(pair);
    }
    Ok(InTurn::from_times(&times))
}

#[cfg(test)]
mod tests {
    use super::InTurn;

    /// A simulated machine runs the engine at exactly twice the floor's time; a spell three
    /// times slower covers the first nine rounds whole, and a shorter one slows the engine
    /// alone in seven others. Timed in turn, the median reads the ratio to the last bit, and
    /// the quartiles show what the short spells did.
    #[test]
    fn spells_over_whole_rounds_and_under_half_of_them_leave_the_median_exact() {
        let rounds: Vec<(f64, f64)> = (0..21)
            .map(|i| {
                let spell = if i < 9 { 3.0 } else { 1.0 };
                let engine_alone = if (10..17).contains(&i) { 1.5 } else { 1.0 };
                (2.0e-3 * spell * engine_alone, 1.0e-3 * spell)
            })
            .collect();
        let paired = InTurn::from_times(&rounds);
        assert_eq!(paired.median(), 2.0);
        // Fourteen rounds read 2 and seven read 3: the 5th from the lowest is 2, the 5th from
        // the highest (the 15th) is 3.
        assert_eq!(paired.quartiles(), (2.0, 3.0));
        // An even count takes the mean of the middle two; no rounds, no ratio.
        let even = InTurn::from_times(&[(1.0, 1.0), (3.0, 1.0)]);
        assert_eq!(even.median(), 2.0);
        assert_eq!(even.quartiles(), (1.0, 3.0));
        assert!(InTurn::from_times(&[]).median().is_nan());
    }
}
