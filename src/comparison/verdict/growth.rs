//! Whether a run is unstable: its energy keeps growing, not merely rises once.
//!
//! **The level.** A run's *level* ℓ(t) is its kinetic plus elastic energy over what it may
//! hold: its initial energy plus the largest |work| of the loads so far (dissipation only
//! removes energy, so a run that follows physics stays at or below 1, up to what its scheme
//! reads above the conserved energy near its limit). An engine that writes no energy columns
//! is read through its state instead: the sum of squares of its output columns over the
//! largest such sum in the first eighth of the run.
//!
//! **The rule.** The run is cut into [`WINDOWS`] equal windows of time, and each window's
//! peak level taken (levels under [`ROUND_OFF`] count as it, so that round-off noise on a run
//! that has come to rest is not growth). The run is *growing* when its largest level is in its
//! last window and that peak is at least [`GROWTH`] times the peak of the window that ends
//! halfway through: the energy is still rising at the end, and has risen by a decade over the
//! second half. A mode that grows geometrically (from round-off or from a disturbance) does
//! that however small it started, as soon as it carries more than the physical energy; a
//! transient that peaks and decays does not (its peak is earlier), nor does a bounded
//! oscillation whose first swing is its largest. One reading above a fixed number never
//! decides it.
//!
//! **The horizon.** A run shorter than [`MIN_INCREMENTS`] increments cannot tell a growing
//! mode from a transient: its verdict is [`Verdict::TooShort`]. A run that is growing at the
//! end of its horizon may still be a late transient (an impact just before the end); the
//! stability map confirms it on a horizon [`CONFIRM`] times longer ([`crate::run::stability`]),
//! where a transient has decayed and a growing mode has grown further.
//!
//! The transient amplification (the largest level and when it occurred) is reported beside
//! the verdict, never as instability.

use crate::contract::{E_ELASTIC, E_KINETIC, History, W_EXTERNAL};
use crate::run::Status;
use serde::{Deserialize, Serialize};

/// Windows the run is cut into.
pub const WINDOWS: usize = 8;

/// How far the last window's peak must stand above the peak of the window that ends halfway
/// for the run to be growing: a decade over the second half.
pub const GROWTH: f64 = 10.0;

/// Levels below this count as it: round-off of an energy relative to what the run may hold.
pub const ROUND_OFF: f64 = 1e-12;

/// The fewest increments a run needs for its growth to be judged (the stability map's scenes
/// are continued in time where a case is shorter than this at an increment). Over the second
/// half of such a run, a decade of growth in energy is an amplitude growing at least 1.12× per
/// increment: slower growth shows only on a longer run.
pub use crate::run::stability::MIN_INCREMENTS;

/// How much longer the horizon on which a run growing at its end is confirmed.
pub const CONFIRM: usize = 4;

/// What the rule says of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Its level is not still rising by a decade over the second half at the end.
    Bounded,
    /// Its level is at its largest at the end and has grown by [`GROWTH`] over the second half.
    Growing,
    /// Fewer than [`MIN_INCREMENTS`] increments, or too few rows for every window to hold
    /// one: the horizon cannot tell.
    TooShort,
}

/// A run's growth, measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Growth {
    /// The rule's verdict.
    pub verdict: Verdict,
    /// The largest level over the run: the transient amplification (1 or less for a run that
    /// follows physics).
    pub peak: f64,
    /// When it occurred, seconds.
    pub peak_time: f64,
    /// The level at the end of the run.
    pub end: f64,
    /// The last window's peak over the peak of the window that ends halfway.
    pub second_half: f64,
}

/// The level of each row of `history` (see the module doc), with its time; `None` for a
/// history without rows.
pub fn levels(history: &History) -> Option<Vec<(f64, f64)>> {
    if history.rows.is_empty() {
        return None;
    }
    let t = history.column("t")?;
    let energies = (
        history.column(E_KINETIC),
        history.column(E_ELASTIC),
        history.column(W_EXTERNAL),
    );
    let level: Vec<f64> = match energies {
        (Some(k), Some(e), Some(w)) => {
            let e0 = k.first()? + e.first()?;
            let mut budget = 0.0f64;
            k.iter()
                .zip(&e)
                .zip(&w)
                .map(|((k, e), w)| {
                    budget = budget.max(e0 + w.abs());
                    let held = k + e;
                    if budget > 0.0 { held / budget } else { held }
                })
                .collect()
        }
        _ => {
            let squares: Vec<f64> = history
                .rows
                .iter()
                .map(|r| r.iter().skip(1).map(|x| x * x).sum())
                .collect();
            let early = squares.len().div_ceil(WINDOWS);
            let scale = squares[..early].iter().fold(0.0f64, |m, x| m.max(*x));
            squares
                .iter()
                .map(|s| if scale > 0.0 { s / scale } else { *s })
                .collect()
        }
    };
    Some(t.into_iter().zip(level).collect())
}

