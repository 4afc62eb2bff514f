//! An engine against a floor, or against another engine, timed in turn: each round times the
//! engine's whole run and the floor's run over as many increments of the same length (or the
//! other engine's whole run) back to back (one first in one round, the other in the next), so
//! that a slow spell of the machine that lasts a round slows both alike and leaves that
//! round's ratio as it is; the median over the rounds sets aside the rounds a shorter spell
//! split. Timed apart (criterion measures each benchmark for seconds, the floors minutes after
//! the engine), the same code's ratio moves by up to 1.7× between runs.
//!
//! Paired rounds do not remove a spell that lasts longer than a case's rounds and slows the
//! two runs by different factors (the engine's run executes several times the floor's
//! instructions, the floor's is one chain of dependent operations): a case whose 21 rounds
//! took under a second read rigid2d_pin_surface's engine over its floor at 1.50 on one run and
//! 2.48 on the next, the same binary. So the pairs of all the cases are interleaved
//! ([`interleaved`]): each round times every pair whose rounds fall there ([`spread`]), so that
//! each pair's rounds are spread over the whole measurement; and each pair also reports the
//! ratio of its two runs' fastest rounds ([`InTurn::fastest`]), which a spell that only adds
//! time does not move as long as each run has a round outside it.

use super::FloorRun;
use crate::engines::{Engine, RunSettings};
use crate::scene::{IncrementRule, Scene};
use std::hint::black_box;
use std::time::Instant;

/// The benchmarks run each seed case at its increment divided by this (10^5 to 2·10^5
/// increments), so that a run's setup is spread thin.
pub const REFINEMENT: f64 = 10.0;

/// The ratios of one run time to another's (an engine's to its floor's, or one engine's to
/// another's), one per round, in increasing order, and the ratio of their fastest rounds.
#[derive(Debug, Clone, PartialEq)]
pub struct InTurn {
    ratios: Vec<f64>,
    fastest: f64,
}

impl InTurn {
    /// From each round's two times, (numerator, denominator).
    pub fn from_times(rounds: &[(f64, f64)]) -> Self {
        let mut ratios: Vec<f64> = rounds.iter().map(|(e, f)| e / f).collect();
        ratios.sort_by(f64::total_cmp);
        let least = |time: fn(&(f64, f64)) -> f64| rounds.iter().map(time).reduce(f64::min);
        let fastest = match (least(|r| r.0), least(|r| r.1)) {
            (Some(first), Some(second)) => first / second,
            _ => f64::NAN,
        };
        InTurn { ratios, fastest }
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

    /// The first run's fastest round over the second's (NaN without rounds), the two read from
    /// rounds that may differ: the least time each was seen to take, the nearest a timing comes
    /// to what it costs where the machine takes nothing from it.
    pub fn fastest(&self) -> f64 {
        self.fastest
    }
}

/// A timed run: its seconds.
pub type TimedRun<'a> = Box<dyn Fn() -> Result<f64, String> + 'a>;

/// Two runs to time in turn over `rounds` rounds: the ratio is `first`'s time over `second`'s.
pub struct Pair<'a> {
    /// What the pair is, for an error.
    pub name: String,
    /// The numerator's run.
    pub first: TimedRun<'a>,
    /// The denominator's run.
    pub second: TimedRun<'a>,
    /// Rounds to time.
    pub rounds: usize,
}

/// `engine`'s whole run of `scene` under `settings` (an increment given, as the job planner
/// sets it) against `floor` over as many increments of that length as its dynamic step takes
/// (as the benchmark runs it). The engine's time includes dropping its output, as criterion's
/// does.
pub fn floor_pair<'a>(
    engine: &'a dyn Engine,
    scene: &'a Scene,
    settings: &'a RunSettings,
    floor: FloorRun,
    rounds: usize,
) -> Result<Pair<'a>, String> {
    let Some(IncrementRule::Given(h)) = settings.increment else {
        return Err(format!("{}: the floor needs an increment given", scene.id));
    };
    let steps = (floor.duration / h).round() as u64;
    let floor_run = move || {
        let started = Instant::now();
        floor.run(h, steps);
        Ok(started.elapsed().as_secs_f64())
    };
    Ok(Pair {
        name: format!("{} / {} against its floor", scene.id, engine.name()),
        first: Box::new(move || whole_run(engine, scene, settings)),
        second: Box::new(floor_run),
        rounds,
    })
}

