//! The stick and slip phases of the friction closed form ([`super::friction`]): the particle's
//! motion along its line, m ẍ = f(t) − k x − friction, under loads that are linear in time
//! within each [`Segment`].
//!
//! With g(t) = f(t) − s μ_k N(t) = g₀ + g₁ τ (τ from the phase's start), a slip phase along
//! s = ±1 from (x, v) is
//!
//! - k = 0: x + v τ + g₀ τ²/(2m) + g₁ τ³/(6m); it stops at the first positive root of the
//!   quadratic v + (g₀ τ + g₁ τ²/2)/m (the numerically stable formula; from rest, at the other
//!   root −2 g₀/g₁ where s g₀ > 0 > s g₁; with g₁ = 0, after τ = −v m/g₀ where s g₀ < 0);
//! - k > 0: the particular solution c + ċ τ (c = g₀/k, ċ = g₁/k) plus a harmonic at ω = √(k/m):
//!   s v = p + W cos ωτ − Y sin ωτ = p + R cos(ωτ + ψ) with p = s ċ, W = s(v − ċ),
//!   Y = s(x − c) ω, R = √(W² + Y²), ψ = atan2(Y, W); it stops at the first ωτ > 0 with
//!   ωτ + ψ ≡ α = atan2(√(R² − p²), −p) (mod 2π) (never where |p| > R). From rest that is
//!   ωτ = 2 atan2(−Y, −p); with ċ = 0, ωτ = atan2(s v/ω, s(x − c)) and the stop is at c + s R/ω.
//!
//! At rest at x the excess of the tangential force over static friction along s,
//! e_s(τ) = s (f(τ) − k x) − μ_s N(τ), is linear in τ: the particle breaks away along s where
//! e_s > 0, or where e_s = 0 and rising, else after τ = −e_s/ė_s where ė_s > 0 (the earlier
//! side). A phase also ends at its segment's end, where the next segment's loads take over.

use super::unsupported;
use crate::engines::EngineError;
use crate::scene::Friction;
use std::f64::consts::TAU;

/// The most phases (stick-slip transitions and segment ends) a scene may have before its duration
/// ends.
const MAX_PHASES: usize = 1_000_000;

/// A stretch of time [start, end) over which the loads are linear in time: the tangential load
/// f(t) = f0 + f1 (t − start) and the normal force N(t) = n0 + n1 (t − start).
#[derive(Debug, Clone, Copy)]
pub(super) struct Segment {
    pub start: f64,
    pub end: f64,
    pub f0: f64,
    pub f1: f64,
    pub n0: f64,
    pub n1: f64,
}

impl Segment {
    /// The tangential load and the normal force at t.
    fn at(&self, t: f64) -> (f64, f64) {
        let tau = t - self.start;
        (self.f0 + self.f1 * tau, self.n0 + self.n1 * tau)
    }
}

/// The motion along the line: m ẍ = f − k x − friction, from x = 0, ẋ = v₀.
#[derive(Debug, Clone)]
pub(super) struct Line {
    pub mass: f64,
    pub stiffness: f64,
    pub v0: f64,
    pub friction: Friction,
    /// The segments, in order, the first from 0, the last to infinity.
    pub segments: Vec<Segment>,
}

/// A phase's motion, from the state at its start.
#[derive(Debug, Clone, Copy)]
enum Motion {
    /// At rest at x.
    Stick { x: f64 },
    /// Slipping without a spring: acceleration a, changing at the rate `jerk`.
    Uniform { x: f64, v: f64, a: f64, jerk: f64 },
    /// Slipping on the spring: harmonic at ω about a centre moving at `drift`.
    Harmonic {
        x: f64,
        v: f64,
        centre: f64,
        drift: f64,
        omega: f64,
    },
}

impl Motion {
    /// Position and velocity τ after the phase's start.
    fn state(&self, tau: f64) -> (f64, f64) {
        match *self {
            Motion::Stick { x } => (x, 0.0),
            Motion::Uniform { x, v, a, jerk } => (
                x + v * tau + 0.5 * a * tau * tau + jerk * tau * tau * tau / 6.0,
                v + a * tau + 0.5 * jerk * tau * tau,
            ),
            Motion::Harmonic {
                x,
                v,
                centre,
                drift,
                omega,
            } => {
                let (sin, cos) = (omega * tau).sin_cos();
                let (y, w) = (x - centre, v - drift);
                (
                    centre + y * cos + w / omega * sin + drift * tau,
                    -y * omega * sin + w * cos + drift,
                )
            }
        }
    }
}