/// Judge a run's growth from its history and the increments it took.
pub fn judge(history: &History, increments: f64) -> Option<Growth> {
    let levels = levels(history)?;
    let (t0, t1) = (levels.first()?.0, levels.last()?.0);
    let (peak_time, peak) =
        levels.iter().copied().fold(
            (t0, f64::NEG_INFINITY),
            |m, (t, l)| if l > m.1 { (t, l) } else { m },
        );
    let end = levels.last()?.1;
    let span = (t1 - t0).max(f64::MIN_POSITIVE);
    let mut windows = [ROUND_OFF; WINDOWS];
    let mut filled = [false; WINDOWS];
    for (t, l) in &levels {
        let k = (((t - t0) / span * WINDOWS as f64) as usize).min(WINDOWS - 1);
        windows[k] = windows[k].max(*l);
        filled[k] = true;
    }
    let last = windows[WINDOWS - 1];
    let second_half = last / windows[WINDOWS / 2 - 1];
    let largest = windows.iter().fold(0.0f64, |m, x| m.max(*x));
    let verdict = if increments < MIN_INCREMENTS || filled.contains(&false) {
        Verdict::TooShort
    } else if last >= largest && second_half >= GROWTH {
        Verdict::Growing
    } else {
        Verdict::Bounded
    };
    Some(Growth {
        verdict,
        peak,
        peak_time,
        end,
        second_half,
    })
}

/// How a run of the stability map came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Outcome {
    /// Bounded, and within the case's tolerance for the engine.
    Accurate,
    /// Bounded, outside that tolerance.
    Inaccurate,
    /// Bounded; the case declares no tolerance for the engine.
    Bounded,
    /// Its energy kept growing, or the engine stopped it as unstable.
    Unstable,
    /// Too few increments over the scene for growth to be judged.
    TooShort,
    /// Failed for another reason (an error mid-run, a panic).
    Failed,
    /// The engine does not model the case (it says why).
    NotApplicable,
}

impl Outcome {
    /// Every outcome, in the legend's order.
    pub const ALL: [Outcome; 7] = [
        Outcome::Accurate,
        Outcome::Inaccurate,
        Outcome::Bounded,
        Outcome::Unstable,
        Outcome::TooShort,
        Outcome::Failed,
        Outcome::NotApplicable,
    ];

    /// Name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Accurate => "accurate",
            Outcome::Inaccurate => "inaccurate",
            Outcome::Bounded => "bounded",
            Outcome::Unstable => "unstable",
            Outcome::TooShort => "too short",
            Outcome::Failed => "failed",
            Outcome::NotApplicable => "not applicable",
        }
    }

    /// From the CSV name.
    pub fn parse(s: &str) -> Option<Outcome> {
        Outcome::ALL.into_iter().find(|o| o.name() == s)
    }

    /// Whether the run stayed bounded (accurate or not).
    pub fn bounded(self) -> bool {
        matches!(
            self,
            Outcome::Accurate | Outcome::Inaccurate | Outcome::Bounded
        )
    }
}