/// Engine `first`'s whole run of `scene` under `first_settings` against engine `second`'s
/// under `second_settings`: the ratio is `first`'s time over `second`'s.
pub fn engines_pair<'a>(
    scene: &'a Scene,
    (first, first_settings): (&'a dyn Engine, &'a RunSettings),
    (second, second_settings): (&'a dyn Engine, &'a RunSettings),
    rounds: usize,
) -> Pair<'a> {
    Pair {
        name: format!("{} / {} against {}", scene.id, first.name(), second.name()),
        first: Box::new(move || whole_run(first, scene, first_settings)),
        second: Box::new(move || whole_run(second, scene, second_settings)),
        rounds,
    }
}

/// The seconds of `engine`'s whole run of `scene` under `settings`, dropping its output
/// included, as criterion's time includes it.
fn whole_run(engine: &dyn Engine, scene: &Scene, settings: &RunSettings) -> Result<f64, String> {
    let started = Instant::now();
    let output = engine.run(black_box(scene), settings);
    drop(output.map_err(|e| format!("{}: {e}", scene.id))?);
    Ok(started.elapsed().as_secs_f64())
}

/// Every pair of `pairs` timed in turn, interleaved, after one untimed run of each of its two
/// runs: round r of the longest pair's R rounds times each pair that [`spread`] places there,
/// its two runs back to back, the one that goes first alternating from one of its rounds to
/// the next. One [`InTurn`] per pair, in order.
pub fn interleaved(pairs: &[Pair]) -> Result<Vec<InTurn>, String> {
    let with = |pair: &Pair, e: String| format!("{}: {e}", pair.name);
    for pair in pairs {
        (pair.first)().map_err(|e| with(pair, e))?;
        (pair.second)().map_err(|e| with(pair, e))?;
    }
    let total = pairs.iter().map(|p| p.rounds).max().unwrap_or(0);
    let mut times: Vec<Vec<(f64, f64)>> =
        pairs.iter().map(|p| Vec::with_capacity(p.rounds)).collect();
    for round in 0..total {
        for (pair, times) in pairs.iter().zip(&mut times) {
            if !spread(round, pair.rounds, total) {
                continue;
            }
            let (first, second) = (&pair.first, &pair.second);
            let timed = if times.len() % 2 == 0 {
                first().and_then(|a| Ok((a, second()?)))
            } else {
                second().and_then(|b| Ok((first()?, b)))
            };
            times.push(timed.map_err(|e| with(pair, e))?);
        }
    }
    Ok(times.iter().map(|t| InTurn::from_times(t)).collect())
}

/// Whether a pair of `rounds` rounds is timed at round `round` of `total` (`rounds` ≤
/// `total`): at `rounds` of them, as evenly apart as whole rounds allow, the first at 0.
fn spread(round: usize, rounds: usize, total: usize) -> bool {
    (round * rounds).div_ceil(total) < ((round + 1) * rounds).div_ceil(total)
}

#[cfg(test)]
mod tests {
    use super::{InTurn, Pair, TimedRun, interleaved, spread};
    use std::cell::RefCell;

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