/// A phase: its start time and motion.
#[derive(Debug, Clone, Copy)]
pub(super) struct Phase {
    start: f64,
    motion: Motion,
}

/// Where a phase ends: the time, and how the next one starts.
enum Next {
    /// At rest at x: stick or slip as the loads decide.
    Rest { t: f64, x: f64 },
    /// At rest where it was, breaking away along s.
    BreakAway { t: f64, s: f64 },
    /// At a segment's end, in the state (x, v).
    Segment { t: f64, x: f64, v: f64 },
    /// After the end of the run.
    Done,
}

impl Line {
    /// The phases that start before `end`, in order, each from the state where the previous
    /// one ends.
    pub(super) fn phases(&self, end: f64) -> Result<Vec<Phase>, EngineError> {
        let mut phases = Vec::new();
        let (mut t, mut x, mut v, mut forced) = (0.0, 0.0, self.v0, None);
        let mut segment = 0;
        loop {
            let seg = &self.segments[segment];
            let moving = forced.take().or((v != 0.0).then(|| v.signum()));
            let (motion, next) = match moving {
                Some(s) => self.slip(seg, (t, x, v), s, end),
                None => match self.break_away(seg, t, x) {
                    Some((0.0, s)) => self.slip(seg, (t, x, v), s, end),
                    away => self.stick(seg, (t, x), away, end),
                },
            };
            phases.push(Phase { start: t, motion });
            match next {
                Next::Rest { t: at, x: to } => (t, x, v) = (at, to, 0.0),
                Next::BreakAway { t: at, s } => (t, v, forced) = (at, 0.0, Some(s)),
                Next::Segment { t: at, x: to, v: w } => {
                    (t, x, v) = (at, to, w);
                    segment += 1;
                }
                Next::Done => return Ok(phases),
            }
            if phases.len() >= MAX_PHASES {
                return unsupported(format!(
                    "the friction closed form needs at most {MAX_PHASES} stick-slip phases (the duration holds more)"
                ));
            }
        }
    }

    /// At rest at x from t in `seg`, breaking away as `away` says ([`Line::break_away`]), before
    /// `end`: the stick and how it ends.
    fn stick(
        &self,
        seg: &Segment,
        (t, x): (f64, f64),
        away: Option<(f64, f64)>,
        end: f64,
    ) -> (Motion, Next) {
        let next = match away {
            Some((tau, s)) if t + tau < seg.end && t + tau <= end => {
                Next::BreakAway { t: t + tau, s }
            }
            Some((tau, _)) if t + tau < seg.end => Next::Done,
            _ if seg.end <= end => Next::Segment {
                t: seg.end,
                x,
                v: 0.0,
            },
            _ => Next::Done,
        };
        (Motion::Stick { x }, next)
    }