/// A stability map run's outcome, from its typed status, its growth (for a run that finished)
/// and its error against its own model's exact solution with the engine's tolerance.
pub fn outcome(
    status: Status,
    growth: Option<&Growth>,
    error: Option<f64>,
    tolerance: Option<f64>,
) -> Outcome {
    match status {
        Status::NotApplicable => Outcome::NotApplicable,
        Status::Unstable => Outcome::Unstable,
        Status::Failed => Outcome::Failed,
        Status::Ok => match growth.map(|g| g.verdict) {
            Some(Verdict::Growing) => Outcome::Unstable,
            Some(Verdict::TooShort) => Outcome::TooShort,
            _ => match super::meets(status, error, tolerance) {
                Some(true) => Outcome::Accurate,
                Some(false) => Outcome::Inaccurate,
                None => Outcome::Bounded,
            },
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A history of `n` rows over `duration` with the given kinetic energy (elastic 0, no
    /// load work): its level is the energy over the initial one.
    fn energy(n: usize, duration: f64, e: impl Fn(f64) -> f64) -> History {
        History {
            columns: ["t", E_KINETIC, E_ELASTIC, W_EXTERNAL]
                .map(String::from)
                .to_vec(),
            rows: (0..n)
                .map(|i| {
                    let t = duration * i as f64 / (n - 1) as f64;
                    vec![t, e(t), 0.0, 0.0]
                })
                .collect(),
        }
    }

    /// The stress pair's transient at 64× (measured on rapier's default configuration over
    /// 300 s): one peak of about 30× its initial energy near 2.2 s, then decay to 2e-14.
    /// Bounded, its peak reported.
    #[test]
    fn a_transient_then_decay_is_bounded() {
        let level = |t: f64| (-t / 10.0).exp() + 29.7 * (-((t - 2.2) / 0.5).powi(2)).exp();
        let h = energy(3001, 300.0, level);
        let g = judge(&h, 5000.0).unwrap();
        assert_eq!(g.verdict, Verdict::Bounded);
        assert!(
            (g.peak / (level(2.2) / level(0.0)) - 1.0).abs() < 1e-12,
            "{g:?}"
        );
        assert!((g.peak_time - 2.2).abs() < 1e-9, "{g:?}");
        assert!(g.end < 1e-12, "{g:?}");
        // Cut to its first 30 s, where the map ran it, it is bounded too.
        let short = energy(301, 30.0, level);
        assert_eq!(judge(&short, 500.0).unwrap().verdict, Verdict::Bounded);
    }

    /// An unstable mode seeded by round-off (1e-16 of the energy) growing at 1.49 per
    /// increment (central differences at ω·h = 2.04) under a physical oscillation of level 1:
    /// invisible for most of the run, then dominant. Growing, whatever the fixed number it
    /// would have crossed.
    #[test]
    fn geometric_growth_from_round_off_is_unstable() {
        let steps = 200.0;
        let rate = 2.0 * 1.49f64.ln() * steps; // per unit time, in energy
        let h = energy(401, 1.0, |t| {
            0.5 + 0.5 * (40.0 * t).cos().powi(2) + 1e-16 * (rate * t).exp()
        });
        let g = judge(&h, steps).unwrap();
        assert_eq!(g.verdict, Verdict::Growing, "{g:?}");
        // The same mode growing slowly enough to stay below round-off at the end is not seen.
        let slow = energy(401, 1.0, |t| 1.0 + 1e-16 * (10.0 * t).exp());
        assert_eq!(judge(&slow, steps).unwrap().verdict, Verdict::Bounded);
        // Growth from a run at rest: every window under round-off but the last ones.
        let rest = energy(401, 1.0, |t| 1e-30 * (60.0 * t).exp());
        assert_eq!(judge(&rest, steps).unwrap().verdict, Verdict::Growing);
    }

    /// A bounded oscillation whose first swings reach 13× its initial energy before settling
    /// back to it, and one that holds a level of 3 (above any fixed cut of 2) throughout: both
    /// bounded.
    #[test]
    fn a_bounded_oscillation_with_a_large_first_peak_is_bounded() {
        let h = energy(1001, 1.0, |t| {
            let swell = 19.0 * (1.0 - (-t / 0.01).exp()) * (-t / 0.05).exp();
            (1.0 + swell) * (0.5 + 0.5 * (300.0 * t).cos())
        });
        let g = judge(&h, 5000.0).unwrap();
        assert_eq!(g.verdict, Verdict::Bounded);
        assert!(g.peak > 10.0 && g.peak_time < 0.1, "{g:?}");
        let held = energy(1001, 1.0, |t| 3.0 + 0.1 * (300.0 * t).sin());
        assert_eq!(judge(&held, 5000.0).unwrap().verdict, Verdict::Bounded);
    }

    /// Under 20 increments the horizon cannot tell, whatever the history.
    #[test]
    fn a_run_of_few_increments_is_too_short_to_tell() {
        let h = energy(201, 1.0, |t| (50.0 * t).exp());
        assert_eq!(judge(&h, 19.0).unwrap().verdict, Verdict::TooShort);
        assert_eq!(judge(&h, 20.0).unwrap().verdict, Verdict::Growing);
        // Too few rows for every window to hold one, however many increments.
        let sparse = energy(6, 1.0, |t| 1.0 + 0.1 * (t * 20.0).sin());
        assert_eq!(judge(&sparse, 1000.0).unwrap().verdict, Verdict::TooShort);
        let empty = History {
            columns: vec!["t".into(), "u".into()],
            rows: Vec::new(),
        };
        assert!(judge(&empty, 1000.0).is_none());
    }

    #[test]
    fn a_map_outcome_follows_the_status_then_the_growth_then_the_tolerance() {
        let g = |verdict| Growth {
            verdict,
            peak: 1.0,
            peak_time: 0.0,
            end: 1.0,
            second_half: 1.0,
        };
        let bounded = g(Verdict::Bounded);
        assert_eq!(
            outcome(Status::Ok, Some(&bounded), Some(1e-3), Some(1e-2)),
            Outcome::Accurate
        );
        assert_eq!(
            outcome(Status::Ok, Some(&bounded), Some(1e-1), Some(1e-2)),
            Outcome::Inaccurate
        );
        assert_eq!(
            outcome(Status::Ok, Some(&bounded), Some(1e-1), None),
            Outcome::Bounded
        );
        assert_eq!(
            outcome(
                Status::Ok,
                Some(&g(Verdict::Growing)),
                Some(1e-3),
                Some(1e-2)
            ),
            Outcome::Unstable
        );
        assert_eq!(
            outcome(
                Status::Ok,
                Some(&g(Verdict::TooShort)),
                Some(1e-3),
                Some(1e-2)
            ),
            Outcome::TooShort
        );
        assert_eq!(
            outcome(Status::Unstable, None, None, Some(1e-2)),
            Outcome::Unstable
        );
        assert_eq!(
            outcome(Status::NotApplicable, None, None, Some(1e-2)),
            Outcome::NotApplicable
        );
    }
}