    /// The same machine, but a spell that slows the engine 1.4× and the floor 1.1× covers
    /// fifteen rounds whole, and the runs' times jitter by up to 4 % and 3 % from round to round: the
    /// median reads about the spell's ratio, 2·1.4/1.1; the fastest rounds, the engine's at
    /// round 1 and the floor's at rounds 0 and 20, the undisturbed 2 exactly.
    #[test]
    fn a_long_spell_that_slows_the_two_unequally_moves_the_median_not_the_fastest() {
        let rounds: Vec<(f64, f64)> = (0..21)
            .map(|i| {
                let (engine, floor) = if (2..17).contains(&i) {
                    (1.4, 1.1)
                } else {
                    (1.0, 1.0)
                };
                let engine_jitter = 1.0 + 0.01 * ((i + 4) % 5) as f64;
                let floor_jitter = 1.0 + 0.01 * (i % 4) as f64;
                (
                    2.0e-3 * engine * engine_jitter,
                    1.0e-3 * floor * floor_jitter,
                )
            })
            .collect();
        let paired = InTurn::from_times(&rounds);
        let spell = 2.0 * 1.4 / 1.1;
        assert!((paired.median() - spell).abs() < 0.1, "{}", paired.median());
        assert_eq!(paired.fastest(), 2.0);
        assert!(InTurn::from_times(&[]).fastest().is_nan());
    }

    /// A pair of k rounds among R is timed at exactly k rounds, the first at round 0, each
    /// ⌊R/k⌋ or ⌈R/k⌉ rounds after the one before, and the last as far from the end.
    #[test]
    fn a_shorter_pair_is_spread_over_the_longest_ones_rounds() {
        for total in 1..=30 {
            for rounds in 1..=total {
                let at: Vec<usize> = (0..total).filter(|&r| spread(r, rounds, total)).collect();
                assert_eq!(at.len(), rounds, "{rounds} of {total}");
                assert_eq!(at[0], 0, "{rounds} of {total}");
                // Gaps between ⌊R/k⌋ and ⌈R/k⌉, the last as wide as the others.
                let mut gaps: Vec<usize> = at.windows(2).map(|w| w[1] - w[0]).collect();
                gaps.push(total - at[rounds - 1]);
                let (least, widest) = (total / rounds, total.div_ceil(rounds));
                let even = gaps.iter().all(|g| (least..=widest).contains(g));
                assert!(even, "{rounds} of {total}: {at:?}");
            }
        }
        let seven: Vec<usize> = (0..21).filter(|&r| spread(r, 7, 21)).collect();
        assert_eq!(seven, [0, 3, 6, 9, 12, 15, 18]);
    }

    /// Two pairs, of 4 rounds and of 2, whose runs log their calls and take fixed times: each
    /// run once untimed, pair by pair; then round by round every pair placed there, its two
    /// runs back to back, the first of them alternating over the pair's own rounds; one
    /// result per pair, in order.
    #[test]
    fn interleaved_pairs_take_turns_round_by_round() {
        let calls = RefCell::new(Vec::new());
        let run = |name: &'static str, seconds: f64| -> TimedRun {
            let calls = &calls;
            Box::new(move || {
                calls.borrow_mut().push(name);
                Ok(seconds)
            })
        };
        let pairs = [
            Pair {
                name: "a".to_string(),
                first: run("a1", 3.0),
                second: run("a2", 1.0),
                rounds: 4,
            },
            Pair {
                name: "b".to_string(),
                first: run("b1", 1.0),
                second: run("b2", 4.0),
                rounds: 2,
            },
        ];
        let results = interleaved(&pairs).expect("runs that do not fail");
        let expected = [
            "a1", "a2", "b1", "b2", // untimed
            "a1", "a2", "b1", "b2", // round 0
            "a2", "a1", // round 1
            "a1", "a2", "b2", "b1", // round 2
            "a2", "a1", // round 3
        ];
        assert_eq!(calls.borrow().as_slice(), expected);
        assert_eq!(results.len(), 2);
        assert_eq!((results[0].median(), results[0].fastest()), (3.0, 3.0));
        assert_eq!((results[1].median(), results[1].fastest()), (0.25, 0.25));
    }
}