    /// At rest at x from t: after how long and along which direction it breaks away under
    /// `seg`'s loads (0: at once), if it does.
    fn break_away(&self, seg: &Segment, t: f64, x: f64) -> Option<(f64, f64)> {
        let (f, n) = seg.at(t);
        let net = f - self.stiffness * x;
        let mu = self.friction.static_coefficient;
        [1.0, -1.0]
            .into_iter()
            .filter_map(|s: f64| {
                let (excess, rate) = (s * net - mu * n, s * seg.f1 - mu * seg.n1);
                if excess > 0.0 || (excess == 0.0 && rate > 0.0) {
                    Some((0.0, s))
                } else if rate > 0.0 {
                    Some((-excess / rate, s))
                } else {
                    None
                }
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Slip along `s` from (x, v) at t in `seg` (v = 0 or of sign s), before `end`: the motion
    /// and how it ends.
    fn slip(&self, seg: &Segment, (t, x, v): (f64, f64, f64), s: f64, end: f64) -> (Motion, Next) {
        let (f, n) = seg.at(t);
        let mu = self.friction.kinetic_coefficient;
        let force = f - s * mu * n;
        let rate = seg.f1 - s * mu * seg.n1;
        let (motion, stop) = if self.stiffness == 0.0 {
            self.uniform(x, v, s, force, rate)
        } else {
            self.harmonic(x, v, s, force, rate)
        };
        let next = match stop {
            Some((tau, at)) if t + tau <= seg.end && t + tau <= end => {
                Next::Rest { t: t + tau, x: at }
            }
            _ if seg.end <= end => {
                let (x, v) = motion.state(seg.end - t);
                Next::Segment { t: seg.end, x, v }
            }
            _ => Next::Done,
        };
        (motion, next)
    }

    /// Slip along `s` from (x, v) without a spring under the net force `force` changing at
    /// `rate`: the motion and, where it stops, after how long and where.
    fn uniform(
        &self,
        x: f64,
        v: f64,
        s: f64,
        force: f64,
        rate: f64,
    ) -> (Motion, Option<(f64, f64)>) {
        let (a, jerk) = (force / self.mass, rate / self.mass);
        let motion = Motion::Uniform { x, v, a, jerk };
        if jerk == 0.0 {
            return (
                motion,
                (s * a < 0.0).then(|| (-v / a, x - v * v / (2.0 * a))),
            );
        }
        let tau = if v == 0.0 {
            // From rest: τ (a + jerk τ/2) = 0 at τ = 0 and at the stop, where it has sped up
            // along s and slowed down again.
            (s * a > 0.0 && s * jerk < 0.0).then(|| -2.0 * a / jerk)
        } else {
            first_positive_root(0.5 * jerk, a, v)
        };
        (motion, tau.map(|tau| (tau, motion.state(tau).0)))
    }

    /// Slip along `s` from (x, v) on the spring under the net force `force` changing at `rate`:
    /// the motion and, where it stops, after how long and where.
    fn harmonic(
        &self,
        x: f64,
        v: f64,
        s: f64,
        force: f64,
        rate: f64,
    ) -> (Motion, Option<(f64, f64)>) {
        let omega = (self.stiffness / self.mass).sqrt();
        let (centre, drift) = (force / self.stiffness, rate / self.stiffness);
        let motion = Motion::Harmonic {
            x,
            v,
            centre,
            drift,
            omega,
        };
        if drift == 0.0 {
            let (z, w) = (s * (x - centre), (s * v / omega).abs());
            return (motion, Some((w.atan2(z) / omega, centre + s * z.hypot(w))));
        }
        let (p, y) = (s * drift, s * (x - centre) * omega);
        let phase = if v == 0.0 {
            // From rest: s v = 2 sin(θ/2) (p sin(θ/2) − Y cos(θ/2)), which first speeds up along
            // s (Y < 0; Y = 0 with p > 0: a full turn) and stops again at tan(θ/2) = Y/p.
            if y < 0.0 {
                Some(2.0 * (-y).atan2(-p))
            } else {
                (p > 0.0).then_some(TAU)
            }
        } else {
            let w = s * (v - drift);
            let r = w.hypot(y);
            (p.abs() <= r).then(|| {
                let alpha = ((r - p) * (r + p)).max(0.0).sqrt().atan2(-p);
                let theta = alpha - y.atan2(w);
                if theta > 0.0 { theta } else { theta + TAU }
            })
        };
        let stop = phase.map(|theta| {
            let tau = theta / omega;
            (tau, motion.state(tau).0)
        });
        (motion, stop)
    }
}

/// The smallest positive root of a τ² + b τ + c = 0 (a ≠ 0, c ≠ 0), if any, by the numerically
/// stable formula: q = −(b + sgn(b) √(b² − 4ac))/2, the roots q/a and c/q.
fn first_positive_root(a: f64, b: f64, c: f64) -> Option<f64> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    [q / a, c / q]
        .into_iter()
        .filter(|r| *r > 0.0)
        .min_by(f64::total_cmp)
}

/// Position and velocity at t, from the phase it falls in (a phase's start belongs to it).
pub(super) fn state_at(phases: &[Phase], t: f64) -> (f64, f64) {
    let k = phases.partition_point(|p| p.start <= t).max(1) - 1;
    phases[k].motion.state(t - phases[k].start)
}
